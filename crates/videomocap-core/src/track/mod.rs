//! 2D tracking (VBA, Pan et al. "Feature tracking"): from the marks of one frame to the
//! positions of all 16 joints in every frame, with a reliability per joint and frame.
//!
//! In: a [`crate::video::Video`] and [`crate::formats::Marks`] (plus any corrections as
//! [`KeyFrames`]). Out: [`crate::formats::Tracks2d`] and a list of weak spans.
//!
//! - `block`: the morph-block `A = {(x, y), m, n, θ}` (Fig. 7)
//! - `frame`: a frame as four `f32` lanes per pixel, sampled bilinearly
//! - `similarity`: the sub-pixel morph-block similarity (eqs. 3–5), the hot loop
//! - `background`: a static camera's background, foreground evidence for the arms
//! - `head`: image-difference head prediction (eqs. 1–5)
//! - `search`: the spiral search path (Fig. 6) and the anchored angular search
//! - `part`: a tracked body part and what each part does per frame (predict, search prior, learn, hold)
//! - `limb`: one limb chain per frame, upper then lower segment, refined as one figure
//! - `body`: the top-down tracker (head → trunk → limbs)
//! - `evidence`: the pose network's evidence weighed in
//! - `chain`: the network's chain over the clip, run only where it adds
//! - `ahead`: the network run on its own thread while VBA's passes run
//! - `doubt`: the evidence of each joint-frame's doubt, for calibrating it (`bench learned
//!   --doubt-dump`)
//! - `occlusion`: interpolation over weak runs, the weak-span report
//! - `smooth`: the finished tracks smoothed over time, weighted by reliability
//! - `run`: tracking a video from its key frames, the order of the steps, re-tracking
//! - `pass`: one pass over consecutive frames, forwards or backwards, re-started at key frames
//! - `replay`: what the passes computed, kept for a re-track (a cache)
//! - `passes`: the two passes, one after the other or at once
//! - `fuse`: the forward and backward passes made one, per joint between its key frames
//! - `shared`: the errors and progress every step uses (below them all)

mod ahead;
mod background;
mod block;
mod body;
mod chain;
mod doubt;
mod evidence;
mod frame;
mod fuse;
mod head;
mod limb;
mod occlusion;
mod params;
mod part;
mod pass;
mod passes;
mod replay;
mod run;
mod search;
mod shared;
mod similarity;
pub(crate) mod smooth;

pub use chain::run_network;
pub use doubt::{DOUBT_FEATURES, FEATURE_COUNT, doubt_features};
pub use evidence::{EvidenceParams, NetFrame, NetworkFrames, weigh};
pub use occlusion::{SpanKind, WeakSpan, weak_spans};
pub use params::TrackerParams;
pub use replay::PassesSeen;
pub use run::{KeyFrames, TrackJob, TrackOutput, track_video};
pub use shared::{TrackError, TrackProgress};
// Inner facts the app and the scoring need, exported by name.
pub use background::KnownBackground;
pub use body::stature_px;
pub use similarity::FloatFrame;
