//! 3D reconstruction (VBA, Pan et al., "Reconstruction of 3D human motion skeleton"): from
//! 2D tracks to a metric skeleton per frame in the camera's space.
//!
//! Each joint's 2D track is first smoothed by the width its own noise calls for (`smoothing`).
//! The key triangle (both shoulders and the chest) calibrates the camera on the best frame
//! (`calibrate`, eqs. 6–9) and is carried to the other frames by its constant side lengths
//! (`propagate`, eqs. 10–11), its path is refitted over the whole clip (`key_path`), and
//! each stretch where both facings fit takes the one that explains the whole clip better;
//! every other joint is placed on its viewing ray at its bone's
//! length from its parent (`backproject`); the two roots of each bone are chosen over the
//! whole sequence (`ambiguity`); a global least-squares pass (`refine`) then adjusts all
//! frames and the bone lengths together. `focal` estimates an unknown focal length;
//! `subject_fit` reads every length from the whole clip when only the subject's height (or
//! some lengths) are known, and marks read lengths as uncertain: the lift solves those bones
//! shorter, leaning towards lying square to their rays, and gives their lengths back after.
//! Last, each foot's contacts with the floor are found and the body is moved in depth so that
//! a planted foot stays put (`contact`).
//! Its input is [`crate::formats::Tracks2d`], its output [`crate::formats::Skeleton3d`].
//! Every front end runs it through [`reconstruct`] (`pipeline`): the camera, the subject's
//! lengths, then the skeleton, reporting each [`LiftStage`] as it starts. What the steps share
//! (the job, its progress and stages, the check of its inputs) is in `job`, below them all.

mod ambiguity;
mod backproject;
mod calibrate;
mod contact;
mod error;
mod facing;
mod focal;
mod job;
mod key_candidates;
mod key_path;
mod least_squares;
mod newton;
mod params;
mod pipeline;
mod prior;
mod propagate;
mod refine;
mod report;
mod smoothing;
mod solve;
mod subject_fit;

pub use ambiguity::{AmbiguityWeights, DepthOverrides, lift_order, resolve};
pub use backproject::Root;
pub use backproject::bone_roots;
pub use calibrate::{KEY_JOINTS, KeyTriangle};
pub use contact::{FEET, FootContacts};
pub use error::LiftError;
pub use focal::{DEFAULT_FOV_LONG_SIDE_DEG, default_focal};
pub use job::{LiftJob, LiftProgress, LiftStage};
pub use params::{LiftParams, retired_lift_settings};
pub use pipeline::{CameraChoice, FocalSource, Reconstruction, SubjectChoice, reconstruct};
pub use prior::{
    BUNDLED_PRIOR, Component, GroupFile, PosePrior, PriorError, PriorFile, PriorGroup, Side, learn,
};
pub use refine::RefineParams;
pub use report::{BoneDepth, FrameFlag, FrameReport, UNSURE_MARGIN};
pub use solve::{LiftOutput, PerFrame, lift, lift_per_frame};
pub use subject_fit::{SubjectFit, subject_from_height};
