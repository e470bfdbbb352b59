//! Accuracy of a 3D skeleton against ground truth: MPJPE after aligning the pelvis, PA-MPJPE
//! (after the best similarity transform, per frame), the spread of each bone's length across
//! frames, and the share of bone-frames whose depth root is the wrong one. Also builds the
//! inputs of the lift benchmark from ground truth (true or noisy 2D, the true subject).

use super::EvalError;
use crate::synth::GroundTruth;
use nalgebra::{Matrix3, Point2, Point3, Vector3};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::formats::{
    Frame3d, FrameIndex, FrameTracks, PointSource, Skeleton3d, SourceInfo, TrackedPoint, Tracks2d,
};
use videomocap_core::lift::{AmbiguityWeights, lift_order, resolve};
use videomocap_core::skeleton::{Bone, Joint, PerJoint, SubjectModel};

/// Accumulated 3D errors.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Pose3dScore {
    /// Sum of per-joint errors after pelvis alignment, metres.
    pub sum_pelvis_m: f64,
    /// Sum of per-joint errors after Procrustes alignment, metres.
    pub sum_pa_m: f64,
    /// Joint samples scored.
    pub joints: usize,
    /// Sum over bones of the standard deviation of their length across frames, metres.
    pub sum_spread_m: f64,
    /// Bones whose spread was measured (per clip).
    pub bones: usize,
    /// Bone-frames whose two roots are far enough apart for the choice to matter.
    pub choices: usize,
    /// Of those, the ones where the other root is nearer the truth.
    pub wrong: usize,
    /// Of the choices, the coin flips: both roots about equally far from the truth (their
    /// distances within [`COIN_FLIP_LENGTHS`] of the bone's length). The parent joint is off
    /// (the rigid key triangle against a flexing reference, an earlier choice), so neither
    /// root is right and the choice hardly changes the error.
    pub coin_flips: usize,
    /// Of the coin flips, the ones counted wrong.
    pub coin_flips_wrong: usize,
    /// Choices on the arms' and legs' bones (upper arms, forearms, thighs, shanks).
    pub limb_choices: usize,
    /// Of those, the wrong ones.
    pub limb_wrong: usize,
    /// Frames whose reference shoulders differ in depth by more than [`FACING_DEPTH_M`], where
    /// the body's facing shows.
    pub facing_frames: usize,
    /// Of those, the frames whose shoulders are in the other depth order: the body mirrored.
    pub facing_mirrored: usize,
}

/// How far apart in depth the reference's shoulders must be for a frame's facing to count
/// ([`Pose3dScore::facing_frames`]), metres.
pub const FACING_DEPTH_M: f64 = 0.05;

/// How close, as a share of the bone's length, the two roots' distances from the truth must be
/// for a depth choice to be a coin flip ([`Pose3dScore::coin_flips`]); the same share as the
/// roots' least separation for the choice to count at all.
pub const COIN_FLIP_LENGTHS: f64 = 0.1;

/// One bone's depth choice against the truth ([`root_choice`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RootChoice {
    /// The other root is nearer the truth.
    pub wrong: bool,
    /// Both roots are about equally far from it ([`Pose3dScore::coin_flips`]).
    pub coin_flip: bool,
}

/// How a bone's depth root was chosen: `known` its solved parent, `solved` the joint on its
/// viewing ray (camera space), `want` the true bone vector. `None` when the two roots on the
/// ray lie within [`COIN_FLIP_LENGTHS`] of the bone's length of each other (the choice does
/// not matter).
pub fn root_choice(
    known: Point3<f64>,
    solved: Point3<f64>,
    want: Vector3<f64>,
) -> Option<RootChoice> {
    let len = (solved - known).norm();
    // The other root on the same ray: s' = 2(r·K) − s.
    let r = solved.coords.try_normalize(f64::EPSILON)?;
    let along = r.dot(&solved.coords);
    let other = 2.0 * r.dot(&known.coords) - along;
    if (other - along).abs() < COIN_FLIP_LENGTHS * len {
        return None;
    }
    let alt = Point3::from(r * other);
    let (d_taken, d_other) = (
        ((solved - known) - want).norm(),
        ((alt - known) - want).norm(),
    );
    Some(RootChoice {
        wrong: d_other < d_taken,
        coin_flip: (d_taken - d_other).abs() < COIN_FLIP_LENGTHS * len,
    })
}

/// Whether a bone solved towards `solved` is a limb's (an elbow, wrist, knee or ankle at its
/// end).
fn is_limb(solved: Joint) -> bool {
    matches!(
        solved,
        Joint::LeftElbow
            | Joint::LeftWrist
            | Joint::RightElbow
            | Joint::RightWrist
            | Joint::LeftKnee
            | Joint::LeftAnkle
            | Joint::RightKnee
            | Joint::RightAnkle
    )
}

impl Pose3dScore {
    /// Adds another score.
    pub fn merge(&mut self, o: &Pose3dScore) {
        self.sum_pelvis_m += o.sum_pelvis_m;
        self.sum_pa_m += o.sum_pa_m;
        self.joints += o.joints;
        self.sum_spread_m += o.sum_spread_m;
        self.bones += o.bones;
        self.choices += o.choices;
        self.wrong += o.wrong;
        self.coin_flips += o.coin_flips;
        self.coin_flips_wrong += o.coin_flips_wrong;
        self.limb_choices += o.limb_choices;
        self.limb_wrong += o.limb_wrong;
        self.facing_frames += o.facing_frames;
        self.facing_mirrored += o.facing_mirrored;
    }

    /// The share of frames whose facing shows that have the body mirrored (shoulders in the
    /// wrong depth order).
    pub fn facing_mirrored_share(&self) -> f64 {
        self.facing_mirrored as f64 / self.facing_frames.max(1) as f64
    }
    /// MPJPE after pelvis alignment, mm.
    pub fn mpjpe_mm(&self) -> f64 {
        1000.0 * self.sum_pelvis_m / self.joints.max(1) as f64
    }
    /// PA-MPJPE, mm.
    pub fn pa_mpjpe_mm(&self) -> f64 {
        1000.0 * self.sum_pa_m / self.joints.max(1) as f64
    }
    /// Mean standard deviation of a bone's length across frames, mm.
    pub fn spread_mm(&self) -> f64 {
        1000.0 * self.sum_spread_m / self.bones.max(1) as f64
    }
    /// Share of depth choices that are wrong.
    pub fn wrong_share(&self) -> f64 {
        self.wrong as f64 / self.choices.max(1) as f64
    }
    /// The depth choices that matter: those that are not coin flips
    /// ([`Pose3dScore::coin_flips`]).
    pub fn decided(&self) -> usize {
        self.choices.saturating_sub(self.coin_flips)
    }
    /// Of the choices that matter, the ones decided the wrong way.
    pub fn decided_wrong(&self) -> usize {
        self.wrong.saturating_sub(self.coin_flips_wrong)
    }
    /// Share of the choices that matter that are wrong ([`Pose3dScore::decided_wrong`] of
    /// [`Pose3dScore::decided`]).
    pub fn decided_wrong_share(&self) -> f64 {
        self.decided_wrong() as f64 / self.decided().max(1) as f64
    }
    /// Share of the arms' and legs' depth choices that are wrong.
    pub fn limb_wrong_share(&self) -> f64 {
        self.limb_wrong as f64 / self.limb_choices.max(1) as f64
    }
}

/// The best similarity transform taking `a` onto `b` (Umeyama 1991), applied to `a`.
fn procrustes(a: &[Point3<f64>], b: &[Point3<f64>]) -> Vec<Point3<f64>> {
    let n = a.len() as f64;
    let ca = a.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / n;
    let cb = b.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / n;
    let mut cov = Matrix3::zeros();
    let mut var_a = 0.0;
    for (p, q) in a.iter().zip(b) {
        let (da, db) = (p.coords - ca, q.coords - cb);
        cov += db * da.transpose();
        var_a += da.norm_squared();
    }
    let svd = cov.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return a.to_vec();
    };
    let mut s = Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        s[(2, 2)] = -1.0;
    }
    let r = u * s * v_t;
    let scale = if var_a > 0.0 {
        (svd.singular_values.component_mul(&s.diagonal())).sum() / var_a
    } else {
        1.0
    };
    a.iter()
        .map(|p| Point3::from(cb + r * (p.coords - ca) * scale))
        .collect()
}

/// Scores a skeleton against the reference (frames matched by index).
pub fn score_skeleton(gt: &GroundTruth, skeleton: &Skeleton3d) -> Result<Pose3dScore, EvalError> {
    let derived = gt.derived();
    let scored: Vec<Joint> = Joint::ALL
        .into_iter()
        .filter(|j| !derived.contains(j))
        .collect();
    let mut s = Pose3dScore::default();
    let mut lengths: BTreeMap<Bone, Vec<f64>> = BTreeMap::new();
    for frame in &skeleton.frames {
        let truth = gt
            .frames
            .get(frame.index.get())
            .ok_or(EvalError {
                gt: gt.frames.len(),
                frame: frame.index.get(),
            })?
            .points3d();
        let p = &frame.points;
        let (pp, tp) = (p[Joint::Pelvis], truth[Joint::Pelvis]);
        let depth_order =
            |q: &PerJoint<Point3<f64>>| q[Joint::LeftShoulder].z - q[Joint::RightShoulder].z;
        if depth_order(&truth).abs() > FACING_DEPTH_M {
            s.facing_frames += 1;
            s.facing_mirrored += usize::from(depth_order(p) * depth_order(&truth) < 0.0);
        }
        for &j in &scored {
            s.sum_pelvis_m += ((p[j] - pp) - (truth[j] - tp)).norm();
        }
        let ours: Vec<Point3<f64>> = scored.iter().map(|&j| p[j]).collect();
        let theirs: Vec<Point3<f64>> = scored.iter().map(|&j| truth[j]).collect();
        for (a, b) in procrustes(&ours, &theirs).iter().zip(&theirs) {
            s.sum_pa_m += (a - b).norm();
        }
        s.joints += scored.len();
        for bone in Bone::ALL {
            let (known, solved) = lift_order(bone);
            if derived.contains(&known) || derived.contains(&solved) {
                continue;
            }
            let (k, c) = (p[known], p[solved]);
            lengths.entry(bone).or_default().push((c - k).norm());
            let Some(choice) = root_choice(k, c, truth[solved] - truth[known]) else {
                continue;
            };
            let limb = is_limb(solved);
            s.choices += 1;
            s.wrong += usize::from(choice.wrong);
            s.coin_flips += usize::from(choice.coin_flip);
            s.coin_flips_wrong += usize::from(choice.coin_flip && choice.wrong);
            s.limb_choices += usize::from(limb);
            s.limb_wrong += usize::from(limb && choice.wrong);
        }
    }
    for values in lengths.values() {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        s.sum_spread_m += var.sqrt();
        s.bones += 1;
    }
    Ok(s)
}

/// The distance between two joints in each of the reference's frames.
fn distances(gt: &GroundTruth, a: Joint, b: Joint) -> Vec<f64> {
    gt.frames
        .iter()
        .map(|f| {
            let p = f.points3d();
            (p[a] - p[b]).norm()
        })
        .collect()
}

/// Mean distance between two joints over the reference's frames.
fn mean_distance(gt: &GroundTruth, a: Joint, b: Joint) -> f64 {
    distances(gt, a, b).iter().sum::<f64>() / gt.frames.len().max(1) as f64
}

/// The subject with the reference's own mean bone lengths and shoulder width (the height, which
/// only sizes the body's breadths, is the clip's stated height, else the default).
pub fn subject_from_truth(gt: &GroundTruth) -> SubjectModel {
    let mut s = SubjectModel {
        height_m: gt
            .stated_height_m
            .unwrap_or(videomocap_core::skeleton::DEFAULT_HEIGHT_M),
        ..SubjectModel::default()
    };
    for (k, b) in Bone::ALL.iter().enumerate() {
        s.bone_length_m[k] = mean_distance(gt, b.parent, b.child);
    }
    s.shoulder_width_m = mean_distance(gt, Joint::LeftShoulder, Joint::RightShoulder);
    s
}

/// Tracks made from the reference's 2D points, plus Gaussian noise of `noise_px` per
/// coordinate (seeded), all fully trusted.
pub fn tracks_from_truth(gt: &GroundTruth, noise_px: f64, seed: u64) -> Tracks2d {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let normal = Normal::new(0.0, noise_px.max(0.0)).ok();
    let mut jitter = || normal.map_or(0.0, |n| n.sample(&mut rng));
    Tracks2d {
        source: SourceInfo {
            path: "gt.json".into(),
            width: gt.width,
            height: gt.height,
            fps: gt.fps,
            frame_count: gt.frames.len(),
        },
        frames: gt
            .frames
            .iter()
            .map(|f| {
                let p = f.points2d();
                FrameTracks {
                    index: FrameIndex(f.index),
                    body3d: None,
                    points: PerJoint::from_fn(|j| TrackedPoint {
                        pos: Point2::new(p[j].x + jitter(), p[j].y + jitter()),
                        confidence: 1.0,
                        source: PointSource::Tracked,
                    }),
                }
            })
            .collect(),
    }
}

/// How much the reference's key triangle flexes: the standard deviation across frames of each
/// of its three sides (shoulder to shoulder, chest to each shoulder), averaged, metres. The lift
/// holds the triangle rigid (eqs. 9–11); a motion-capture chest, on the line from neck to
/// pelvis, rides the bending spine, so even exact 2D with the mean lengths misplaces it.
pub fn key_triangle_flex_m(gt: &GroundTruth) -> f64 {
    let sides = [
        (Joint::LeftShoulder, Joint::RightShoulder),
        (Joint::Chest, Joint::LeftShoulder),
        (Joint::Chest, Joint::RightShoulder),
    ];
    let n = gt.frames.len().max(1) as f64;
    sides
        .iter()
        .map(|&(a, b)| {
            let lengths = distances(gt, a, b);
            let mean = lengths.iter().sum::<f64>() / n;
            (lengths.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / n).sqrt()
        })
        .sum::<f64>()
        / sides.len() as f64
}

/// The lift's root choices on their own: every frame's key triangle (both shoulders and the
/// chest) put where the reference has it, every other joint solved from the true 2D points with
/// `subject`'s lengths and its root chosen by [`resolve`]. What stays wrong is the depth
/// ambiguity's alone, the key triangle's share of the error removed.
pub fn lift_on_reference_key(
    gt: &GroundTruth,
    subject: &SubjectModel,
    weights: &AmbiguityWeights,
) -> Skeleton3d {
    let camera = gt.camera();
    let key: Vec<[Point3<f64>; 3]> = gt
        .frames
        .iter()
        .map(|f| {
            let p = f.points3d();
            [
                p[Joint::LeftShoulder],
                p[Joint::RightShoulder],
                p[Joint::Chest],
            ]
        })
        .collect();
    let rays: Vec<PerJoint<Vector3<f64>>> = gt
        .frames
        .iter()
        .map(|f| f.points2d().map(|_, p| camera.ray(p)))
        .collect();
    let index: Vec<FrameIndex> = gt.frames.iter().map(|f| FrameIndex(f.index)).collect();
    let resolved = resolve(
        &key,
        &rays,
        &index,
        &[],
        subject,
        weights,
        &Default::default(),
    );
    Skeleton3d {
        camera,
        fps: Some(gt.fps),
        bone_lengths_m: Default::default(),
        frames: index
            .iter()
            .zip(resolved.points)
            .map(|(&index, points)| Frame3d {
                index,
                points,
                flags: Vec::new(),
            })
            .collect(),
    }
}

/// The flat cut-out, the baseline of every 3D table: each joint of `tracks` on its viewing ray
/// (through `camera`) at the depth of the reference's pelvis on that frame, as if the body were a
/// figure cut out of card facing the camera. A lift that does not beat it has added no depth.
pub fn cutout(gt: &GroundTruth, tracks: &Tracks2d, camera: PinholeCamera) -> Skeleton3d {
    let frames = tracks
        .frames
        .iter()
        .filter_map(|f| {
            let depth = gt.frames.get(f.index.get())?.points3d()[Joint::Pelvis].z;
            Some(Frame3d {
                index: f.index,
                points: f.points.map(|_, p| {
                    let ray = camera.ray(&p.pos);
                    Point3::from(ray * (depth / ray.z))
                }),
                flags: Vec::new(),
            })
        })
        .collect();
    Skeleton3d {
        camera,
        fps: Some(gt.fps),
        bone_lengths_m: BTreeMap::new(),
        frames,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reference of `frames` (joints in camera space) seen by a 500 px camera.
    fn reference(frames: &[PerJoint<Point3<f64>>]) -> (GroundTruth, PinholeCamera) {
        let camera = PinholeCamera::centred(500.0, 640, 480);
        let gt = GroundTruth {
            source: "test".into(),
            fps: 30.0,
            width: 640,
            height: 480,
            focal_px: camera.focal_px,
            cx: camera.cx,
            cy: camera.cy,
            joints: Joint::ALL.iter().map(|j| j.name().to_owned()).collect(),
            derived_joints: vec![],
            stated_height_m: Some(1.7),
            bone_lengths_m: BTreeMap::new(),
            frames: frames
                .iter()
                .enumerate()
                .map(|(index, p)| crate::synth::GroundTruthFrame {
                    index,
                    points2d: p
                        .0
                        .iter()
                        .map(|q| {
                            let uv = camera.project(q).unwrap_or(Point2::origin());
                            [uv.x, uv.y]
                        })
                        .collect(),
                    points3d: p.0.iter().map(|q| [q.x, q.y, q.z]).collect(),
                    visible: vec![true; 16],
                })
                .collect(),
        };
        (gt, camera)
    }

    /// A body 3 m away with its left shoulder 20 cm nearer the camera than its right.
    fn turned_body() -> PerJoint<Point3<f64>> {
        PerJoint::from_fn(|j| {
            let k = j.index() as f64;
            let z = match j {
                Joint::LeftShoulder => 2.9,
                Joint::RightShoulder => 3.1,
                _ => 3.0 + 0.01 * k,
            };
            Point3::new(0.05 * k - 0.4, 0.1 * k - 0.8, z)
        })
    }

    #[test]
    fn a_mirrored_body_is_counted_and_the_cutout_keeps_only_the_depth_of_the_pelvis() {
        let body = turned_body();
        let (gt, camera) = reference(&[body, body]);
        let mut mirrored = body;
        mirrored[Joint::LeftShoulder].z = 3.1;
        mirrored[Joint::RightShoulder].z = 2.9;
        let skeleton = Skeleton3d {
            camera,
            fps: Some(30.0),
            bone_lengths_m: BTreeMap::new(),
            frames: [body, mirrored]
                .iter()
                .enumerate()
                .map(|(index, p)| Frame3d {
                    index: FrameIndex(index),
                    points: *p,
                    flags: vec![],
                })
                .collect(),
        };
        let s = score_skeleton(&gt, &skeleton).unwrap();
        assert_eq!((s.facing_frames, s.facing_mirrored), (2, 1));
        assert!((s.facing_mirrored_share() - 0.5).abs() < 1e-12);
        // The cut-out flattens every joint onto the pelvis's depth: off by the joints' own
        // depths, nothing else.
        let flat = cutout(&gt, &tracks_from_truth(&gt, 0.0, 1), camera);
        let c = score_skeleton(&gt, &flat).unwrap();
        assert!(
            c.mpjpe_mm() > 10.0 && c.mpjpe_mm() < 200.0,
            "{}",
            c.mpjpe_mm()
        );
        let p = &flat.frames[0].points;
        assert!(
            Joint::ALL
                .iter()
                .all(|&j| (p[j].z - body[Joint::Pelvis].z).abs() < 1e-9)
        );
    }

    #[test]
    fn a_root_choice_is_wrong_right_or_a_coin_flip() {
        // A 0.3 m bone from a parent 3 m ahead, tilted 30° towards the camera.
        let known = Point3::new(0.0, 0.0, 3.0);
        let tilt = 30f64.to_radians();
        let want = Vector3::new(0.3 * tilt.cos(), 0.0, -0.3 * tilt.sin());
        let truth = known + want;
        // The mirror root on the same ray.
        let r = truth.coords.normalize();
        let mirror = Point3::from(r * (2.0 * r.dot(&known.coords) - r.dot(&truth.coords)));
        let right = root_choice(known, truth, want);
        assert_eq!(
            right,
            Some(RootChoice {
                wrong: false,
                coin_flip: false
            })
        );
        let wrong = root_choice(known, mirror, want);
        assert_eq!(
            wrong,
            Some(RootChoice {
                wrong: true,
                coin_flip: false
            })
        );
        // The parent solved off its true place: the true bone hung from it ends on the plane
        // halfway between the two roots on the ray (here beyond the ray's nearest point to
        // the parent), so either root is as far from it.
        let foot = Point3::from(r * r.dot(&known.coords));
        let to_foot = foot - known;
        let half = (0.09 - to_foot.norm_squared()).sqrt();
        let sideways = to_foot * (0.3 / to_foot.norm());
        let flip = root_choice(known, foot - r * half, sideways);
        assert_eq!(
            flip,
            Some(RootChoice {
                wrong: false,
                coin_flip: true
            })
        );
        assert_eq!(
            root_choice(known, foot + r * half, sideways).map(|c| c.coin_flip),
            Some(true)
        );
        // A bone square to its end's viewing ray: both roots together, no choice.
        let end = Point3::new(0.0, 0.3, 3.0);
        let square = Vector3::new(0.3, 0.0, 0.0);
        assert_eq!(root_choice(end - square, end, square), None);
    }

    #[test]
    fn procrustes_undoes_a_similarity() {
        let a: Vec<Point3<f64>> = (0..6)
            .map(|i| Point3::new(i as f64, (i * i) as f64 * 0.1, (i % 3) as f64))
            .collect();
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.5, 1.1);
        let b: Vec<Point3<f64>> = a
            .iter()
            .map(|p| Point3::from(r * p.coords * 1.7 + Vector3::new(1.0, 2.0, 3.0)))
            .collect();
        for (p, q) in procrustes(&a, &b).iter().zip(&b) {
            assert!((p - q).norm() < 1e-9);
        }
    }
}
