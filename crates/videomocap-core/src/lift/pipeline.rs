//! The lift as every front end runs it: the camera, then the subject, then the skeleton
//! ([`reconstruct`]). The CLI (`lift`, `run`, `batch`), the app and the benchmarks call it, so a
//! choice of camera or subject means the same everywhere.

use super::error::LiftError;
use super::focal::{default_focal, estimate_focal};
use super::job::{LiftJob, LiftStage};
use super::params::LiftParams;
use super::solve::{LiftOutput, lift};
use super::subject_fit::{SubjectFit, subject_from_height};
use super::{DepthOverrides, LiftProgress};
use crate::camera::PinholeCamera;
use crate::formats::{KnownLengths, Tracks2d};
use crate::skeleton::{Proportions, SubjectModel};
use std::sync::atomic::AtomicBool;

/// How the camera's focal length is chosen (the principal point is the image centre unless the
/// camera is given whole).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CameraChoice {
    /// The default: [`super::DEFAULT_FOV_LONG_SIDE_DEG`] across the longer image side.
    Default,
    /// A focal length the user knows, pixels.
    FocalPx(f64),
    /// A horizontal field of view the user knows, degrees.
    FovDeg(f64),
    /// Estimated from the tracks (on the proportions table's lengths: the focal length at
    /// which the per-frame lift misses least).
    Estimate,
    /// A whole camera (calibrated elsewhere, or a benchmark's true camera).
    Given(PinholeCamera),
}

/// Whose body is lifted.
#[derive(Debug, Clone, PartialEq)]
pub enum SubjectChoice {
    /// The height a user states (metres) and any lengths they measured: the proportions table
    /// scaled to the height, every other length read from the tracks.
    Height {
        /// Standing height, metres.
        height_m: f64,
        /// Lengths the user measured.
        known: KnownLengths,
    },
    /// A body whose every length is known (a benchmark's true lengths).
    Model(Box<SubjectModel>),
}

/// Where the focal length came from, for the user.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FocalSource {
    /// The default field of view.
    Default,
    /// Given by the user (a focal length, a field of view or a whole camera).
    Given,
    /// Estimated from the tracks.
    Estimated,
}

/// What [`reconstruct`] made.
#[derive(Debug, Clone, PartialEq)]
pub struct Reconstruction {
    /// The skeleton, per-frame solve, root choices and reports.
    pub output: LiftOutput,
    /// The camera the lift used.
    pub camera: PinholeCamera,
    /// Where its focal length came from.
    pub focal_source: FocalSource,
    /// The subject the lift used.
    pub subject: SubjectModel,
    /// What was read from the tracks about the body (`None` for [`SubjectChoice::Model`]).
    pub fit: Option<SubjectFit>,
}

impl Reconstruction {
    /// One line on the camera for the user.
    pub fn camera_line(&self) -> String {
        let f = self.camera.focal_px;
        let fov = 2.0
            * (f64::from(self.camera.width.max(1)) / 2.0 / f)
                .atan()
                .to_degrees();
        match self.focal_source {
            FocalSource::Default => format!(
                "focal length {f:.0} px: the default {:.0}° across the longer image side (give the focal length or the field of view if you know the camera)",
                super::DEFAULT_FOV_LONG_SIDE_DEG
            ),
            FocalSource::Given => {
                format!("focal length {f:.0} px (horizontal field of view {fov:.0}°)")
            }
            FocalSource::Estimated => {
                format!("estimated focal length {f:.0} px (horizontal field of view {fov:.0}°)")
            }
        }
    }
}

/// The lift, stage by stage: 1. the camera, 2. the subject's lengths read from the tracks
/// through it, 3. the skeleton (per frame, then refined when `params.refine`), with the user's
/// depth `overrides`. `progress` hears each stage as it starts and the refinement's steps.
pub fn reconstruct(
    tracks: &Tracks2d,
    camera: CameraChoice,
    subject: &SubjectChoice,
    params: &LiftParams,
    overrides: DepthOverrides,
    progress: &mut dyn FnMut(&LiftProgress),
    cancel: &AtomicBool,
) -> Result<Reconstruction, LiftError> {
    let stage = |stage| LiftProgress {
        stage,
        done: 0,
        total: 1,
    };
    // 1. The camera.
    progress(&stage(LiftStage::Camera));
    let (camera, focal_source) = choose_camera(tracks, camera, subject, params)?;
    // 2. The subject.
    progress(&stage(LiftStage::Subject));
    let (subject, fit) = match subject {
        SubjectChoice::Height { height_m, known } => {
            let (s, fit) = subject_from_height(*height_m, tracks, camera, params, known)?;
            (s, Some(fit))
        }
        SubjectChoice::Model(s) => (s.as_ref().clone(), None),
    };
    // 3. The skeleton.
    let job = LiftJob {
        tracks,
        camera,
        subject: subject.clone(),
        params: *params,
        overrides,
    };
    let output = lift(&job, progress, cancel)?;
    Ok(Reconstruction {
        output,
        camera,
        focal_source,
        subject,
        fit,
    })
}

/// The camera of `choice` for the tracks' image.
fn choose_camera(
    tracks: &Tracks2d,
    choice: CameraChoice,
    subject: &SubjectChoice,
    params: &LiftParams,
) -> Result<(PinholeCamera, FocalSource), LiftError> {
    let (w, h) = (tracks.source.width, tracks.source.height);
    let centred = |f| PinholeCamera::centred(f, w, h);
    Ok(match choice {
        CameraChoice::Default => (centred(default_focal(w, h)), FocalSource::Default),
        CameraChoice::FocalPx(f) => (centred(f), FocalSource::Given),
        CameraChoice::FovDeg(fov) => (
            centred(PinholeCamera::focal_from_horizontal_fov(fov, w)),
            FocalSource::Given,
        ),
        CameraChoice::Given(c) => (c, FocalSource::Given),
        CameraChoice::Estimate => {
            // On the table's lengths at the stated height: the lengths read from the tracks
            // depend on the camera.
            let table = match subject {
                SubjectChoice::Height { height_m, .. } => {
                    SubjectModel::from_height(*height_m, Proportions::default())?
                }
                SubjectChoice::Model(s) => s.as_ref().clone(),
            };
            let job = LiftJob {
                tracks,
                camera: centred(1.0),
                subject: table,
                params: *params,
                overrides: Default::default(),
            };
            let est = estimate_focal(&job)?;
            (centred(est.focal_px), FocalSource::Estimated)
        }
    })
}
