//! Forward and backward passes made one (beyond the paper): between two key frames of a joint,
//! the forward pass leaves the earlier key and the backward pass the later one.
//!
//! The forward pass holds, except where it demonstrably went astray: a forward pass that
//! arrives at the later key off it (the joint needed the correction) went astray after the last
//! frame where the two passes agreed, and those frames go to the backward pass, which came from
//! the correction, if it stayed sound all the way back to where it rejoined. A correction in the
//! middle of a bad run thus repairs the frames before it as well as after.
//!
//! Measured on `bench correct` (PCK@0.2 after corrections), where the simulated user corrects
//! the first frame that goes wrong, so the frames before a correction were right and the
//! backward pass can only spoil them: forward only dev 0.783, test 0.786; this rule dev 0.782,
//! test 0.790. Tried on dev and dropped: the more reliable pass in each run of disagreement
//! 0.753, the pass whose key is nearer 0.755, the forward pass but where it is weak 0.767 (the
//! reliabilities of two passes on one frame do not tell which went astray); every frame after
//! the last agreement without the soundness check, test 0.776.

use super::body::JointResult;
use crate::formats::KeyFrames;
use crate::skeleton::{Joint, PerJoint};
use std::collections::BTreeMap;
use std::ops::Range;

/// One pass's result per frame (`None` where it did not run).
pub(crate) type PassResults = [Option<PerJoint<JointResult>>];

/// Where a pass arrived on the key frames it went through, before the keys re-started it.
pub(crate) type Arrivals = BTreeMap<usize, PerJoint<JointResult>>;

/// Passes within this of each other, in torsos, agree: both are right there.
pub(crate) const AGREE_TORSO: f64 = 0.1;

/// Fuses the forward and backward results over `range`: per joint and frame, one of the two
/// (the switch chosen per stretch between the joint's key frames), the one there is where only
/// one ran. Frames where neither ran stay `None`.
pub(crate) fn fuse(
    [forward, backward]: [&PassResults; 2],
    [forward_arrived, backward_arrived]: [&Arrivals; 2],
    keys: &KeyFrames,
    range: Range<usize>,
    torso_px: f64,
    weak: f32,
) -> Vec<Option<PerJoint<JointResult>>> {
    let mut out: Vec<Option<PerJoint<JointResult>>> =
        range.clone().map(|f| forward[f].or(backward[f])).collect();
    let torso = torso_px.max(1.0);
    for j in Joint::ALL {
        let key_frames: Vec<usize> = keys
            .frames
            .iter()
            .filter(|(_, k)| k[j].is_some())
            .map(|(&f, _)| f.get())
            .collect();
        for f in range.clone() {
            // Before the joint's first key only the backward pass is anchored; after its last,
            // only the forward one.
            let pick = match (forward[f], backward[f]) {
                (Some(a), Some(b)) => {
                    let before_first = key_frames.first().is_none_or(|&k| f < k);
                    let after_last = key_frames.last().is_none_or(|&k| f > k);
                    if before_first {
                        b[j]
                    } else if after_last {
                        a[j]
                    } else {
                        continue;
                    }
                }
                (Some(a), None) => a[j],
                (None, Some(b)) => b[j],
                (None, None) => continue,
            };
            if let Some(o) = out[f - range.start].as_mut() {
                o[j] = pick;
            }
        }
        for w in key_frames.windows(2) {
            let stretch = w[0].max(range.start)..(w[1] + 1).min(range.end);
            if stretch.len() < 2 {
                continue;
            }
            let mut both: Option<Vec<(JointResult, JointResult)>> = stretch
                .clone()
                .map(|f| Some((forward[f]?[j], backward[f]?[j])))
                .collect();
            // At each end the pass that arrived there, as it arrived (before the key put it
            // right): whether it agrees with the key it ran towards.
            if let Some(pairs) = both.as_mut() {
                if let (Some(p), Some(b), true) = (
                    pairs.first_mut(),
                    backward_arrived.get(&w[0]),
                    stretch.start == w[0],
                ) {
                    p.1 = b[j];
                }
                if let (Some(p), Some(f), true) = (
                    pairs.last_mut(),
                    forward_arrived.get(&w[1]),
                    stretch.end == w[1] + 1,
                ) {
                    p.0 = f[j];
                }
            }
            let picks = match both {
                Some(pairs) => fuse_stretch(&pairs, torso, weak),
                // A stretch the passes cover in part: the more reliable one per frame.
                None => stretch
                    .clone()
                    .filter_map(|f| match (forward[f], backward[f]) {
                        (Some(a), Some(b)) if b[j].reliability > a[j].reliability => Some(b[j]),
                        (Some(a), _) => Some(a[j]),
                        (None, b) => b.map(|b| b[j]),
                    })
                    .collect(),
            };
            for (f, r) in stretch.zip(picks) {
                if let Some(o) = out[f - range.start].as_mut() {
                    o[j] = r;
                }
            }
        }
    }
    out
}

/// One stretch's (forward, backward) pairs made one. The passes agree where they are within
/// [`AGREE_TORSO`] of each other. The forward pass holds (it left the earlier key, and the user
/// saw it up to the later one) except where it demonstrably went astray: when it arrives at
/// the later key off it, the frames after the last agreement go to the backward pass, if that
/// pass stayed sound (reliability at least `weak`) from the key back to where it rejoined the
/// forward pass. A backward pass that never rejoins, or weakens before it does, may itself have
/// lost the joint next to the correction: the forward pass keeps those frames.
fn fuse_stretch(pairs: &[(JointResult, JointResult)], torso: f64, weak: f32) -> Vec<JointResult> {
    let agree = |(a, b): &(JointResult, JointResult)| (a.pos - b.pos).norm() <= AGREE_TORSO * torso;
    let take_backward_after = pairs
        .iter()
        .rposition(agree)
        .filter(|&last| pairs[last + 1..].iter().all(|p| p.1.reliability >= weak));
    pairs
        .iter()
        .enumerate()
        .map(|(f, (a, b))| match take_backward_after {
            Some(last) if f > last => *b,
            _ => *a,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::FrameIndex;
    use nalgebra::Point2;

    fn at(x: f64, reliability: f32) -> PerJoint<JointResult> {
        PerJoint::from_fn(|_| JointResult {
            pos: Point2::new(x, 0.0),
            reliability,
        })
    }

    fn keys_at(frames: &[usize]) -> KeyFrames {
        let mut keys = KeyFrames::default();
        for &f in frames {
            for j in Joint::ALL {
                keys.set(FrameIndex(f), j, Point2::new(0.0, 0.0));
            }
        }
        keys
    }

    /// The forward pass strays at frame 6 and stays astray (still claiming to be sure); the
    /// backward pass is right all along. The frames from 6 on go to the backward pass.
    #[test]
    fn a_pass_that_strays_loses_the_frames_after_it_strayed() {
        let n = 12;
        let forward: Vec<_> = (0..n)
            .map(|f| Some(at(if f < 6 { 0.0 } else { 80.0 }, 0.9)))
            .collect();
        let backward: Vec<_> = (0..n).map(|_| Some(at(1.0, 0.8))).collect();
        let fused = fuse(
            [&forward, &backward],
            [&Arrivals::new(), &Arrivals::new()],
            &keys_at(&[0, n - 1]),
            0..n,
            100.0,
            0.5,
        );
        for (f, r) in fused.iter().enumerate() {
            let x = r.expect("fused")[Joint::LeftWrist].pos.x;
            assert!(x < 2.0, "frame {f} took the stray pass ({x})");
        }
    }

    /// Both passes stray in the middle of a stretch, in turn: the forward one is right up to
    /// frame 4, the backward one from frame 4 back; the fused track is right everywhere, and frames
    /// after the last key (only the forward pass) and before the first (only the backward one)
    /// take the pass that ran.
    #[test]
    fn each_pass_keeps_the_half_next_to_its_key() {
        let n = 10;
        let forward: Vec<_> = (0..n)
            .map(|f| (f >= 2).then(|| at(if f <= 4 || f == 9 { 0.0 } else { 60.0 }, 0.9)))
            .collect();
        let backward: Vec<_> = (0..n)
            .map(|f| (f <= 8).then(|| at(if (2..4).contains(&f) { -60.0 } else { 0.0 }, 0.9)))
            .collect();
        let fused = fuse(
            [&forward, &backward],
            [&Arrivals::new(), &Arrivals::new()],
            &keys_at(&[2, 8]),
            0..n,
            100.0,
            0.5,
        );
        for (f, r) in fused.iter().enumerate() {
            let x = r.expect("fused")[Joint::Neck].pos.x;
            assert!(x.abs() < 1e-9, "frame {f}: {x}");
        }
    }
}
