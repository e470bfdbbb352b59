//! VBA's two passes over the clip: forwards from the first full key to the end, backwards from
//! the last key to the start, one after the other, or at once on the two threads when the
//! backward pass's frames are all kept from an earlier run (a re-track: `replay`).
//!
//! The backward pass starts from the forward pass's pose on the last key, so the two are
//! independent from there on: run at once, the backward pass waits for the forward pass to
//! reach the last key (on a re-track, where the forward pass is taken up from the earlier run,
//! at once) and each then runs on its own thread. Either way each pass computes the same
//! numbers in the same order: the tracks are the same, byte for byte.

use super::background::Background;
use super::body::JointResult;
use super::params::Tuning;
use super::pass::{PassContext, Scale};
use super::replay::{FrameStore, Recorded};
use super::shared::{TrackError, TrackProgress};
use crate::formats::{FrameIndex, KeyFrames};
use crate::skeleton::{Joint, PerJoint};
use crate::video::Video;
use image::RgbImage;
use nalgebra::Point2;
use rayon::ThreadPool;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::mpsc::sync_channel;
use std::sync::{Arc, Mutex};

/// Per frame, one pass's result in video pixels (`None` = not tracked).
pub(super) type PassResults = Vec<Option<PerJoint<JointResult>>>;
/// Where a pass arrived on the key frames it went through.
pub(super) type Arrivals = BTreeMap<usize, PerJoint<JointResult>>;
/// Per pass its results per frame and arrivals at keys, and the pass as it ran (`replay`).
pub(super) type RanPasses = ([PassResults; 2], [Arrivals; 2], [Option<Recorded>; 2]);

/// The pose a pass starts from on frame `f`: the forward pass's result there (`at`, or
/// `first_pose` at reliability 1 where it has none) with the hand-placed joints put in; and
/// that result, whose reliabilities the joints not placed there keep ([`keep_reliability`]).
fn starting(
    at: Option<PerJoint<JointResult>>,
    first_pose: &PerJoint<Point2<f64>>,
    keys: &KeyFrames,
    f: usize,
) -> (PerJoint<Point2<f64>>, PerJoint<JointResult>) {
    let base = at.unwrap_or_else(|| {
        first_pose.map(|_, p| JointResult {
            pos: *p,
            reliability: 1.0,
        })
    });
    (keyed(&base.map(|_, r| r.pos), keys, f), base)
}

/// A pass's result on its first frame `f` with the reliability `before` had for every joint
/// not placed there.
fn keep_reliability(
    now: &mut PerJoint<JointResult>,
    before: &PerJoint<JointResult>,
    keys: &KeyFrames,
    f: usize,
) {
    for j in Joint::ALL {
        if !keys.is_key(FrameIndex(f), j) {
            now[j].reliability = before[j].reliability;
        }
    }
}

/// The two passes: forwards from the first key frame `start` to the end, then backwards over
/// `backward_frames` (from the last key frame to the start), each re-started at every key frame
/// on the way; each pass starts from the pose on its first frame with the hand-placed joints
/// put in, the joints not placed there keeping the reliability they had. At once when
/// [`at_once`] can; on `pool` (its threads) when there is one.
pub(super) fn run_passes(
    ctx: &mut PassContext,
    pool: Option<&ThreadPool>,
    first_pose: &PerJoint<Point2<f64>>,
    (start, backward_frames): (usize, &[usize]),
    earlier: [Option<&Recorded>; 2],
) -> Result<RanPasses, TrackError> {
    let n = ctx.video.info().frame_count;
    let forward_frames: Vec<usize> = (start..n).collect();
    let orders: [&[usize]; 2] = [&forward_frames, backward_frames];
    let kept = |f: &usize| matches!(ctx.earlier_frames.get(*f), Some(Some(_)));
    if let Some(pool) = pool.filter(|_| ctx.threads >= 2)
        && !backward_frames.is_empty()
        && backward_frames.iter().all(kept)
        && let Some(mut second) = ctx.video.reopen(0)
    {
        return at_once(ctx, &mut second, pool, first_pose, orders, earlier);
    }
    let keys = ctx.keys;
    let mut results: [PassResults; 2] = [vec![None; n], vec![None; n]];
    let mut arrivals: [Arrivals; 2] = Default::default();
    let mut recorded: [Option<Recorded>; 2] = [None, None];
    for (k, order) in orders.into_iter().enumerate() {
        let Some(&first) = order.first() else {
            continue;
        };
        // Both passes start from the forward pass's pose there.
        let (pose, before) = starting(results[0][first], first_pose, keys, first);
        let (out, record) = match pool {
            Some(pool) => pool.install(|| ctx.pass(order, &pose, earlier[k]))?,
            None => ctx.pass(order, &pose, earlier[k])?,
        };
        recorded[k] = Some(record);
        for (f, r) in order.iter().zip(out.results) {
            results[k][*f] = Some(r);
        }
        arrivals[k].extend(out.arrivals);
        if let Some(now) = results[k][first].as_mut() {
            keep_reliability(now, &before, keys, first);
        }
    }
    Ok((results, arrivals, recorded))
}

/// [`run_passes`] with the two passes at once (see the module): the backward pass on a
/// second reader of the video (it reads none of its frames there: they are all kept), its
/// start taken from the forward pass's progress on the last key; the progress of both told in
/// the order the frames finish.
fn at_once(
    ctx: &mut PassContext,
    second: &mut Video,
    pool: &ThreadPool,
    first_pose: &PerJoint<Point2<f64>>,
    [forward_frames, backward_frames]: [&[usize]; 2],
    earlier: [Option<&Recorded>; 2],
) -> Result<RanPasses, TrackError> {
    let (n, keys, total) = (ctx.video.info().frame_count, ctx.keys, ctx.total);
    let like = ctx.like();
    let last_key = backward_frames[0];
    let told = Mutex::new((&mut *ctx.progress, ctx.done));
    let relay = |p: &TrackProgress| {
        if let Ok(mut told) = told.lock() {
            told.1 += 1;
            let done = told.1;
            (told.0)(&TrackProgress {
                done,
                total,
                frame: p.frame.clone(),
            });
        }
    };
    let (tx, rx) = sync_channel::<PerJoint<JointResult>>(1);
    let mut backward_progress = |p: &TrackProgress| relay(p);
    let mut backward = like.context(second, &mut backward_progress, FrameStore::new(n, &[]));
    let first = forward_frames[0];
    let (pose, before) = starting(None, first_pose, keys, first);
    let (forward_out, backward_out) = std::thread::scope(|s| {
        let backward = &mut backward;
        let back = s.spawn(move || {
            let at = rx.recv().map_err(|_| TrackError::Cancelled)?;
            let (pose, before) = starting(Some(at), first_pose, keys, last_key);
            let out = pool.install(|| backward.pass(backward_frames, &pose, earlier[1]))?;
            Ok::<_, TrackError>((out, before))
        });
        let forward = {
            // The forward pass's result on the last key, as it is told (in video pixels, its
            // reliability unchanged) is where the backward pass starts.
            let mut forward_progress = move |p: &TrackProgress| {
                if let Some(f) = p.frame.as_ref().filter(|f| f.index.get() == last_key) {
                    let _ = tx.try_send(f.points.map(|_, t| JointResult {
                        pos: t.pos,
                        reliability: t.confidence,
                    }));
                }
                relay(p);
            };
            let store = std::mem::replace(&mut ctx.store, FrameStore::new(0, &[]));
            let mut forward = like.context(ctx.video, &mut forward_progress, store);
            let out = pool.install(|| forward.pass(forward_frames, &pose, earlier[0]));
            (out, forward.damaged, forward.store)
        };
        (forward, back.join())
    });
    let (forward_out, damaged, store) = forward_out;
    let (mut forward_out, forward_record) = forward_out?;
    let ((backward_out, backward_record), back_before) =
        backward_out.map_err(|_| TrackError::Cancelled)??;
    ctx.store = store;
    ctx.damaged.extend(damaged);
    ctx.damaged.extend(std::mem::take(&mut backward.damaged));
    ctx.store.absorb(std::mem::replace(
        &mut backward.store,
        FrameStore::new(0, &[]),
    ));
    if let Ok((_, done)) = told.into_inner() {
        ctx.done = done;
    }
    let mut results: [PassResults; 2] = [vec![None; n], vec![None; n]];
    if let Some(r) = forward_out.results.first_mut() {
        keep_reliability(r, &before, keys, first);
    }
    let mut backward_results = backward_out.results;
    if let Some(r) = backward_results.first_mut() {
        keep_reliability(r, &back_before, keys, last_key);
    }
    for (k, (order, out)) in [
        (forward_frames, forward_out.results),
        (backward_frames, backward_results),
    ]
    .into_iter()
    .enumerate()
    {
        for (f, r) in order.iter().zip(out) {
            results[k][*f] = Some(r);
        }
    }
    let arrivals = [forward_out.arrivals, backward_out.arrivals];
    Ok((
        results,
        arrivals,
        [Some(forward_record), Some(backward_record)],
    ))
}

/// What two passes run at once share of a [`PassContext`] ([`PassContext::like`]).
pub(crate) struct Like<'a> {
    scale: Scale,
    params: Tuning,
    keys: &'a KeyFrames,
    path: PathBuf,
    size: (u32, u32),
    threads: usize,
    total: usize,
    cancel: &'a AtomicBool,
    background: Option<Arc<Background>>,
    earlier_frames: &'a [Option<Arc<RgbImage>>],
}

impl<'a> Like<'a> {
    /// A context like the one this came from, with its own reader of the video, progress and
    /// store of frames, and nothing done yet.
    pub(crate) fn context<'b, 'p>(
        &self,
        video: &'b mut Video,
        progress: &'p mut (dyn FnMut(&TrackProgress) + Send),
        store: FrameStore,
    ) -> PassContext<'b, 'p>
    where
        'a: 'b,
    {
        PassContext {
            video,
            scale: self.scale,
            params: self.params,
            keys: self.keys,
            path: self.path.clone(),
            width: self.size.0,
            height: self.size.1,
            threads: self.threads,
            damaged: Vec::new(),
            done: 0,
            total: self.total,
            progress,
            cancel: self.cancel,
            background: self.background.clone(),
            earlier_frames: self.earlier_frames,
            store,
        }
    }
}

impl<'a> PassContext<'a, '_> {
    /// What a pass run beside this context's shares with it ([`Like::context`]).
    pub(crate) fn like(&self) -> Like<'a> {
        Like {
            scale: self.scale,
            params: self.params,
            keys: self.keys,
            path: self.path.clone(),
            size: (self.width, self.height),
            threads: self.threads,
            total: self.total,
            cancel: self.cancel,
            background: self.background.clone(),
            earlier_frames: self.earlier_frames,
        }
    }
}

/// A pose with the joints placed by hand on frame `f` put in.
fn keyed(base: &PerJoint<Point2<f64>>, keys: &KeyFrames, f: usize) -> PerJoint<Point2<f64>> {
    match keys.frames.get(&FrameIndex(f)) {
        Some(k) => base.map(|j, p| k[j].unwrap_or(*p)),
        None => *base,
    }
}
