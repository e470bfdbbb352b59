//! Why a lift could not run.

use crate::formats::FrameIndex;
use crate::setting_range::Range;
use crate::skeleton::{Joint, ProportionsError};

/// Errors of the 3D reconstruction. Frames that are merely hard (Newton not converging, a bone
/// too long for its 2D image) are not errors: they are flagged in [`super::FrameReport`].
#[derive(Debug, thiserror::Error)]
pub enum LiftError {
    #[error("the tracks have no frames")]
    NoFrames,
    #[error("frame {frame}: joint {joint} has a position that is not a finite number")]
    NonFinite { frame: FrameIndex, joint: Joint },
    #[error("focal length must be a positive finite number of pixels, got {0}")]
    BadFocal(f64),
    #[error(
        "the key triangle (both shoulders and the chest) is degenerate in every frame: the shoulders lie on top of each other or on the chest, so the camera cannot be calibrated"
    )]
    DegenerateKeyTriangle,
    #[error(
        "the subject's proportions give no key triangle: the chest–shoulder bones ({chest_shoulder_m:.3} m) must be longer than half the shoulder width ({shoulder_width_m:.3} m)"
    )]
    BadKeyTriangle {
        chest_shoulder_m: f64,
        shoulder_width_m: f64,
    },
    #[error("lift setting \"{name}\" must be {want}, got {value}")]
    BadSetting {
        name: &'static str,
        value: f64,
        want: &'static str,
    },
    #[error("camera calibration on the key triangle did not converge on frame {frame}")]
    CalibrationFailed { frame: FrameIndex },
    #[error(transparent)]
    Subject(#[from] ProportionsError),
    #[error(
        "the given {name} ({given_m:.3} m) is shorter than the video shows it ({seen_m:.3} m at the clip's scale): check the length, its unit and the bone's name"
    )]
    LengthContradicted {
        name: &'static str,
        given_m: f64,
        seen_m: f64,
    },
    #[error(transparent)]
    Prior(#[from] super::prior::PriorError),
    #[error("cancelled")]
    Cancelled,
}

/// Checks one lift setting: finite, and above 0 when `positive` (a tolerance or a deviation
/// divides), else at least 0 (a weight or a width, where 0 turns the term off).
pub(crate) fn check_setting(
    name: &'static str,
    value: f64,
    positive: bool,
) -> Result<(), LiftError> {
    let range = if positive {
        Range::Positive
    } else {
        Range::NonNegative
    };
    range
        .check(value)
        .map_err(|want| LiftError::BadSetting { name, value, want })
}
