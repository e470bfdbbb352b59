//! The pose network run ahead of VBA's passes (issue 95): on a worker thread with its own reader
//! of the video, while the passes run, so that both cores are busy.
//!
//! [`super::evidence::run_network`] crops each frame where the network proposed on the frame
//! before, and from VBA's body only on a full key frame (where that body is the user's marks),
//! after a frame where the network found nobody, or where a partial key refuses the network's
//! body. So from every full key frame on, the network's chain needs nothing of VBA until one of
//! the last two happens: those frames can be run before VBA's passes end. The worker runs them
//! and stops each chain where it would need VBA, going on from the next full key frame.
//!
//! It leaves out the frames the chain's rule leaves out (`chain::may_skip`, which reads only the
//! network's output, so it skips what `run_network` skips; a pelvis or head-top key there is
//! looked at and its crop passed on, as `run_network` does), and once the chain is
//! done runs the skipped frames the network's own checks send back to it
//! (`chain::needs_network` without VBA), while VBA may still be running.
//!
//! What it finds is only a cache for `run_network` (a frame is taken from it when its crop is
//! exactly the one `run_network` makes there, the network's output depending on nothing else):
//! the result is the same whether the worker got far, not far, or did not run at all, however
//! the threads were scheduled.

use super::chain::{SkipRule, looked_at, may_skip, needs_network, skipped};
use super::evidence::{NetFrame, NetworkFrames, look, refuses};
use crate::formats::{FrameIndex, KeyFrames};
use crate::network::{Crop, PoseNetwork};
use crate::video::Video;
use nalgebra::Point2;
use std::sync::atomic::{AtomicBool, Ordering};

/// The frames the network's chain reaches from the full key frames without VBA's body (`None`
/// elsewhere), each frame's crop made exactly as [`super::evidence::run_network`] makes it;
/// frames of `previous` (an earlier run on this video) with the same crop are taken from it.
/// Stops early, with what it has, when `stop` or `cancel` is set.
pub(crate) fn run_ahead(
    video: &mut Video,
    network: &PoseNetwork,
    keys: &KeyFrames,
    previous: Option<&NetworkFrames>,
    stop: &AtomicBool,
    cancel: &AtomicBool,
) -> Vec<Option<NetFrame>> {
    let n = video.info().frame_count;
    let previous = previous.filter(|p| p.len() == n);
    let rule = SkipRule::default();
    let mut out: Vec<Option<NetFrame>> = vec![None; n];
    let mut left_out = vec![false; n];
    // The crop the chain proposes for frame `t` (`None`: no chain runs there).
    let mut next: Option<Crop> = None;
    let halted = || stop.load(Ordering::Relaxed) || cancel.load(Ordering::Relaxed);
    for t in 0..n {
        if halted() {
            break;
        }
        let key = keys.frames.get(&FrameIndex(t));
        // A full key's crop: VBA's body there is the marks themselves.
        let full = key.is_some_and(|k| k.iter().all(|(_, p)| p.is_some()));
        let leave =
            next.is_some() && !full && may_skip(&rule, n, t, &left_out, |s| out[s].as_ref());
        if leave && !looked_at(keys, t) {
            out[t] = Some(skipped(next));
            left_out[t] = true;
            continue;
        }
        let marks = key
            .filter(|_| full)
            .map(|k| k.map(|_, p| p.unwrap_or(Point2::origin())));
        let crop = match (&marks, next) {
            (Some(m), _) => Crop::around(m),
            (None, Some(c)) => Some(c),
            // The chain needs VBA's body here: it waits for the next full key.
            (None, None) => continue,
        };
        let mut frame = look(video, network, t, crop, previous);
        if marks.is_none() && key.is_some_and(|k| refuses(k, &frame)) {
            // `run_network` looks again with VBA's body here: leave it the frame.
            next = None;
            continue;
        }
        if leave {
            // As `run_network`: a key on a frame the chain leaves out passes its crop on.
            frame.next = crop;
            left_out[t] = true;
        }
        next = frame.next;
        out[t] = Some(frame);
    }
    // The skipped frames the network's own checks send back to it.
    for t in 1..n.saturating_sub(1) {
        let Some(crop) = out[t].as_ref().filter(|f| f.skipped).map(|f| f.crop) else {
            continue;
        };
        if halted() {
            break;
        }
        if out[t + 1].is_some()
            && needs_network(&rule, out[t - 1].as_ref(), out[t + 1].as_ref(), None)
        {
            out[t] = Some(look(video, network, t, crop, previous));
        }
    }
    out
}

/// The cache `run_network` reads: the worker's frames where it has them, else an earlier run's
/// (`previous`), else an empty frame (no crop, so never taken).
pub(crate) fn merged(
    ahead: Vec<Option<NetFrame>>,
    previous: Option<&NetworkFrames>,
) -> NetworkFrames {
    let n = ahead.len();
    let previous = previous.filter(|p| p.len() == n);
    ahead
        .into_iter()
        .enumerate()
        .map(|(t, a)| {
            a.or_else(|| previous.and_then(|p| p.get(t).cloned()))
                .unwrap_or(NetFrame {
                    crop: None,
                    joints: None,
                    next: None,
                    world: None,
                    skipped: false,
                })
        })
        .collect()
}
