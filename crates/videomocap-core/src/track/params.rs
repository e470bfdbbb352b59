//! The tracker's settings, each with its default and what it does (the GUI shows these as
//! tooltips).

use super::shared::TrackError;
use super::similarity::SimilarityWeights;
use crate::setting_range::Range;
use serde::{Deserialize, Serialize};

/// Settings removed from the tracker (their special cases gave no gain on the benchmark's test
/// split, `docs/method.md`, 2026-11-28): older project and settings files that hold them still
/// load; the keys are dropped once, on load, and never written again.
const RETIRED: [&str; 6] = [
    "head_min_share",
    "twin_merge_s",
    "twin_guard_torso",
    "upper_arm_short_penalty",
    "arm_rescue",
    "gait_completion",
];

/// Settings of the VBA tracker. Serialised as JSON (`--tracker-settings`); missing keys take
/// their defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(remote = "Self", default, deny_unknown_fields)]
pub struct TrackerParams {
    /// Weights of the morph-block similarity (eqs. 3–5) and of the key-frame model.
    pub weights: SimilarityWeights,
    /// Spacing of the head's spiral search path, tracker pixels. Default 2.
    pub head_step_px: f64,
    /// Δθ of the head search, degrees. Default 6.
    pub head_d_theta_deg: f64,
    /// Δm of the head search, fraction of m. Default 0.06.
    pub head_d_m: f64,
    /// Most rings of the spiral path. Default 12.
    pub head_max_rings: usize,
    /// Half-range of the trunk's angle search around its prediction, degrees. Default 20.
    pub trunk_range_deg: f64,
    /// Half-range of the trunk's length search, fraction. Default 0.15.
    pub trunk_range_m: f64,
    /// Half-range of a limb's angle search around its prediction, degrees. Default 30.
    pub limb_range_deg: f64,
    /// Half-range of a limb's length search, fraction (foreshortening). Default 0.3.
    pub limb_range_m: f64,
    /// Half-range of the second, wide search when the narrow one finds only a weak match
    /// (fast limbs), degrees. Default 100.
    pub wide_range_deg: f64,
    /// The fastest a limb turns away from its prediction, degrees per second: the wide
    /// search reaches no further per frame than this over the frame rate (and never beyond
    /// `wide_range_deg`); 0 = no limit. Default 4000 (a pitcher's elbow extends at about
    /// 2500 °/s): from 40 frames/s up the wide search narrows, at 60 frames/s to 67°, at 120
    /// to 33°. A walker's forearm no longer flips up onto the background in one frame. `bench
    /// track`'s suite misses at PCK@0.2 (of 24208; the 30 frames/s clips and the real sample
    /// unchanged) with 0 / 3000 / 3500 / 4000 / 5000 / 6000: 1401 / 1355 / 1355 / 1341 / 1368
    /// / 1443 (at 6000 run_side's far leg goes, 246 → 591 misses; at 4000 walk_toward_frontal
    /// 99 → 59, run_side 246 → 231, walk_across_side 130 → 125).
    pub wide_speed_deg_s: f64,
    /// Angle step of the coarse scans, degrees. Default 3.
    pub coarse_step_deg: f64,
    /// Motion prior: cost (8-bit levels) added per degree an anchored block turns away from its
    /// prediction. Default 0.1.
    pub angle_penalty: f32,
    /// Motion prior: cost added per unit of |ln(length / predicted length)|. Default 8.
    pub length_penalty: f32,
    /// How much of the last frame's angular velocity the prediction keeps. Default 0.7.
    pub velocity_damping: f64,
    /// Linear weight of the adaptive colour model's update per frame. Default 0.15.
    pub update_rate: f32,
    /// `c0` of the reliability `c0 / (c0 + cost)`: the cost (mean difference, 8-bit levels)
    /// that maps to reliability 0.5. Default 20.
    pub reliability_c0: f32,
    /// Reliability below which a joint is weak: not learnt from, and filled by interpolation
    /// when reliable frames surround it. Default 0.45.
    pub weak_reliability: f32,
    /// Longest run of weak frames filled by interpolation, seconds; longer runs are reported
    /// and left as tracked. Default 0.5.
    pub max_gap_s: f64,
    /// The tracker works on frames shrunk so that the marked person is at most this tall,
    /// pixels (speed on large videos; the sampling grids are capped anyway). Default 300: on
    /// the 1080×1920 sample (a person of 840 px) the tracker runs 1.2–1.5 times as fast as at
    /// 480, and `bench track` measured the suite and the sample no worse (PCK@0.2 0.898 →
    /// 0.904 and 0.759 → 0.771). 0 keeps every video at full size.
    pub working_stature_px: f64,
    /// Have FFmpeg deliver frames at the working scale, converting them to RGB at that size
    /// (at 1080×1920 cheaper than converting at full size and shrinking). The video's frame
    /// cache is emptied when tracking starts and ends. Default true.
    pub decoder_scaling: bool,
    /// Limb and head blocks are this many times the body part's breadth from the proportions,
    /// so their margins (eq. 5's b2) hold the part's outline against the background. Default 1.0.
    pub block_width_scale: f64,
    /// Search the head's starts beside the hip patch, and the four limb chains, in parallel
    /// (results are the same either way; a spiral's rings always share the worker threads,
    /// whose number the job's thread count sets).
    pub parallel: bool,
    /// Track a patch around the hips and re-hang the trunk from the neck to it when it matches
    /// clearly better than where the rigid trunk put the pelvis (a bending spine). Default true.
    pub hip_patch: bool,
    /// How much lower (8-bit levels) the hip patch's cost must be for the trunk to follow it.
    /// Default 3.
    pub hip_margin: f32,
    /// A forearm or shank turned further than this from its upper segment's direction in the
    /// image (degrees) is folded back onto it, which elbows and knees cannot do: the match is
    /// refused and the joint held. Default 165 (180 turns the check off).
    pub fold_limit_deg: f64,
    /// Cost (8-bit levels) per unit of ln(full length / length) that a limb block shorter than
    /// its full image length pays (beyond the paper). The length search is centred on the last
    /// length, so a limb that matched the other leg at half its length where the legs cross
    /// stayed short; this pull lets it grow back. Full length: proportions × marked stature ×
    /// the head's zoom. Default 8 (0 turns it off); it also resists true foreshortening, which
    /// costs a frontal seated knee.
    pub short_penalty: f32,
    /// Beyond the paper: the forearms' own pull towards full length (as
    /// [`TrackerParams::short_penalty`], for the forearms' blocks only). A forearm crossing the
    /// trunk, or in a sleeve of its colour, shrinks towards the elbow with the ordinary pull and
    /// leaves the wrist short; a stronger pull keeps it long, but also resists a hand pointing
    /// at the camera. Measured with `bench track`'s suite (joint-frames missed at PCK@0.2, of
    /// 24208) and the real sample (PCK@0.2) at 8 (the ordinary pull) / 10 / 11 / 12 / 13 / 14 /
    /// 15 / 16 / 18 / 20 / 30: suite 1401 / 1337 / 1362 / 1340 / 1406 / 1387 / 1613 / 1363 /
    /// 1511 / 1639 / 1623, real sample 0.805 / 0.811 / 0.833 / 0.834 / 0.822 / 0.839 / 0.843 /
    /// 0.841 / 0.845 / 0.845 / 0.845 (at 12 its left wrist 66.3 → 51.4 px). It stays at the
    /// ordinary 8 because the lift from those better tracks came out worse: at 10 to 14 the
    /// real sample lifted with its true bone lengths takes the trunk's mirror image for the
    /// whole clip (156 → 249–271 mm; a near tie between two calibrations, as
    /// the retired upper arms' own pull found at 34), and at 12 the suite lifted from the height went
    /// 94.9 → 101.0 mm (dance_turns_frontal 92.7 → 120.8). Raise it (12) for real video whose
    /// wrists fall short, and check the 3D view. Default 8.
    pub forearm_short_penalty: f32,
    /// Refine each limb chain as one figure after its segments are found (beyond the paper):
    /// the elbow or knee and the wrist or ankle move by sub-pixel steps while the sum of both
    /// segments' costs falls, so a middle joint the upper segment put a pixel off no longer
    /// leaves the lower segment anchored wrongly. Default true.
    pub chain_refine: bool,
    /// Beyond the paper: in the chain refinement each shoulder may leave the place the rigid
    /// trunk block gives it (a shoulder rises with a raised arm, and sinks as the body bends
    /// sideways), paying this cost (8-bit levels) per square tracker pixel of the shift; the
    /// shift carries over to the next frame. Default 0.05 (10 px cost 5); 0 holds the shoulders
    /// on the trunk. Where the shoulders truly stay put (the synthetic suite's bodies) it moves
    /// them by about a pixel, and the lift, which holds the shoulders and chest as a rigid
    /// triangle, feels that: there 0 gives the better 3D.
    ///
    /// What is left: in a side view the far shoulder is hidden in the trunk, and as the
    /// walker crosses the image the shoulders' image separation turns from −20 to +15 px
    /// (walk_across_side), which the rigid trunk cannot follow (its right shoulder PCK@0.2
    /// 0.60, run_side 0.46). Tried and not kept (suite / real sample PCK@0.2, against 0.903 /
    /// 0.805): the shoulders' shifts across the trunk made mirror images of each other, both
    /// averaged 0.904 / 0.739, weighted by the upper arms' reliabilities 0.905 / 0.739 (to the
    /// 4th power 0.906 / 0.748), or the less reliable arm's shoulder mirroring the other's
    /// 0.910 / 0.750 (at a reliability margin of 0.05; 0.2: 0.904 / 0.805). The far shoulders
    /// came right (run_side's 0.46 → 1.00), but on the real sample a raised arm's shoulder
    /// rises and the mirror then pulled the hanging arm's shoulder inwards, off its arm (left
    /// elbow PCK@0.2 0.78 → 0.12); gating it to side views by the shoulders' image separation
    /// did not separate the clips (the real sample's ratio to the trunk 0.30–0.46, the side
    /// views' 0.22–0.32). Mirroring only the shift across the trunk (not along it), and only
    /// while both upper arms hang (within 37° of the trunk, or 60°), still lost the real
    /// sample's left arm: 0.906 / 0.753 at a margin of 0.05, 0.906 / 0.747 at 0.1, 0.904 /
    /// 0.805 at 0.2. Four mirrored frames, the largest moving the left shoulder about 11 px
    /// outwards, were enough (left elbow 0.78 → 0.12).
    pub shoulder_spring: f32,
    /// Beyond the paper: weight of the foreground lane in the arms' blocks (upper arms and
    /// forearms), against the colours' (each 8-bit level of foreground difference counts this
    /// much against a level of colour difference). The lane is each pixel's difference from the
    /// static camera's background (`super::background`), 0 to 255 from no difference to
    /// `foreground_tau` and beyond; without a background (a moving camera) it is 0 everywhere.
    /// An arm's block must then stand out from the background where it did on the key frame:
    /// a forearm no longer settles on a wall of its own colour. The reliability still reads the
    /// colours alone. 0 = off. Default 0.2. `bench track`'s suite misses at PCK@0.2 (of 24208;
    /// with `head_min_share` 0) at 0 / 0.1 / 0.15 / 0.2 / 0.3: 1318 / 1222 / 1219 / 1217 /
    /// 1280 (treadmill_raised 144 → 112, dance_oblique 384 → 317 at 0.2), the real sample
    /// 0.805 / 0.796 / 0.787 / 0.810 / 0.787. On the legs as well it was chaotic: 1235 to
    /// 1700, walk_across_side 114 to 516 misses (two legs that both stand out from the
    /// background are told apart by their colours alone), and on the head and trunk the
    /// median's ghost of a person who stands still, then bows, held bend_side's trunk where
    /// it had stood (36 → 513 misses).
    pub arm_foreground: f32,
    /// The colour difference from the background (largest channel, 8-bit levels) at which a
    /// pixel counts fully as foreground; also how near its median a steady background pixel
    /// stays. Default 20. With `arm_foreground` 0.2: 15 / 20 / 25 gave 1206 / 1217 / 1253
    /// misses, the real sample 0.784 / 0.810 / 0.796.
    pub foreground_tau: f32,
    /// Beyond the paper: the finished tracks smoothed over time (`super::smooth`), a
    /// Gaussian window of this standard deviation, seconds, each neighbour weighted by its
    /// reliability; key frames and joints off the frame stay put. 0 (the default) turns it
    /// off. At 0.02 (0.6 of a frame at 30 frames/s, 2.4 at 120) `bench track`'s suite misses
    /// at PCK@0.2 fell 1318 → 1288 of 24208 (the real sample 0.805 either way), but the lift,
    /// which smooths each track by the jitter it measures on it, then smooths too little:
    /// `bench lift`'s suite from the tracker with true lengths 87.2 → 89.7 mm (from the height
    /// 94.0 → 96.6; dance_turns_frontal 92.7 → 119.6, its root choices flipping; 93.3 at
    /// 0.01, 116–119 from 0.015 to 0.04). So it is for 2D work: tracks to be read or exported
    /// as they are.
    pub smooth_s: f64,
    /// Weigh the pose network's evidence beside VBA's own (when the caller has the network):
    /// off tracks with VBA alone. Figures in `docs/method.md` ("The pose network as evidence").
    pub network: bool,
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
            weights: SimilarityWeights::default(),
            head_step_px: 2.0,
            head_d_theta_deg: 6.0,
            head_d_m: 0.06,
            head_max_rings: 12,
            trunk_range_deg: 20.0,
            trunk_range_m: 0.15,
            limb_range_deg: 30.0,
            limb_range_m: 0.3,
            wide_range_deg: 100.0,
            wide_speed_deg_s: 4000.0,
            coarse_step_deg: 3.0,
            angle_penalty: 0.1,
            length_penalty: 8.0,
            velocity_damping: 0.7,
            update_rate: 0.15,
            reliability_c0: 20.0,
            weak_reliability: 0.45,
            max_gap_s: 0.5,
            working_stature_px: 300.0,
            decoder_scaling: true,
            block_width_scale: 1.0,
            parallel: true,
            hip_patch: true,
            hip_margin: 3.0,
            fold_limit_deg: 165.0,
            short_penalty: 8.0,
            forearm_short_penalty: 8.0,
            chain_refine: true,
            shoulder_spring: 0.05,
            arm_foreground: 0.2,
            foreground_tau: 20.0,
            smooth_s: 0.0,
            network: true,
        }
    }
}

fn check(name: &'static str, value: f64, range: Range) -> Result<(), TrackError> {
    range
        .check(value)
        .map_err(|want| TrackError::BadSetting { name, value, want })
}

impl SimilarityWeights {
    /// Checks the weights: none negative, the centre and margin not both 0 (eq. 4 would divide
    /// by 0), the key-frame mix a share.
    pub fn validate(&self) -> Result<(), TrackError> {
        // Destructured so that a new weight cannot be left unchecked.
        let SimilarityWeights {
            rgb,
            centre,
            margin,
            key,
        } = *self;
        for (name, w) in ["weights.rgb[0]", "weights.rgb[1]", "weights.rgb[2]"]
            .into_iter()
            .zip(rgb)
        {
            check(name, w.into(), Range::NonNegative)?;
        }
        check(
            "weights.rgb (sum)",
            rgb.iter().sum::<f32>().into(),
            Range::Positive,
        )?;
        check("weights.centre", centre.into(), Range::NonNegative)?;
        check("weights.margin", margin.into(), Range::NonNegative)?;
        check(
            "weights.centre + weights.margin",
            (centre + margin).into(),
            Range::Positive,
        )?;
        check("weights.key", key.into(), Range::Unit)
    }
}

impl TrackerParams {
    /// The settings for a video of `fps` frames per second: the wide search's half-range
    /// limited by `wide_speed_deg_s` (unchanged when either is 0 or the rate unknown).
    pub fn at_frame_rate(self, fps: f64) -> TrackerParams {
        if self.wide_speed_deg_s > 0.0 && fps.is_finite() && fps > 0.0 {
            TrackerParams {
                wide_range_deg: self.wide_range_deg.min(self.wide_speed_deg_s / fps),
                ..self
            }
        } else {
            self
        }
    }

    /// Checks every setting is in the range it means something in (a settings file or a
    /// project can hold anything): steps and scales above 0, penalties, times and margins not
    /// negative, shares between 0 and 1, length ranges below 1 (a length must stay positive).
    pub fn validate(&self) -> Result<(), TrackError> {
        use Range::{Fraction, HalfTurn, NonNegative, Positive, Unit};
        // Destructured so that a new setting cannot be left unchecked.
        let TrackerParams {
            weights,
            head_step_px,
            head_d_theta_deg,
            head_d_m,
            head_max_rings: _,
            trunk_range_deg,
            trunk_range_m,
            limb_range_deg,
            limb_range_m,
            wide_range_deg,
            wide_speed_deg_s,
            coarse_step_deg,
            angle_penalty,
            length_penalty,
            velocity_damping,
            update_rate,
            reliability_c0,
            weak_reliability,
            max_gap_s,
            working_stature_px,
            decoder_scaling: _,
            block_width_scale,
            parallel: _,
            hip_patch: _,
            hip_margin,
            fold_limit_deg,
            short_penalty,
            forearm_short_penalty,
            chain_refine: _,
            shoulder_spring,
            arm_foreground,
            foreground_tau,
            smooth_s,
            network: _,
        } = *self;
        weights.validate()?;
        let checks: [(&'static str, f64, Range); 27] = [
            ("head_step_px", head_step_px, Positive),
            ("head_d_theta_deg", head_d_theta_deg, NonNegative),
            ("head_d_m", head_d_m, Fraction),
            ("trunk_range_deg", trunk_range_deg, NonNegative),
            ("trunk_range_m", trunk_range_m, Fraction),
            ("limb_range_deg", limb_range_deg, NonNegative),
            ("limb_range_m", limb_range_m, Fraction),
            ("wide_range_deg", wide_range_deg, NonNegative),
            ("wide_speed_deg_s", wide_speed_deg_s, NonNegative),
            ("coarse_step_deg", coarse_step_deg, Positive),
            ("angle_penalty", angle_penalty.into(), NonNegative),
            ("length_penalty", length_penalty.into(), NonNegative),
            ("velocity_damping", velocity_damping, Unit),
            ("update_rate", update_rate.into(), Unit),
            ("reliability_c0", reliability_c0.into(), Positive),
            ("weak_reliability", weak_reliability.into(), Unit),
            ("max_gap_s", max_gap_s, NonNegative),
            ("smooth_s", smooth_s, NonNegative),
            ("working_stature_px", working_stature_px, NonNegative),
            ("block_width_scale", block_width_scale, Positive),
            ("hip_margin", hip_margin.into(), NonNegative),
            ("fold_limit_deg", fold_limit_deg, HalfTurn),
            ("short_penalty", short_penalty.into(), NonNegative),
            (
                "forearm_short_penalty",
                forearm_short_penalty.into(),
                NonNegative,
            ),
            ("shoulder_spring", shoulder_spring.into(), NonNegative),
            ("arm_foreground", arm_foreground.into(), NonNegative),
            ("foreground_tau", foreground_tau.into(), Positive),
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
            "max_gap_s": 0.4}"#;
        let read: TrackerParams = serde_json::from_str(old).unwrap();
        assert_eq!(read.max_gap_s, 0.4);
        let written = serde_json::to_string(&read).unwrap();
        for key in [
            "twin_merge_s",
            "twin_guard_torso",
            "arm_rescue",
            "upper_arm_short_penalty",
            "gait_completion",
            "head_min_share",
        ] {
            assert!(!written.contains(key), "{key} written");
        }
        assert!(serde_json::from_str::<TrackerParams>(r#"{"arm_rescu": true}"#).is_err());
    }

    #[test]
    fn the_defaults_are_valid() {
        assert!(TrackerParams::default().validate().is_ok());
    }

    #[test]
    fn the_documented_defaults_are_the_defaults() {
        let json = crate::formats::documented_json("## tracker settings");
        let documented: TrackerParams = serde_json::from_str(json).unwrap();
        // The document rounds the thirds.
        assert!(
            documented
                .weights
                .rgb
                .iter()
                .all(|w| (w - 1.0 / 3.0).abs() < 1e-3)
        );
        let rounded = TrackerParams {
            weights: SimilarityWeights {
                rgb: documented.weights.rgb,
                ..SimilarityWeights::default()
            },
            ..TrackerParams::default()
        };
        assert_eq!(documented, rounded);
    }

    #[test]
    fn the_wide_search_reaches_no_further_per_frame_than_a_limb_turns() {
        let d = TrackerParams::default();
        // 4000 °/s: 133° a frame at 30 frames/s, beyond the 100° range; 67° at 60, 33° at 120.
        assert_eq!(d.at_frame_rate(30.0).wide_range_deg, 100.0);
        assert!((d.at_frame_rate(60.0).wide_range_deg - 4000.0 / 60.0).abs() < 1e-9);
        assert!((d.at_frame_rate(120.0).wide_range_deg - 4000.0 / 120.0).abs() < 1e-9);
        // No limit, or no known rate: the range as set.
        let free = TrackerParams {
            wide_speed_deg_s: 0.0,
            ..d
        };
        assert_eq!(free.at_frame_rate(120.0).wide_range_deg, 100.0);
        assert_eq!(d.at_frame_rate(0.0).wide_range_deg, 100.0);
        assert_eq!(d.at_frame_rate(f64::NAN).wide_range_deg, 100.0);
    }

    #[test]
    fn a_setting_out_of_its_range_is_named() {
        let with = |edit: fn(&mut TrackerParams)| {
            let mut p = TrackerParams::default();
            edit(&mut p);
            p
        };
        let cases: [(&str, TrackerParams); 8] = [
            ("short_penalty", with(|p| p.short_penalty = -1.0)),
            ("wide_speed_deg_s", with(|p| p.wide_speed_deg_s = -1.0)),
            (
                "forearm_short_penalty",
                with(|p| p.forearm_short_penalty = -0.5),
            ),
            (
                "forearm_short_penalty",
                with(|p| p.forearm_short_penalty = f32::NAN),
            ),
            ("limb_range_m", with(|p| p.limb_range_m = 1.0)),
            ("coarse_step_deg", with(|p| p.coarse_step_deg = 0.0)),
            ("fold_limit_deg", with(|p| p.fold_limit_deg = 200.0)),
            (
                "weights.centre + weights.margin",
                with(|p| (p.weights.centre, p.weights.margin) = (0.0, 0.0)),
            ),
        ];
        for (name, params) in cases {
            match params.validate() {
                Err(TrackError::BadSetting { name: got, .. }) => assert_eq!(got, name),
                other => panic!("{name}: expected a bad setting, got {other:?}"),
            }
        }
    }
}
