//! The tracker's settings, each with its default and what it does (the GUI shows these as
//! tooltips).

use super::shared::TrackError;
use super::similarity::SimilarityWeights;
use crate::setting_range::Range;
use serde::{Deserialize, Serialize};

/// Settings removed from the tracker: older project and settings files that hold them still
/// load; the keys are dropped once, on load, and never written again. The first six were
/// special cases that gave no gain on the benchmark's test split (2026-11-28); the rest are
/// fitted constants now ([`Tuning`], issue 92: a user changes about ten settings, each named
/// for what it does).
const RETIRED: [&str; 28] = [
    "head_min_share",
    "twin_merge_s",
    "twin_guard_torso",
    "upper_arm_short_penalty",
    "arm_rescue",
    "gait_completion",
    "weights",
    "head_step_px",
    "head_d_theta_deg",
    "head_d_m",
    "head_max_rings",
    "trunk_range_deg",
    "trunk_range_m",
    "limb_range_m",
    "wide_range_deg",
    "wide_speed_deg_s",
    "coarse_step_deg",
    "angle_penalty",
    "length_penalty",
    "velocity_damping",
    "update_rate",
    "reliability_c0",
    "decoder_scaling",
    "block_width_scale",
    "parallel",
    "hip_margin",
    "fold_limit_deg",
    "foreground_tau",
];

/// The tracker's settings a user changes, each named for what it does (the app's Tracker
/// panel shows exactly these). Serialised as JSON (`--tracker-settings`, a project's
/// `settings.tracker`); missing keys take their defaults, retired keys of older files are
/// dropped on load. Everything else the tracker uses is a fitted constant (`Tuning`, beside it).
/// Measurements behind each default: `docs/method.md` ("The tracker's settings and
/// constants").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(remote = "Self", default, deny_unknown_fields)]
pub struct TrackerParams {
    /// Weigh the pose network's evidence beside VBA's own (when the caller has the network):
    /// off tracks with VBA alone. Default on.
    pub network: bool,
    /// Reliability below which a joint is weak: not learnt from, and filled by interpolation
    /// when reliable frames surround it. Default 0.45.
    pub weak_reliability: f32,
    /// Longest run of weak frames filled by interpolation, seconds; longer runs are reported
    /// and left as tracked. Default 0.5.
    pub max_gap_s: f64,
    /// The finished tracks smoothed over time (`super::smooth`): a Gaussian window of this
    /// standard deviation, seconds, each neighbour weighted by its reliability; keys and joints
    /// off the frame stay put. For 2D work (the lift smooths by the jitter it measures).
    /// Default 0 (off).
    pub smooth_s: f64,
    /// The tracker works on frames shrunk so that the marked person is at most this tall,
    /// pixels (speed on large videos); 0 keeps every video at full size. Default 300.
    pub working_stature_px: f64,
    /// Half-range of a limb's angle search around its prediction, degrees. Default 30.
    pub limb_range_deg: f64,
    /// How strongly a limb block shorter than its full image length is pulled back (cost in
    /// 8-bit levels per unit of ln(full / length); legs crossing); 0 turns it off. Default 8.
    pub short_penalty: f32,
    /// The same pull for the forearms' blocks: raise it (12) when a forearm crossing the body
    /// shrinks towards the elbow and the wrist falls short. Default 8.
    pub forearm_short_penalty: f32,
    /// Track a patch around the hips and re-hang the trunk from the neck to it when it matches
    /// clearly better than where the rigid trunk put the pelvis (a bending spine). Default on.
    pub hip_patch: bool,
    /// Refine each limb chain as one figure after its segments are found: the middle and end
    /// joints move by sub-pixel steps while both segments' costs fall. Default on.
    pub chain_refine: bool,
    /// In the chain refinement, the cost per square tracker pixel a shoulder pays for leaving
    /// the place the rigid trunk gives it (a shoulder rises with its arm); 0 holds it on the
    /// trunk. Default 0.05.
    pub shoulder_spring: f32,
    /// With a static camera, the weight of the foreground lane in the arms' blocks (an arm must
    /// stand out from the background where it did on the key frame); 0 = off. Default 0.2.
    pub arm_foreground: f32,
}

// The derives above are `remote = "Self"`: they make inherent `TrackerParams::serialize` and
// `::deserialize`, which these trait impls call after migrating retired keys away.
impl Serialize for TrackerParams {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        TrackerParams::serialize(self, serializer)
    }
}

impl<'de> Deserialize<'de> for TrackerParams {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let mut map = serde_json::Map::deserialize(deserializer)?;
        for key in RETIRED {
            map.remove(key);
        }
        TrackerParams::deserialize(serde_json::Value::Object(map)).map_err(serde::de::Error::custom)
    }
}

impl Default for TrackerParams {
    fn default() -> Self {
        TrackerParams {
            network: true,
            weak_reliability: 0.45,
            max_gap_s: 0.5,
            smooth_s: 0.0,
            working_stature_px: 300.0,
            limb_range_deg: 30.0,
            short_penalty: 8.0,
            forearm_short_penalty: 8.0,
            hip_patch: true,
            chain_refine: true,
            shoulder_spring: 0.05,
            arm_foreground: 0.2,
        }
    }
}

/// What the tracker's steps read: the user's [`TrackerParams`] with the fitted constants beside
/// them (each with its reason; the measurements in `docs/method.md`, "The tracker's settings
/// and constants"), and what the run decides (threads, the frame rate's limit on the wide
/// search, whether the decoder shrinks the frames).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Tuning {
    /// Weights of the morph-block similarity (eqs. 3–5) and of the key-frame model: equal
    /// channels, the centre twice the margin (the paper's `W1 > W2`), the two models alike.
    pub(crate) weights: SimilarityWeights,
    /// Spacing of the head's spiral search path, tracker pixels.
    pub(crate) head_step_px: f64,
    /// Δθ of the head search, degrees.
    pub(crate) head_d_theta_deg: f64,
    /// Δm of the head search, fraction of m.
    pub(crate) head_d_m: f64,
    /// Most rings of the spiral path.
    pub(crate) head_max_rings: usize,
    /// Half-range of the trunk's angle search around its prediction, degrees.
    pub(crate) trunk_range_deg: f64,
    /// Half-range of the trunk's length search, fraction.
    pub(crate) trunk_range_m: f64,
    /// The user's [`TrackerParams::limb_range_deg`].
    pub(crate) limb_range_deg: f64,
    /// Half-range of a limb's length search, fraction (foreshortening).
    pub(crate) limb_range_m: f64,
    /// Half-range of the wide search when the narrow one finds only a weak match (fast
    /// limbs), degrees; limited per frame by [`WIDE_SPEED_DEG_S`] over the frame rate.
    pub(crate) wide_range_deg: f64,
    /// Angle step of the coarse scans, degrees.
    pub(crate) coarse_step_deg: f64,
    /// Motion prior: cost per degree an anchored block turns away from its prediction.
    pub(crate) angle_penalty: f32,
    /// Motion prior: cost per unit of |ln(length / predicted length)|.
    pub(crate) length_penalty: f32,
    /// How much of the last frame's angular velocity the prediction keeps.
    pub(crate) velocity_damping: f64,
    /// Linear weight of the adaptive colour model's update per frame (Akita 1984).
    pub(crate) update_rate: f32,
    /// `c0` of the reliability `c0 / (c0 + cost)`: the mean difference (8-bit levels) that
    /// maps to reliability 0.5.
    pub(crate) reliability_c0: f32,
    /// The user's [`TrackerParams::weak_reliability`].
    pub(crate) weak_reliability: f32,
    /// Blocks are this many times the part's breadth from the proportions, so their margins
    /// hold the part's outline against the background.
    pub(crate) block_width_scale: f64,
    /// The head's starts beside the hip patch, and the four limb chains, in parallel (more
    /// than one thread; the results are the same either way).
    pub(crate) parallel: bool,
    /// The user's [`TrackerParams::hip_patch`].
    pub(crate) hip_patch: bool,
    /// How much lower (8-bit levels) the hip patch's cost must be for the trunk to follow it.
    pub(crate) hip_margin: f32,
    /// A forearm or shank turned further than this from its upper segment (degrees) is folded
    /// back, which elbows and knees cannot do (they flex to about 150°): the match is refused.
    pub(crate) fold_limit_deg: f64,
    /// The user's [`TrackerParams::short_penalty`].
    pub(crate) short_penalty: f32,
    /// The user's [`TrackerParams::forearm_short_penalty`].
    pub(crate) forearm_short_penalty: f32,
    /// The user's [`TrackerParams::chain_refine`].
    pub(crate) chain_refine: bool,
    /// The user's [`TrackerParams::shoulder_spring`].
    pub(crate) shoulder_spring: f32,
    /// The user's [`TrackerParams::arm_foreground`].
    pub(crate) arm_foreground: f32,
    /// The colour difference from the background (largest channel, 8-bit levels) at which a
    /// pixel counts fully as foreground.
    pub(crate) foreground_tau: f32,
}

/// The fastest a limb turns away from its prediction, degrees per second (a pitcher's elbow
/// extends at about 2500 °/s): the wide search reaches no further per frame.
pub(crate) const WIDE_SPEED_DEG_S: f64 = 4000.0;

impl TrackerParams {
    /// The user's settings with the fitted constants, for a video of `fps` frames per second
    /// tracked on `threads` threads (the wide search limited by [`WIDE_SPEED_DEG_S`] over the
    /// frame rate, when known).
    pub(crate) fn tuning(&self, fps: f64, threads: usize) -> Tuning {
        let wide_range_deg: f64 = 100.0;
        Tuning {
            weights: SimilarityWeights::default(),
            head_step_px: 2.0,
            head_d_theta_deg: 6.0,
            head_d_m: 0.06,
            head_max_rings: 12,
            trunk_range_deg: 20.0,
            trunk_range_m: 0.15,
            limb_range_deg: self.limb_range_deg,
            limb_range_m: 0.3,
            wide_range_deg: if fps.is_finite() && fps > 0.0 {
                wide_range_deg.min(WIDE_SPEED_DEG_S / fps)
            } else {
                wide_range_deg
            },
            coarse_step_deg: 3.0,
            angle_penalty: 0.1,
            length_penalty: 8.0,
            velocity_damping: 0.7,
            update_rate: 0.15,
            reliability_c0: 20.0,
            weak_reliability: self.weak_reliability,
            block_width_scale: 1.0,
            parallel: threads > 1,
            hip_patch: self.hip_patch,
            hip_margin: 3.0,
            fold_limit_deg: 165.0,
            short_penalty: self.short_penalty,
            forearm_short_penalty: self.forearm_short_penalty,
            chain_refine: self.chain_refine,
            shoulder_spring: self.shoulder_spring,
            arm_foreground: self.arm_foreground,
            foreground_tau: 20.0,
        }
    }
}

fn check(name: &'static str, value: f64, range: Range) -> Result<(), TrackError> {
    range
        .check(value)
        .map_err(|want| TrackError::BadSetting { name, value, want })
}

impl TrackerParams {
    /// Checks every setting is in the range it means something in (a settings file or a
    /// project can hold anything): penalties, times, ranges and the spring not negative, the
    /// weak threshold between 0 and 1.
    pub fn validate(&self) -> Result<(), TrackError> {
        use Range::{NonNegative, Unit};
        // Destructured so that a new setting cannot be left unchecked.
        let TrackerParams {
            network: _,
            weak_reliability,
            max_gap_s,
            smooth_s,
            working_stature_px,
            limb_range_deg,
            short_penalty,
            forearm_short_penalty,
            hip_patch: _,
            chain_refine: _,
            shoulder_spring,
            arm_foreground,
        } = *self;
        let checks: [(&'static str, f64, Range); 9] = [
            ("weak_reliability", weak_reliability.into(), Unit),
            ("max_gap_s", max_gap_s, NonNegative),
            ("smooth_s", smooth_s, NonNegative),
            ("working_stature_px", working_stature_px, NonNegative),
            ("limb_range_deg", limb_range_deg, NonNegative),
            ("short_penalty", short_penalty.into(), NonNegative),
            (
                "forearm_short_penalty",
                forearm_short_penalty.into(),
                NonNegative,
            ),
            ("shoulder_spring", shoulder_spring.into(), NonNegative),
            ("arm_foreground", arm_foreground.into(), NonNegative),
        ];
        checks
            .into_iter()
            .try_for_each(|(name, value, range)| check(name, value, range))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn retired_settings_in_older_files_are_read_and_dropped() {
        let old = r#"{"twin_merge_s": 0.2, "twin_guard_torso": 0.15, "arm_rescue": true,
            "upper_arm_short_penalty": 35.0, "gait_completion": true, "head_min_share": 0.7,
            "weights": {"rgb": [0.3, 0.3, 0.4], "centre": 1.0, "margin": 0.5, "key": 0.5},
            "head_step_px": 3.0, "fold_limit_deg": 170.0, "parallel": false,
            "decoder_scaling": false, "max_gap_s": 0.4, "short_penalty": 6.0}"#;
        let read: TrackerParams = serde_json::from_str(old).unwrap();
        assert_eq!(read.max_gap_s, 0.4);
        assert_eq!(read.short_penalty, 6.0);
        let written = serde_json::to_string(&read).unwrap();
        for key in RETIRED {
            assert!(!written.contains(&format!("\"{key}\"")), "{key} written");
        }
        assert!(serde_json::from_str::<TrackerParams>(r#"{"arm_rescu": true}"#).is_err());
    }

    #[test]
    fn a_user_changes_at_most_twelve_settings() {
        let written = serde_json::to_value(TrackerParams::default()).unwrap();
        let keys = written.as_object().map_or(0, |m| m.len());
        assert!(keys <= 12, "{keys} settings");
    }

    #[test]
    fn the_defaults_are_valid() {
        assert!(TrackerParams::default().validate().is_ok());
    }

    #[test]
    fn the_documented_defaults_are_the_defaults() {
        let json = crate::formats::documented_json("## tracker settings");
        let documented: TrackerParams = serde_json::from_str(json).unwrap();
        assert_eq!(documented, TrackerParams::default());
    }

    #[test]
    fn the_wide_search_reaches_no_further_per_frame_than_a_limb_turns() {
        let d = TrackerParams::default();
        // 4000 °/s: 133° a frame at 30 frames/s, beyond the 100° range; 67° at 60, 33° at 120.
        assert_eq!(d.tuning(30.0, 1).wide_range_deg, 100.0);
        assert!((d.tuning(60.0, 1).wide_range_deg - 4000.0 / 60.0).abs() < 1e-9);
        assert!((d.tuning(120.0, 1).wide_range_deg - 4000.0 / 120.0).abs() < 1e-9);
        // No known rate: the whole range.
        assert_eq!(d.tuning(0.0, 1).wide_range_deg, 100.0);
        assert_eq!(d.tuning(f64::NAN, 1).wide_range_deg, 100.0);
        assert!(!d.tuning(30.0, 1).parallel && d.tuning(30.0, 2).parallel);
    }

    #[test]
    fn a_setting_out_of_its_range_is_named() {
        let with = |edit: fn(&mut TrackerParams)| {
            let mut p = TrackerParams::default();
            edit(&mut p);
            p
        };
        let cases: [(&str, TrackerParams); 5] = [
            ("short_penalty", with(|p| p.short_penalty = -1.0)),
            (
                "forearm_short_penalty",
                with(|p| p.forearm_short_penalty = -0.5),
            ),
            (
                "forearm_short_penalty",
                with(|p| p.forearm_short_penalty = f32::NAN),
            ),
            ("weak_reliability", with(|p| p.weak_reliability = 1.5)),
            ("limb_range_deg", with(|p| p.limb_range_deg = -3.0)),
        ];
        for (name, params) in cases {
            match params.validate() {
                Err(TrackError::BadSetting { name: got, .. }) => assert_eq!(got, name),
                other => panic!("{name}: expected a bad setting, got {other:?}"),
            }
        }
    }
}
