//! One pass of the tracker over consecutive frames, forwards or backwards: frames decoded (and
//! shrunk to the working scale) on a second thread while the body tracker steps through them,
//! re-started with the hand-placed joints at every key frame on the way.

use super::background::{self, Background};
use super::body::{BodyTracker, JointResult};
use super::params::Tuning;
use super::replay::{FrameStore, Recorded, Resume, checkpoint_interval};
use super::shared::{TrackError, TrackProgress};
use crate::formats::{FrameIndex, FrameTracks, KeyFrames, PointSource, TrackedPoint};
use crate::skeleton::{Joint, PerJoint, Proportions};
use crate::video::{Video, VideoError};
use image::RgbImage;
use nalgebra::Point2;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Converts between video pixels and the working scale (pixel centres at integers).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Scale {
    pub(crate) sx: f64,
    pub(crate) sy: f64,
    pub(crate) width: u32,
    pub(crate) height: u32,
}

impl Scale {
    pub(crate) fn to_work(self, p: Point2<f64>) -> Point2<f64> {
        Point2::new((p.x + 0.5) / self.sx - 0.5, (p.y + 0.5) / self.sy - 0.5)
    }
    pub(crate) fn to_video(self, p: Point2<f64>) -> Point2<f64> {
        Point2::new((p.x + 0.5) * self.sx - 0.5, (p.y + 0.5) * self.sy - 0.5)
    }
    /// The frame at the working size: as it is when the decoder already shrank it, else
    /// averaged over boxes (`fast_image_resize`: a 1080×1920 frame in 1.6 ms, against 15 ms
    /// for `image`'s thumbnail, with the same pixels to a seventh of a level on average).
    pub(crate) fn shrink(&self, image: Arc<RgbImage>) -> Arc<RgbImage> {
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

/// One pass's results.
pub(crate) struct PassOutput {
    /// Per frame of the pass's order, the joints in video pixels.
    pub(crate) results: Vec<PerJoint<JointResult>>,
    /// Per key frame the pass went through (not its first), where it arrived before the
    /// hand-placed joints re-started it: how well it agrees with that key.
    pub(crate) arrivals: BTreeMap<usize, PerJoint<JointResult>>,
}

/// What a pass runs with: the video and how its frames are checked and scaled, the keys, the
/// progress, the background, and an earlier run's frames (`replay`).
pub(crate) struct PassContext<'a, 'p> {
    pub(crate) video: &'a mut Video,
    pub(crate) scale: Scale,
    pub(crate) params: Tuning,
    pub(crate) keys: &'a KeyFrames,
    pub(crate) path: PathBuf,
    /// The size frames arrive at from the video (full or, when it scales, working size).
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) threads: usize,
    /// Frames that could not be decoded so far.
    pub(crate) damaged: Vec<usize>,
    pub(crate) done: usize,
    pub(crate) total: usize,
    pub(crate) progress: &'p mut (dyn FnMut(&TrackProgress) + Send),
    pub(crate) cancel: &'a AtomicBool,
    /// The static camera's background at the working size, when there is one.
    pub(crate) background: Option<Arc<Background>>,
    /// An earlier run's working-size frames, per frame of the clip (`replay`).
    pub(crate) earlier_frames: &'a [Option<Arc<RgbImage>>],
    /// The working-size frames this run read, kept for the next.
    pub(crate) store: FrameStore,
}

impl PassContext<'_, '_> {
    /// The static camera's background from [`background::SAMPLES`] frames spread over the
    /// clip's `n` frames, at the working size ([`Background::estimate`]; `None` for a moving
    /// camera). When the whole clip fits in the video's frame cache every frame is read, so
    /// that the passes find them there and the clip is decoded once (reading only the samples
    /// forwards decodes the frames between them all the same, and the first pass would then
    /// decode them again).
    pub(crate) fn estimate_background(
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
    /// its first frame and re-started with the hand-placed joints at every key frame on the way
    /// (the parts they touch; the others go on as they were, `BodyTracker::restart`); returns
    /// the results in video pixels, one per frame of `order` (the first is the starting pose),
    /// and where the pass arrived on each key frame before it was re-started there. What an
    /// `earlier` run of the pass computed before the first frame whose keys changed is taken
    /// from it (`replay`); the pass is returned as it ran, for the next run.
    pub(crate) fn pass(
        &mut self,
        order: &[usize],
        pose: &PerJoint<Point2<f64>>,
        earlier: Option<&Recorded>,
    ) -> Result<(PassOutput, Recorded), TrackError> {
        let frames = FrameCheck {
            path: self.path.clone(),
            width: self.width,
            height: self.height,
        };
        let resume = earlier.and_then(|r| r.resume(order, pose, self.keys));
        let mut stepper = Stepper {
            tracker: None,
            start: pose,
            scale: self.scale,
            params: self.params,
            background: self.background.clone(),
            keys: self.keys,
            cancel: self.cancel,
            path: self.path.clone(),
            proportions: Proportions::default(),
            arrivals: BTreeMap::new(),
            checkpoints: BTreeMap::new(),
            interval: checkpoint_interval(order.len()),
        };
        let (scale, total) = (self.scale, self.total);
        let mut out = Vec::with_capacity(order.len());
        let from = match resume {
            Some(r) => self.take_up(order, r, &frames, &mut stepper, &mut out)?,
            None => 0,
        };
        let mut done = self.done;
        let progress = &mut *self.progress;
        let store = &mut self.store;
        let mut take = |index: usize, image: Option<Arc<RgbImage>>| -> Result<(), TrackError> {
            if let Some(image) = &image {
                store.keep(index, image);
            }
            let r = stepper.step(out.len(), index, image)?;
            done += 1;
            emit(progress, done, total, index, &r);
            out.push(r);
            Ok(())
        };
        let rest = &order[from..];
        if self.threads <= 1 {
            for &index in rest {
                let image = frame_at(self.video, self.earlier_frames, index, &frames, scale)?;
                if image.is_none() {
                    self.damaged.push(index);
                }
                take(index, image)?;
            }
        } else {
            let source = Source {
                earlier: self.earlier_frames,
                frames: &frames,
                scale,
            };
            decode_ahead(self.video, rest, &source, &mut self.damaged, &mut take)?;
        }
        self.done = done;
        let recorded = Recorded {
            order: order.to_vec(),
            start: *pose,
            keys: self.keys.clone(),
            results: out.clone(),
            arrivals: stepper.arrivals.clone(),
            checkpoints: stepper.checkpoints,
        };
        Ok((
            PassOutput {
                results: out,
                arrivals: stepper.arrivals,
            },
            recorded,
        ))
    }
}

impl PassContext<'_, '_> {
    /// Takes up an earlier run of the pass over `order` where `r` says: its results (told to
    /// the progress) into `out`, its arrivals and checkpoints into `stepper`, and the tracker
    /// there on the frame it last saw. Returns the position in `order` to go on from.
    fn take_up(
        &mut self,
        order: &[usize],
        r: Resume,
        frames: &FrameCheck,
        stepper: &mut Stepper,
        out: &mut Vec<PerJoint<JointResult>>,
    ) -> Result<usize, TrackError> {
        for (&index, result) in order.iter().zip(r.results) {
            self.done += 1;
            emit(self.progress, self.done, self.total, index, result);
        }
        out.extend_from_slice(r.results);
        stepper.arrivals = r.arrivals;
        stepper.checkpoints = r.checkpoints;
        let from = r.at + 1;
        if from < order.len() {
            let index = order[r.at];
            let image = frame_at(self.video, self.earlier_frames, index, frames, self.scale)?
                .ok_or(TrackError::StartFrameDamaged {
                    path: self.path.clone(),
                    frame: index,
                })?;
            stepper.tracker = Some(r.tracker.clone().resumed(&image));
        }
        Ok(from)
    }
}

/// Tells the progress callback that frame `index` is done, with its joints `r`.
fn emit(
    progress: &mut (dyn FnMut(&TrackProgress) + Send),
    done: usize,
    total: usize,
    index: usize,
    r: &PerJoint<JointResult>,
) {
    progress(&TrackProgress {
        done,
        total,
        frame: Some(FrameTracks {
            index: FrameIndex(index),
            body3d: None,
            points: r.map(|_, j| TrackedPoint {
                pos: j.pos,
                confidence: j.reliability,
                source: PointSource::Tracked,
            }),
        }),
    });
}

/// The size a pass's frames must arrive at, and the file to name when one does not.
struct FrameCheck {
    path: PathBuf,
    width: u32,
    height: u32,
}

impl FrameCheck {
    /// An error naming the file and frame when `image` is not the size the pass began at.
    fn check(&self, index: usize, image: &RgbImage) -> Result<(), TrackError> {
        if image.width() != self.width || image.height() != self.height {
            Err(TrackError::FrameSize {
                path: self.path.clone(),
                frame: index,
                got_w: image.width(),
                got_h: image.height(),
                width: self.width,
                height: self.height,
            })
        } else {
            Ok(())
        }
    }
}

/// Frame `index` of `video`, checked and shrunk to the working scale; `None` where the file is
/// damaged.
fn decoded(
    video: &mut Video,
    index: usize,
    frames: &FrameCheck,
    scale: Scale,
) -> Result<Option<Arc<RgbImage>>, TrackError> {
    undamaged(video.frame(index))?
        .map(|frame| {
            frames.check(index, &frame.image)?;
            Ok(scale.shrink(frame.image))
        })
        .transpose()
}

/// Frame `index` at the working scale: the earlier run's (`earlier`, per frame of the clip)
/// where it kept it, else decoded ([`decoded`]).
fn frame_at(
    video: &mut Video,
    earlier: &[Option<Arc<RgbImage>>],
    index: usize,
    frames: &FrameCheck,
    scale: Scale,
) -> Result<Option<Arc<RgbImage>>, TrackError> {
    match earlier.get(index) {
        Some(Some(image)) => Ok(Some(Arc::clone(image))),
        _ => decoded(video, index, frames, scale),
    }
}

/// Where a pass's frames come from: an earlier run's frames, else the video, checked and
/// shrunk.
struct Source<'a> {
    earlier: &'a [Option<Arc<RgbImage>>],
    frames: &'a FrameCheck,
    scale: Scale,
}

/// Decodes (and shrinks) the frames of `order` on another thread while `take` tracks them
/// here, in order (an earlier run's frames taken as they are); damaged frames are noted in
/// `damaged`.
fn decode_ahead(
    video: &mut Video,
    order: &[usize],
    source: &Source,
    damaged: &mut Vec<usize>,
    take: &mut dyn FnMut(usize, Option<Arc<RgbImage>>) -> Result<(), TrackError>,
) -> Result<(), TrackError> {
    let stop_flag = AtomicBool::new(false);
    let stop = &stop_flag;
    std::thread::scope(|s| -> Result<(), TrackError> {
        let (tx, rx) = std::sync::mpsc::sync_channel::<Decoded>(6);
        s.spawn(move || send_decoded(video, order, source, &tx, stop));
        let result = (|| {
            for _ in 0..order.len() {
                let (index, image) = rx.recv().map_err(|_| TrackError::Cancelled)??;
                if image.is_none() {
                    damaged.push(index);
                }
                take(index, image)?;
            }
            Ok(())
        })();
        stop.store(true, Ordering::Relaxed);
        drop(rx);
        result
    })
}

/// A frame decoded ahead: its index and image (`None` where the file is damaged), or an error.
type Decoded = Result<(usize, Option<Arc<RgbImage>>), TrackError>;

/// The decoding thread: a forward chunk is sent frame by frame as decoded; a backward one is
/// gathered and sent in reverse. Stops when `stop` is set or the receiver has gone.
fn send_decoded(
    video: &mut Video,
    order: &[usize],
    source: &Source,
    tx: &std::sync::mpsc::SyncSender<Decoded>,
    stop: &AtomicBool,
) {
    for chunk in decode_order(order) {
        let mut images = Vec::with_capacity(if chunk.reverse { chunk.decode.len() } else { 0 });
        for &index in &chunk.decode {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            let item = frame_at(video, source.earlier, index, source.frames, source.scale)
                .map(|image| (index, image));
            if chunk.reverse {
                images.push(item);
            } else if tx.send(item).is_err() {
                return;
            }
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
}

/// The body tracker stepping through one pass's frames: started on the first from `start`,
/// re-started at each key frame on the way.
struct Stepper<'a> {
    tracker: Option<BodyTracker>,
    /// The pass's starting pose, video pixels.
    start: &'a PerJoint<Point2<f64>>,
    scale: Scale,
    params: Tuning,
    background: Option<Arc<Background>>,
    keys: &'a KeyFrames,
    cancel: &'a AtomicBool,
    path: PathBuf,
    proportions: Proportions,
    /// Where the pass arrived on each key frame before it was re-started there.
    arrivals: BTreeMap<usize, PerJoint<JointResult>>,
    /// The tracker after every `interval`-th frame of the pass, for a re-track (`replay`).
    checkpoints: BTreeMap<usize, BodyTracker>,
    interval: usize,
}

impl Stepper<'_> {
    /// Frame `index`, at `position` in the pass: its joints, and the tracker kept every
    /// `interval` frames ([`BodyTracker::checkpoint`]).
    fn step(
        &mut self,
        position: usize,
        index: usize,
        image: Option<Arc<RgbImage>>,
    ) -> Result<PerJoint<JointResult>, TrackError> {
        let r = self.track(index, image)?;
        if position.is_multiple_of(self.interval)
            && let Some(t) = self.tracker.as_mut()
        {
            self.checkpoints.insert(position, t.checkpoint());
        }
        Ok(r)
    }

    /// Frame `index`'s joints in video pixels. A damaged frame (`image` `None`) keeps the last
    /// pose, lost: the tracker waits for the next frame.
    fn track(
        &mut self,
        index: usize,
        image: Option<Arc<RgbImage>>,
    ) -> Result<PerJoint<JointResult>, TrackError> {
        if self.cancel.load(Ordering::Relaxed) {
            return Err(TrackError::Cancelled);
        }
        let scale = self.scale;
        let to_video = |r: PerJoint<JointResult>| {
            r.map(|_, j| JointResult {
                pos: scale.to_video(j.pos),
                reliability: j.reliability,
            })
        };
        let Some(image) = image else {
            let t = self
                .tracker
                .as_ref()
                .ok_or_else(|| TrackError::StartFrameDamaged {
                    path: self.path.clone(),
                    frame: index,
                })?;
            return Ok(to_video(t.pose().map(|_, j| JointResult {
                pos: j.pos,
                reliability: 0.0,
            })));
        };
        let Some(t) = self.tracker.as_mut() else {
            let work = self.start.map(|_, p| scale.to_work(*p));
            let t = BodyTracker::new(
                &image,
                &work,
                &self.proportions,
                self.params,
                self.background.clone(),
            );
            let mut r = t.pose();
            for j in Joint::ALL {
                r[j].reliability = 1.0;
            }
            self.tracker = Some(t);
            return Ok(to_video(r));
        };
        let mut r = t.step(&image);
        if let Some(key) = self.keys.frames.get(&FrameIndex(index)) {
            self.arrivals.insert(index, to_video(r));
            let tracked = r.map(|_, j| j.pos);
            let work_keys = key.map(|_, k| k.map(|p| scale.to_work(p)));
            let fixed = tracked.map(|j, p| work_keys[j].unwrap_or(*p));
            let placed = work_keys.map(|_, k| k.is_some());
            t.restart(&image, &fixed, &placed, &self.proportions);
            for j in Joint::ALL {
                if work_keys[j].is_some() {
                    r[j] = JointResult {
                        pos: fixed[j],
                        reliability: 1.0,
                    };
                }
            }
        }
        Ok(to_video(r))
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
