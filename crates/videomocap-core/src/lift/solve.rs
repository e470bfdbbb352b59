//! The lift of a whole sequence: checks, calibration on the best frame, propagation to the
//! others, root choices, the optional global refinement, and the per-frame report.

use super::ambiguity::{AmbiguityWeights, DepthOverrides, Resolved, resolve};

use super::calibrate::{
    KEY_JOINTS, KeyTriangle, Residuals, calibrate_all, calibrate_from, longest_side, shape,
    starting_poses,
};
use super::error::{LiftError, check_setting};
use super::key_path::{centroid, chain_pitch_prior, smooth_key_path, tilt_m};
use super::pipeline::LiftStage;
use super::propagate::key_depths;
use super::refine::{RefineParams, RefineSummary, refine, track_weight};
use super::report::{BoneDepth, FrameFlag, FrameReport, flag_too_long};
use super::smoothing::{adaptive_sigmas, median_noise_px, smoothed_images};
use crate::camera::PinholeCamera;
use crate::formats::{Frame3d, FrameIndex, PointSource, Skeleton3d, Tracks2d};
use crate::skeleton::{BONE_COUNT, Bone, Joint, PerJoint, SubjectModel};
use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicBool, Ordering};

/// Settings of the lift; every field has a documented default and can be given as JSON.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LiftParams {
    /// Run the global refinement after the per-frame solve (default true), then set every bone
    /// back to exactly its refined length (`super::refine::snap_to_lengths`), so the BVH's
    /// fixed offsets give the skeleton back exactly. `bench lift` reports both; on the synthetic
    /// suite with true lengths it lowers the error 49.2 → 47.7 mm with 2 px white noise (four
    /// draws), 94.2 → 93.9 mm with the tracker's output, exact tracks 11.5 → 11.3 mm; on the
    /// real sample 68.1 → 66.7 mm with its reference 2D and 174.0 → 172.3 mm with the
    /// tracker's output. It lowers every overall row but one: the real sample from the
    /// tracker's output and the height (162.0 → 162.2 mm).
    pub refine: bool,
    /// A key-triangle calibration fits when its residual is below this RMS, pixels (default 1).
    pub calibration_tolerance_px: f64,
    /// A calibrated key-triangle pose is made exact by eqs. 10–11 when they then hold within this
    /// RMS residual, metres (default 0.005).
    pub propagation_tolerance_m: f64,
    /// When above 0, the per-frame solve works on tracks smoothed over time by a Gaussian of
    /// this many seconds, the same for every joint (default 0: see `adaptive_smoothing`).
    /// Measured on the synthetic suite, 0.066 s (two frames at 30 fps) halved the error with
    /// 2 px white noise (150 → 80 mm) but raised it with exact tracks (31 → 51 mm: a grazing
    /// key triangle turns a pixel of lag into centimetres of depth).
    pub smoothing_s: f64,
    /// When `smoothing_s` is 0, smooth each joint's track by the width its own noise calls for
    /// (`super::smoothing`; default true). On the synthetic suite with true lengths: 2 px
    /// white noise 162 → 77.5 mm, exact tracks 31.1 → 31.1 mm, the tracker's output
    /// 151.5 → 157.7 mm (its errors are drift and jumps more than white noise).
    pub adaptive_smoothing: bool,
    /// Refit the key triangle's path over the whole clip after it is chosen frame by frame
    /// (`super::key_path`: reprojection, rigid sides, acceleration and the trunk's pitch
    /// towards the camera by least squares, as firm as the tracks are noisy; default true).
    /// With the calibration frame chosen by size as well, on the synthetic suite with true
    /// lengths: 2 px noise (four draws) 71.0 → 53.3 mm, exact tracks 20.4 → 20.6 mm, the
    /// tracker's output 111.3 → 112.0 mm; the real sample with noise 73.1 → 70.5 mm, with its
    /// reference 2D 69.2 → 69.3 mm.
    pub key_path_smoothing: bool,
    /// Weights of the depth-ambiguity priors.
    pub ambiguity: AmbiguityWeights,
    /// Weights of the global refinement.
    pub refinement: RefineParams,
    /// Hold a planted foot in place (default true): each foot's contacts with the floor are
    /// found and the body is moved along the planted ankle's viewing ray so the ankle keeps one
    /// depth over each (it stays on its 2D track).
    pub foot_lock: bool,
}

impl Default for LiftParams {
    fn default() -> Self {
        LiftParams {
            refine: true,
            calibration_tolerance_px: 1.0,
            propagation_tolerance_m: 0.005,
            smoothing_s: 0.0,
            adaptive_smoothing: true,
            key_path_smoothing: true,
            ambiguity: AmbiguityWeights::default(),
            refinement: RefineParams::default(),
            foot_lock: true,
        }
    }
}

/// What to lift and how.
#[derive(Debug, Clone)]
pub struct LiftJob<'a> {
    /// The 2D tracks.
    pub tracks: &'a Tracks2d,
    /// The camera (focal length given or estimated by `super::focal`).
    pub camera: PinholeCamera,
    /// The subject's bone lengths and shoulder width.
    pub subject: SubjectModel,
    /// Settings.
    pub params: LiftParams,
    /// Root choices forced by the user.
    pub overrides: DepthOverrides,
}

/// The per-frame solve before refinement.
#[derive(Debug, Clone, PartialEq)]
pub struct PerFrame {
    /// Joints and root choices.
    pub resolved: Resolved,
    /// One report per frame.
    pub reports: Vec<FrameReport>,
    /// The frame the camera was calibrated on.
    pub calibration_frame: usize,
    /// The (smoothed) 2D points the solve used, per frame.
    pub images: Vec<PerJoint<Point2<f64>>>,
}

/// Where the lift is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiftProgress {
    /// What is being done.
    pub stage: LiftStage,
    /// Steps done.
    pub done: usize,
    /// Steps in this stage.
    pub total: usize,
}

/// The result of a lift.
#[derive(Debug, Clone, PartialEq)]
pub struct LiftOutput {
    /// The final skeleton (refined when refinement ran).
    pub skeleton: Skeleton3d,
    /// The per-frame skeleton (eqs. 6–11 and the root choices), before refinement.
    pub per_frame: Skeleton3d,
    /// Per frame, each bone's depth choice (indexed like [`Bone::ALL`]), for flipping and for
    /// pointing at the unsure ones.
    pub bones: Vec<[BoneDepth; BONE_COUNT]>,
    /// One report per frame (its flags those of the final skeleton).
    pub reports: Vec<FrameReport>,
    /// The frame the camera was calibrated on.
    pub calibration_frame: usize,
    /// What the refinement did, if it ran.
    pub refinement: Option<RefineSummary>,
    /// Per frame, whether each foot (left, right) was found planted (all false with
    /// `foot_lock` off).
    pub contacts: super::contact::FootContacts,
}

impl LiftParams {
    /// Checks every setting is in the range it means something in (a settings file can hold
    /// anything): tolerances positive, the smoothing width not negative, and the ambiguity
    /// weights and refinement deviations as their own `validate` says.
    pub fn validate(&self) -> Result<(), LiftError> {
        // Destructured so that a new setting cannot be left unchecked.
        let LiftParams {
            refine: _,
            calibration_tolerance_px,
            propagation_tolerance_m,
            smoothing_s,
            adaptive_smoothing: _,
            key_path_smoothing: _,
            foot_lock: _,
            ambiguity,
            refinement,
        } = *self;
        check_setting("calibration_tolerance_px", calibration_tolerance_px, true)?;
        check_setting("propagation_tolerance_m", propagation_tolerance_m, true)?;
        check_setting("smoothing_s", smoothing_s, false)?;
        ambiguity.validate()?;
        refinement.validate()
    }
}

/// Checks the job's inputs.
fn check(job: &LiftJob<'_>) -> Result<(), LiftError> {
    job.params.validate()?;
    let f = job.camera.focal_px;
    if !(f.is_finite() && f > 0.0) {
        return Err(LiftError::BadFocal(f));
    }
    if job.tracks.frames.is_empty() {
        return Err(LiftError::NoFrames);
    }
    for frame in &job.tracks.frames {
        for (joint, p) in frame.points.iter() {
            if !(p.pos.x.is_finite() && p.pos.y.is_finite()) {
                return Err(LiftError::NonFinite {
                    frame: frame.index,
                    joint,
                });
            }
        }
    }
    Ok(())
}

fn key_image(images: &[PerJoint<Point2<f64>>], t: usize) -> [Point2<f64>; 3] {
    KEY_JOINTS.map(|j| images[t][j])
}

/// Shoulders on top of each other or on the chest (closer than one pixel).
fn degenerate(image: &[Point2<f64>; 3]) -> bool {
    (image[0] - image[1]).norm() < 1.0
        || (image[0] - image[2]).norm() < 1.0
        || (image[1] - image[2]).norm() < 1.0
}

/// Distance in metres between where each joint is and where its track says it is, at its
/// depth: how badly a skeleton misses its 2D points.
pub(crate) fn miss_m(
    cam: &PinholeCamera,
    points: &PerJoint<Point3<f64>>,
    image: &PerJoint<Point2<f64>>,
) -> f64 {
    Joint::ALL
        .iter()
        .map(|&j| {
            cam.project(&points[j])
                .map_or(1.0, |p| (p - image[j]).norm() / cam.focal_px * points[j].z)
        })
        .sum()
}

/// Eqs. 6–11 and the root choices for every frame.
pub fn lift_per_frame(job: &LiftJob<'_>) -> Result<PerFrame, LiftError> {
    per_frame_solve(job, &job.subject.length_doubt, false)
}

/// [`lift_per_frame`], flagging a bone too long only beyond its length's `doubt` (per bone, a
/// share of the length); `shortened` when the job's subject is already solved that much shorter
/// than read ([`SubjectModel::leaning`]).
fn per_frame_solve(
    job: &LiftJob<'_>,
    doubt: &[f64; BONE_COUNT],
    shortened: bool,
) -> Result<PerFrame, LiftError> {
    check(job)?;
    let cam = &job.camera;
    let tracks = job.tracks;
    let n = tracks.frames.len();
    let triangle = KeyTriangle::from_subject(&job.subject)?;
    let sides = super::calibrate::KEY_LINES.map(|(i, j)| triangle.side(i, j));
    let fps = if tracks.source.fps.is_finite() && tracks.source.fps > 0.0 {
        tracks.source.fps
    } else {
        30.0
    };
    let sigma = if job.params.smoothing_s > 0.0 {
        PerJoint([job.params.smoothing_s * fps; crate::skeleton::JOINT_COUNT])
    } else if job.params.adaptive_smoothing {
        adaptive_sigmas(tracks)
    } else {
        PerJoint([0.0; crate::skeleton::JOINT_COUNT])
    };
    let images = smoothed_images(tracks, &sigma);
    let rays: Vec<_> = images.iter().map(|im| im.map(|_, p| cam.ray(p))).collect();
    let frame_index: Vec<FrameIndex> = tracks.frames.iter().map(|f| f.index).collect();
    let bodies: Vec<_> = tracks
        .frames
        .iter()
        .map(|f| f.body3d.as_deref().cloned())
        .collect();

    // The calibration frame: the best-shaped key triangle, weighted by the trust in its points
    // and by its size in the image (a pixel of noise turns a small triangle further: with one
    // draw of 2 px noise the suite's far walk was calibrated 0.5 m too near on its first frame,
    // 301 mm MPJPE; by size, 30 frames later, 53 mm).
    let calibration_frame = (0..n)
        .filter(|&t| !degenerate(&key_image(&images, t)))
        .max_by(|&a, &b| {
            let score = |t: usize| {
                let trust = KEY_JOINTS
                    .iter()
                    .map(|&j| f64::from(tracks.frames[t].points[j].confidence))
                    .fold(1.0, f64::min)
                    .max(0.05);
                let k = key_image(&images, t);
                shape(&k) * longest_side(&k) * trust
            };
            score(a).total_cmp(&score(b))
        })
        .ok_or(LiftError::DegenerateKeyTriangle)?;
    let mut calibrations = calibrate_all(
        cam,
        &triangle,
        &key_image(&images, calibration_frame),
        job.params.calibration_tolerance_px,
    );
    // Poses too deep for the trunk's image length are dropped, unless every pose is.
    let max_depth = deepest_trunk(cam, &job.subject, &images[calibration_frame]);
    let plausible = |c: &super::calibrate::Calibration| {
        plausible_key(&triangle.points.map(|p| c.pose.apply(&p)), max_depth)
    };
    if calibrations.iter().any(plausible) {
        calibrations.retain(plausible);
    }
    // Several poses fit three points. Each is carried through the whole sequence and the
    // whole body is built on it; the one kept explains the tracks best (bones too long for
    // their image give a wrong pose away) with the least prior and acceleration cost of the
    // root choices (a wrong pose twists the shoulders against the hips and bends knees the
    // wrong way for the whole clip), each part weighed on its own scale ([`fit_score`]).
    let key_of = |pose: &super::calibrate::Pose| triangle.points.map(|p| pose.apply(&p));
    // What the key path's refit needs: the key joints' smoothed image points, their trust, and
    // their tracks' noise (the key joints' own: the tracker carries them with the trunk block,
    // steadier than the limbs; on the suite from the tracker's output 113.1 → 111.8 mm against
    // the median over all joints, other inputs within 0.5 mm).
    let key_observed: Vec<[Point2<f64>; 3]> = (0..n).map(|t| key_image(&images, t)).collect();
    let key_weights: Vec<[f64; 3]> = tracks
        .frames
        .iter()
        .map(|f| KEY_JOINTS.map(|j| track_weight(&f.points[j])))
        .collect();
    let noise_px = median_noise_px(tracks, &KEY_JOINTS);
    let mut best: Option<(f64, Vec<FrameReport>, Resolved)> = None;
    // Every frame's candidate poses, computed once.
    let per_frame: Vec<(Vec<[Point3<f64>; 3]>, bool)> = (0..n)
        .map(|t| {
            let max_depth = deepest_trunk(cam, &job.subject, &images[t]);
            key_candidates(job, &triangle, &sides, &key_image(&images, t), max_depth)
        })
        .collect();
    for c in &calibrations {
        let mut candidates: Vec<Vec<[Point3<f64>; 3]>> =
            per_frame.iter().map(|(k, _)| k.clone()).collect();
        candidates[calibration_frame] = vec![key_of(&c.pose)];
        // With noisy tracks the chain also keeps the trunk's pitch towards the camera near the
        // calibration frame's (the refit's pitch term, weighed alike): the frame by frame
        // choice then seldom tips a facing triangle the wrong way (2 px noise, four draws on
        // the suite: 56.8 → 53.3 mm, wrong roots 16.6 → 14.3 %; fixed weights from 0.05 to 0.4
        // gave 53.0–53.9; the real sample with noise and the tracker's output unchanged).
        let pitch = job
            .params
            .key_path_smoothing
            .then(|| chain_pitch_prior(noise_px, fps, &key_of(&c.pose)))
            .flatten();
        let mut key = smoothest_key_path(&candidates, pitch);
        if job.params.key_path_smoothing {
            key = smooth_key_path(
                cam,
                &key,
                &key_observed,
                &key_weights,
                &triangle.points,
                noise_px,
                fps,
            );
        }
        // The whole body built on a key path, and how well it explains the clip.
        let build = |key: &[[Point3<f64>; 3]]| {
            let resolved = resolve(
                key,
                &rays,
                &frame_index,
                &bodies,
                &job.subject,
                &job.params.ambiguity,
                &job.overrides,
            );
            let miss: f64 = (0..n)
                .map(|t| miss_m(cam, &resolved.points[t], &images[t]))
                .sum();
            let mut score = fit_score(miss, &resolved.group_costs);
            let facing_weight = job.params.ambiguity.image_facing;
            if facing_weight > 0.0
                && let Some(cost) = super::ambiguity::image_facing_cost(key, &bodies)
            {
                score += facing_weight * cost.max(FIT_FLOOR).ln();
            }
            (resolved, score)
        };
        // The facing decided stretch by stretch over the whole clip (see `facing_by_segments`).
        key = facing_by_segments(key, &per_frame, |k| build(k).1);
        let mut reports: Vec<FrameReport> = tracks
            .frames
            .iter()
            .zip(&per_frame)
            .zip(&key)
            .map(|((f, (_, converged)), k)| FrameReport {
                index: f.index,
                key_rms_m: super::calibrate::KEY_LINES
                    .iter()
                    .zip(&sides)
                    .map(|(&(i, j), side)| ((k[i] - k[j]).norm() - side).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    / 3f64.sqrt(),
                flags: (!*converged)
                    .then_some(FrameFlag::KeyTriangleNotConverged)
                    .into_iter()
                    .chain(
                        Joint::ALL
                            .into_iter()
                            .filter_map(|j| match f.points[j].source {
                                PointSource::OffFrame => Some(FrameFlag::OffFrame(j)),
                                PointSource::Lost => Some(FrameFlag::Lost(j)),
                                PointSource::Tracked | PointSource::Interpolated => None,
                            }),
                    )
                    .collect(),
            })
            .collect();
        let (resolved, score) = build(&key);
        if best.as_ref().is_none_or(|b| score < b.0) {
            let lengths = &job.subject.bone_length_m;
            let solved = (&resolved.points[..], &images[..], lengths);
            flag_too_long(job, &mut reports, solved, doubt, shortened);
            best = Some((score, reports, resolved));
        }
    }
    let Some((_, reports, resolved)) = best else {
        return Err(LiftError::CalibrationFailed {
            frame: frame_index[calibration_frame],
        });
    };
    Ok(PerFrame {
        resolved,
        reports,
        calibration_frame,
        images,
    })
}

/// The least a part's cost counts as in [`fit_score`] (in the part's own unit: metres for the
/// miss, squared metres for a group's cost, both summed over the clip): a part that fits
/// exactly (cost 0) would otherwise outvote every other. 0.01 and 0.1 chose the same poses on
/// every clip of `bench lift`.
pub const FIT_FLOOR: f64 = 0.01;

/// How badly a calibration pose, carried through the clip, fits: the sum of the logarithms of
/// the 2D miss (metres, [`miss_m`] summed over the frames) and of each group of bones' prior
/// and acceleration cost ([`Resolved::group_costs`]), each at least [`FIT_FLOOR`]; lower is
/// better. Each part is compared on its own scale (the log of a product of per-part costs, as
/// if each had its own unknown spread), so a part the tracker lost, whose cost is large under
/// every pose, cannot outvote the parts that agree. On the synthetic suite from the tracker's
/// output (true lengths) the plain sum let a raised camera's badly tracked legs pick the
/// trunk tipped the other way (treadmill_raised 353.9 mm); with this sum of logs 174.2 mm,
/// and the suite 117.7 → 103.5 mm (from the height 119.5 → 117.7); exact and noisy 2D and the
/// real sample within 0.1 mm.
pub fn fit_score(miss_m: f64, group_costs: &[f64]) -> f64 {
    std::iter::once(miss_m)
        .chain(group_costs.iter().copied())
        .map(|c| c.max(FIT_FLOOR).ln())
        .sum()
}

/// How deep the trunk can be and still look as long as it does in the image: a segment of
/// length `L` at depth `Z` spans at most about `f·L/Z` pixels, so `Z ≤ f·L/l` for the trunk
/// (neck to pelvis, `l` pixels), with half as much again for perspective and tracking error;
/// unbounded when the trunk's image is under a pixel.
fn deepest_trunk(
    cam: &PinholeCamera,
    subject: &SubjectModel,
    image: &PerJoint<Point2<f64>>,
) -> f64 {
    let trunk_m = subject.trunk_m();
    let trunk_px = (image[Joint::Neck] - image[Joint::Pelvis]).norm();
    if trunk_px < 1.0 {
        f64::INFINITY
    } else {
        1.5 * cam.focal_px * trunk_m / trunk_px
    }
}

/// The nearest a key joint may be to the camera, metres: no one films a trunk from closer.
pub const NEAREST_KEY_M: f64 = 0.2;

/// Whether a key pose may be kept: its centroid no deeper than `max_depth`, every joint at
/// least [`NEAREST_KEY_M`] in front of the camera. A pinhole images a triangle with every point
/// negated (behind the camera) exactly as the triangle itself, so calibration can land there.
fn plausible_key(key: &[Point3<f64>; 3], max_depth: f64) -> bool {
    centroid(key).z <= max_depth && key.iter().all(|p| p.z >= NEAREST_KEY_M)
}

/// Every pose of the key triangle that fits one frame (a three-point pose has up to four), each
/// made exact by eqs. 10–11; when none fits within tolerance, the closest fit, and `false`.
/// Poses whose centroid lies deeper than `max_depth` are dropped: a thin image triangle (a side
/// view) is also fitted by a tiny far-away triangle whose key lines pass near the marked points,
/// and on the synthetic suite with 2 px noise such fits, chained over frames, carried the trunk
/// thousands of kilometres away. So are poses with a key joint nearer than [`NEAREST_KEY_M`]
/// (behind the camera, too): three rays are also met by such a triangle, and on the suite from
/// the tracker's output one of them, chained in, tipped a bending trunk seen from the side over
/// (bend_side, true lengths: 136.0 → 115.4 mm). When every pose is dropped, the closest point
/// fit (its twin in front when it lies behind the camera), brought along its rays to
/// `max_depth` at most (and `false`).
fn key_candidates(
    job: &LiftJob<'_>,
    triangle: &KeyTriangle,
    sides: &[f64; 3],
    image: &[Point2<f64>; 3],
    max_depth: f64,
) -> (Vec<[Point3<f64>; 3]>, bool) {
    let cam = &job.camera;
    let fits = calibrate_all(cam, triangle, image, job.params.calibration_tolerance_px);
    let closest_point_fit = || {
        starting_poses(cam, triangle, image)
            .into_iter()
            .map(|start| calibrate_from(cam, triangle, image, start, Residuals::Points))
            .min_by(|a, b| a.rms_px.total_cmp(&b.rms_px))
            .map(|c| c.pose)
    };
    let converged = !fits.is_empty();
    let poses: Vec<_> = if converged {
        fits.iter().map(|c| c.pose).collect()
    } else {
        closest_point_fit().into_iter().collect()
    };
    let depth = |k: &[Point3<f64>; 3]| centroid(k).z;
    let mut out: Vec<[Point3<f64>; 3]> = Vec::new();
    for pose in poses {
        let k = triangle.points.map(|p| pose.apply(&p));
        let snapped = key_depths(cam, image, sides, k.map(|p| p.z));
        let k = if snapped.rms_m < job.params.propagation_tolerance_m {
            snapped.points
        } else {
            k
        };
        if plausible_key(&k, max_depth)
            && !out
                .iter()
                .any(|o| (0..3).all(|i| (o[i] - k[i]).norm() < 1e-3))
        {
            out.push(k);
        }
    }
    if out.is_empty() {
        if let Some(pose) = closest_point_fit() {
            let k = triangle.points.map(|p| pose.apply(&p));
            // A fit behind the camera is turned to its twin in front (the same image).
            let k = if depth(&k) < 0.0 {
                k.map(|p| Point3::from(-p.coords))
            } else {
                k
            };
            let scale = (max_depth / depth(&k)).min(1.0);
            out.push(k.map(|p| Point3::from(p.coords * scale)));
        }
        return (out, false);
    }
    (out, converged)
}

/// The shoulders' depth difference (left minus right), metres: which way the body faces.
fn facing_m(k: &[Point3<f64>; 3]) -> f64 {
    k[0].z - k[1].z
}

/// A facing shows when the shoulders' depths differ by more than this, metres.
const FACING_SHOWS_M: f64 = 0.05;

/// The key path with each stretch of frames where the other facing also fits (a candidate pose
/// of the frame with the shoulders in the other depth order) turned to it when that explains the
/// whole clip better (`score`, lower is better: [`fit_score`] of the body built on the path).
/// A turn through side-on splits the clip into such stretches, and each is decided by all its
/// frames' evidence rather than by the chain's smoothness at the crossing.
fn facing_by_segments(
    mut key: Vec<[Point3<f64>; 3]>,
    candidates: &[(Vec<[Point3<f64>; 3]>, bool)],
    score: impl Fn(&[[Point3<f64>; 3]]) -> f64,
) -> Vec<[Point3<f64>; 3]> {
    let n = key.len();
    // Each frame's other facing, when one fits: the candidate most like the chosen pose among
    // those facing the other way.
    let other: Vec<Option<[Point3<f64>; 3]>> = (0..n)
        .map(|t| {
            let f = facing_m(&key[t]);
            if f.abs() < FACING_SHOWS_M {
                return None;
            }
            candidates[t]
                .0
                .iter()
                .filter(|c| facing_m(c) * f < 0.0 && facing_m(c).abs() >= FACING_SHOWS_M)
                .min_by(|a, b| {
                    let d = |c: &[Point3<f64>; 3]| {
                        (0..3).map(|i| (c[i] - key[t][i]).norm()).sum::<f64>()
                    };
                    d(a).total_cmp(&d(b))
                })
                .copied()
        })
        .collect();
    let mut segments = Vec::new();
    let mut t = 0;
    while t < n {
        if other[t].is_some() {
            let start = t;
            while t < n && other[t].is_some() {
                t += 1;
            }
            segments.push(start..t);
        } else {
            t += 1;
        }
    }
    // Longest first; at most a handful, each one more whole-clip solve.
    segments.sort_by_key(|s| std::cmp::Reverse(s.len()));
    let mut best = score(&key);
    for s in segments.into_iter().take(8) {
        if s.len() < 3 {
            continue;
        }
        let mut trial = key.clone();
        for t in s.clone() {
            if let Some(o) = other[t] {
                trial[t] = o;
            }
        }
        let v = score(&trial);
        if v < best {
            best = v;
            key = trial;
        }
    }
    key
}

/// Squared acceleration of the key joints over three frames.
fn key_acceleration(a: &[Point3<f64>; 3], b: &[Point3<f64>; 3], c: &[Point3<f64>; 3]) -> f64 {
    (0..3)
        .map(|i| (c[i].coords - b[i].coords * 2.0 + a[i].coords).norm_squared())
        .sum()
}

/// The smoothest sequence of key-triangle poses through the per-frame candidates (Viterbi over
/// pairs of frames, least squared acceleration): where two solutions of eqs. 10–11 meet and
/// part again, the one continuing the motion is kept. `pitch`, `(weight, reference)`, adds each
/// pose's squared pitch deviation ([`tilt_m`] from `reference`) times `weight`.
fn smoothest_key_path(
    candidates: &[Vec<[Point3<f64>; 3]>],
    pitch: Option<(f64, f64)>,
) -> Vec<[Point3<f64>; 3]> {
    // Each candidate's pitch cost, once.
    let pitch_cost: Vec<Vec<f64>> = candidates
        .iter()
        .map(|frame| {
            frame
                .iter()
                .map(|k| {
                    pitch.map_or(0.0, |(weight, reference)| {
                        weight * (tilt_m(k) - reference).powi(2)
                    })
                })
                .collect()
        })
        .collect();
    let n = candidates.len();
    if n == 0 {
        return Vec::new();
    }
    if n == 1 {
        return vec![candidates[0][0]];
    }
    // cost[(a, b)]: best with frame t−1 at a and frame t at b.
    let mut cost: Vec<Vec<f64>> = candidates[0]
        .iter()
        .zip(&pitch_cost[0])
        .map(|(a, pitch_a)| {
            candidates[1]
                .iter()
                .zip(&pitch_cost[1])
                .map(|(b, pitch_b)| {
                    pitch_a + pitch_b + (0..3).map(|i| (b[i] - a[i]).norm_squared()).sum::<f64>()
                })
                .collect()
        })
        .collect();
    let mut back: Vec<Vec<Vec<usize>>> = Vec::new();
    for t in 2..n {
        let (kb, kc) = (candidates[t - 1].len(), candidates[t].len());
        let mut next = vec![vec![f64::INFINITY; kc]; kb];
        let mut from = vec![vec![0usize; kc]; kb];
        for b in 0..kb {
            for c in 0..kc {
                let pitch_c = pitch_cost[t][c];
                for (a, row) in cost.iter().enumerate() {
                    let total = row[b]
                        + pitch_c
                        + key_acceleration(
                            &candidates[t - 2][a],
                            &candidates[t - 1][b],
                            &candidates[t][c],
                        );
                    if total < next[b][c] {
                        next[b][c] = total;
                        from[b][c] = a;
                    }
                }
            }
        }
        cost = next;
        back.push(from);
    }
    let mut best = (0, 0, f64::INFINITY);
    for (a, row) in cost.iter().enumerate() {
        for (b, &v) in row.iter().enumerate() {
            if v < best.2 {
                best = (a, b, v);
            }
        }
    }
    let mut path = vec![0usize; n];
    path[n - 2] = best.0;
    path[n - 1] = best.1;
    for t in (2..n).rev() {
        path[t - 2] = back[t - 2][path[t - 1]][path[t]];
    }
    path.iter()
        .enumerate()
        .map(|(t, &k)| candidates[t][k])
        .collect()
}

/// A skeleton3d from per-frame joints.
fn skeleton(
    job: &LiftJob<'_>,
    points: &[PerJoint<Point3<f64>>],
    bone_lengths: &[f64; BONE_COUNT],
    reports: &[FrameReport],
) -> Skeleton3d {
    Skeleton3d {
        camera: job.camera,
        fps: Some(job.tracks.source.fps),
        bone_lengths_m: Bone::ALL
            .iter()
            .zip(bone_lengths)
            .map(|(b, l)| (b.key(), *l))
            .collect(),
        frames: job
            .tracks
            .frames
            .iter()
            .zip(points)
            .zip(reports)
            .map(|((f, p), r)| Frame3d {
                index: f.index,
                points: *p,
                flags: r.flags.iter().map(ToString::to_string).collect(),
            })
            .collect(),
    }
}

/// One frame's joints with every bone given back `lengths` along its direction, parents first
/// (the lift solved uncertain bones shorter: [`SubjectModel::leaning`]).
fn with_lengths(p: &PerJoint<Point3<f64>>, lengths: &[f64; BONE_COUNT]) -> PerJoint<Point3<f64>> {
    let mut out = *p;
    // Bone::ALL lists every parent's bone before its children's.
    for (b, &length) in Bone::ALL.iter().zip(lengths) {
        // A bone of no length (child on its parent) keeps its child there.
        let d = p[b.child] - p[b.parent];
        let n = d.norm();
        out.0[b.child.index()] = out[b.parent] + if n > 0.0 { d * (length / n) } else { d };
    }
    out
}

/// The whole lift: per frame, then (if enabled) the global refinement. Bones with a length
/// doubt ([`SubjectModel::length_doubt`]) are solved that much shorter, leaning towards lying
/// square to their rays, and given back their lengths along the directions found.
pub fn lift(
    job: &LiftJob<'_>,
    progress: &mut dyn FnMut(&LiftProgress),
    cancel: &AtomicBool,
) -> Result<LiftOutput, LiftError> {
    let leaning = LiftJob {
        subject: job.subject.leaning(),
        ..job.clone()
    };
    let mut out = lift_leaning(&leaning, &job.subject.length_doubt, progress, cancel)?;
    if job.subject.length_doubt.iter().any(|&d| d > 0.0) {
        // The refined lengths, each over its doubt's share.
        let full = |s: &Skeleton3d| -> [f64; BONE_COUNT] {
            std::array::from_fn(|k| {
                let b = Bone::ALL[k];
                s.bone_lengths_m
                    .get(&b.key())
                    .copied()
                    .unwrap_or(job.subject.bone_length(b))
                    / (1.0 - job.subject.length_doubt[k]).max(1e-6)
            })
        };
        for s in [&mut out.skeleton, &mut out.per_frame] {
            let lengths = full(s);
            for f in &mut s.frames {
                f.points = with_lengths(&f.points, &lengths);
            }
            for (b, l) in Bone::ALL.iter().zip(lengths) {
                s.bone_lengths_m.insert(b.key(), l);
            }
        }
    }
    Ok(out)
}

/// [`lift`] on the subject as given, solved `doubt` shorter than read.
fn lift_leaning(
    job: &LiftJob<'_>,
    doubt: &[f64; BONE_COUNT],
    progress: &mut dyn FnMut(&LiftProgress),
    cancel: &AtomicBool,
) -> Result<LiftOutput, LiftError> {
    progress(&LiftProgress {
        stage: LiftStage::PerFrame,
        done: 0,
        total: 1,
    });
    let per = per_frame_solve(job, doubt, true)?;
    if cancel.load(Ordering::Relaxed) {
        return Err(LiftError::Cancelled);
    }
    let per_frame = skeleton(
        job,
        &per.resolved.points,
        &job.subject.bone_length_m,
        &per.reports,
    );
    let (final_skeleton, refinement, reports) = if job.params.refine {
        let weights: Vec<PerJoint<f64>> = job
            .tracks
            .frames
            .iter()
            .map(|f| f.points.map(|_, p| track_weight(p)))
            .collect();
        // The refinement sees the same smoothed points: fitted to the raw ones it brought the
        // noise back (2 px noise on the suite: 80 → 108 mm).
        let refined = refine(
            &job.camera,
            &per.images,
            &weights,
            &per.resolved.points,
            &job.subject,
            job.tracks.source.fps,
            median_noise_px(job.tracks, &Joint::ALL),
            &job.params.refinement,
            &mut |done, total| {
                progress(&LiftProgress {
                    stage: LiftStage::Refine,
                    done,
                    total,
                })
            },
            cancel,
        )?;
        // The flags of what the refined skeleton still cannot explain.
        let mut reports = per.reports.clone();
        let solved = (&refined.points[..], &per.images[..], &refined.bone_lengths);
        flag_too_long(job, &mut reports, solved, doubt, true);
        (
            skeleton(job, &refined.points, &refined.bone_lengths, &reports),
            Some(refined.summary),
            reports,
        )
    } else {
        (per_frame.clone(), None, per.reports)
    };
    // Last, the feet: a planted foot holds its depth and the body follows.
    let (final_skeleton, contacts) = plant(job, &per.images, final_skeleton);
    Ok(LiftOutput {
        skeleton: final_skeleton,
        per_frame,
        bones: per
            .resolved
            .choices
            .iter()
            .zip(&per.resolved.too_long)
            .zip(&per.resolved.margins)
            .map(|((roots, single), margins)| {
                std::array::from_fn(|b| BoneDepth {
                    root: roots[b],
                    single_root: single[b],
                    margin: margins[b],
                })
            })
            .collect(),
        reports,
        calibration_frame: per.calibration_frame,
        refinement,
        contacts,
    })
}

/// The lift's last stage ([`super::contact`]): each foot's contacts found on `skeleton`, and
/// with `foot_lock` the body moved in depth so a planted foot stays put.
fn plant(
    job: &LiftJob<'_>,
    images: &[PerJoint<Point2<f64>>],
    mut skeleton: Skeleton3d,
) -> (Skeleton3d, super::contact::FootContacts) {
    let n = skeleton.frames.len();
    if !job.params.foot_lock {
        return (skeleton, vec![[false; 2]; n]);
    }
    let mut points: Vec<PerJoint<Point3<f64>>> = skeleton.frames.iter().map(|f| f.points).collect();
    let fps = skeleton.fps.unwrap_or(30.0);
    // A foot lost or off the frame is never planted.
    let seen: Vec<[bool; 2]> = job
        .tracks
        .frames
        .iter()
        .map(|f| {
            super::contact::FEET.map(|a| {
                !matches!(
                    f.points[a].source,
                    PointSource::Lost | PointSource::OffFrame
                )
            })
        })
        .collect();
    let contacts = super::contact::foot_contacts(&job.camera, images, &points, &seen, fps);
    super::contact::plant_feet(&mut points, &contacts);
    for ((f, p), c) in skeleton.frames.iter_mut().zip(points).zip(&contacts) {
        f.points = p;
        for (k, ankle) in super::contact::FEET.iter().enumerate() {
            if c[k] {
                f.flags
                    .push(format!("{}{}", crate::formats::CONTACT_FLAG, ankle.name()));
            }
        }
    }
    (skeleton, contacts)
}

#[cfg(test)]
mod tests;
