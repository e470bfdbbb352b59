//! The lift of a whole sequence, in order: checks, smoothing, calibration on the best frame,
//! each frame's key candidates (`key_candidates`) and the smoothest key path, the facing
//! (`facing`), the depth roots (`ambiguity`), the optional global refinement (`refine`), the
//! per-frame report and the planted feet (`contact`). Its settings are in `params`.

use super::ambiguity::{DepthOverrides, PriorMemo, Resolved, resolve_with};
use super::facing::facing_by_segments;
use super::key_candidates::{deepest_trunk, key_candidates, plausible_key, smoothest_key_path};
use super::params::LiftParams;

use super::calibrate::{
    CALIBRATION_TOLERANCE_PX, KEY_JOINTS, KeyTriangle, calibrate_all, longest_side, shape,
};
use super::error::LiftError;
use super::key_path::{chain_pitch_prior, smooth_key_path};
use super::pipeline::LiftStage;
use super::refine::{RefineParams, RefineSummary, refine, track_weight};
use super::report::{BoneDepth, FrameFlag, FrameReport, flag_too_long};
use super::smoothing::{adaptive_sigmas, median_noise_px, smoothed_images};
use crate::camera::PinholeCamera;
use crate::formats::{Frame3d, FrameIndex, NetworkBody, PointSource, Skeleton3d, Tracks2d};
use crate::skeleton::{BONE_COUNT, Bone, Joint, PerJoint, SubjectModel};
use nalgebra::{Point2, Point3};
use std::sync::atomic::{AtomicBool, Ordering};

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

/// Checks the job's inputs.
fn check(job: &LiftJob<'_>) -> Result<(), LiftError> {
    job.params.validate()?;
    if job.params.pose_prior > 0.0 {
        super::prior::PosePrior::bundled()?;
    }
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
    let sigma = if !job.params.smooth_tracks {
        PerJoint([0.0; crate::skeleton::JOINT_COUNT])
    } else if job.params.smoothing_s > 0.0 {
        PerJoint([job.params.smoothing_s * fps; crate::skeleton::JOINT_COUNT])
    } else {
        adaptive_sigmas(tracks)
    };
    let images = smoothed_images(tracks, &sigma);
    let rays: Vec<_> = images.iter().map(|im| im.map(|_, p| cam.ray(p))).collect();
    let frame_index: Vec<FrameIndex> = tracks.frames.iter().map(|f| f.index).collect();
    let bodies = network_bodies(tracks);
    // Frames without the network's body while others have one (and its evidence is weighed).
    let no_image_depth = |t: usize| {
        job.params.image_depth > 0.0 && bodies[t].is_none() && bodies.iter().any(Option::is_some)
    };

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
        CALIBRATION_TOLERANCE_PX,
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
    let weights = job.params.ambiguity();
    // The prior's costs, kept between the whole-clip solves below (same rays and subject).
    let memo = PriorMemo::new(n);
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
            .steady_trunk
            .then(|| chain_pitch_prior(noise_px, fps, &key_of(&c.pose)))
            .flatten();
        let mut key = smoothest_key_path(&candidates, pitch);
        if job.params.steady_trunk {
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
            let resolved = resolve_with(
                key,
                &rays,
                &frame_index,
                &bodies,
                &job.subject,
                &weights,
                &job.overrides,
                &memo,
            );
            let miss: f64 = (0..n)
                .map(|t| miss_m(cam, &resolved.points[t], &images[t]))
                .sum();
            let mut score = fit_score(miss, &resolved.group_costs);
            let facing_weight = weights.image_facing;
            if facing_weight > 0.0
                && let Some(cost) = super::ambiguity::image_facing_cost(key, &bodies)
            {
                score += facing_weight * cost.max(FIT_FLOOR).ln();
            }
            (resolved, score)
        };
        // The facing decided stretch by stretch over the whole clip (see `facing_by_segments`).
        key = facing_by_segments(key, &per_frame, &bodies, |k| build(k).1);
        let mut reports: Vec<FrameReport> = tracks
            .frames
            .iter()
            .zip(&per_frame)
            .zip(&key)
            .enumerate()
            .map(|(t, ((f, (_, converged)), k))| FrameReport {
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
                    .chain(no_image_depth(t).then_some(FrameFlag::NoImageDepth))
                    .collect(),
            })
            .collect();
        let (resolved, score) = build(&key);
        if best.as_ref().is_none_or(|b| score < b.0) {
            let lengths = &job.subject.bone_length_m;
            let solved = (&resolved.points[..], &images[..], lengths);
            flag_too_long(job, &mut reports, solved, doubt, shortened);
            flag_unusual(job, &mut reports, &resolved);
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

/// Flags the frames whose pose the learned prior finds unusual ([`FrameFlag::UnusualPose`]),
/// the camera's up (−Y) standing in for the world's.
fn flag_unusual(job: &LiftJob<'_>, reports: &mut [FrameReport], resolved: &Resolved) {
    let Some(prior) = super::prior::PosePrior::bundled()
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
fn network_bodies(tracks: &Tracks2d) -> Vec<Option<NetworkBody>> {
    tracks
        .frames
        .iter()
        .map(|f| f.body3d.as_deref().cloned())
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
        // The network's bodies pull the limbs' directions; off with the image's evidence.
        let bodies = if job.params.image_depth > 0.0 {
            network_bodies(job.tracks)
        } else {
            Vec::new()
        };
        // The refinement sees the same smoothed points: fitted to the raw ones it brought the
        // noise back (2 px noise on the suite: 80 → 108 mm).
        let refined = refine(
            &job.camera,
            &per.images,
            &weights,
            &per.resolved.points,
            &bodies,
            &job.subject,
            job.tracks.source.fps,
            median_noise_px(job.tracks, &Joint::ALL),
            &RefineParams::default(),
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
        // Only where the image is longer than the bone could be already on its rays: a miss the
        // refinement made itself (smoothing, the network's depth) is not a slip of the image.
        for (r, p) in reports.iter_mut().zip(&per.reports) {
            r.flags
                .retain(|f| !matches!(f, FrameFlag::TooLong(_)) || p.flags.contains(f));
        }
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
