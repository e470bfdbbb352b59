//! The types every step of tracking shares: its errors and its progress. They sit below the
//! steps (no step's file is used here), so the stage's files form a line, not a circle
//! (`scripts/module_cycles.py`).

use crate::formats::FrameTracks;
use crate::video::VideoError;
use std::path::PathBuf;

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
