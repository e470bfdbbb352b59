//! Tracking a whole video: the passes over the frames, key frames, and the result.
//!
//! One function shows the order ([`track_video`]): a forward pass from the first key frame (the
//! marks) to the end, then a backward pass from the last key frame to the start, each re-started
//! with the hand-placed joints at every key frame on the way (`pass`); the two made one
//! per joint between its key frames (`fuse`); the pose network's evidence weighed in
//! (`evidence`, unless turned off); then short weak runs interpolated with key
//! frames as anchors ([`super::occlusion`]), never runs that leave the frame, and the tracks
//! smoothed when asked. A
//! joint that ends up outside the image is off the frame (confidence 0, its position the
//! tracker's estimate).
//!
//! Tracking is a function of the video, the keys and the settings (issue 90): nothing an
//! earlier run left changes the result. What an earlier run of the same video computed is only
//! a cache of values that depend on nothing else (the background; the network's output for a
//! frame and a crop exactly as it was).

use super::ahead::{merged, run_ahead};
use super::background::KnownBackground;
use super::body::{JointResult, stature_px};
use super::chain::run_network;
use super::evidence::{EvidenceParams, NetFrame, NetworkFrames, flag_jumps, weigh};
use super::fuse::fuse;
use super::occlusion::{WeakSpan, fill_weak_runs, weak_spans};
use super::params::TrackerParams;
use super::pass::{PassContext, Scale};
use super::passes::{Arrivals, PassResults, run_passes};
use super::replay::{FrameStore, PassesSeen, SeenRun};
use super::shared::{TrackError, TrackProgress};
use super::smooth::smooth_tracks;
use crate::camera::point_in_frame;
pub use crate::formats::KeyFrames;
use crate::formats::{FrameIndex, FrameTracks, PointSource, SourceInfo, TrackedPoint, Tracks2d};
use crate::network::PoseNetwork;
use crate::skeleton::{Joint, PerJoint, Proportions};
use crate::video::{Video, VideoInfo};
use nalgebra::Point2;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// The frame cache of the network's own reader of the video (it reads each frame once, in
/// order).
const AHEAD_CACHE_BYTES: usize = 0;

/// What to track.
#[derive(Debug, Clone)]
pub struct TrackJob {
    /// The marks and corrections.
    pub keys: KeyFrames,
    /// Settings.
    pub params: TrackerParams,
    /// Worker threads (1 = decode and track on the calling thread, limbs in sequence).
    pub threads: usize,
    /// The background an earlier run of this video found ([`TrackOutput::background`]): used
    /// when it fits (same working size and threshold) instead of reading the clip again.
    pub background: Option<KnownBackground>,
    /// The pose network whose evidence is weighed in (`None`, or the setting `network` off:
    /// VBA alone).
    pub network: Option<Arc<PoseNetwork>>,
    /// What the network saw in an earlier run of this video ([`TrackOutput::network`]): a
    /// frame whose crop is exactly the one it had then is not run again (a cache: the result is
    /// the same with or without it).
    pub previous_network: Option<NetworkFrames>,
    /// What VBA's passes computed in an earlier run of this video ([`TrackOutput::passes`]):
    /// a pass's frames before the first whose keys changed are not tracked again, nor its
    /// frames decoded again (a cache: the result is the same with or without it).
    pub previous_passes: Option<PassesSeen>,
}

impl TrackJob {
    /// A whole-video job from the marks of one frame (no corrections, no earlier result).
    pub fn from_marks(
        marks: &crate::formats::Marks,
        params: TrackerParams,
        threads: usize,
    ) -> TrackJob {
        TrackJob {
            keys: KeyFrames::from_marks(marks),
            params,
            threads,
            background: None,
            network: None,
            previous_network: None,
            previous_passes: None,
        }
    }

    /// This job with the pose network's evidence weighed in.
    pub fn with_network(mut self, network: Option<Arc<PoseNetwork>>) -> TrackJob {
        self.network = network;
        self
    }
}

/// The result: tracks and the report of weak spans.
#[derive(Debug, Clone)]
pub struct TrackOutput {
    /// Tracks of every frame.
    pub tracks: Tracks2d,
    /// Every run of weak frames per joint, interpolated or left weak.
    pub spans: Vec<WeakSpan>,
    /// The shrink factor of the working scale: video pixels per tracker pixel (1 = full size).
    pub shrink: f64,
    /// Frames the decoder could not read (damaged or cut-short files), ascending. They are
    /// tracked as lost (reliability 0) and filled like occlusions, not fatal.
    pub damaged: Vec<usize>,
    /// The background this run used (`None` when the settings use none): give it to the next
    /// job on this video ([`TrackJob::background`]).
    pub background: Option<KnownBackground>,
    /// What the pose network saw on each frame (`None`: tracked with VBA alone): give it to
    /// the next job on this video ([`TrackJob::previous_network`]).
    pub network: Option<NetworkFrames>,
    /// What VBA's passes computed (`None` when a frame could not be decoded): give it to the
    /// next job on this video ([`TrackJob::previous_passes`]).
    pub passes: Option<PassesSeen>,
}

/// Tracks the video from its key frames.
///
/// When the person is taller than the working stature, `decoder_scaling` is on and the backend
/// can scale while it converts pixels, the video delivers working-size frames during tracking (at 1080×1920 that
/// costs less than converting at full size and shrinking) and full-size ones again afterwards.
pub fn track_video(
    video: &mut Video,
    job: &TrackJob,
    progress: &mut (dyn FnMut(&TrackProgress) + Send),
    cancel: &AtomicBool,
) -> Result<TrackOutput, TrackError> {
    job.params.validate()?;
    let info = video.info().clone();
    let network = job.network.as_deref().filter(|_| job.params.network);
    // 1. VBA's passes, forwards and backwards, made one per joint; meanwhile the network runs
    // ahead on its own reader of the video where it needs nothing of VBA.
    let (passes, ahead) = passes_with_network_ahead(video, &info, job, network, progress, cancel);
    if (video.info().width, video.info().height) != (info.width, info.height) {
        // Back to the size the caller had (full size unless it shrank the video itself).
        video.output_size(Some((info.width, info.height)));
    }
    let Passes {
        mut tracks,
        mut done,
        total,
        shrink,
        damaged,
        background,
        seen,
    } = passes?;
    // 2. The network's evidence weighed in, the user's marks deciding whose body it is.
    let net = match network {
        Some(network) => {
            let cached = ahead.map(|a| merged(a, job.previous_network.as_ref()));
            let reuse = cached.as_ref().or(job.previous_network.as_ref());
            let mut tick = || {
                done += 1;
                progress(&TrackProgress {
                    done,
                    total,
                    frame: None,
                });
            };
            let net = run_network(video, &tracks, network, &job.keys, reuse, &mut tick, cancel)?;
            tracks = weigh(&tracks, &net, &job.keys, &EvidenceParams::default());
            Some(net)
        }
        None => None,
    };
    // 3.–5. Weak runs filled, smoothing, jumps shown weak.
    let mut frames = tracks.frames;
    let spans = finish_frames(&mut frames, job, info.fps, net.is_some());
    Ok(TrackOutput {
        damaged,
        background,
        tracks: Tracks2d {
            source: tracks.source,
            frames,
        },
        spans,
        shrink,
        network: net,
        passes: seen,
    })
}

/// [`track_video`]'s first step: VBA's passes ([`track_at_working_scale`]) while the network
/// runs ahead on its own reader of the video where it needs nothing of VBA (`ahead`: a cache
/// for the second step, the result the same without it). Only with a second thread to run on:
/// a job given one CPU (a batch task on one core) stays on one thread
/// (`tests/batch_threads.rs`). A worker that panicked leaves no cache: the network's frames
/// are run in the second step.
fn passes_with_network_ahead(
    video: &mut Video,
    info: &VideoInfo,
    job: &TrackJob,
    network: Option<&PoseNetwork>,
    progress: &mut (dyn FnMut(&TrackProgress) + Send),
    cancel: &AtomicBool,
) -> (Result<Passes, TrackError>, Option<Vec<Option<NetFrame>>>) {
    let reader = network
        .filter(|_| job.threads >= 2)
        .and_then(|_| video.reopen(AHEAD_CACHE_BYTES));
    let stop = AtomicBool::new(false);
    std::thread::scope(|s| {
        let stop = &stop;
        let worker = network.zip(reader).map(|(net, mut reader)| {
            let previous = job.previous_network.as_ref();
            s.spawn(move || run_ahead(&mut reader, net, &job.keys, previous, stop, cancel))
        });
        let passes = track_at_working_scale(video, info, job, network.is_some(), progress, cancel);
        if passes.is_err() {
            stop.store(true, Ordering::Relaxed);
        }
        (passes, worker.and_then(|w| w.join().ok()))
    })
}

/// [`track_video`]'s last steps on the weighed `frames`: short weak runs interpolated and long
/// ones reported (3), the tracks smoothed when asked, the filled runs with the rest (4), and
/// with the network (`with_network`) a joint that jumps shown weak where it is, for review
/// (5). Returns the weak runs to report.
fn finish_frames(
    frames: &mut [FrameTracks],
    job: &TrackJob,
    fps: f64,
    with_network: bool,
) -> Vec<WeakSpan> {
    let max_gap = (job.params.max_gap_s * fps).round().max(1.0) as usize;
    let is_key = |f: FrameIndex, j: Joint| job.keys.is_key(f, j);
    let spans = fill_weak_runs(frames, job.params.weak_reliability, max_gap, &is_key);
    smooth_tracks(frames, job.params.smooth_s * fps, 0, &is_key);
    if with_network {
        flag_jumps(frames, &job.keys);
        weak_spans(frames, job.params.weak_reliability, &is_key)
    } else {
        spans
    }
}

/// VBA's result before the network, the filling of weak runs and smoothing.
struct Passes {
    /// Every frame's joints in video pixels (key frames' joints as placed).
    tracks: Tracks2d,
    /// Progress so far, and in all (the network's frames included).
    done: usize,
    total: usize,
    shrink: f64,
    damaged: Vec<usize>,
    background: Option<KnownBackground>,
    seen: Option<PassesSeen>,
}

/// The shrink factor that brings the marked person to the working stature (1 when they are no
/// taller), and the frame size it gives. Any factor, not only whole ones: a whole factor halved
/// a person just over the working stature and left one just under it at full size.
fn working_scale(
    job: &TrackJob,
    pose: &PerJoint<Point2<f64>>,
    width: u32,
    height: u32,
) -> (f64, (u32, u32)) {
    let working = job.params.working_stature_px;
    let shrink = stature_px(pose, &Proportions::default()) / working;
    // A working stature of 0 or less (or a person of no size) keeps the full size.
    if !(working > 0.0 && shrink.is_finite() && shrink > 1.0) {
        return (1.0, (width, height));
    }
    let side = |full: u32| ((f64::from(full) / shrink).round() as u32).clamp(2, full.max(2));
    (shrink, (side(width), side(height)))
}

/// Where tracking starts: the first key frame with all 16 joints and its pose, after checking
/// the video is long enough and every key frame lies in it.
fn checked_start(
    info: &VideoInfo,
    job: &TrackJob,
) -> Result<(usize, PerJoint<Point2<f64>>), TrackError> {
    let n = info.frame_count;
    if n < 2 {
        return Err(TrackError::TooShort {
            path: info.path.clone(),
            frames: n,
        });
    }
    if let Some((&frame, _)) = job.keys.frames.range(FrameIndex(n)..).next() {
        return Err(TrackError::KeyFrameOutOfRange {
            path: info.path.clone(),
            frame: frame.get(),
            frames: n,
        });
    }
    let (first_key, first_pose) = job.keys.first_full().ok_or(TrackError::NoFullKeyFrame)?;
    // The tracker works in video positions, which are frame numbers.
    Ok((first_key.get(), first_pose))
}

/// The fused results as tracks in video pixels: a key's joints as placed (confidence 1), a
/// joint outside the image off the frame (confidence 0), a frame no pass reached at the first
/// key's pose with confidence 0.
fn frames_of(
    raw: Vec<Option<PerJoint<JointResult>>>,
    first_pose: &PerJoint<Point2<f64>>,
    job: &TrackJob,
    info: &VideoInfo,
) -> Vec<FrameTracks> {
    raw.into_iter()
        .enumerate()
        .map(|(index, r)| FrameTracks {
            index: FrameIndex(index),
            body3d: None,
            points: r
                .unwrap_or_else(|| {
                    first_pose.map(|_, p| JointResult {
                        pos: *p,
                        reliability: 0.0,
                    })
                })
                .map(|j, r| {
                    let key = job.keys.frames.get(&FrameIndex(index)).and_then(|k| k[j]);
                    let pos = key.unwrap_or(r.pos);
                    if key.is_some() {
                        TrackedPoint {
                            pos,
                            confidence: 1.0,
                            source: PointSource::Tracked,
                        }
                    } else if point_in_frame(&pos, info.width, info.height) {
                        TrackedPoint {
                            pos,
                            confidence: r.reliability,
                            source: PointSource::Tracked,
                        }
                    } else {
                        TrackedPoint {
                            pos,
                            confidence: 0.0,
                            source: PointSource::OffFrame,
                        }
                    }
                }),
        })
        .collect()
}

/// [`track_video`]'s passes, with the video's full-size info; `network`: the network's frames
/// are counted in the progress's total. The steps: where to start, the working scale, the
/// background, the two passes, their fusion, the tracks.
fn track_at_working_scale(
    video: &mut Video,
    info: &VideoInfo,
    job: &TrackJob,
    network: bool,
    progress: &mut (dyn FnMut(&TrackProgress) + Send),
    cancel: &AtomicBool,
) -> Result<Passes, TrackError> {
    let n = info.frame_count;
    let (start, first_pose) = checked_start(info, job)?;
    let (shrink, (ww, wh)) = working_scale(job, &first_pose, info.width, info.height);
    let scale = Scale {
        sx: f64::from(info.width) / f64::from(ww),
        sy: f64::from(info.height) / f64::from(wh),
        width: ww,
        height: wh,
    };
    // Frames come out at the working size if the backend can make them so (at 1080×1920
    // converting at that size is cheaper than converting at full size and shrinking); not when
    // the video's frames are already decoded in its cache, which the change would empty.
    let decoded = if shrink > 1.0 && video.cached_bytes() == 0 && video.output_size(Some((ww, wh)))
    {
        (ww, wh)
    } else {
        (info.width, info.height)
    };
    let params = job.params.tuning(info.fps, job.threads);
    let backward_frames = backward_order(job, start);
    let work = (scale.width, scale.height, scale.sx, scale.sy);
    let run = SeenRun::new(info.path.clone(), n, params, work, decoded);
    let earlier = job.previous_passes.as_ref().and_then(|p| p.for_run(&run));
    let (earlier_frames, earlier_passes) = earlier.unwrap_or((&[], [None, None]));
    let mut ctx = PassContext {
        video,
        scale,
        params,
        keys: &job.keys,
        path: info.path.clone(),
        width: decoded.0,
        height: decoded.1,
        threads: job.threads,
        damaged: Vec::new(),
        done: 0,
        total: (n - start) + backward_frames.len() + if network { n } else { 0 },
        progress,
        cancel,
        background: None,
        earlier_frames,
        store: FrameStore::new(n, earlier_frames),
    };
    let background = with_background(&mut ctx, job, (ww, wh), n)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(job.threads.max(1))
        .build()
        .ok();
    let orders = (start, backward_frames.as_slice());
    let (results, arrivals, recorded) =
        run_passes(&mut ctx, pool.as_ref(), &first_pose, orders, earlier_passes)?;
    let tracks = fused(&results, &arrivals, &first_pose, job, info);
    let mut damaged = std::mem::take(&mut ctx.damaged);
    damaged.sort_unstable();
    damaged.dedup();
    // A damaged frame's pass results are not kept: a re-track would not know it was damaged.
    let seen = damaged
        .is_empty()
        .then(|| PassesSeen::new(run, ctx.store.into_frames(), recorded));
    Ok(Passes {
        tracks,
        done: ctx.done,
        total: ctx.total,
        shrink,
        damaged,
        background,
        seen,
    })
}

/// Each joint's frames from the pass that holds there (`fuse`), as tracks of the whole clip.
fn fused(
    results: &[PassResults; 2],
    arrivals: &[Arrivals; 2],
    first_pose: &PerJoint<Point2<f64>>,
    job: &TrackJob,
    info: &VideoInfo,
) -> Tracks2d {
    let n = info.frame_count;
    let torso_px = (first_pose[Joint::Neck] - first_pose[Joint::Pelvis]).norm();
    let raw = fuse(
        [&results[0], &results[1]],
        [&arrivals[0], &arrivals[1]],
        &job.keys,
        0..n,
        torso_px,
        job.params.weak_reliability,
    );
    let frames = frames_of(raw, first_pose, job, info);
    let source = SourceInfo {
        path: info.path.clone(),
        width: info.width,
        height: info.height,
        fps: info.fps,
        frame_count: n,
    };
    Tracks2d { source, frames }
}

/// The backward pass's frames: from the last key frame down to the start of the clip (none
/// when the last key is the first frame; `start` when there is no key).
fn backward_order(job: &TrackJob, start: usize) -> Vec<usize> {
    let last_key = job
        .keys
        .frames
        .keys()
        .next_back()
        .map_or(start, |k| k.get());
    if last_key > 0 {
        (0..=last_key).rev().collect()
    } else {
        Vec::new()
    }
}

/// The static camera's background for the passes (`ctx.background`), at the working `size`:
/// none when the arms' foreground lane is off, the job's known one when it fits, else
/// estimated from the clip's `n` frames. Returns it to hand to the next job.
fn with_background(
    ctx: &mut PassContext<'_, '_>,
    job: &TrackJob,
    size: (u32, u32),
    n: usize,
) -> Result<Option<KnownBackground>, TrackError> {
    let tau = ctx.params.foreground_tau;
    let known = job.background.as_ref().and_then(|k| k.get(size, tau));
    ctx.background = match known {
        _ if job.params.arm_foreground <= 0.0 => None,
        Some(known) => known,
        None => ctx.estimate_background(n, tau)?.map(Arc::new),
    };
    Ok((job.params.arm_foreground > 0.0)
        .then(|| KnownBackground::new(size, tau, ctx.background.clone())))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(working_stature_px: f64) -> TrackJob {
        TrackJob {
            keys: KeyFrames::default(),
            params: TrackerParams {
                working_stature_px,
                ..TrackerParams::default()
            },
            threads: 1,
            background: None,
            network: None,
            previous_network: None,
            previous_passes: None,
        }
    }

    /// A person a tenth over the working stature is shrunk by 1.1, not halved; one under it,
    /// or any person when the working stature is 0 or less, is tracked at full size.
    #[test]
    fn the_working_scale_brings_the_person_to_the_working_stature() {
        let pose = PerJoint::from_fn(|j| {
            let k = j.index() as f64;
            Point2::new(300.0 + 7.0 * k, 200.0 + 45.0 * k)
        });
        let stature = stature_px(&pose, &Proportions::default());
        let (shrink, size) = working_scale(&job(stature / 1.1), &pose, 1080, 1920);
        assert!((shrink - 1.1).abs() < 1e-9, "shrink {shrink}");
        assert_eq!(size, (982, 1745));
        for working in [stature * 1.5, 0.0, -1.0] {
            assert_eq!(
                working_scale(&job(working), &pose, 1080, 1920),
                (1.0, (1080, 1920)),
                "working stature {working}"
            );
        }
    }
}
