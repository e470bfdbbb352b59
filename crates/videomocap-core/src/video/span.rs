//! A span of a longer video as a video of its own: frames `start..start + len` of the source,
//! numbered from 0. Lets a short stretch of an hour-long file be tracked without touching the
//! rest (the bench's long-video measurement does this).

use super::{VideoError, VideoInfo, VideoSource};
use image::RgbImage;

/// Frames `start..start + len` of another source, renumbered from 0.
pub struct SpanSource {
    inner: Box<dyn VideoSource>,
    start: usize,
    info: VideoInfo,
}

impl SpanSource {
    /// The span `start..start + len` of `inner`; an error when it reaches past the end.
    pub fn new(
        inner: Box<dyn VideoSource>,
        start: usize,
        len: usize,
    ) -> Result<SpanSource, VideoError> {
        let whole = inner.info().clone();
        let end = start
            .checked_add(len)
            .filter(|&e| e <= whole.frame_count && len > 0);
        let Some(end) = end else {
            return Err(VideoError::FrameOutOfRange {
                path: whole.path,
                index: start.saturating_add(len.max(1)) - 1,
                count: whole.frame_count,
            });
        };
        let t0 = inner.time_of(start);
        let duration_s = inner.time_of(end - 1) - t0 + 1.0 / whole.fps;
        let info = VideoInfo {
            frame_count: len,
            duration_s,
            ..whole
        };
        Ok(SpanSource { inner, start, info })
    }
}

impl VideoSource for SpanSource {
    fn info(&self) -> &VideoInfo {
        &self.info
    }

    fn reopen(&self) -> Option<Box<dyn VideoSource>> {
        Some(Box::new(SpanSource {
            inner: self.inner.reopen()?,
            start: self.start,
            info: self.info.clone(),
        }))
    }

    fn output_size(&mut self, size: Option<(u32, u32)>) -> bool {
        if !self.inner.output_size(size) {
            return false;
        }
        self.info.width = self.inner.info().width;
        self.info.height = self.inner.info().height;
        true
    }

    fn time_of(&self, index: usize) -> f64 {
        self.inner.time_of(self.start + index) - self.inner.time_of(self.start)
    }

    fn decode(&mut self, index: usize) -> Result<RgbImage, VideoError> {
        if index >= self.info.frame_count {
            return Err(VideoError::FrameOutOfRange {
                path: self.info.path.clone(),
                index,
                count: self.info.frame_count,
            });
        }
        self.inner.decode(self.start + index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::video::ImageSequence;

    #[test]
    fn a_span_is_the_same_frames_renumbered() {
        let dir = tempfile::tempdir().unwrap();
        for i in 0..6u8 {
            RgbImage::from_pixel(4, 3, image::Rgb([i * 40, 0, 0]))
                .save(dir.path().join(format!("f{i}.png")))
                .unwrap();
        }
        let open = || Box::new(ImageSequence::open(dir.path(), 10.0).unwrap());
        let mut span = SpanSource::new(open(), 2, 3).unwrap();
        assert_eq!(span.info().frame_count, 3);
        assert!((span.info().duration_s - 0.3).abs() < 1e-9);
        assert!((span.time_of(2) - 0.2).abs() < 1e-9);
        assert_eq!(span.decode(0).unwrap().get_pixel(0, 0)[0], 80);
        assert_eq!(span.decode(2).unwrap().get_pixel(0, 0)[0], 160);
        assert!(span.decode(3).is_err());
        assert!(SpanSource::new(open(), 4, 3).is_err());
        assert!(SpanSource::new(open(), 0, 0).is_err());
    }
}
