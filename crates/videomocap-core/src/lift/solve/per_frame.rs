//! The per-frame solve (eqs. 6–11 and the root choices), as named steps: the inputs prepared
//! once (smoothed points, rays, the network's bodies, every frame's key candidates), the
//! calibration frame and its poses, then for each pose the key path, its facing stretch by
//! stretch and the body built on it, the pose whose body explains the clip best kept.

use super::super::ambiguity::{Margins, PriorMemo, Resolved, resolve_with};
use super::super::calibrate::{
    CALIBRATION_TOLERANCE_PX, Calibration, KEY_JOINTS, KEY_LINES, KeyTriangle, calibrate_all,
    longest_side, shape,
};
use super::super::error::LiftError;
use super::super::facing::facing_by_segments;
use super::super::job::{LiftJob, check};
use super::super::key_candidates::{
    deepest_trunk, key_candidates, plausible_key, smoothest_key_path,
};
use super::super::key_path::{chain_pitch_prior, smooth_key_path};
use super::super::refine::track_weight;
use super::super::report::{FrameFlag, FrameReport, flag_too_long};
use super::super::smoothing::{adaptive_sigmas, median_noise_px, smoothed_images};
use super::PerFrame;
use crate::camera::PinholeCamera;
use crate::formats::{FrameIndex, NetworkBody, PointSource, Tracks2d};
use crate::skeleton::{BONE_COUNT, JOINT_COUNT, Joint, PerJoint};
use nalgebra::{Point2, Point3, Vector3};

/// A key path: the key joints (shoulders, chest) of every frame.
type KeyPath = Vec<[Point3<f64>; 3]>;

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

/// What every calibration pose's solve reads, prepared once per lift.
struct Prepared {
    triangle: KeyTriangle,
    /// The key triangle's side lengths, in [`KEY_LINES`]' order.
    sides: [f64; 3],
    fps: f64,
    /// The smoothed image points per frame.
    images: Vec<PerJoint<Point2<f64>>>,
    rays: Vec<PerJoint<Vector3<f64>>>,
    frame_index: Vec<FrameIndex>,
    bodies: Vec<Option<NetworkBody>>,
    /// What the key path's refit needs: the key joints' smoothed image points, their trust, and
    /// their tracks' noise (the key joints' own: the tracker carries them with the trunk block,
    /// steadier than the limbs; on the suite from the tracker's output 113.1 → 111.8 mm against
    /// the median over all joints, other inputs within 0.5 mm).
    key_observed: Vec<[Point2<f64>; 3]>,
    key_weights: Vec<[f64; 3]>,
    noise_px: f64,
    /// Every frame's candidate poses of the key triangle, and whether its solve converged.
    per_frame: Vec<(KeyPath, bool)>,
}

/// The lift's inputs read from the job: smoothing, rays, the network's bodies and every
/// frame's key candidates.
fn prepare(job: &LiftJob<'_>) -> Result<Prepared, LiftError> {
    let tracks = job.tracks;
    let n = tracks.frames.len();
    let triangle = KeyTriangle::from_subject(&job.subject)?;
    let sides = KEY_LINES.map(|(i, j)| triangle.side(i, j));
    let fps = if tracks.source.fps.is_finite() && tracks.source.fps > 0.0 {
        tracks.source.fps
    } else {
        30.0
    };
    let sigma = if !job.params.smooth_tracks {
        PerJoint([0.0; JOINT_COUNT])
    } else if job.params.smoothing_s > 0.0 {
        PerJoint([job.params.smoothing_s * fps; JOINT_COUNT])
    } else {
        adaptive_sigmas(tracks)
    };
    let images = smoothed_images(tracks, &sigma);
    let rays = images
        .iter()
        .map(|im| im.map(|_, p| job.camera.ray(p)))
        .collect();
    let per_frame = (0..n)
        .map(|t| {
            let max_depth = deepest_trunk(&job.camera, &job.subject, &images[t]);
            key_candidates(job, &triangle, &sides, &key_image(&images, t), max_depth)
        })
        .collect();
    Ok(Prepared {
        sides,
        fps,
        rays,
        frame_index: tracks.frames.iter().map(|f| f.index).collect(),
        bodies: network_bodies(tracks),
        key_observed: (0..n).map(|t| key_image(&images, t)).collect(),
        key_weights: tracks
            .frames
            .iter()
            .map(|f| KEY_JOINTS.map(|j| track_weight(&f.points[j])))
            .collect(),
        noise_px: median_noise_px(tracks, &KEY_JOINTS),
        per_frame,
        images,
        triangle,
    })
}

/// The calibration frame: the best-shaped key triangle, weighted by the trust in its points
/// and by its size in the image (a pixel of noise turns a small triangle further: with one
/// draw of 2 px noise the suite's far walk was calibrated 0.5 m too near on its first frame,
/// 301 mm MPJPE; by size, 30 frames later, 53 mm).
fn calibration_frame(tracks: &Tracks2d, images: &[PerJoint<Point2<f64>>]) -> Option<usize> {
    (0..images.len())
        .filter(|&t| !degenerate(&key_image(images, t)))
        .max_by(|&a, &b| {
            let score = |t: usize| {
                let trust = KEY_JOINTS
                    .iter()
                    .map(|&j| f64::from(tracks.frames[t].points[j].confidence))
                    .fold(1.0, f64::min)
                    .max(0.05);
                let k = key_image(images, t);
                shape(&k) * longest_side(&k) * trust
            };
            score(a).total_cmp(&score(b))
        })
}

/// The key triangle's poses on the calibration frame `at`; poses too deep for the trunk's
/// image length are dropped, unless every pose is.
fn calibrations(job: &LiftJob<'_>, prep: &Prepared, at: usize) -> Vec<Calibration> {
    let mut calibrations = calibrate_all(
        &job.camera,
        &prep.triangle,
        &key_image(&prep.images, at),
        CALIBRATION_TOLERANCE_PX,
    );
    let max_depth = deepest_trunk(&job.camera, &job.subject, &prep.images[at]);
    let plausible =
        |c: &Calibration| plausible_key(&prep.triangle.points.map(|p| c.pose.apply(&p)), max_depth);
    if calibrations.iter().any(plausible) {
        calibrations.retain(plausible);
    }
    calibrations
}

/// [`lift_per_frame`], flagging a bone too long only beyond its length's `doubt` (per bone, a
/// share of the length); `shortened` when the job's subject is already solved that much shorter
/// than read ([`crate::skeleton::SubjectModel::leaning`]).
///
/// Several poses fit three points. Each is carried through the whole sequence and the whole
/// body is built on it; the one kept explains the tracks best (bones too long for their image
/// give a wrong pose away) with the least prior and acceleration cost of the root choices (a
/// wrong pose twists the shoulders against the hips and bends knees the wrong way for the whole
/// clip), each part weighed on its own scale ([`fit_score`]).
pub(super) fn per_frame_solve(
    job: &LiftJob<'_>,
    doubt: &[f64; BONE_COUNT],
    shortened: bool,
) -> Result<PerFrame, LiftError> {
    check(job)?;
    let prep = prepare(job)?;
    let at = calibration_frame(job.tracks, &prep.images).ok_or(LiftError::DegenerateKeyTriangle)?;
    // The prior's costs, kept between the whole-clip solves below (same rays and subject).
    let memo = PriorMemo::new(prep.images.len());
    let mut best: Option<(f64, Vec<FrameReport>, KeyPath)> = None;
    for c in &calibrations(job, &prep, at) {
        let mut key = key_path(job, &prep, at, c);
        // The facing decided stretch by stretch over the whole clip (see `facing_by_segments`).
        key = facing_by_segments(key, &prep.per_frame, &prep.bodies, |k| {
            build(job, &prep, &memo, k, Margins::Skip).1
        });
        let (resolved, score) = build(job, &prep, &memo, &key, Margins::Skip);
        if best.as_ref().is_none_or(|b| score < b.0) {
            let mut reports = frame_reports(job, &prep, &key);
            let lengths = &job.subject.bone_length_m;
            let solved = (&resolved.points[..], &prep.images[..], lengths);
            flag_too_long(job, &mut reports, solved, doubt, shortened);
            flag_unusual(job, &mut reports, &resolved);
            best = Some((score, reports, key));
        }
    }
    let Some((_, reports, key)) = best else {
        return Err(LiftError::CalibrationFailed {
            frame: prep.frame_index[at],
        });
    };
    // The chosen body once more, now with its bones' margins (the same solve: the trials
    // above skip them).
    let resolved = build(job, &prep, &memo, &key, Margins::Compute).0;
    Ok(PerFrame {
        resolved,
        reports,
        calibration_frame: at,
        images: prep.images,
    })
}

/// The key path carried from the calibration pose `c` on frame `at`: the smoothest chain of
/// the frames' candidates, refitted over the whole clip when the trunk is kept steady.
fn key_path(job: &LiftJob<'_>, prep: &Prepared, at: usize, c: &Calibration) -> KeyPath {
    let pose = prep.triangle.points.map(|p| c.pose.apply(&p));
    let mut candidates: Vec<KeyPath> = prep.per_frame.iter().map(|(k, _)| k.clone()).collect();
    candidates[at] = vec![pose];
    // With noisy tracks the chain also keeps the trunk's pitch towards the camera near the
    // calibration frame's (the refit's pitch term, weighed alike): the frame by frame
    // choice then seldom tips a facing triangle the wrong way (2 px noise, four draws on
    // the suite: 56.8 → 53.3 mm, wrong roots 16.6 → 14.3 %; fixed weights from 0.05 to 0.4
    // gave 53.0–53.9; the real sample with noise and the tracker's output unchanged).
    let pitch = job
        .params
        .steady_trunk
        .then(|| chain_pitch_prior(prep.noise_px, prep.fps, &pose))
        .flatten();
    let key = smoothest_key_path(&candidates, pitch);
    if !job.params.steady_trunk {
        return key;
    }
    smooth_key_path(
        &job.camera,
        &key,
        &prep.key_observed,
        &prep.key_weights,
        &prep.triangle.points,
        prep.noise_px,
        prep.fps,
    )
}

/// The whole body built on a key path, and how well it explains the clip ([`fit_score`], with
/// the network's word on the facing weighed as the image's depth evidence is).
fn build(
    job: &LiftJob<'_>,
    prep: &Prepared,
    memo: &PriorMemo,
    key: &[[Point3<f64>; 3]],
    margins: Margins,
) -> (Resolved, f64) {
    let weights = job.params.ambiguity();
    let resolved = resolve_with(
        key,
        &prep.rays,
        &prep.frame_index,
        &prep.bodies,
        &job.subject,
        &weights,
        &job.overrides,
        memo,
        margins,
    );
    let miss: f64 = (0..key.len())
        .map(|t| miss_m(&job.camera, &resolved.points[t], &prep.images[t]))
        .sum();
    let mut score = fit_score(miss, &resolved.group_costs);
    if weights.image_depth > 0.0
        && let Some(cost) = super::super::ambiguity::image_facing_cost(key, &prep.bodies)
    {
        score += weights.image_depth * cost.max(FIT_FLOOR).ln();
    }
    (resolved, score)
}

/// Each frame's report on the key path `key`: how far the key triangle is from its sides'
/// lengths, and the flags of the frame's input (the key triangle's solve not converged, a
/// joint off the frame or lost, no network body where others have one).
fn frame_reports(job: &LiftJob<'_>, prep: &Prepared, key: &[[Point3<f64>; 3]]) -> Vec<FrameReport> {
    // Frames without the network's body while others have one (and its evidence is weighed).
    let no_image_depth = |t: usize| {
        job.params.image_depth > 0.0
            && prep.bodies[t].is_none()
            && prep.bodies.iter().any(Option::is_some)
    };
    job.tracks
        .frames
        .iter()
        .zip(&prep.per_frame)
        .zip(key)
        .enumerate()
        .map(|(t, ((f, (_, converged)), k))| FrameReport {
            index: f.index,
            key_rms_m: KEY_LINES
                .iter()
                .zip(&prep.sides)
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
                .chain(no_image_depth(t).then_some(FrameFlag::NoImageDepth))
                .collect(),
        })
        .collect()
}

/// The least a part's cost counts as in [`fit_score`] (in the part's own unit: metres for the
/// miss, squared metres for a group's cost, both summed over the clip): a part that fits
/// exactly (cost 0) would otherwise outvote every other. 0.01 and 0.1 chose the same poses on
/// every clip of `bench lift`.
pub(super) const FIT_FLOOR: f64 = 0.01;

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
pub(super) fn fit_score(miss_m: f64, group_costs: &[f64]) -> f64 {
    std::iter::once(miss_m)
        .chain(group_costs.iter().copied())
        .map(|c| c.max(FIT_FLOOR).ln())
        .sum()
}

/// Flags the frames whose pose the learned prior finds unusual ([`FrameFlag::UnusualPose`]),
/// the camera's up (−Y) standing in for the world's.
fn flag_unusual(job: &LiftJob<'_>, reports: &mut [FrameReport], resolved: &Resolved) {
    let Some(prior) = super::super::prior::PosePrior::bundled()
        .ok()
        .filter(|_| job.params.pose_prior > 0.0)
    else {
        return;
    };
    let up = -nalgebra::Vector3::y();
    for (report, p) in reports.iter_mut().zip(&resolved.points) {
        if prior.is_unusual(p, &up) {
            report.flags.push(FrameFlag::UnusualPose);
        }
    }
}

/// Each frame's 3D body from the pose network, where the tracks carry one.
pub(super) fn network_bodies(tracks: &Tracks2d) -> Vec<Option<NetworkBody>> {
    tracks
        .frames
        .iter()
        .map(|f| f.body3d.as_deref().cloned())
        .collect()
}
