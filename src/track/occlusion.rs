//! Occlusion handling (Pan et al., end of "Trunk and Limb"): a run of low-reliability frames
//! between reliable ones is filled by linear interpolation of the joint; longer runs, and runs
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
    /// Left as tracked and reported: too long to interpolate, or not bounded by reliable frames.
    Weak,
    /// The joint is off the frame somewhere in the run: left as the tracker estimated it.
    OffFrame,
}

impl fmt::Display for SpanKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SpanKind::Interpolated => "interpolated",
            SpanKind::Weak => "weak",
            SpanKind::OffFrame => "off frame",
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

/// Fills short weak runs by interpolation, marks the rest lost, and lists every weak run.
/// `frames` must hold consecutive frame indices; `is_key(frame position, joint)` marks
/// hand-placed joints.
pub fn fill_weak_runs(
    frames: &mut [FrameTracks],
    weak: f32,
    max_gap: usize,
    is_key: &dyn Fn(usize, Joint) -> bool,
) -> Vec<WeakSpan> {
    let n = frames.len();
    for joint in Joint::ALL {
        let weak_runs = runs(n, |i| {
            is_key(i, joint) || frames[i].points[joint].confidence >= weak
        });
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
/// holds a lost (or, in files without states, a weak tracked) point, interpolated otherwise.
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
}
