//! Motion quality as an animator sees it, against the reference motion capture: jitter (the
//! mean third difference of the joints, as WHAM reports it, beside the reference's own), foot
//! sliding (the ankle's horizontal travel over each of the reference's contact phases, beside
//! the reference's own), the root's path over the clip after aligning the first frame, the
//! root's height over the floor as each export finds its floor, and the acceleration error of
//! the pelvis-aligned joints.
//!
//! "Horizontal" and "height" are the reference's: its floor is found by the exporter's own
//! [`WorldFrame::estimate`] on the reference skeleton, and the estimate (in the same camera
//! frame) is measured along the same axes.

use crate::synth::GroundTruth;
use nalgebra::{Point3, Vector3};
use videomocap_core::export::WorldFrame;
use videomocap_core::formats::{CONTACT_FLAG, Skeleton3d};
use videomocap_core::skeleton::{Joint, PerJoint};

/// A reference ankle is in contact when it is within this height of its lowest (metres) ...
pub const CONTACT_HEIGHT_M: f64 = 0.05;

/// ... and slower than this (metres per second, horizontal and vertical together).
pub const CONTACT_SPEED_M_S: f64 = 0.3;

/// A contact phase counts from this many frames on.
pub const MIN_PHASE_FRAMES: usize = 3;

/// One frame's joints, metres.
type Pose = PerJoint<Point3<f64>>;

/// Sums over a clip (or several): each figure is a sum and a count, so clips merge.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MotionScore {
    /// Third differences of the estimate's joints, m/s³, summed.
    pub jitter: f64,
    /// The reference's, over the same samples.
    pub ref_jitter: f64,
    /// Joint samples of the third differences.
    pub jitter_n: usize,
    /// The estimate's ankle travel over the reference's contact phases, metres, summed.
    pub slide_m: f64,
    /// The reference's own.
    pub ref_slide_m: f64,
    /// Contact phases.
    pub phases: usize,
    /// The pelvis's distance from the reference's after aligning the first frame, metres.
    pub root_m: f64,
    /// Frames of the root path.
    pub root_n: usize,
    /// |the pelvis's height over the floor − the reference's|, metres, summed over the root
    /// path's frames, each in its own export world.
    pub root_height_m: f64,
    /// |estimated − reference| acceleration of the pelvis-aligned joints, m/s², summed.
    pub accel: f64,
    /// Joint samples of the acceleration.
    pub accel_n: usize,
}

impl MotionScore {
    /// Adds another clip's sums.
    pub fn merge(&mut self, o: &MotionScore) {
        self.jitter += o.jitter;
        self.ref_jitter += o.ref_jitter;
        self.jitter_n += o.jitter_n;
        self.slide_m += o.slide_m;
        self.ref_slide_m += o.ref_slide_m;
        self.phases += o.phases;
        self.root_m += o.root_m;
        self.root_n += o.root_n;
        self.root_height_m += o.root_height_m;
        self.accel += o.accel;
        self.accel_n += o.accel_n;
    }

    /// Mean jitter of the estimate and of the reference, m/s³.
    pub fn jitter(&self) -> (f64, f64) {
        let n = self.jitter_n.max(1) as f64;
        (self.jitter / n, self.ref_jitter / n)
    }

    /// Mean ankle travel per contact phase, estimate and reference, centimetres.
    pub fn slide_cm(&self) -> (f64, f64) {
        let n = self.phases.max(1) as f64;
        (100.0 * self.slide_m / n, 100.0 * self.ref_slide_m / n)
    }

    /// Mean root path error, millimetres.
    pub fn root_mm(&self) -> f64 {
        1000.0 * self.root_m / self.root_n.max(1) as f64
    }

    /// Mean root height error, millimetres.
    pub fn root_height_mm(&self) -> f64 {
        1000.0 * self.root_height_m / self.root_n.max(1) as f64
    }

    /// Mean acceleration error, m/s².
    pub fn accel(&self) -> f64 {
        self.accel / self.accel_n.max(1) as f64
    }
}

/// The joints scored (the reference's derived joints left out).
fn scored(gt: &GroundTruth) -> Vec<Joint> {
    let derived = gt.derived();
    Joint::ALL
        .into_iter()
        .filter(|j| !derived.contains(j))
        .collect()
}

/// Scores `skeleton` against the reference over the longest run of consecutive frames both
/// hold; `None` when the reference's floor cannot be found or no run is four frames long.
pub fn score_motion(gt: &GroundTruth, skeleton: &Skeleton3d) -> Option<MotionScore> {
    let pairs = longest_common_run(gt, skeleton);
    if pairs.len() < 4 {
        return None;
    }
    let est: Vec<_> = pairs.iter().map(|p| p.1).collect();
    let truth: Vec<_> = pairs.iter().map(|p| p.2).collect();
    let contacts: Vec<_> = pairs.iter().map(|p| p.3).collect();
    let world = WorldFrame::estimate(&truth, &[]).ok()?;
    let est_world = WorldFrame::estimate(&est, &contacts).ok()?;
    let (fps, joints) = (gt.fps, scored(gt));
    let mut s = MotionScore::default();
    jitter_and_acceleration(&mut s, &est, &truth, &joints, fps);
    // The root's path after aligning the first frame.
    for t in 0..est.len() {
        let e = est[t][Joint::Pelvis] - est[0][Joint::Pelvis];
        let r = truth[t][Joint::Pelvis] - truth[0][Joint::Pelvis];
        s.root_m += (e - r).norm();
        s.root_n += 1;
        let height = |w: &WorldFrame, p: &Point3<f64>| w.to_world(p).y;
        let truth_height = height(&world, &truth[t][Joint::Pelvis]);
        s.root_height_m += (height(&est_world, &est[t][Joint::Pelvis]) - truth_height).abs();
    }
    foot_sliding(&mut s, &est, &truth, &world, fps);
    Some(s)
}

/// A frame both hold: its index, the estimate, the reference, the estimate's planted joints.
type Pair = (usize, Pose, Pose, PerJoint<bool>);

/// The frames both hold over the longest run of consecutive indices.
fn longest_common_run(gt: &GroundTruth, skeleton: &Skeleton3d) -> Vec<Pair> {
    let pairs: Vec<Pair> = skeleton
        .frames
        .iter()
        .filter_map(|f| {
            let t = f.index.get();
            let contact = f.joint_flags(CONTACT_FLAG);
            Some((t, f.points, gt.frames.get(t)?.points3d(), contact))
        })
        .collect();
    let start = (0..pairs.len())
        .filter(|&k| k == 0 || pairs[k].0 != pairs[k - 1].0 + 1)
        .collect::<Vec<_>>();
    let Some(run) = start
        .iter()
        .enumerate()
        .map(|(i, &s)| s..start.get(i + 1).copied().unwrap_or(pairs.len()))
        .max_by_key(|r| r.len())
    else {
        return Vec::new();
    };
    pairs[run].to_vec()
}

/// Jitter (third differences, the estimate's and the reference's own) and the acceleration
/// error of the pelvis-aligned joints.
fn jitter_and_acceleration(
    s: &mut MotionScore,
    est: &[Pose],
    truth: &[Pose],
    joints: &[Joint],
    fps: f64,
) {
    for t in 0..est.len() - 3 {
        for &j in joints {
            let third = |p: &[PerJoint<Point3<f64>>]| {
                (p[t + 3][j].coords - 3.0 * p[t + 2][j].coords + 3.0 * p[t + 1][j].coords
                    - p[t][j].coords)
                    .norm()
                    * fps.powi(3)
            };
            s.jitter += third(est);
            s.ref_jitter += third(truth);
            s.jitter_n += 1;
        }
    }
    for t in 1..est.len() - 1 {
        for &j in joints {
            let accel = |p: &[PerJoint<Point3<f64>>]| -> Vector3<f64> {
                let q = |k: usize| p[k][j] - p[k][Joint::Pelvis];
                (q(t + 1) - 2.0 * q(t) + q(t - 1)) * fps * fps
            };
            s.accel += (accel(est) - accel(truth)).norm();
            s.accel_n += 1;
        }
    }
}

/// Foot sliding over the reference's contact phases: each ankle's horizontal travel while the
/// reference's ankle is low and slow, the estimate's and the reference's own.
fn foot_sliding(s: &mut MotionScore, est: &[Pose], truth: &[Pose], world: &WorldFrame, fps: f64) {
    let up = |v: Vector3<f64>| (world.rotation * v).y;
    let horizontal = |v: Vector3<f64>| {
        let w = world.rotation * v;
        (w.x * w.x + w.z * w.z).sqrt()
    };
    for ankle in [Joint::LeftAnkle, Joint::RightAnkle] {
        let height: Vec<f64> = truth.iter().map(|p| up(p[ankle].coords)).collect();
        let lowest = height.iter().copied().fold(f64::INFINITY, f64::min);
        let contact: Vec<bool> = (0..truth.len())
            .map(|t| {
                let (a, b) = (t.saturating_sub(1), (t + 1).min(truth.len() - 1));
                let speed =
                    (truth[b][ankle] - truth[a][ankle]).norm() * fps / (b - a).max(1) as f64;
                height[t] - lowest < CONTACT_HEIGHT_M && speed < CONTACT_SPEED_M_S
            })
            .collect();
        let mut t = 0;
        while t < contact.len() {
            if !contact[t] {
                t += 1;
                continue;
            }
            let from = t;
            while t < contact.len() && contact[t] {
                t += 1;
            }
            if t - from < MIN_PHASE_FRAMES {
                continue;
            }
            let travel = |p: &[PerJoint<Point3<f64>>]| -> f64 {
                (from + 1..t)
                    .map(|k| horizontal(p[k][ankle] - p[k - 1][ankle]))
                    .sum()
            };
            s.slide_m += travel(est);
            s.ref_slide_m += travel(truth);
            s.phases += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::GroundTruth;
    use videomocap_core::formats::{Frame3d, FrameIndex};

    fn reference() -> GroundTruth {
        let dir = crate::repo_root().join("sample_videos/synth_walk_oblique");
        GroundTruth::load(&dir.join("gt.json")).unwrap()
    }

    fn skeleton_of(
        gt: &GroundTruth,
        moved: impl Fn(usize, Point3<f64>) -> Point3<f64>,
    ) -> Skeleton3d {
        Skeleton3d {
            camera: gt.camera(),
            fps: Some(gt.fps),
            bone_lengths_m: Default::default(),
            frames: gt
                .frames
                .iter()
                .map(|f| Frame3d {
                    index: FrameIndex(f.index),
                    points: f.points3d().map(|_, p| moved(f.index, *p)),
                    flags: Vec::new(),
                })
                .collect(),
        }
    }

    /// The reference scores nothing against itself but its own jitter and sliding; a body that
    /// wanders in depth slides its feet and strays from the root's path by as much; frame-to-
    /// frame noise is jitter.
    #[test]
    fn the_reference_is_perfect_and_wandering_or_shaking_shows() {
        let gt = reference();
        let same = score_motion(&gt, &skeleton_of(&gt, |_, p| p)).unwrap();
        assert!(same.phases > 0, "a walk has contact phases");
        assert!(same.root_mm() < 1e-9 && same.accel() < 1e-9);
        assert!(same.root_height_mm() < 1e-6, "{}", same.root_height_mm());
        let (j, rj) = same.jitter();
        assert!((j - rj).abs() < 1e-9);
        let (sl, rsl) = same.slide_cm();
        assert!((sl - rsl).abs() < 1e-9 && rsl < 5.0, "{rsl} cm");
        // Wandering 1 cm per frame in depth.
        let wander = score_motion(
            &gt,
            &skeleton_of(&gt, |t, p| p + Vector3::z() * 0.01 * t as f64),
        )
        .unwrap();
        let (sl, rsl) = wander.slide_cm();
        assert!(sl > rsl + 1.0, "{sl} against {rsl}");
        assert!(wander.root_mm() > 50.0, "{}", wander.root_mm());
        // Shaking ±5 mm every other frame.
        let shake = score_motion(
            &gt,
            &skeleton_of(&gt, |t, p| {
                p + Vector3::x() * if t % 2 == 0 { 0.005 } else { -0.005 }
            }),
        )
        .unwrap();
        let (j, rj) = shake.jitter();
        assert!(j > rj + 100.0, "{j} against {rj}");
    }
}
