//! The lift's settings: what can be given as JSON (`--lift-settings`, the app's Lift
//! settings, a batch row), each with its documented default, and their checks.

use super::ambiguity::AmbiguityWeights;
use super::error::{LiftError, check_setting};
use super::refine::RefineParams;
use serde::{Deserialize, Serialize};

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
