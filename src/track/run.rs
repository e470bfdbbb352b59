//! Tracking a whole video: the passes over the frames, key frames, and the result.
//!
//! From the first key frame (the marks) a forward pass runs to the end and a backward pass to
//! the start. Each later key frame (a frame where the user corrected joints) restarts the
//! forward pass there with the corrected pose and fresh key-frame colour models, and a backward
//! pass from it fills the weak frames before it, keeping for each joint and frame whichever pass
//! is more reliable. A joint that ends up outside the image is off the frame (confidence 0, its
//! position the tracker's estimate). Short weak runs are then interpolated with key frames as
//! anchors ([`super::occlusion`]), never runs that leave the frame. Frames are decoded (and shrunk to the working scale) on a separate
//! thread while the tracker works, unless one thread is asked for.

use super::background::{self, Background};
use super::body::{BodyTracker, JointResult, stature_px};
use super::gait::{GaitOutcome, complete_gaits};
use super::occlusion::{WeakSpan, fill_weak_runs, weak_spans, weaken_merged_twins};
use super::params::TrackerParams;
use super::smooth::smooth_tracks;
use crate::camera::point_in_frame;
use crate::formats::{FrameTracks, PointSource, SourceInfo, TrackedPoint, Tracks2d};
use crate::skeleton::{JOINT_COUNT, Joint, PerJoint, Proportions};
use crate::video::{Video, VideoError, VideoInfo};
use image::RgbImage;
use nalgebra::Point2;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Hand-placed joints per frame: the marks, and every correction made since.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KeyFrames {
    /// Per frame index, the joints placed by hand there.
    pub frames: BTreeMap<usize, PerJoint<Option<Point2<f64>>>>,
}

impl KeyFrames {
    /// Key frames from marks (all 16 joints on one frame).
    pub fn from_marks(marks: &crate::formats::Marks) -> KeyFrames {
        let mut frames = BTreeMap::new();
        frames.insert(marks.frame, marks.points.map(|_, p| Some(*p)));
        KeyFrames { frames }
    }

    /// Places one joint by hand on a frame (that frame becomes a key frame for the joint).
    pub fn set(&mut self, frame: usize, joint: Joint, pos: Point2<f64>) {
        self.frames
            .entry(frame)
            .or_insert_with(|| PerJoint([None; JOINT_COUNT]))[joint] = Some(pos);
    }

    /// Whether a joint was placed by hand on a frame.
    pub fn is_key(&self, frame: usize, joint: Joint) -> bool {
        self.frames
            .get(&frame)
            .is_some_and(|joints| joints[joint].is_some())
    }
}

/// Tracking could not run.
#[derive(Debug, thiserror::Error)]
pub enum TrackError {
    #[error(transparent)]
    Video(#[from] VideoError),
    #[error("{path}: has {frames} frame(s); tracking needs at least 2")]
    TooShort { path: PathBuf, frames: usize },
    #[error("no key frame with all 16 joints placed (mark the first frame fully)")]
    NoFullKeyFrame,
    #[error("key frame {frame} is past the end of {path} ({frames} frames)")]
    KeyFrameOutOfRange {
        path: PathBuf,
        frame: usize,
        frames: usize,
    },
    #[error("{path}: frame {frame} is {got_w}×{got_h} but the video is {width}×{height}")]
    FrameSize {
        path: PathBuf,
        frame: usize,
        got_w: u32,
        got_h: u32,
        width: u32,
        height: u32,
    },
    #[error("re-tracking from frame {frame} needs an earlier result that covers it")]
    NoEarlierResult { frame: usize },
    #[error("{path}: frame {frame}, where tracking starts, could not be decoded (damaged file?)")]
    StartFrameDamaged { path: PathBuf, frame: usize },
    #[error("tracker setting \"{name}\" must be {want}, got {value}")]
    BadSetting {
        name: &'static str,
        value: f64,
        want: &'static str,
    },
    #[error("cancelled")]
    Cancelled,
}

/// What to track.
#[derive(Debug, Clone)]
pub struct TrackJob {
    /// The marks and corrections.
    pub keys: KeyFrames,
    /// Settings.
    pub params: TrackerParams,
    /// Worker threads (1 = decode and track on the calling thread, limbs in sequence).
    pub threads: usize,
    /// Re-track from this frame on, keeping an earlier result before it (`None` = everything).
    pub from: Option<usize>,
    /// The earlier result (needed with `from`).
    pub previous: Option<Tracks2d>,
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
            from: None,
            previous: None,
        }
    }
}

/// Progress of a tracking run.
#[derive(Debug, Clone)]
pub struct TrackProgress {
    /// Frames processed so far (over all passes).
    pub done: usize,
    /// Frames to process in all (an estimate: backward gap passes are added as found).
    pub total: usize,
    /// The frame just tracked (for drawing results as they arrive).
    pub frame: Option<FrameTracks>,
}

/// The result: tracks and the report of weak spans.
#[derive(Debug, Clone)]
pub struct TrackOutput {
    /// Tracks of every frame.
    pub tracks: Tracks2d,
    /// Every run of weak frames per joint, interpolated, completed from the gait or left weak.
    pub spans: Vec<WeakSpan>,
    /// What gait completion found and did (nothing when it is off).
    pub gait: GaitOutcome,
    /// The shrink factor of the working scale: video pixels per tracker pixel (1 = full size).
    pub shrink: f64,
    /// Frames the decoder could not read (damaged or cut-short files), ascending. They are
    /// tracked as lost (reliability 0) and filled like occlusions, not fatal.
    pub damaged: Vec<usize>,
}

/// Converts between video pixels and the working scale (pixel centres at integers).
#[derive(Debug, Clone, Copy)]
struct Scale {
    sx: f64,
    sy: f64,
    width: u32,
    height: u32,
}

impl Scale {
    fn to_work(self, p: Point2<f64>) -> Point2<f64> {
        Point2::new((p.x + 0.5) / self.sx - 0.5, (p.y + 0.5) / self.sy - 0.5)
    }
    fn to_video(self, p: Point2<f64>) -> Point2<f64> {
        Point2::new((p.x + 0.5) * self.sx - 0.5, (p.y + 0.5) * self.sy - 0.5)
    }
    /// The frame at the working size: as it is when the decoder already shrank it, else
    /// averaged over boxes (`fast_image_resize`: a 1080×1920 frame in 1.6 ms, against 15 ms
    /// for `image`'s thumbnail, with the same pixels to a seventh of a level on average).
    fn shrink(&self, image: Arc<RgbImage>) -> Arc<RgbImage> {
        use fast_image_resize::{FilterType, ResizeAlg, ResizeOptions, Resizer};
        if self.width == image.width() && self.height == image.height() {
            return image;
        }
        let mut small = RgbImage::new(self.width, self.height);
        let options = ResizeOptions::new().resize_alg(ResizeAlg::Convolution(FilterType::Box));
        match Resizer::new().resize(&*image, &mut small, &options) {
            Ok(()) => Arc::new(small),
            // Not reached: both images are RGB8 and neither is empty.
            Err(_) => Arc::new(image::imageops::thumbnail(&*image, self.width, self.height)),
        }
    }
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
    let out = track_at_working_scale(video, &info, job, progress, cancel);
    if (video.info().width, video.info().height) != (info.width, info.height) {
        // Back to the size the caller had (full size unless it shrank the video itself).
        video.output_size(Some((info.width, info.height)));
    }
    out
}

/// The first key frame with all 16 joints, and its pose.
fn first_full_key(job: &TrackJob) -> Option<(usize, PerJoint<Point2<f64>>)> {
    job.keys.frames.iter().find_map(|(f, joints)| {
        let all: Option<Vec<Point2<f64>>> = joints.0.iter().copied().collect();
        all.map(|v| (*f, PerJoint::from_fn(|j| v[j.index()])))
    })
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

/// [`track_video`] with the video's full-size info.
fn track_at_working_scale(
    video: &mut Video,
    info: &VideoInfo,
    job: &TrackJob,
    progress: &mut (dyn FnMut(&TrackProgress) + Send),
    cancel: &AtomicBool,
) -> Result<TrackOutput, TrackError> {
    let n = info.frame_count;
    if n < 2 {
        return Err(TrackError::TooShort {
            path: info.path.clone(),
            frames: n,
        });
    }
    if let Some((&frame, _)) = job.keys.frames.range(n..).next() {
        return Err(TrackError::KeyFrameOutOfRange {
            path: info.path.clone(),
            frame,
            frames: n,
        });
    }
    let (first_key, first_pose) = first_full_key(job).ok_or(TrackError::NoFullKeyFrame)?;
    let (shrink, (ww, wh)) = working_scale(job, &first_pose, info.width, info.height);
    let scale = Scale {
        sx: f64::from(info.width) / f64::from(ww),
        sy: f64::from(info.height) / f64::from(wh),
        width: ww,
        height: wh,
    };
    // Frames come out at the working size if the backend can make them so.
    let decoded = if shrink > 1.0 && job.params.decoder_scaling && video.output_size(Some((ww, wh)))
    {
        (ww, wh)
    } else {
        (info.width, info.height)
    };
    let mut params = job.params.at_frame_rate(info.fps);
    params.parallel = params.parallel && job.threads > 1;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(job.threads.max(1))
        .build()
        .ok();

    // Per frame, the raw result in video pixels (None = not tracked yet).
    let mut raw: Vec<Option<PerJoint<JointResult>>> = vec![None; n];
    let start = match job.from {
        Some(from) => {
            let prev = job
                .previous
                .as_ref()
                .filter(|p| p.frames.len() == n && from < n)
                .ok_or(TrackError::NoEarlierResult { frame: from })?;
            // Up to and including the corrected frame: the re-track starts there from what the
            // user saw, with their corrections put in (not from the first key frame's pose).
            for f in &prev.frames[..=from] {
                raw[f.index] = Some(f.points.map(|_, p| JointResult {
                    pos: p.pos,
                    reliability: p.confidence,
                }));
            }
            from
        }
        None => first_key,
    };
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
        total: (n - start) + if job.from.is_none() { first_key } else { 0 },
        progress,
        cancel,
        background: None,
    };
    ctx.background = if job.params.arm_foreground > 0.0 {
        ctx.estimate_background(n, job.params.foreground_tau)?
            .map(Arc::new)
    } else {
        None
    };
    let start_pose = |raw: &[Option<PerJoint<JointResult>>], f: usize| -> PerJoint<Point2<f64>> {
        let base = raw[f].map(|r| r.map(|_, j| j.pos)).unwrap_or(first_pose);
        keyed(&base, &job.keys, f)
    };
    let run = |ctx: &mut PassContext, raw: &mut Vec<Option<PerJoint<JointResult>>>| {
        // Forward from the start to the end, re-keyed at every key frame on the way.
        let pose = if job.from.is_some() {
            start_pose(raw, start)
        } else {
            first_pose
        };
        let forward: Vec<usize> = (start..n).collect();
        // The earlier result on the start frame: its joints that were not corrected keep
        // their confidence (the pass vouches for its whole starting pose).
        let before = raw[start];
        let results = ctx.pass(&forward, &pose, true)?;
        for (f, r) in forward.iter().zip(results) {
            raw[*f] = Some(r);
        }
        if let (Some(before), Some(now)) = (before, raw[start].as_mut()) {
            for j in Joint::ALL {
                if !job.keys.is_key(start, j) {
                    now[j].reliability = before[j].reliability;
                }
            }
        }
        // Backward from the first key frame to the start.
        if job.from.is_none() && first_key > 0 {
            let backward: Vec<usize> = (0..=first_key).rev().collect();
            let results = ctx.pass(&backward, &first_pose, false)?;
            for (f, r) in backward.iter().zip(results).skip(1) {
                raw[*f] = Some(r);
            }
        }
        // Backward gap passes from each later key frame over the weak frames before it.
        let keys: Vec<usize> = job.keys.frames.keys().copied().collect();
        for w in keys.windows(2) {
            let (lo, hi) = (w[0], w[1]);
            if hi <= start.max(lo) {
                continue;
            }
            let weak_first = (lo + 1..hi).find(|&f| {
                raw[f].is_some_and(|r| {
                    r.0.iter()
                        .any(|j| j.reliability < ctx.params.weak_reliability)
                })
            });
            let Some(from) = weak_first else { continue };
            let backward: Vec<usize> = (from..=hi).rev().collect();
            ctx.total += backward.len();
            let pose = start_pose(raw, hi);
            let results = ctx.pass(&backward, &pose, false)?;
            for (f, r) in backward.iter().zip(results).skip(1) {
                if let Some(old) = raw[*f].as_mut() {
                    for j in Joint::ALL {
                        if r[j].reliability > old[j].reliability {
                            old[j] = r[j];
                        }
                    }
                }
            }
        }
        Ok::<(), TrackError>(())
    };
    match &pool {
        Some(pool) => pool.install(|| run(&mut ctx, &mut raw))?,
        None => run(&mut ctx, &mut raw)?,
    }

    let mut frames: Vec<FrameTracks> = raw
        .into_iter()
        .enumerate()
        .map(|(index, r)| FrameTracks {
            index,
            points: r
                .unwrap_or_else(|| {
                    first_pose.map(|_, p| JointResult {
                        pos: *p,
                        reliability: 0.0,
                    })
                })
                .map(|j, r| {
                    let key = job.keys.frames.get(&index).and_then(|k| k[j]);
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
        .collect();
    let max_gap = (job.params.max_gap_s * info.fps).round().max(1.0) as usize;
    if job.params.twin_merge_s > 0.0 {
        weaken_merged_twins(
            &mut frames,
            job.params.weak_reliability,
            (job.params.twin_merge_s * info.fps).round().max(2.0) as usize,
            job.from.map_or(0, |f| f + 1),
            &|i, j| job.keys.is_key(i, j),
        );
    }
    let is_key = |i: usize, j: Joint| job.keys.is_key(i, j);
    let mut spans = fill_weak_runs(&mut frames, job.params.weak_reliability, max_gap, &is_key);
    let source = SourceInfo {
        path: info.path.clone(),
        width: info.width,
        height: info.height,
        fps: info.fps,
        frame_count: n,
    };
    let gait = if job.params.gait_completion {
        complete_gaits(&mut frames, &source, &is_key)
    } else {
        GaitOutcome::default()
    };
    // Points completed from the gait change the weak runs they lay in.
    if gait.limbs.iter().any(|g| g.completed > 0) {
        spans = weak_spans(&frames, job.params.weak_reliability, &is_key);
    }
    // Smoothed last (when asked for): the filled runs and the gait's copies are smoothed with
    // the rest. A re-track smooths what it tracked; the earlier result before it was smoothed
    // already.
    let first = job.from.map_or(0, |f| f + 1);
    smooth_tracks(&mut frames, job.params.smooth_s * info.fps, first, &is_key);
    // The corrected frame's reliable joints stay as the user saw them: the side-on trunk's
    // shoulders and hips, set again above, would otherwise lose their smoothing there. (The
    // earlier result covers every frame and `from` lies in it: checked before tracking.)
    if let (Some(from), Some(prev)) = (job.from, job.previous.as_ref()) {
        for j in Joint::ALL {
            let was = prev.frames[from].points[j];
            if !job.keys.is_key(from, j) && was.confidence >= job.params.weak_reliability {
                frames[from].points[j] = was;
            }
        }
    }
    let mut damaged = std::mem::take(&mut ctx.damaged);
    damaged.sort_unstable();
    damaged.dedup();
    Ok(TrackOutput {
        damaged,
        tracks: Tracks2d { source, frames },
        spans,
        gait,
        shrink,
    })
}

/// A pose with the joints placed by hand on frame `f` put in.
fn keyed(base: &PerJoint<Point2<f64>>, keys: &KeyFrames, f: usize) -> PerJoint<Point2<f64>> {
    match keys.frames.get(&f) {
        Some(k) => base.map(|j, p| k[j].unwrap_or(*p)),
        None => *base,
    }
}

struct PassContext<'a, 'p> {
    video: &'a mut Video,
    scale: Scale,
    params: TrackerParams,
    keys: &'a KeyFrames,
    path: PathBuf,
    /// The size frames arrive at from the video (full or, when it scales, working size).
    width: u32,
    height: u32,
    threads: usize,
    /// Frames that could not be decoded so far.
    damaged: Vec<usize>,
    done: usize,
    total: usize,
    progress: &'p mut (dyn FnMut(&TrackProgress) + Send),
    cancel: &'a AtomicBool,
    /// The static camera's background at the working size, when there is one.
    background: Option<Arc<Background>>,
}

impl PassContext<'_, '_> {
    /// The static camera's background from [`background::SAMPLES`] frames spread over the
    /// clip's `n` frames, at the working size ([`Background::estimate`]; `None` for a moving
    /// camera). When the whole clip fits in the video's frame cache every frame is read, so
    /// that the passes find them there and the clip is decoded once (reading only the samples
    /// forwards decodes the frames between them all the same, and the first pass would then
    /// decode them again).
    fn estimate_background(
        &mut self,
        n: usize,
        tau: f32,
    ) -> Result<Option<Background>, TrackError> {
        let samples = background::sample_indices(n, background::SAMPLES);
        let read: Vec<usize> = if n <= self.video.cache_capacity_frames() {
            (0..n).collect()
        } else {
            samples.clone()
        };
        let mut images = Vec::with_capacity(samples.len());
        for index in read {
            if self.cancel.load(Ordering::Relaxed) {
                return Err(TrackError::Cancelled);
            }
            let Some(frame) = undamaged(self.video.frame(index))? else {
                continue;
            };
            if samples.binary_search(&index).is_ok()
                && (frame.image.width(), frame.image.height()) == (self.width, self.height)
            {
                images.push(self.scale.shrink(frame.image));
            }
        }
        let refs: Vec<&RgbImage> = images.iter().map(|i| i.as_ref()).collect();
        Ok(Background::estimate(&refs, tau))
    }
    /// Tracks over `order` (consecutive frames, forwards or backwards), starting from `pose` on
    /// its first frame; returns the results in video pixels, one per frame of `order` (the
    /// first is the starting pose). Forward passes re-key at key frames on the way.
    fn pass(
        &mut self,
        order: &[usize],
        pose: &PerJoint<Point2<f64>>,
        rekey: bool,
    ) -> Result<Vec<PerJoint<JointResult>>, TrackError> {
        let scale = self.scale;
        let params = self.params;
        let background = self.background.clone();
        let keys = self.keys;
        let cancel = self.cancel;
        let (path, width, height) = (self.path.clone(), self.width, self.height);
        let to_video = |r: PerJoint<JointResult>| {
            r.map(|_, j| JointResult {
                pos: scale.to_video(j.pos),
                reliability: j.reliability,
            })
        };
        let mut out = Vec::with_capacity(order.len());
        let mut tracker: Option<BodyTracker> = None;
        let proportions = Proportions::default();
        let check = |index: usize, image: &RgbImage| {
            if image.width() != width || image.height() != height {
                Err(TrackError::FrameSize {
                    path: path.clone(),
                    frame: index,
                    got_w: image.width(),
                    got_h: image.height(),
                    width,
                    height,
                })
            } else {
                Ok(())
            }
        };
        let mut handle = |ctx_done: &mut usize,
                          index: usize,
                          image: Option<Arc<RgbImage>>|
         -> Result<PerJoint<JointResult>, TrackError> {
            if cancel.load(Ordering::Relaxed) {
                return Err(TrackError::Cancelled);
            }
            let Some(image) = image else {
                // A damaged frame: the last pose, lost; the tracker waits for the next frame.
                let t = tracker
                    .as_ref()
                    .ok_or_else(|| TrackError::StartFrameDamaged {
                        path: path.clone(),
                        frame: index,
                    })?;
                *ctx_done += 1;
                return Ok(to_video(t.pose().map(|_, j| JointResult {
                    pos: j.pos,
                    reliability: 0.0,
                })));
            };
            let result = match tracker.as_mut() {
                None => {
                    let work = pose.map(|_, p| scale.to_work(*p));
                    let t =
                        BodyTracker::new(&image, &work, &proportions, params, background.clone());
                    let mut r = t.pose();
                    for j in Joint::ALL {
                        r[j].reliability = 1.0;
                    }
                    tracker = Some(t);
                    r
                }
                Some(t) => {
                    let mut r = t.step(&image);
                    if rekey && keys.frames.contains_key(&index) {
                        let tracked = r.map(|_, j| j.pos);
                        let work_keys = keys.frames[&index].map(|_, k| k.map(|p| scale.to_work(p)));
                        let fixed = tracked.map(|j, p| work_keys[j].unwrap_or(*p));
                        *t = BodyTracker::new(
                            &image,
                            &fixed,
                            &proportions,
                            params,
                            background.clone(),
                        );
                        for j in Joint::ALL {
                            if work_keys[j].is_some() {
                                r[j] = JointResult {
                                    pos: fixed[j],
                                    reliability: 1.0,
                                };
                            }
                        }
                    }
                    r
                }
            };
            *ctx_done += 1;
            Ok(to_video(result))
        };
        let mut done = self.done;
        let total = self.total;
        let progress = &mut *self.progress;
        let mut emit = |done: usize, index: usize, r: &PerJoint<JointResult>| {
            progress(&TrackProgress {
                done,
                total,
                frame: Some(FrameTracks {
                    index,
                    points: r.map(|_, j| TrackedPoint {
                        pos: j.pos,
                        confidence: j.reliability,
                        source: PointSource::Tracked,
                    }),
                }),
            });
        };
        let damaged = &mut self.damaged;
        if self.threads <= 1 {
            for &index in order {
                let image = match undamaged(self.video.frame(index))? {
                    Some(frame) => {
                        check(index, &frame.image)?;
                        Some(scale.shrink(frame.image))
                    }
                    None => {
                        damaged.push(index);
                        None
                    }
                };
                let r = handle(&mut done, index, image)?;
                emit(done, index, &r);
                out.push(r);
            }
        } else {
            // Decode (and shrink) ahead on another thread.
            let video = &mut *self.video;
            let order_owned = order.to_vec();
            let stop_flag = AtomicBool::new(false);
            let stop = &stop_flag;
            std::thread::scope(|s| -> Result<(), TrackError> {
                type Decoded = Result<(usize, Option<Arc<RgbImage>>), TrackError>;
                let (tx, rx) = std::sync::mpsc::sync_channel::<Decoded>(6);
                s.spawn(move || {
                    for chunk in decode_order(&order_owned) {
                        let mut images = Vec::with_capacity(chunk.decode.len());
                        for &index in &chunk.decode {
                            if stop.load(Ordering::Relaxed) {
                                return;
                            }
                            let item = undamaged(video.frame(index)).and_then(|frame| {
                                frame
                                    .map(|frame| {
                                        check(index, &frame.image)?;
                                        Ok(scale.shrink(frame.image))
                                    })
                                    .transpose()
                                    .map(|image| (index, image))
                            });
                            images.push(item);
                        }
                        if chunk.reverse {
                            images.reverse();
                        }
                        for item in images {
                            if tx.send(item).is_err() {
                                return;
                            }
                        }
                    }
                });
                let result = (|| {
                    for _ in 0..order.len() {
                        let (index, image) = rx.recv().map_err(|_| TrackError::Cancelled)??;
                        if image.is_none() {
                            damaged.push(index);
                        }
                        let r = handle(&mut done, index, image)?;
                        emit(done, index, &r);
                        out.push(r);
                    }
                    Ok(())
                })();
                stop.store(true, Ordering::Relaxed);
                drop(rx);
                result
            })?;
        }
        self.done = done;
        Ok(out)
    }
}

/// A decoded frame, `None` when the file is damaged there (the decoder's error for that
/// frame), or another error.
fn undamaged(
    frame: Result<crate::video::Frame, VideoError>,
) -> Result<Option<crate::video::Frame>, TrackError> {
    match frame {
        Ok(f) => Ok(Some(f)),
        Err(VideoError::Decode { .. }) => Ok(None),
        Err(e) => Err(e.into()),
    }
}

/// A run of frames the decoder reads forwards, sent in reverse for backward passes.
struct DecodeChunk {
    decode: Vec<usize>,
    reverse: bool,
}

/// Splits a pass's frame order into decoder-friendly chunks (backward passes decode 32 frames
/// forwards at a time and hand them over in reverse).
fn decode_order(order: &[usize]) -> Vec<DecodeChunk> {
    let backward = order.len() > 1 && order[1] < order[0];
    if !backward {
        return vec![DecodeChunk {
            decode: order.to_vec(),
            reverse: false,
        }];
    }
    order
        .chunks(32)
        .map(|c| DecodeChunk {
            decode: c.iter().rev().copied().collect(),
            reverse: true,
        })
        .collect()
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
            from: None,
            previous: None,
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
