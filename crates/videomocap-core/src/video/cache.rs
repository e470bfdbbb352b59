//! A least-recently-used frame cache bounded in bytes, so that scrubbing is fast and an hour of
//! 1080p never fills memory.

use image::RgbImage;
use lru::LruCache;
use std::num::NonZeroUsize;
use std::sync::Arc;

/// Default cache budget: 512 MiB (≈ 86 frames of 1080p RGB8, 580 frames of 640×480).
pub const DEFAULT_CACHE_BYTES: usize = 512 * 1024 * 1024;

/// Decoded frames by index, evicting the least recently used beyond a byte budget.
pub struct FrameCache {
    frames: LruCache<usize, Arc<RgbImage>>,
    frame_bytes: usize,
}

impl FrameCache {
    /// A cache holding at most `budget_bytes` of frames of `frame_bytes` each (at least one frame).
    pub fn new(budget_bytes: usize, frame_bytes: usize) -> FrameCache {
        let capacity = (budget_bytes / frame_bytes.max(1)).max(1);
        FrameCache {
            frames: LruCache::new(NonZeroUsize::MIN.saturating_add(capacity - 1)),
            frame_bytes,
        }
    }

    /// The frame if cached (and marks it recently used).
    pub fn get(&mut self, index: usize) -> Option<Arc<RgbImage>> {
        self.frames.get(&index).cloned()
    }

    /// Stores a frame, evicting the least recently used one when full.
    pub fn insert(&mut self, index: usize, image: Arc<RgbImage>) {
        self.frames.put(index, image);
    }

    /// Bytes held now.
    pub fn used_bytes(&self) -> usize {
        self.frames.len() * self.frame_bytes
    }

    /// Bytes of one frame.
    pub fn frame_bytes(&self) -> usize {
        self.frame_bytes
    }

    /// How many frames fit.
    pub fn capacity_frames(&self) -> usize {
        self.frames.cap().get()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_bounds_the_bytes_held() {
        let bytes = 4 * 4 * 3;
        let mut c = FrameCache::new(bytes * 3, bytes);
        for i in 0..10 {
            c.insert(i, Arc::new(RgbImage::new(4, 4)));
            assert!(c.used_bytes() <= bytes * 3);
        }
        assert_eq!(c.capacity_frames(), 3);
        assert!(c.get(9).is_some() && c.get(6).is_none());
    }

    #[test]
    fn least_recently_used_goes_first() {
        let mut c = FrameCache::new(2, 1);
        c.insert(0, Arc::new(RgbImage::new(1, 1)));
        c.insert(1, Arc::new(RgbImage::new(1, 1)));
        c.get(0);
        c.insert(2, Arc::new(RgbImage::new(1, 1)));
        assert!(c.get(0).is_some() && c.get(1).is_none());
    }

    #[test]
    fn a_tiny_budget_still_keeps_one_frame() {
        let mut c = FrameCache::new(0, 1000);
        c.insert(5, Arc::new(RgbImage::new(1, 1)));
        assert!(c.get(5).is_some());
    }
}
