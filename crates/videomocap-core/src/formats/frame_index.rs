//! The number of a frame in its video, as every file and stage stores it.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A frame's number in its video (0-based), as opposed to a position in a slice of frames:
/// tracks, skeletons and key frames are stored by it, and a clip that starts later in its video
/// (or skips a frame) has positions and frame numbers that differ.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct FrameIndex(pub usize);

impl FrameIndex {
    /// The frame number as a plain integer (for arithmetic and display).
    pub fn get(self) -> usize {
        self.0
    }

    /// The frame's time in seconds at `fps` frames a second.
    pub fn seconds(self, fps: f64) -> f64 {
        self.0 as f64 / fps
    }
}

impl fmt::Display for FrameIndex {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl From<usize> for FrameIndex {
    fn from(n: usize) -> Self {
        FrameIndex(n)
    }
}

impl std::ops::Add<usize> for FrameIndex {
    type Output = FrameIndex;
    /// The frame `n` frames later.
    fn add(self, n: usize) -> FrameIndex {
        FrameIndex(self.0 + n)
    }
}
