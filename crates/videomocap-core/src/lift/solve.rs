//! The lift of a whole sequence, in order: checks, smoothing, calibration on the best frame,
//! each frame's key candidates (`key_candidates`) and the smoothest key path, the facing
//! (`facing`), the depth roots (`ambiguity`), the optional global refinement (`refine`), the
//! per-frame report and the planted feet (`contact`). Its settings are in `params`.

mod per_frame;

pub use per_frame::lift_per_frame;
pub(crate) use per_frame::miss_m;
use per_frame::{network_bodies, per_frame_solve};

use super::ambiguity::Resolved;
use super::error::LiftError;
use super::job::{LiftJob, LiftProgress, LiftStage};
use super::refine::{RefineParams, RefineSummary, refine, track_weight};
use super::report::{BoneDepth, FrameFlag, FrameReport, flag_too_long};
use super::smoothing::median_noise_px;
use crate::formats::{Frame3d, PointSource, Skeleton3d};
use crate::skeleton::{BONE_COUNT, Bone, Joint, PerJoint};
use nalgebra::{Point2, Point3};
use std::sync::atomic::{AtomicBool, Ordering};

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
/// doubt ([`crate::skeleton::SubjectModel::length_doubt`]) are solved that much shorter,
/// leaning towards lying square to their rays, and given back their lengths along the
/// directions found.
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
        let (skeleton, summary, reports) = refine_whole(job, &per, doubt, progress, cancel)?;
        (skeleton, Some(summary), reports)
    } else {
        (per_frame.clone(), None, per.reports.clone())
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

/// The global refinement of the per-frame solve `per` ([`refine`]), its skeleton and the
/// frames' reports with what it still cannot explain.
fn refine_whole(
    job: &LiftJob<'_>,
    per: &PerFrame,
    doubt: &[f64; BONE_COUNT],
    progress: &mut dyn FnMut(&LiftProgress),
    cancel: &AtomicBool,
) -> Result<(Skeleton3d, RefineSummary, Vec<FrameReport>), LiftError> {
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
    Ok((
        skeleton(job, &refined.points, &refined.bone_lengths, &reports),
        refined.summary,
        reports,
    ))
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
