//! Beyond the paper: gait completion. In a side view of a walk or a run the far arm and leg
//! are hidden behind the body half the time, and the tracker's far elbow, wrist, knee and ankle
//! drift onto the near limb or the trunk, often confidently. But a gait is periodic and its two
//! sides move alike half a stride apart: the far limb at frame `t` bends as the near limb did at
//! `t ± T/2`. So when one side's limb swings periodically and its copy, shifted by half the
//! period, agrees with the frames where the far limb is clearly seen, the far limb's joints that
//! are weak or far from that copy are put where the copy says, hung from the far limb's own
//! shoulder or hip, and marked as completed from the gait ([`PointSource::Gait`]) for the user
//! to check.
//!
//! Measured with `bench track` (suite / real sample PCK@0.2 against 0.903 / 0.805, lost 3.55 %
//! of the suite's joint-frames): see [`complete_gaits`] for the figures of each rule.

use super::side_trunk::{TrunkReport, correct_trunk};
use crate::camera::point_in_frame;
use crate::formats::{FrameTracks, PointSource, SourceInfo, TrackedPoint};
use crate::skeleton::Joint;
use nalgebra::Vector2;
use serde::Serialize;

/// A limb as its two segments, left side: upper (shoulder → elbow, hip → knee) and lower.
const ARM: [(Joint, Joint); 2] = [
    (Joint::LeftShoulder, Joint::LeftElbow),
    (Joint::LeftElbow, Joint::LeftWrist),
];
/// The leg, as [`ARM`].
const LEG: [(Joint, Joint); 2] = [
    (Joint::LeftHip, Joint::LeftKnee),
    (Joint::LeftKnee, Joint::LeftAnkle),
];

/// The least autocorrelation of the donor's swing at its period: the upper arms and thighs of
/// the suite's walks and runs reach 0.48–1.00; dances, a dribbling arm, sitting down and
/// bending −0.07–0.38 (a waving arm 0.43, but it swings by 0.2°: [`MIN_SWING_DEG`]).
pub const MIN_AUTOCORR: f64 = 0.4;

/// The least standard deviation of the donor's upper segment's image angle, degrees: a limb
/// that hardly swings (a raised or hanging arm) has no gait to copy.
pub const MIN_SWING_DEG: f64 = 5.0;

/// The range of stride periods, seconds, taken for a gait.
pub const PERIOD_S: (f64, f64) = (0.4, 2.5);

/// A far joint tracked at least this reliably (or placed by hand) counts as clearly seen: the
/// frames the copy is checked against, and the joints kept unless the copy is far
/// ([`REPLACE_TORSO`]).
pub const SEEN_RELIABILITY: f32 = 0.6;

/// The most the copy may differ, median over the clearly seen frames, from the far limb's own
/// segments, in torso lengths (neck to pelvis): walks and runs agree within 0.03–0.15, a
/// jumping jack (both sides moving together, not half a period apart) 0.29–1.16.
pub const MAX_DISAGREEMENT_TORSO: f64 = 0.2;

/// A clearly seen far joint further than this from the copy, torso lengths, is replaced too:
/// a confident block riding on the near limb. As far as a copy may disagree with the far limb
/// at the median ([`MAX_DISAGREEMENT_TORSO`]). Measured on `bench track`'s suite with the
/// side-on trunk centred and the stride searched over [`MAX_LAG_SHARE`]: PCK@0.2 0.931 at 0.4,
/// 0.933 at 0.25, 0.934 at 0.2, 0.935 at 0.15; walk_across_side 0.935 → 0.952 from 0.4 to 0.2,
/// dribble_oblique 0.926 → 0.921 (its strides are uneven) and 0.913 at 0.15.
pub const REPLACE_TORSO: f64 = 0.2;

/// A clearly seen far joint far from the copy ([`REPLACE_TORSO`]) is replaced only when the
/// copy came from donor joints at most this much less reliable than it: treadmill_raised's
/// legs fail in turn, half a stride apart, so there the copy came from the donor riding on the
/// far leg (suite lost 2.04 → 1.98 %, PCK@0.2 unchanged at 0.915; a margin of 0.05 gave 1.98 %
/// too, 0 2.06 %, −0.05 2.15 %). Later 0.2 replaced run_side's far wrist where it was tracked
/// confidently beside the body (its confidence 0.7–0.76, the donor's a little lower): suite
/// misses at PCK@0.2 of 24208 at 0.1 / 0.2 / 1: 1341 / 1318 / 1319 (run_side 231 → 206 at
/// 0.2, treadmill_raised unchanged at 144); with the tracks smoothed (`smooth_s` 0.02) at 0.1
/// / 0.15 / 0.2 / 0.3: 1303 / 1285 / 1288 / 1288. The real sample (no gait) is unchanged.
pub const REPLACE_MARGIN: f32 = 0.2;

/// The fewest clearly seen frames the copy is checked against.
pub const MIN_CHECKS: usize = 10;

/// Which limbs of a gait.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LimbPair {
    /// Shoulder, elbow, wrist.
    Arms,
    /// Hip, knee, ankle.
    Legs,
}

/// What gait completion found and did.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct GaitOutcome {
    /// Per pair of limbs (arms, then legs).
    pub limbs: Vec<GaitReport>,
    /// The side-on trunk's perspective, when the legs are a gait.
    pub trunk: Option<TrunkReport>,
}

/// What gait completion found for one pair of limbs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GaitReport {
    /// Arms or legs.
    pub limbs: LimbPair,
    /// The side copied from: the one whose middle and end joints were tracked more reliably
    /// (summed over the frames where they were tracked, not filled in).
    pub donor: &'static str,
    /// The donor's stride period, seconds (`None` when its swing has none).
    pub period_s: Option<f64>,
    /// Median disagreement of the copy with the clearly seen far limb, torso lengths (`None`
    /// when the swing was no gait).
    pub disagreement: Option<f64>,
    /// Far joint-frames put where the copy says.
    pub completed: usize,
}

impl GaitReport {
    /// The side copied onto: the other one than [`GaitReport::donor`].
    pub fn far(&self) -> &'static str {
        if self.donor == "left" {
            "right"
        } else {
            "left"
        }
    }
}

/// Completes the far limbs of a gait in `frames` (consecutive frame indices, after the weak
/// runs are filled) of `video` and reports what it did. Joints placed by hand
/// (`is_key(frame position, joint)`) and joints off the frame are never moved, nor is a joint
/// whose copy falls outside the frame.
///
/// Per pair: the donor is the side whose elbow and wrist (knee and ankle) have the higher summed
/// reliability where tracked (so a second run on its own output keeps its donor); its stride
/// period is the first peak of the autocorrelation of its upper segment's image angle after
/// the first negative lag (lags up to [`MAX_LAG_SHARE`] of the clip) that comes within
/// [`LATER_PEAK_MARGIN`] of the highest. A gait needs an autocorrelation of at least
/// [`MIN_AUTOCORR`], a swing of [`MIN_SWING_DEG`] and a period in [`PERIOD_S`]. The copy of a
/// far joint at frame `t` is its own parent plus the donor's segment averaged over `t − T/2`
/// and `t + T/2` (whichever lie in the video), down the chain. It is used only where it agrees
/// with the clearly seen far limb ([`MAX_DISAGREEMENT_TORSO`]), and then replaces far joints
/// that are weak (under [`SEEN_RELIABILITY`]) or far from it ([`REPLACE_TORSO`],
/// [`REPLACE_MARGIN`]).
///
/// When the legs are such a gait, the body keeps its heading: first the shoulders and hips are
/// set to the perspective of a side-on trunk ([`correct_trunk`]), so the copies hang from
/// where the body has them; then the arms and legs are examined again and completed.
///
/// On `bench track`'s suite, the limbs alone: PCK@0.2 0.903 → 0.915, lost 3.55 → 1.98 %
/// (walk_across_side 0.816 → 0.869, run_side 0.770 → 0.823, treadmill_oblique 0.954 → 0.970,
/// dribble_oblique 0.939 → 0.926: uneven dribbling strides, treadmill_raised 0.899 → 0.890);
/// jumping jacks, dances, waves and the real sample unchanged (no gait, or a copy that
/// disagrees). Replacing every far joint-frame gave 0.917 / 2.04 % but dribble_oblique 0.905;
/// replacing only weak ones 0.913 / 2.2 %. A donor chosen from the ground truth would give
/// about 0.920. With the trunk's perspective first: 0.926, lost 1.87 % (walk_across_side 0.933,
/// run_side 0.859; no other clip changed by more than 0.006 in PCK@0.1). Applied to every clip,
/// not only to gaits, the perspective cost the turning dancers (dance_oblique 0.798 → 0.762) and
/// the real sample (0.805 → 0.796). Then with the trunk's pairs centred by the model, the
/// stride searched over [`MAX_LAG_SHARE`] and seen joints replaced beyond [`REPLACE_TORSO`]
/// (0.2, was 0.4): 0.934, lost 1.86 % (walk_across_side 0.952, run_side 0.907, dribble_oblique
/// 0.921). Fitting the stride to the copy's agreement with the seen far limb (±10–30 % of the
/// autocorrelation's, before the longer lags) gave 0.930–0.931 against 0.931: the seen far
/// limb is itself often wrong, and run_side's arm stride went from 0.70 to 0.66 s. Replacing
/// joints that sit on the donor's own joint whatever their reliability gave 0.934 (run_side
/// +0.005 at 0.2 torso); not kept.
pub fn complete_gaits(
    frames: &mut [FrameTracks],
    video: &SourceInfo,
    is_key: &dyn Fn(usize, Joint) -> bool,
) -> GaitOutcome {
    // A gait by its legs: first the side-on trunk's perspective, so that the copies below hang
    // from shoulders and hips where the body has them.
    let (_, legs) = examine(frames, video.fps, is_key, LimbPair::Legs, LEG);
    let trunk =
        legs.and_then(|g| correct_trunk(frames, video, g.far[0].0 == Joint::RightHip, is_key));
    let limbs = [(LimbPair::Arms, ARM), (LimbPair::Legs, LEG)]
        .into_iter()
        .map(|(limbs, left)| {
            let (mut report, gait) = examine(frames, video.fps, is_key, limbs, left);
            if let Some(gait) = gait {
                report.completed = complete(frames, video, is_key, &gait);
            }
            report
        })
        .collect();
    GaitOutcome { limbs, trunk }
}

/// A pair of limbs found to be a gait: which side to copy, onto which, and half the stride.
struct PairGait {
    donor: [(Joint, Joint); 2],
    far: [(Joint, Joint); 2],
    half: f64,
}

impl PairGait {
    /// The donor's segments half a stride away in `frames`.
    fn copy<'a>(&self, frames: &'a [FrameTracks]) -> HalfStride<'a> {
        HalfStride {
            frames,
            donor: self.donor,
            half: self.half,
        }
    }
}

/// Whether a pair of limbs is a gait whose copy agrees with the far limb (see
/// [`complete_gaits`]), and the report so far (nothing completed yet).
fn examine(
    frames: &[FrameTracks],
    fps: f64,
    is_key: &dyn Fn(usize, Joint) -> bool,
    limbs: LimbPair,
    left: [(Joint, Joint); 2],
) -> (GaitReport, Option<PairGait>) {
    let right = left.map(|(a, b)| (a.mirrored(), b.mirrored()));
    let summed = |segs: &[(Joint, Joint); 2]| -> f64 {
        frames
            .iter()
            .flat_map(|f| segs.iter().map(|&(_, b)| f.points[b]))
            .filter(|p| p.source == PointSource::Tracked)
            .map(|p| f64::from(p.confidence))
            .sum()
    };
    let (donor, far) = if summed(&right) > summed(&left) {
        (right, left)
    } else {
        (left, right)
    };
    let mut report = GaitReport {
        limbs,
        donor: if donor == left { "left" } else { "right" },
        period_s: None,
        disagreement: None,
        completed: 0,
    };
    let (upper_a, upper_b) = donor[0];
    let angles: Vec<f64> = frames
        .iter()
        .map(|f| {
            let d = f.points[upper_b].pos - f.points[upper_a].pos;
            d.y.atan2(d.x)
        })
        .collect();
    // Lags up to the longest stride: the work grows with the video's length only linearly.
    let max_lag = (PERIOD_S.1 * fps).ceil() as usize + 1;
    let min_lag = (PERIOD_S.0 * fps).ceil() as usize;
    let Some(swing) = Swing::of(&unwrapped(&angles), min_lag, max_lag) else {
        return (report, None);
    };
    report.period_s = Some(swing.period as f64 / fps);
    let period_ok = (PERIOD_S.0 * fps..=PERIOD_S.1 * fps).contains(&(swing.period as f64));
    if swing.autocorr < MIN_AUTOCORR || swing.std_deg < MIN_SWING_DEG || !period_ok {
        return (report, None);
    }
    let gait = PairGait {
        donor,
        far,
        half: swing.period as f64 / 2.0,
    };
    let copy = gait.copy(frames);
    // The copy's check against the clearly seen far limb (its own segments).
    let mut errors = Vec::new();
    for (t, f) in frames.iter().enumerate() {
        let torso = f.torso_px().max(1.0);
        for (seg, &(a, b)) in far.iter().enumerate() {
            let p = f.points[b];
            let seen = is_key(t, b) || clearly_seen(&p);
            if let (true, Some(v)) = (seen, copy.segment(t, seg)) {
                errors.push((v - (p.pos - f.points[a].pos)).norm() / torso);
            }
        }
    }
    if errors.len() < MIN_CHECKS {
        return (report, None);
    }
    errors.sort_by(f64::total_cmp);
    let disagreement = errors[errors.len() / 2];
    report.disagreement = Some(disagreement);
    if disagreement > MAX_DISAGREEMENT_TORSO {
        return (report, None);
    }
    (report, Some(gait))
}

/// Whether a point was tracked at least [`SEEN_RELIABILITY`] (not filled in).
fn clearly_seen(p: &TrackedPoint) -> bool {
    p.source == PointSource::Tracked && p.confidence >= SEEN_RELIABILITY
}

/// Puts the far limb's joints where the copy says (see [`complete_gaits`]); returns how many.
fn complete(
    frames: &mut [FrameTracks],
    video: &SourceInfo,
    is_key: &dyn Fn(usize, Joint) -> bool,
    gait: &PairGait,
) -> usize {
    let copy = gait.copy(frames);
    let far = gait.far;
    // Down the chain: the lower segment hangs from the middle joint, completed or not.
    let mut completed = Vec::new();
    for (t, f) in frames.iter().enumerate() {
        let torso = f.torso_px().max(1.0);
        let mut parent = f.points[far[0].0].pos;
        for (seg, &(_, b)) in far.iter().enumerate() {
            let p = f.points[b];
            let Some(v) = copy.segment(t, seg) else {
                parent = p.pos;
                continue;
            };
            let pred = parent + v;
            let weak = !clearly_seen(&p);
            let movable = !is_key(t, b)
                && p.source != PointSource::OffFrame
                && point_in_frame(&pred, video.width, video.height);
            let reliability = copy.reliability(t, seg);
            let off = (pred - p.pos).norm() / torso > REPLACE_TORSO
                && reliability >= p.confidence - REPLACE_MARGIN;
            if movable && (weak || off) {
                completed.push((t, b, pred, reliability));
                parent = pred;
            } else {
                parent = p.pos;
            }
        }
    }
    let count = completed.len();
    for (t, j, pos, confidence) in completed {
        let p = &mut frames[t].points[j];
        p.pos = pos;
        p.confidence = confidence;
        p.source = PointSource::Gait;
    }
    count
}

/// The donor's segments, half a stride away.
struct HalfStride<'a> {
    frames: &'a [FrameTracks],
    donor: [(Joint, Joint); 2],
    half: f64,
}

impl HalfStride<'_> {
    /// The frame positions `t ± half` that lie in the video.
    fn sources(&self, t: usize) -> impl Iterator<Item = f64> + use<> {
        let last = (self.frames.len() - 1) as f64;
        let t = t as f64;
        [t - self.half, t + self.half]
            .into_iter()
            .filter(move |s| (0.0..=last).contains(s))
    }

    /// The donor's segment `seg` (image vector, parent to child) averaged over the sources of
    /// frame `t`, each linearly interpolated between frames; `None` when neither lies in the
    /// video.
    fn segment(&self, t: usize, seg: usize) -> Option<Vector2<f64>> {
        let (a, b) = self.donor[seg];
        let vec = |i: usize| self.frames[i].points[b].pos - self.frames[i].points[a].pos;
        let vs: Vec<Vector2<f64>> = self
            .sources(t)
            .map(|s| {
                let (i0, w) = (s.floor() as usize, s.fract());
                let i1 = (i0 + 1).min(self.frames.len() - 1);
                vec(i0) * (1.0 - w) + vec(i1) * w
            })
            .collect();
        (!vs.is_empty()).then(|| vs.iter().sum::<Vector2<f64>>() / vs.len() as f64)
    }

    /// The confidence of a completed joint: the donor's child joint's lowest reliability at
    /// the frames its copy came from, averaged over the sources.
    fn reliability(&self, t: usize, seg: usize) -> f32 {
        let b = self.donor[seg].1;
        let cs: Vec<f32> = self
            .sources(t)
            .map(|s| {
                let i0 = s.floor() as usize;
                let i1 = (i0 + 1).min(self.frames.len() - 1);
                let c = |i: usize| self.frames[i].points[b].confidence;
                c(i0).min(c(i1))
            })
            .collect();
        cs.iter().sum::<f32>() / cs.len().max(1) as f32
    }
}

/// Angles without their jumps of a full turn.
fn unwrapped(angles: &[f64]) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::with_capacity(angles.len());
    for &a in angles {
        let mut a = a;
        if let Some(&last) = out.last() {
            a = last + (a - last + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
        }
        out.push(a);
    }
    out
}

/// A series' periodicity: its period (frames), the autocorrelation there, and its standard
/// deviation.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Swing {
    period: usize,
    autocorr: f64,
    std_deg: f64,
}

/// The longest lag searched for the stride, as a share of the series: a lag leaves the rest of
/// the series to compare, so half a series (the usual bound) misses the period of a clip under
/// two strides long. run_side (171 frames at 120 frames/s, stride about 92 frames) had its
/// period cut to 84 frames at half, and copies half a stride off by 4 frames; at two thirds
/// it is found at 91 (suite PCK@0.2 with the copies of [`REPLACE_TORSO`]: 0.931 → 0.934,
/// run_side 0.882 → 0.907).
pub const MAX_LAG_SHARE: f64 = 2.0 / 3.0;

/// A later peak of the autocorrelation must beat the first by more than this to be taken for
/// the period: with lags up to [`MAX_LAG_SHARE`] a clip of several strides shows peaks at two
/// and three strides nearly as high as at one (treadmill_oblique: 1 s chosen over 3 s).
pub const LATER_PEAK_MARGIN: f64 = 0.1;

impl Swing {
    /// The period of a series: the first local peak of its normalised autocorrelation after
    /// its first negative lag that is within [`LATER_PEAK_MARGIN`] of the highest there (lags
    /// from `min_lag`, up to [`MAX_LAG_SHARE`] of the series and at most `max_lag`); `None` for
    /// a constant series or one that never turns negative there. Lags under `min_lag` (the
    /// shortest stride taken) are never the period: a wobble in the tracked angle peaked there
    /// first and cost the whole gait (run_side with `short_penalty` 10: the legs' period came
    /// out 0.16 s, outside [`PERIOD_S`]).
    fn of(series: &[f64], min_lag: usize, max_lag: usize) -> Option<Swing> {
        let n = series.len();
        let mean = series.iter().sum::<f64>() / n.max(1) as f64;
        let s: Vec<f64> = series.iter().map(|x| x - mean).collect();
        let var = s.iter().map(|x| x * x).sum::<f64>() / n.max(1) as f64;
        if var.is_nan() || var <= 0.0 {
            return None;
        }
        let ac = |lag: usize| {
            s[..n - lag]
                .iter()
                .zip(&s[lag..])
                .map(|(a, b)| a * b)
                .sum::<f64>()
                / (n - lag) as f64
                / var
        };
        let end = ((n as f64 * MAX_LAG_SHARE) as usize).min(max_lag + 1);
        let first_negative = (1..end).find(|&l| ac(l) < 0.0)?;
        // (lag, autocorrelation) from the first negative lag on.
        let curve: Vec<(usize, f64)> = (first_negative.max(min_lag)..end)
            .map(|l| (l, ac(l)))
            .collect();
        let highest = curve
            .iter()
            .map(|&(_, a)| a)
            .fold(f64::NEG_INFINITY, f64::max);
        // A local peak: no lower than its neighbours searched (the last lag has one).
        let peak = |i: usize| {
            let a = curve[i].1;
            (i == 0 || a >= curve[i - 1].1) && curve.get(i + 1).is_none_or(|next| a >= next.1)
        };
        let (period, autocorr) = (0..curve.len())
            .find(|&i| peak(i) && curve[i].1 >= highest - LATER_PEAK_MARGIN)
            .map(|i| curve[i])?;
        Some(Swing {
            period,
            autocorr,
            std_deg: var.sqrt().to_degrees(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::TrackedPoint;
    use crate::skeleton::PerJoint;
    use nalgebra::Point2;
    use std::f64::consts::TAU;

    const PERIOD: f64 = 30.0;

    fn video() -> SourceInfo {
        SourceInfo {
            path: "walk.mp4".into(),
            width: 200,
            height: 300,
            fps: 30.0,
            frame_count: 120,
        }
    }

    /// A side view's walker at 30 frames/s, torso 100 px: each limb swings with a period of 30
    /// frames, the right side half a period behind the left (`in_phase`: both sides together,
    /// mirrored, as in a jumping jack). The truth.
    fn walker(frames: usize, in_phase: bool, swing_deg: f64) -> Vec<FrameTracks> {
        (0..frames)
            .map(|t| {
                let mut pos = PerJoint::from_fn(|_| Point2::new(100.0, 100.0));
                pos[Joint::HeadTop] = Point2::new(100.0, 20.0);
                pos[Joint::Neck] = Point2::new(100.0, 50.0);
                pos[Joint::Chest] = Point2::new(100.0, 90.0);
                pos[Joint::Pelvis] = Point2::new(100.0, 150.0);
                for (left, sign) in [(true, 1.0), (false, -1.0)] {
                    let phase = if left || in_phase { 0.0 } else { PERIOD / 2.0 };
                    let s = (TAU * (t as f64 + phase) / PERIOD).sin();
                    let mirror = if in_phase && !left { -1.0 } else { 1.0 };
                    let side = |j: Joint| if left { j } else { j.mirrored() };
                    let at = |base: Point2<f64>, deg: f64, len: f64| {
                        let a = (90.0 + mirror * deg).to_radians();
                        base + nalgebra::Vector2::new(a.cos(), a.sin()) * len
                    };
                    let shoulder = Point2::new(100.0 + 2.0 * sign, 60.0);
                    let hip = Point2::new(100.0 + 3.0 * sign, 150.0);
                    let upper = swing_deg * s;
                    let elbow = at(shoulder, upper, 40.0);
                    let wrist = at(elbow, upper + 20.0 + 10.0 * s, 35.0);
                    let knee = at(hip, 0.8 * upper, 50.0);
                    let ankle = at(knee, 0.8 * upper - 15.0 - 15.0 * s, 50.0);
                    pos[side(Joint::LeftShoulder)] = shoulder;
                    pos[side(Joint::LeftElbow)] = elbow;
                    pos[side(Joint::LeftWrist)] = wrist;
                    pos[side(Joint::LeftHip)] = hip;
                    pos[side(Joint::LeftKnee)] = knee;
                    pos[side(Joint::LeftAnkle)] = ankle;
                }
                FrameTracks {
                    index: t,
                    points: pos.map(|_, &p| TrackedPoint {
                        pos: p,
                        confidence: 0.8,
                        source: PointSource::Tracked,
                    }),
                }
            })
            .collect()
    }

    /// The far (right) elbow, wrist, knee and ankle ride on the near limb's in the frames where
    /// the right arm swings forward: weak in even frames, confidently wrong in odd ones (where
    /// the limbs are well apart). The riding points are listed.
    fn hidden(truth: &[FrameTracks]) -> (Vec<FrameTracks>, Vec<(usize, Joint)>) {
        let mut tracked = truth.to_vec();
        let mut hid = Vec::new();
        for (t, f) in tracked.iter_mut().enumerate() {
            if (TAU * (t as f64 + PERIOD / 2.0) / PERIOD).sin() < 0.3 {
                continue;
            }
            for j in [
                Joint::RightElbow,
                Joint::RightWrist,
                Joint::RightKnee,
                Joint::RightAnkle,
            ] {
                let on_near = f.points[j.mirrored()].pos;
                // A confident point is replaced only when it is clearly off the stride.
                let off = (on_near - f.points[j].pos).norm() > (REPLACE_TORSO + 0.05) * 100.0;
                if t % 2 == 0 || off {
                    f.points[j].pos = on_near;
                    f.points[j].confidence = if t % 2 == 0 { 0.3 } else { 0.7 };
                    hid.push((t, j));
                }
            }
        }
        (tracked, hid)
    }

    fn err(a: &FrameTracks, b: &FrameTracks, j: Joint) -> f64 {
        (a.points[j].pos - b.points[j].pos).norm()
    }

    #[test]
    fn a_hidden_far_limb_is_completed_from_the_near_one_half_a_stride_away() {
        let truth = walker(120, false, 25.0);
        let (mut tracks, hid) = hidden(&truth);
        assert!(
            hid.iter().any(|&(t, _)| t % 2 == 1),
            "confidently wrong points"
        );
        let key = (hid[5].0, Joint::RightWrist);
        tracks[key.0].points[Joint::RightWrist].pos =
            truth[key.0].points[Joint::RightWrist].pos + nalgebra::Vector2::new(7.0, 0.0);
        let before = tracks.clone();
        let reports = complete_gaits(&mut tracks, &video(), &|t, j| (t, j) == key).limbs;
        for r in &reports {
            assert_eq!(r.donor, "left", "{r:?}");
            let period = r.period_s.expect("a period");
            assert!((period * 30.0 - PERIOD).abs() <= 1.0, "{r:?}");
            assert!(r.disagreement.is_some_and(|d| d < 0.02), "{r:?}");
        }
        let mut completed = 0;
        for &(t, j) in &hid {
            if (t, j) == key {
                assert_eq!(tracks[t].points[j], before[t].points[j], "the key is kept");
                continue;
            }
            let p = tracks[t].points[j];
            assert_eq!(p.source, PointSource::Gait, "frame {t} {j}");
            // Hung from the far limb's own joints: within a pixel of the truth.
            assert!(err(&tracks[t], &truth[t], j) < 1.0, "frame {t} {j}");
            completed += 1;
        }
        assert_eq!(
            reports.iter().map(|r| r.completed).sum::<usize>(),
            completed
        );
        // The clearly seen far joints and everything else are as tracked.
        for (t, f) in tracks.iter().enumerate() {
            for j in Joint::ALL {
                if !hid.contains(&(t, j)) {
                    assert_eq!(f.points[j], before[t].points[j], "frame {t} {j}");
                }
            }
        }
    }

    #[test]
    fn limbs_moving_together_or_not_swinging_are_left_alone() {
        for (in_phase, swing) in [(true, 25.0), (false, 2.0)] {
            let truth = walker(120, in_phase, swing);
            let (mut tracks, _) = hidden(&truth);
            let before = tracks.clone();
            let reports = complete_gaits(&mut tracks, &video(), &|_, _| false).limbs;
            assert_eq!(tracks, before, "in phase {in_phase}, swing {swing}°");
            assert!(reports.iter().all(|r| r.completed == 0), "{reports:?}");
            if in_phase {
                // A gait by its swing, refused by the check against the seen far limb.
                assert!(
                    reports
                        .iter()
                        .all(|r| r.disagreement.is_some_and(|d| d > MAX_DISAGREEMENT_TORSO)),
                    "{reports:?}"
                );
            }
        }
    }

    #[test]
    fn a_far_joint_seen_more_reliably_than_the_copy_is_kept() {
        let truth = walker(120, false, 25.0);
        let (mut tracks, hid) = hidden(&truth);
        let &(t, j) = hid.iter().find(|&&(t, _)| t % 2 == 1).unwrap();
        // The donor's joints at 0.75: a copy is trusted over 0.95 at most.
        for f in tracks.iter_mut() {
            for d in [
                Joint::LeftElbow,
                Joint::LeftWrist,
                Joint::LeftKnee,
                Joint::LeftAnkle,
            ] {
                f.points[d].confidence = 0.75;
            }
        }
        tracks[t].points[j].confidence = 0.97;
        let kept = tracks[t].points[j];
        complete_gaits(&mut tracks, &video(), &|_, _| false);
        assert_eq!(tracks[t].points[j], kept);
        tracks[t].points[j].confidence = 0.9;
        complete_gaits(&mut tracks, &video(), &|_, _| false);
        assert_eq!(tracks[t].points[j].source, PointSource::Gait);
    }

    #[test]
    fn off_frame_joints_are_never_moved() {
        let truth = walker(120, false, 25.0);
        let (mut tracks, hid) = hidden(&truth);
        let (t, j) = hid[0];
        tracks[t].points[j] = TrackedPoint {
            pos: Point2::new(-20.0, 100.0),
            confidence: 0.0,
            source: PointSource::OffFrame,
        };
        let kept = tracks[t].points[j];
        complete_gaits(&mut tracks, &video(), &|_, _| false);
        assert_eq!(tracks[t].points[j], kept);
    }

    #[test]
    fn a_copy_outside_the_frame_is_not_used() {
        let truth = walker(120, false, 25.0);
        let (mut tracks, hid) = hidden(&truth);
        // The frame ends at y = 219.5: the ankles' copies fall below it.
        let short = SourceInfo {
            height: 220,
            ..video()
        };
        complete_gaits(&mut tracks, &short, &|_, _| false);
        let mut kept = 0;
        for &(t, j) in &hid {
            let p = tracks[t].points[j];
            if p.source == PointSource::Gait {
                assert!(p.pos.y <= 219.5, "frame {t} {j}: {}", p.pos);
            } else {
                kept += 1;
            }
        }
        assert!(kept > 0);
    }

    #[test]
    fn the_swing_period_is_the_autocorrelation_peak() {
        let series: Vec<f64> = (0..150)
            .map(|t| (TAU * t as f64 / 37.0).sin() + 0.3 * (TAU * t as f64 / 12.0).cos())
            .collect();
        let s = Swing::of(&series, 0, 75).unwrap();
        assert!((36..=38).contains(&s.period), "{s:?}");
        assert!(s.autocorr > 0.8, "{s:?}");
        assert!(Swing::of(&[1.0; 50], 0, 75).is_none());
        // Lags capped below the period: no period found there.
        assert!(Swing::of(&series, 0, 20).is_none_or(|s| s.period <= 20));
        // A strong shorter swing (a wobbling track) peaks first; lags under the shortest
        // stride are not searched, so the stride is still found.
        let wobbly: Vec<f64> = (0..150)
            .map(|t| (TAU * t as f64 / 37.0).sin() + 3.0 * (TAU * t as f64 / 9.0).cos())
            .collect();
        assert!(Swing::of(&wobbly, 0, 75).is_some_and(|s| s.period < 20));
        let s = Swing::of(&wobbly, 20, 75).unwrap();
        assert!((36..=38).contains(&s.period), "{s:?}");
        // Angles across ±180° unwrap to one smooth series.
        let u = unwrapped(&[3.1, -3.1, -3.0, 3.0]);
        assert!(u.windows(2).all(|w| (w[1] - w[0]).abs() < 0.3), "{u:?}");
    }

    #[test]
    fn a_clip_under_two_strides_long_still_gives_the_stride() {
        // run_side's case: 171 frames, stride 92 frames (half the series would stop at 85).
        let stride = |t: usize| (TAU * t as f64 / 92.0).sin();
        let short: Vec<f64> = (0..171).map(stride).collect();
        let s = Swing::of(&short, 0, 300).unwrap();
        assert!((90..=94).contains(&s.period), "{s:?}");
        // Many strides: the first peak, not a later one nearly as high.
        let long: Vec<f64> = (0..120)
            .map(|t| (TAU * t as f64 / 30.0).sin() + 0.05 * ((t * 7919) % 13) as f64 / 13.0)
            .collect();
        let s = Swing::of(&long, 0, 300).unwrap();
        assert!((29..=31).contains(&s.period), "{s:?}");
    }
}
