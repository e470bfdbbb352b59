//! The lift's settings: the few a user may change (`--lift-settings`, the app's Lift settings,
//! a batch row), each named for what it does to the result and with its documented default,
//! and their checks. Everything else the lift weighs is a fitted constant beside the code that
//! uses it (measurements in `docs/method.md`). Files written before 2026-11-29 held 30 settings:
//! they still load, the ones kept renamed and the retired ones dropped
//! ([`retired_lift_settings`] names them).

use super::ambiguity::AmbiguityWeights;
use super::error::{LiftError, check_setting};
use serde::{Deserialize, Serialize};

/// Settings of the lift; every field has a documented default and can be given as JSON.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(from = "StoredLiftParams")]
pub struct LiftParams {
    /// Polish the whole clip after the per-frame solve (default true): one least-squares pass
    /// over every frame (reprojection, bone lengths, smooth motion), then every bone set back
    /// to its length, so the BVH's fixed offsets give the skeleton back exactly.
    pub refine: bool,
    /// Smooth the tracks over time before the lift (default true); off for tracks that are
    /// already clean.
    pub smooth_tracks: bool,
    /// With `smooth_tracks`: every joint's track by a Gaussian this many seconds wide; 0 (the
    /// default) each joint by as much as its own jitter calls for.
    pub smoothing_s: f64,
    /// Keep the trunk's path steady (default true): the shoulders' and chest's 3D path is
    /// refitted over the whole clip (reprojection, rigid sides, acceleration, as firm as their
    /// tracks are noisy).
    pub steady_trunk: bool,
    /// Keep planted feet still (default true): each foot's contacts with the floor are found
    /// and the body is moved along the planted ankle's viewing ray so the ankle keeps one depth
    /// over each (it stays on its 2D track).
    pub foot_lock: bool,
    /// In a walk or run, how strongly an arm whose depth is in doubt is taken to swing against
    /// its own leg (default 1; 0 = off).
    pub arm_swing: f64,
    /// How strongly a hand whose depth is in doubt is kept out of the trunk and the thighs
    /// (default 10; 0 = off).
    pub hands_outside_body: f64,
    /// How much the pose network's 3D body counts for each bone's depth and the body's facing
    /// where the tracks carry it (default 1; 0 = geometry alone, which also turns off the
    /// refinement's pull towards the network's bone directions).
    pub image_depth: f64,
    /// How much the pose prior learned from motion capture counts in each bone's depth choice
    /// (default 1; 0 = the geometry alone: the 2D miss and smooth motion).
    pub pose_prior: f64,
}

impl Default for LiftParams {
    fn default() -> Self {
        let fitted = AmbiguityWeights::default();
        LiftParams {
            refine: true,
            smooth_tracks: true,
            smoothing_s: 0.0,
            steady_trunk: true,
            foot_lock: true,
            arm_swing: fitted.arm_swing,
            hands_outside_body: fitted.contact,
            image_depth: fitted.image_depth,
            pose_prior: 1.0,
        }
    }
}

impl LiftParams {
    /// Checks every setting is in the range it means something in (a settings file can hold
    /// anything): the smoothing width and the weights finite and not negative.
    pub fn validate(&self) -> Result<(), LiftError> {
        // Destructured so that a new setting cannot be left unchecked.
        let LiftParams {
            refine: _,
            smooth_tracks: _,
            smoothing_s,
            steady_trunk: _,
            foot_lock: _,
            arm_swing,
            hands_outside_body,
            image_depth,
            pose_prior,
        } = *self;
        check_setting("pose_prior", pose_prior, false)?;
        check_setting("smoothing_s", smoothing_s, false)?;
        check_setting("arm_swing", arm_swing, false)?;
        check_setting("hands_outside_body", hands_outside_body, false)?;
        check_setting("image_depth", image_depth, false)
    }

    /// The depth-ambiguity weights: the fitted ones with the user's three.
    pub(super) fn ambiguity(&self) -> AmbiguityWeights {
        AmbiguityWeights {
            arm_swing: self.arm_swing,
            contact: self.hands_outside_body,
            image_depth: self.image_depth,
            pose_prior: self.pose_prior * AmbiguityWeights::default().pose_prior,
            ..AmbiguityWeights::default()
        }
    }
}

/// The settings of an older file that no longer exist (each now a fitted constant), as
/// `name` or `group.name`; empty for a current file. A front end shows them, then the file's
/// next save drops them.
pub fn retired_lift_settings(json: &serde_json::Value) -> Vec<String> {
    let Some(map) = json.as_object() else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (key, value) in map {
        match key.as_str() {
            "calibration_tolerance_px" | "propagation_tolerance_m" => {
                out.push(key.clone());
            }
            "ambiguity" | "refinement" => {
                for inner in value.as_object().into_iter().flat_map(|m| m.keys()) {
                    let kept = key == "ambiguity"
                        && matches!(inner.as_str(), "arm_swing" | "contact" | "image_depth");
                    if !kept {
                        out.push(format!("{key}.{inner}"));
                    }
                }
            }
            _ => {}
        }
    }
    out
}

/// What a settings file may hold: today's settings and, from older files, the ones renamed
/// (`key_path_smoothing`, `adaptive_smoothing`, `ambiguity.arm_swing`, `ambiguity.contact`,
/// `ambiguity.image_depth`) and the ones retired (read and dropped). Unknown names are refused.
#[derive(Deserialize)]
#[serde(
    default,
    deny_unknown_fields,
    expecting = "lift settings (a JSON object)"
)]
struct StoredLiftParams {
    refine: bool,
    smooth_tracks: Option<bool>,
    smoothing_s: f64,
    steady_trunk: Option<bool>,
    foot_lock: bool,
    arm_swing: Option<f64>,
    hands_outside_body: Option<f64>,
    image_depth: Option<f64>,
    pose_prior: Option<f64>,
    // Renamed.
    key_path_smoothing: Option<bool>,
    ambiguity: Option<OldAmbiguity>,
    adaptive_smoothing: Option<bool>,
    // Retired.
    #[allow(dead_code)]
    calibration_tolerance_px: Option<serde_json::Value>,
    #[allow(dead_code)]
    propagation_tolerance_m: Option<serde_json::Value>,
    #[allow(dead_code)]
    refinement: Option<serde_json::Value>,
}

/// The old `ambiguity` group: three of its weights live on under new names.
#[derive(Deserialize, Default)]
#[serde(
    default,
    expecting = "the older files' ambiguity weights (a JSON object)"
)]
struct OldAmbiguity {
    arm_swing: Option<f64>,
    contact: Option<f64>,
    image_depth: Option<f64>,
}

impl Default for StoredLiftParams {
    fn default() -> Self {
        let d = LiftParams::default();
        StoredLiftParams {
            refine: d.refine,
            smooth_tracks: None,
            smoothing_s: d.smoothing_s,
            steady_trunk: None,
            foot_lock: d.foot_lock,
            arm_swing: None,
            hands_outside_body: None,
            image_depth: None,
            pose_prior: None,
            key_path_smoothing: None,
            ambiguity: None,
            calibration_tolerance_px: None,
            propagation_tolerance_m: None,
            adaptive_smoothing: None,
            refinement: None,
        }
    }
}

impl From<StoredLiftParams> for LiftParams {
    fn from(s: StoredLiftParams) -> Self {
        let d = LiftParams::default();
        let old = s.ambiguity.unwrap_or_default();
        // The old switch turned off only the automatic smoothing (a fixed width still smoothed).
        let old_smoothing = s.adaptive_smoothing.map(|a| a || s.smoothing_s > 0.0);
        LiftParams {
            refine: s.refine,
            smooth_tracks: s.smooth_tracks.or(old_smoothing).unwrap_or(d.smooth_tracks),
            smoothing_s: s.smoothing_s,
            steady_trunk: s
                .steady_trunk
                .or(s.key_path_smoothing)
                .unwrap_or(d.steady_trunk),
            foot_lock: s.foot_lock,
            arm_swing: s.arm_swing.or(old.arm_swing).unwrap_or(d.arm_swing),
            hands_outside_body: s
                .hands_outside_body
                .or(old.contact)
                .unwrap_or(d.hands_outside_body),
            image_depth: s.image_depth.or(old.image_depth).unwrap_or(d.image_depth),
            pose_prior: s.pose_prior.unwrap_or(d.pose_prior),
        }
    }
}
