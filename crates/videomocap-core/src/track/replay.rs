//! What VBA's passes computed, kept for a re-track of the same video (issue 95): a cache, the
//! result the same with it or without it, byte for byte.
//!
//! A pass steps the body tracker through its frames in order, re-started at every key on the
//! way, so its result up to a frame depends only on its first frame, its starting pose, the
//! keys on the frames before and the frames themselves. A re-track after a correction on frame
//! `d` therefore finds every frame of a pass before `d` as it was. Each pass keeps its results
//! and the body tracker's state every [`checkpoint_interval`] frames (without the frame it
//! holds, which the frame it last saw makes again); a re-track takes the results up to the
//! last checkpoint before the first frame whose keys changed and steps on from that checkpoint.
//! The working-size frames the passes read are kept too, up to [`FRAMES_BUDGET_BYTES`], so
//! that a re-track need not decode the clip again.

use super::body::{BodyTracker, JointResult};
use super::params::Tuning;
use crate::formats::{FrameIndex, KeyFrames};
use crate::skeleton::PerJoint;
use image::RgbImage;
use nalgebra::Point2;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

/// At most this many bytes of working-size frames are kept for the next re-track: a 300-frame
/// 1080×1920 clip tracked at 389×692 holds 242 MB; frames beyond the budget (a longer clip)
/// are decoded again.
pub(super) const FRAMES_BUDGET_BYTES: usize = 256 * 1024 * 1024;

/// Checkpoints of the body tracker kept per pass at most (beside the first and last frames):
/// every 8th frame up to 512 frames, sparser beyond, so a long clip's checkpoints stay small
/// (one holds the parts' colour models, about 0.1 MB at the working stature).
const MAX_CHECKPOINTS: usize = 64;

/// Frames between two checkpoints of a pass over `len` frames: 8, or more for a long pass
/// ([`MAX_CHECKPOINTS`]). A re-track steps again at most this many frames it had before.
pub(super) fn checkpoint_interval(len: usize) -> usize {
    len.div_ceil(MAX_CHECKPOINTS).max(8)
}

/// A frame of the clip at the working size, when kept.
pub(super) type KeptFrame = Option<Arc<RgbImage>>;

/// What an earlier run's passes computed on a video, for the next run on it
/// ([`super::TrackOutput::passes`], [`super::TrackJob::previous_passes`]): each pass's results
/// and the body tracker's checkpoints, and the working-size frames (see the module). Cheap to
/// clone (shared).
#[derive(Clone)]
pub struct PassesSeen(Arc<Seen>);

/// Its size only: frames and trackers would fill a log.
impl std::fmt::Debug for PassesSeen {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PassesSeen")
            .field("frames_kept", &self.0.frames.iter().flatten().count())
            .finish_non_exhaustive()
    }
}

/// The run a cache comes from: reused only by a run with the same of all of these.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct SeenRun {
    pub(super) path: PathBuf,
    pub(super) frame_count: usize,
    pub(super) tuning: Tuning,
    /// The working scale, and the size the video delivered frames at (the decoder's shrink
    /// and the box filter's differ in their pixels).
    pub(super) work: (u32, u32, f64, f64),
    pub(super) decoded: (u32, u32),
}

impl SeenRun {
    pub(super) fn new(
        path: PathBuf,
        frame_count: usize,
        tuning: Tuning,
        work: (u32, u32, f64, f64),
        decoded: (u32, u32),
    ) -> SeenRun {
        SeenRun {
            path,
            frame_count,
            tuning,
            work,
            decoded,
        }
    }
}

struct Seen {
    run: SeenRun,
    /// Per frame of the clip, its working-size frame when kept.
    frames: Vec<Option<Arc<RgbImage>>>,
    /// The forward and the backward pass.
    passes: [Option<Recorded>; 2],
}

impl PassesSeen {
    /// What the passes of a run like `run` can take from this cache: the frames and the two
    /// passes' records, or nothing when it comes from another video or other settings.
    pub(super) fn for_run(&self, run: &SeenRun) -> Option<(&[KeptFrame], [Option<&Recorded>; 2])> {
        (self.0.run == *run).then(|| {
            let [a, b] = &self.0.passes;
            (self.0.frames.as_slice(), [a.as_ref(), b.as_ref()])
        })
    }

    /// The cache of a run: its identity, the frames kept and its two passes.
    pub(super) fn new(
        run: SeenRun,
        frames: Vec<Option<Arc<RgbImage>>>,
        passes: [Option<Recorded>; 2],
    ) -> PassesSeen {
        PassesSeen(Arc::new(Seen {
            run,
            frames,
            passes,
        }))
    }
}

/// The working-size frames a run read, kept up to [`FRAMES_BUDGET_BYTES`] (the earlier run's
/// first, then the ones this run read, in the order read).
pub(super) struct FrameStore {
    frames: Vec<Option<Arc<RgbImage>>>,
    bytes: usize,
}

impl FrameStore {
    /// A store for a clip of `n` frames holding the `earlier` run's frames already.
    pub(super) fn new(n: usize, earlier: &[Option<Arc<RgbImage>>]) -> FrameStore {
        let mut store = FrameStore {
            frames: vec![None; n],
            bytes: 0,
        };
        for (index, image) in earlier.iter().enumerate() {
            if let Some(image) = image {
                store.keep(index, image);
            }
        }
        store
    }

    /// Keeps frame `index` while the budget allows.
    pub(super) fn keep(&mut self, index: usize, image: &Arc<RgbImage>) {
        let bytes = image.as_raw().len();
        match self.frames.get_mut(index) {
            Some(slot @ None) if self.bytes + bytes <= FRAMES_BUDGET_BYTES => {
                *slot = Some(Arc::clone(image));
                self.bytes += bytes;
            }
            _ => {}
        }
    }

    /// Keeps `other`'s frames too, while the budget allows.
    pub(super) fn absorb(&mut self, other: FrameStore) {
        for (index, image) in other.frames.into_iter().enumerate() {
            if let Some(image) = image {
                self.keep(index, &image);
            }
        }
    }

    /// The frames kept, per frame of the clip.
    pub(super) fn into_frames(self) -> Vec<Option<Arc<RgbImage>>> {
        self.frames
    }
}

/// One pass as it ran: its frames, starting pose and the keys it saw, its results and
/// arrivals, and the body tracker every [`checkpoint_interval`] frames.
pub(super) struct Recorded {
    pub(super) order: Vec<usize>,
    pub(super) start: PerJoint<Point2<f64>>,
    pub(super) keys: KeyFrames,
    pub(super) results: Vec<PerJoint<JointResult>>,
    pub(super) arrivals: BTreeMap<usize, PerJoint<JointResult>>,
    /// Per position in `order`, the tracker after that frame (its frame buffers empty:
    /// [`BodyTracker::checkpoint`]).
    pub(super) checkpoints: BTreeMap<usize, BodyTracker>,
}

/// Where a pass takes up an earlier run's: its results up to position `at` of its order (and
/// the arrivals there), and the tracker after that frame.
pub(super) struct Resume<'a> {
    pub(super) at: usize,
    pub(super) results: &'a [PerJoint<JointResult>],
    pub(super) arrivals: BTreeMap<usize, PerJoint<JointResult>>,
    pub(super) tracker: &'a BodyTracker,
    pub(super) checkpoints: BTreeMap<usize, BodyTracker>,
}

impl Recorded {
    /// Where a pass over `order` from `start` with `keys` can take up this one: after the last
    /// checkpoint before the first frame whose keys differ (all of it when none does); `None`
    /// when it ran over other frames or from another pose.
    pub(super) fn resume(
        &self,
        order: &[usize],
        start: &PerJoint<Point2<f64>>,
        keys: &KeyFrames,
    ) -> Option<Resume<'_>> {
        if self.order != order || self.start != *start || self.results.len() != order.len() {
            return None;
        }
        let key = |k: &KeyFrames, f: usize| k.frames.get(&FrameIndex(f)).copied();
        // The first frame's keys are in `start`; a tracker re-starts at the frames after it.
        let changed = (1..order.len())
            .find(|&i| key(keys, order[i]) != key(&self.keys, order[i]))
            .unwrap_or(order.len());
        let (&at, tracker) = self.checkpoints.range(..changed).next_back()?;
        let frames = &order[..=at];
        Some(Resume {
            at,
            results: &self.results[..=at],
            arrivals: self
                .arrivals
                .iter()
                .filter(|(f, _)| frames.contains(f))
                .map(|(f, r)| (*f, *r))
                .collect(),
            tracker,
            checkpoints: self
                .checkpoints
                .range(..=at)
                .map(|(i, t)| (*i, t.clone()))
                .collect(),
        })
    }
}
