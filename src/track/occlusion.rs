//! Occlusion handling (Pan et al., end of "Trunk and Limb"): a run of low-reliability frames
//! between reliable ones is filled by linear interpolation of the joint, unless its track moves
//! like the joint around it (kept, still weak: `KEEP_STEP_FACTOR`); longer runs, and runs
//! with no reliable frame on one side, are reported as weak spans and never silently filled.
//! Runs in which the joint leaves the image are reported as off-frame spans and never filled:
//! a straight line between the exit and the re-entry would draw the joint inside the frame.
//! The points of runs left weak are marked lost, so the tracks alone (a saved file, a project,
//! an undone edit) give the same spans again ([`weak_spans`]).
//! Key frames (hand-placed joints) always count as reliable anchors.

use crate::formats::{FrameTracks, PointSource};
use crate::skeleton::Joint;
use serde::Serialize;
use std::fmt;

/// What happened to a run of weak frames of one joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpanKind {
    /// Filled by linear interpolation between the reliable frames around it.
    Interpolated,
    /// Left as tracked and reported: too long to interpolate, not bounded by reliable frames,
    /// or moving like the joint around it.
    Weak,
    /// The joint is off the frame somewhere in the run: left as the tracker estimated it.
    OffFrame,
    /// Completed from the gait somewhere in the run (a hidden far limb, [`super::gait`]),
    /// nowhere lost or left weak.
    Gait,
}

impl fmt::Display for SpanKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SpanKind::Interpolated => "interpolated",
            SpanKind::Weak => "weak",
            SpanKind::OffFrame => "off frame",
            SpanKind::Gait => "from the gait",
        })
    }
}

/// A run of consecutive weak frames of one joint.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WeakSpan {
    /// The joint's name.
    pub joint: &'static str,
    /// First frame of the run.
    pub start: usize,
    /// Last frame of the run (inclusive).
    pub end: usize,
    /// Interpolated or left weak.
    pub kind: SpanKind,
    /// Lowest reliability in the run.
    pub min_reliability: f32,
}

/// The runs `(first, last)` (positions in `frames`) of consecutive frames that are not
/// `reliable`.
fn runs(n: usize, reliable: impl Fn(usize) -> bool) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        if reliable(i) {
            i += 1;
            continue;
        }
        let start = i;
        while i < n && !reliable(i) {
            i += 1;
        }
        out.push((start, i - 1));
    }
    out
}

/// Beyond the paper: a weak run whose track moves like the joint around it is kept as tracked
/// (still weak, still reported), not interpolated: no step of it, from the reliable frame
/// before to the one after, is longer than this many times the joint's speed at the run's ends
/// (the faster end, at least [`KEEP_FLOOR_TORSO`]). A tracker that lost its joint jumps to what
/// it locked on; a low score alone (a sleeve seen against a new background) does not mean the
/// joint is lost, and a straight line cuts off a round trip: a jumping jack's raised elbow,
/// tracked within 6 px at reliability 0.40, was drawn 67 px off by the line. `bench track`'s
/// suite: PCK@0.2 0.886 → 0.888, lost 3.8 → 3.6 % (jumping jacks 0.973 → 1.000; never
/// interpolating at all: 0.886). Factors 1, 2, 3 gave 0.886, 0.888, 0.888 (measured before
/// the end speeds were restricted to reliable frames, when 1.5 gave 0.889).
const KEEP_STEP_FACTOR: f64 = 1.5;

/// The least speed [`KEEP_STEP_FACTOR`] scales, in torso lengths (neck to pelvis) per frame.
const KEEP_FLOOR_TORSO: f64 = 0.02;

/// The median image distance from neck to pelvis over the frames, pixels.
fn median_torso(frames: &[FrameTracks]) -> f64 {
    let mut d: Vec<f64> = frames
        .iter()
        .map(FrameTracks::torso_px)
        .filter(|d| d.is_finite())
        .collect();
    d.sort_by(f64::total_cmp);
    d.get(d.len() / 2).copied().unwrap_or(0.0)
}

/// Whether the weak run `start..=end` of `joint` (bounded by reliable frames) moves like the
/// joint at its ends ([`KEEP_STEP_FACTOR`]) and was tracked in every frame (none held).
fn moves_with_its_anchors(
    frames: &[FrameTracks],
    joint: Joint,
    start: usize,
    end: usize,
    floor: f64,
    reliable: &[bool],
) -> bool {
    // A part held at its last angle (a match refused, reliability 0) is not a track.
    if frames[start..=end]
        .iter()
        .any(|f| f.points[joint].confidence <= 0.0)
    {
        return false;
    }
    let pos = |i: usize| frames[i].points[joint].pos;
    let step = |i: usize| (pos(i + 1) - pos(i)).norm();
    // Speeds between reliable frames only: a neighbouring weak run's jump is no speed.
    let before = if start >= 2 && reliable[start - 2] {
        step(start - 2)
    } else {
        0.0
    };
    let after = if end + 2 < frames.len() && reliable[end + 2] {
        step(end + 1)
    } else {
        0.0
    };
    let limit = KEEP_STEP_FACTOR * before.max(after).max(floor);
    (start - 1..=end).all(|i| step(i) <= limit)
}

/// Twin joints closer than this, in torso lengths (neck to pelvis, median over the clip), are
/// on one spot for [`weaken_merged_twins`]. On treadmill_raised each knee is hidden behind the
/// other leg for part of every stride, and its track rides on the other knee a median 0.10
/// torso off it (0.08 at the lower quartile), which 0.05 did not catch. The suite of `bench
/// track` at 0.05 / 0.1 / 0.12 / 0.13 / 0.15 / 0.17 / 0.2 / 0.25: 1609 / 1578 / 1546 / 1546 /
/// 1556 / 1740 / 1764 / 2041 misses at PCK@0.2 (of 24208 joint-frames), treadmill_raised
/// 0.893 → 0.925 at 0.12; from 0.17 run_side's swinging legs, which pass close by each other,
/// lose their tracked crossings (0.908 → 0.846).
pub const MERGE_TORSO: f64 = 0.12;

/// Frames before and after a merge begins over which each twin's velocity is measured.
const FOLLOW_FRAMES: usize = 3;

/// The least change of velocity, torso lengths per frame, that marks a twin as the follower:
/// two joints resting together (a side view's feet side by side) change nothing. At 0.02 the
/// suite lost 2.16 % of joint-frames unflagged, at 0.01 1.94 %.
pub const FOLLOW_FLOOR_TORSO: f64 = 0.01;

/// The left joints whose right twins ([`Joint::mirrored`]) a tracker can confuse with them
/// where the limbs overlap.
const TWINS: [Joint; 4] = [
    Joint::LeftElbow,
    Joint::LeftWrist,
    Joint::LeftKnee,
    Joint::LeftAnkle,
];

/// Beyond the paper: a block that followed its twin. Twin joints (left and right elbows,
/// wrists, knees, ankles) tracked within [`MERGE_TORSO`] of each other for at least
/// `min_frames` consecutive frames: limbs cross in a few frames, so a longer merge means one
/// block rides on the other (a side view's far leg on the near one), confidently wrong. The
/// twin whose velocity changed more when they met (by at least [`FOLLOW_FLOOR_TORSO`]) is the
/// follower; its confidence is capped at half of `weak` over the merge, so that
/// [`fill_weak_runs`] interpolates or reports it. Merges present from the first frame (the
/// marks put the joints together) and frames with a key or an off-frame twin are left alone,
/// and so are frames before `fresh` (a re-track keeps them as the user saw them, though a
/// merge that runs on past the corrected frame is found over all of it).
pub fn weaken_merged_twins(
    frames: &mut [FrameTracks],
    weak: f32,
    min_frames: usize,
    fresh: usize,
    is_key: &dyn Fn(usize, Joint) -> bool,
) {
    let torso = median_torso(frames);
    for (a, b) in TWINS.map(|j| (j, j.mirrored())) {
        let merged: Vec<bool> = frames
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let (p, q) = (f.points[a], f.points[b]);
                !is_key(i, a)
                    && !is_key(i, b)
                    && p.source == PointSource::Tracked
                    && q.source == PointSource::Tracked
                    && (p.pos - q.pos).norm() <= MERGE_TORSO * torso
            })
            .collect();
        for (start, end) in runs(frames.len(), |i| !merged[i]) {
            let k = FOLLOW_FRAMES.min(start).min(end - start);
            if end + 1 - start < min_frames || k == 0 {
                continue;
            }
            let turn = |j: Joint| {
                let pos = |i: usize| frames[i].points[j].pos;
                let before = (pos(start) - pos(start - k)) / k as f64;
                let inside = (pos(start + k) - pos(start)) / k as f64;
                (inside - before).norm()
            };
            let (ta, tb) = (turn(a), turn(b));
            if ta.max(tb) < FOLLOW_FLOOR_TORSO * torso {
                continue;
            }
            let follower = if ta >= tb { a } else { b };
            for f in frames[..=end].iter_mut().skip(start.max(fresh)) {
                let c = &mut f.points[follower].confidence;
                *c = c.min(weak * 0.5);
            }
        }
    }
}

/// Fills short weak runs by interpolation (keeping those that move like the joint around
/// them), marks the rest lost, and lists every weak run.
/// `frames` must hold consecutive frame indices; `is_key(frame position, joint)` marks
/// hand-placed joints.
pub fn fill_weak_runs(
    frames: &mut [FrameTracks],
    weak: f32,
    max_gap: usize,
    is_key: &dyn Fn(usize, Joint) -> bool,
) -> Vec<WeakSpan> {
    let n = frames.len();
    let floor = KEEP_FLOOR_TORSO * median_torso(frames);
    for joint in Joint::ALL {
        let reliable: Vec<bool> = (0..n)
            .map(|i| is_key(i, joint) || frames[i].points[joint].confidence >= weak)
            .collect();
        let weak_runs = runs(n, |i| reliable[i]);
        for (start, end) in weak_runs {
            let run = &mut frames[start..=end];
            if run
                .iter()
                .any(|f| f.points[joint].source == PointSource::OffFrame)
            {
                continue;
            }
            let len = end - start + 1;
            if start > 0 && end + 1 < n && len <= max_gap {
                if moves_with_its_anchors(frames, joint, start, end, floor, &reliable) {
                    continue;
                }
                let a = frames[start - 1].points[joint].pos;
                let b = frames[end + 1].points[joint].pos;
                for (k, f) in frames[start..=end].iter_mut().enumerate() {
                    let t = (k + 1) as f64 / (len + 1) as f64;
                    let p = &mut f.points[joint];
                    p.pos = a + (b - a) * t;
                    p.source = PointSource::Interpolated;
                }
            } else {
                for f in run {
                    f.points[joint].source = PointSource::Lost;
                }
            }
        }
    }
    weak_spans(frames, weak, is_key)
}

/// Lists every weak run of tracks as [`fill_weak_runs`] left them (or as read from a file):
/// consecutive frames of a joint that are not key frames and not tracked with reliability at
/// least `weak`. A run is off the frame when the joint leaves the image in it, weak when it
/// holds a lost (or, in files without states, a weak tracked) point, from the gait when it
/// holds a point completed from the gait, interpolated otherwise.
pub fn weak_spans(
    frames: &[FrameTracks],
    weak: f32,
    is_key: &dyn Fn(usize, Joint) -> bool,
) -> Vec<WeakSpan> {
    let mut spans = Vec::new();
    for joint in Joint::ALL {
        let weak_runs = runs(frames.len(), |i| {
            let p = frames[i].points[joint];
            is_key(i, joint) || (p.source == PointSource::Tracked && p.confidence >= weak)
        });
        for (start, end) in weak_runs {
            let run = &frames[start..=end];
            let has = |source| run.iter().any(|f| f.points[joint].source == source);
            let kind = if has(PointSource::OffFrame) {
                SpanKind::OffFrame
            } else if has(PointSource::Lost) || has(PointSource::Tracked) {
                SpanKind::Weak
            } else if has(PointSource::Gait) {
                SpanKind::Gait
            } else {
                SpanKind::Interpolated
            };
            spans.push(WeakSpan {
                joint: joint.name(),
                start: run[0].index,
                end: run[run.len() - 1].index,
                kind,
                min_reliability: run
                    .iter()
                    .map(|f| f.points[joint].confidence)
                    .fold(f32::INFINITY, f32::min),
            });
        }
    }
    spans.sort_by_key(|s| (s.start, s.joint));
    spans
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::TrackedPoint;
    use crate::skeleton::PerJoint;
    use nalgebra::Point2;

    fn frames(conf: &[f32]) -> Vec<FrameTracks> {
        conf.iter()
            .enumerate()
            .map(|(i, &c)| FrameTracks {
                index: i,
                points: PerJoint::from_fn(|_| TrackedPoint {
                    pos: Point2::new(i as f64 * 10.0 + if c < 0.5 { 100.0 } else { 0.0 }, 0.0),
                    confidence: c,
                    source: PointSource::Tracked,
                }),
            })
            .collect()
    }

    #[test]
    fn a_short_bounded_run_is_interpolated_and_a_long_one_reported() {
        let mut f = frames(&[0.9, 0.9, 0.1, 0.2, 0.9, 0.1, 0.1, 0.1, 0.1, 0.9]);
        let spans = fill_weak_runs(&mut f, 0.5, 3, &|_, _| false);
        let head: Vec<_> = spans.iter().filter(|s| s.joint == "head_top").collect();
        assert_eq!(head.len(), 2);
        assert_eq!(
            (head[0].start, head[0].end, head[0].kind),
            (2, 3, SpanKind::Interpolated)
        );
        assert_eq!(
            (head[1].start, head[1].end, head[1].kind),
            (5, 8, SpanKind::Weak)
        );
        // Interpolated on the line between frames 1 and 4 (x = 10 … 40).
        assert!((f[2].points[Joint::HeadTop].pos.x - 20.0).abs() < 1e-9);
        assert!((f[3].points[Joint::HeadTop].pos.x - 30.0).abs() < 1e-9);
        assert_eq!(f[3].points[Joint::Neck].source, PointSource::Interpolated);
        // The long run keeps its tracked (wrong) positions, marked lost.
        assert_eq!(f[6].points[Joint::HeadTop].source, PointSource::Lost);
        assert_eq!(f[6].points[Joint::HeadTop].pos.x, 160.0);
        // The tracks alone give the same spans.
        assert_eq!(weak_spans(&f, 0.5, &|_, _| false), spans);
    }

    #[test]
    fn a_weak_run_that_moves_like_its_joint_is_kept_and_a_jump_is_filled() {
        // A round trip out and back (an arm raised and lowered), tracked weakly but smoothly:
        // a straight line between frames 2 and 6 would cut it off.
        let xs = [0.0, 10.0, 20.0, 28.0, 32.0, 28.0, 20.0, 10.0, 0.0];
        let conf = [0.9, 0.9, 0.9, 0.3, 0.3, 0.3, 0.9, 0.9, 0.9];
        let make = |xs: &[f64]| {
            let mut f = frames(&conf);
            for (f, &x) in f.iter_mut().zip(xs) {
                for j in Joint::ALL {
                    f.points[j].pos = Point2::new(x, 0.0);
                }
                // A torso of 100 px: the least speed counted is 2 px per frame.
                f.points[Joint::Pelvis].pos.y = 100.0;
            }
            f
        };
        let mut f = make(&xs);
        let spans = fill_weak_runs(&mut f, 0.5, 5, &|_, _| false);
        let p = f[4].points[Joint::LeftWrist];
        assert_eq!((p.pos.x, p.source), (32.0, PointSource::Tracked));
        let wrist: Vec<_> = spans.iter().filter(|s| s.joint == "left_wrist").collect();
        assert_eq!(
            (wrist[0].start, wrist[0].end, wrist[0].kind),
            (3, 5, SpanKind::Weak)
        );
        assert_eq!(weak_spans(&f, 0.5, &|_, _| false), spans);
        // The same run jumping 60 px away and back (a lock on something else) is filled.
        let mut jumpy = xs;
        jumpy[3..6].iter_mut().for_each(|x| *x += 60.0);
        let mut f = make(&jumpy);
        fill_weak_runs(&mut f, 0.5, 5, &|_, _| false);
        let p = f[4].points[Joint::LeftWrist];
        assert_eq!((p.pos.x, p.source), (20.0, PointSource::Interpolated));
        // A part held at its last angle (reliability 0) inside the run is filled too.
        let mut f = make(&xs);
        f[4].points[Joint::LeftWrist].confidence = 0.0;
        fill_weak_runs(&mut f, 0.5, 5, &|_, _| false);
        assert_eq!(
            f[4].points[Joint::LeftWrist].source,
            PointSource::Interpolated
        );
    }

    #[test]
    fn a_run_that_leaves_the_frame_is_never_filled() {
        // A short bounded run, which would be interpolated, but the joint is off the frame in
        // its middle frame: the whole run stays as the tracker left it.
        let mut f = frames(&[0.9, 0.2, 0.0, 0.2, 0.9]);
        f[2].points[Joint::LeftWrist].source = PointSource::OffFrame;
        let before: Vec<_> = f.iter().map(|f| f.points[Joint::LeftWrist]).collect();
        let spans = fill_weak_runs(&mut f, 0.5, 10, &|_, _| false);
        let wrist: Vec<_> = spans.iter().filter(|s| s.joint == "left_wrist").collect();
        assert_eq!(wrist.len(), 1);
        assert_eq!(
            (wrist[0].start, wrist[0].end, wrist[0].kind),
            (1, 3, SpanKind::OffFrame)
        );
        let after: Vec<_> = f.iter().map(|f| f.points[Joint::LeftWrist]).collect();
        assert_eq!(before, after);
        // The other joints' identical runs are filled as usual.
        assert_eq!(
            f[2].points[Joint::RightWrist].source,
            PointSource::Interpolated
        );
    }

    #[test]
    fn runs_at_the_ends_are_never_filled_and_key_frames_anchor() {
        let mut f = frames(&[0.1, 0.9, 0.9, 0.1]);
        let spans = fill_weak_runs(&mut f, 0.5, 10, &|_, _| false);
        assert!(spans.iter().all(|s| s.kind == SpanKind::Weak));
        let mut f = frames(&[0.9, 0.1, 0.1]);
        let spans = fill_weak_runs(&mut f, 0.5, 10, &|i, _| i == 2);
        assert!(
            spans
                .iter()
                .all(|s| s.kind == SpanKind::Interpolated && s.end == 1)
        );
    }

    /// Frames with a torso of 100 px (neck at 0, pelvis at 100) and the ankles at the given x.
    fn ankles(left: &[f64], right: &[f64]) -> Vec<FrameTracks> {
        let mut f = frames(&vec![0.9; left.len()]);
        for (f, (&l, &r)) in f.iter_mut().zip(left.iter().zip(right)) {
            for j in Joint::ALL {
                f.points[j].pos = Point2::new(0.0, 0.0);
            }
            f.points[Joint::Pelvis].pos.y = 100.0;
            f.points[Joint::LeftAnkle].pos.x = l;
            f.points[Joint::RightAnkle].pos.x = r;
        }
        f
    }

    fn confidences(f: &[FrameTracks], j: Joint) -> Vec<f32> {
        f.iter().map(|f| f.points[j].confidence).collect()
    }

    /// The left ankle walks on at 10 px a frame; the right one comes the other way, meets it
    /// at frame 4 and, lost, rides along with it, `beside` px off, for six frames.
    fn riding(beside: f64) -> (Vec<f64>, Vec<f64>) {
        let left: Vec<f64> = (0..10).map(|i| 10.0 * i as f64).collect();
        let right = (0..10)
            .map(|i| {
                if i < 4 {
                    80.0 - 10.0 * i as f64
                } else {
                    left[i] + beside
                }
            })
            .collect();
        (left, right)
    }

    #[test]
    fn a_joint_riding_on_its_twin_is_made_weak_and_a_crossing_is_not() {
        let (left, right) = riding(0.0);
        let mut f = ankles(&left, &right);
        weaken_merged_twins(&mut f, 0.5, 4, 0, &|_, _| false);
        assert!(confidences(&f, Joint::LeftAnkle).iter().all(|&c| c == 0.9));
        let right_conf = confidences(&f, Joint::RightAnkle);
        assert!(right_conf[..4].iter().all(|&c| c == 0.9), "{right_conf:?}");
        assert!(right_conf[4..].iter().all(|&c| c == 0.25), "{right_conf:?}");
        // Shorter than four frames together: a crossing, left alone.
        let mut f = ankles(&left[..7], &right[..7]);
        weaken_merged_twins(&mut f, 0.5, 4, 0, &|_, _| false);
        assert!(confidences(&f, Joint::RightAnkle).iter().all(|&c| c == 0.9));
        // A key frame inside the merge splits it into runs too short to count.
        let mut f = ankles(&left, &right);
        weaken_merged_twins(&mut f, 0.5, 4, 0, &|i, _| i == 6);
        assert!(confidences(&f, Joint::RightAnkle).iter().all(|&c| c == 0.9));
        // A re-track from frame 5 keeps frames 0 to 5 as they were; the merge is still found.
        let mut f = ankles(&left, &right);
        weaken_merged_twins(&mut f, 0.5, 4, 6, &|_, _| false);
        let right_conf = confidences(&f, Joint::RightAnkle);
        assert!(right_conf[..6].iter().all(|&c| c == 0.9), "{right_conf:?}");
        assert!(right_conf[6..].iter().all(|&c| c == 0.25), "{right_conf:?}");
    }

    #[test]
    fn a_joint_riding_beside_its_twin_is_made_weak() {
        // The lost right ankle rides 10 px (a tenth of the torso) beside the left one: it
        // follows it, though never onto the same spot.
        let (left, right) = riding(10.0);
        let mut f = ankles(&left, &right);
        weaken_merged_twins(&mut f, 0.5, 4, 0, &|_, _| false);
        let right_conf = confidences(&f, Joint::RightAnkle);
        assert!(right_conf[4..].iter().all(|&c| c == 0.25), "{right_conf:?}");
        assert!(confidences(&f, Joint::LeftAnkle).iter().all(|&c| c == 0.9));
    }

    #[test]
    fn twins_resting_together_are_left_alone() {
        // Feet side by side from the marks on, or still when they meet: nothing followed.
        let still = [50.0; 10];
        let mut f = ankles(&still, &still);
        weaken_merged_twins(&mut f, 0.5, 4, 0, &|_, _| false);
        let mut g = ankles(
            &still,
            &[52.0, 52.0, 60.0, 60.0, 51.0, 51.0, 51.0, 51.0, 51.0, 51.0],
        );
        weaken_merged_twins(&mut g, 0.5, 4, 0, &|_, _| false);
        for f in [&f, &g] {
            for j in [Joint::LeftAnkle, Joint::RightAnkle] {
                assert!(confidences(f, j).iter().all(|&c| c == 0.9));
            }
        }
    }
}
