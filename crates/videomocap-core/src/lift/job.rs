//! What every step of the lift shares: the job (what to lift and how), its progress and its
//! stages, and the check of its inputs. Below the steps (no step's file is used here), so the
//! lift's files form a line, not a circle (`scripts/module_cycles.py`).

use super::ambiguity::DepthOverrides;
use super::error::LiftError;
use super::params::LiftParams;
use crate::camera::PinholeCamera;
use crate::formats::Tracks2d;
use crate::skeleton::SubjectModel;
use std::fmt;

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

/// The stages of [`super::reconstruct`], in the order they run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LiftStage {
    /// Choosing the focal length.
    Camera,
    /// Reading the body's lengths from the tracks.
    Subject,
    /// Calibration on the key triangle, its path, the roots of every bone (eqs. 6–11).
    PerFrame,
    /// The global least-squares refinement of all frames and lengths.
    Refine,
}

impl fmt::Display for LiftStage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LiftStage::Camera => "camera",
            LiftStage::Subject => "body lengths",
            LiftStage::PerFrame => "per-frame solve",
            LiftStage::Refine => "global refinement",
        })
    }
}

/// Checks the job's inputs.
pub(crate) fn check(job: &LiftJob<'_>) -> Result<(), LiftError> {
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
