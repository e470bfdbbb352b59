//! Frame sources: video files through FFmpeg and image sequences, with frame-accurate random
//! access, display rotation applied, and a frame cache bounded in bytes.
//!
//! In: a path (a video file or a directory of PNG/JPEG images). Out: RGB8 frames by index.
//! Free of any GUI code (the GUI runs a [`Video`] on a worker thread).

mod cache;
#[cfg(feature = "ffmpeg")]
mod encode;
mod error;
#[cfg(feature = "ffmpeg")]
mod ffmpeg;
mod image_sequence;
pub mod proxy;
mod span;

pub use cache::{DEFAULT_CACHE_BYTES, FrameCache};
#[cfg(feature = "ffmpeg")]
pub use encode::{EncodeParams, Mp4Writer};
pub use error::VideoError;
#[cfg(feature = "ffmpeg")]
pub use ffmpeg::FfmpegSource;
pub use image_sequence::{DEFAULT_SEQUENCE_FPS, ImageSequence};
pub use span::SpanSource;

use image::RgbImage;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What a frame source knows about its video.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VideoInfo {
    /// The file or directory opened.
    pub path: PathBuf,
    /// Width of the frames as displayed (after rotation), pixels.
    pub width: u32,
    /// Height of the frames as displayed (after rotation), pixels.
    pub height: u32,
    /// Average frames per second (frame count over duration for variable frame rate).
    pub fps: f64,
    /// Number of frames.
    pub frame_count: usize,
    /// Duration in seconds (last frame's time plus one frame).
    pub duration_s: f64,
    /// Clockwise rotation applied for display, degrees (0, 90, 180 or 270).
    pub rotation_deg: u32,
    /// Codec or image format name.
    pub codec: String,
    /// Whether frame times are unevenly spaced (variable frame rate).
    pub variable_frame_rate: bool,
    /// The longest run of frames from one keyframe to the next (or to the end): how many frames
    /// a random seek may have to decode. 1 for image sequences.
    pub keyframe_interval: usize,
}

/// One decoded frame.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Index in display order (0-based).
    pub index: usize,
    /// Presentation time from the start of the video, seconds.
    pub time_s: f64,
    /// The pixels, RGB8, as displayed (rotation applied). Shared with the cache.
    pub image: Arc<RgbImage>,
}

/// A backend that decodes frames by index. Implementations must return exactly the i-th
/// displayed frame for any `i` in any order.
pub trait VideoSource: Send {
    /// Metadata of the video.
    fn info(&self) -> &VideoInfo;
    /// Presentation time of frame `index`, seconds from the first frame.
    fn time_of(&self, index: usize) -> f64;
    /// Decodes frame `index` (display order) to RGB8.
    fn decode(&mut self, index: usize) -> Result<RgbImage, VideoError>;
    /// Makes later frames come out `size` (as displayed), or full size again with `None`, if
    /// the backend can scale while it converts pixels (cheaper than shrinking the full frame
    /// afterwards); returns whether it did. The info then reports the new size.
    fn output_size(&mut self, _size: Option<(u32, u32)>) -> bool {
        false
    }
    /// A second, independent reader of the same frames at the same output size (for a worker
    /// thread that reads while this one is read elsewhere), or `None` if the backend cannot
    /// make one. Its frames are the same bits as this one's.
    fn reopen(&self) -> Option<Box<dyn VideoSource>> {
        None
    }
}

/// Options for [`Video::open`].
#[derive(Debug, Clone)]
pub struct OpenOptions {
    /// Frame cache budget in bytes.
    pub cache_bytes: usize,
    /// Frame rate assumed for image sequences.
    pub sequence_fps: f64,
    /// Threads a video file's decoder may use (`None`: as many as the process may use).
    pub decoder_threads: Option<usize>,
}

impl Default for OpenOptions {
    fn default() -> Self {
        OpenOptions {
            cache_bytes: DEFAULT_CACHE_BYTES,
            sequence_fps: DEFAULT_SEQUENCE_FPS,
            decoder_threads: None,
        }
    }
}

/// An open video: a backend plus a bounded frame cache. The one type the rest of the program uses.
pub struct Video {
    source: Box<dyn VideoSource>,
    cache: FrameCache,
}

impl Video {
    /// Opens a video file (through FFmpeg) or a directory of images.
    pub fn open(path: &Path, options: &OpenOptions) -> Result<Video, VideoError> {
        let meta = std::fs::metadata(path).map_err(|source| VideoError::Io {
            path: path.to_owned(),
            source,
        })?;
        let source: Box<dyn VideoSource> = if meta.is_dir() {
            Box::new(ImageSequence::open(path, options.sequence_fps)?)
        } else {
            open_file(path, options.decoder_threads)?
        };
        Ok(Video::from_source(source, options.cache_bytes))
    }

    /// Wraps an already open backend.
    pub fn from_source(source: Box<dyn VideoSource>, cache_bytes: usize) -> Video {
        let info = source.info();
        let frame_bytes = info.width as usize * info.height as usize * 3;
        Video {
            cache: FrameCache::new(cache_bytes, frame_bytes),
            source,
        }
    }

    /// Asks the backend to deliver frames at `size` (`None`: full size) while it converts
    /// them ([`VideoSource::output_size`]); when the size changes the cache is emptied, since
    /// its frames have the old size. Returns whether the backend did it.
    pub fn output_size(&mut self, size: Option<(u32, u32)>) -> bool {
        let before = (self.info().width, self.info().height);
        if !self.source.output_size(size) {
            return false;
        }
        let info = self.source.info();
        if (info.width, info.height) == before {
            return true;
        }
        let frame_bytes = info.width as usize * info.height as usize * 3;
        let budget = self.cache.capacity_frames() * self.cache.frame_bytes();
        self.cache = FrameCache::new(budget, frame_bytes);
        true
    }

    /// Metadata of the video.
    pub fn info(&self) -> &VideoInfo {
        self.source.info()
    }

    /// Frame `index` in display order, from the cache or decoded.
    pub fn frame(&mut self, index: usize) -> Result<Frame, VideoError> {
        let count = self.info().frame_count;
        if index >= count {
            return Err(VideoError::FrameOutOfRange {
                path: self.info().path.clone(),
                index,
                count,
            });
        }
        let image = match self.cache.get(index) {
            Some(image) => image,
            None => {
                let image = Arc::new(self.source.decode(index)?);
                self.cache.insert(index, Arc::clone(&image));
                image
            }
        };
        Ok(Frame {
            index,
            time_s: self.source.time_of(index),
            image,
        })
    }

    /// Frames `start..start + len` of this video as a video of its own, numbered from 0 (the
    /// cache starts empty).
    pub fn into_span(self, start: usize, len: usize) -> Result<Video, VideoError> {
        let cache_bytes = self.cache.capacity_frames() * self.cache.frame_bytes();
        let span = SpanSource::new(self.source, start, len)?;
        Ok(Video::from_source(Box::new(span), cache_bytes))
    }

    /// A second, independent reader of this video's frames at its current output size, with a
    /// cache of `cache_bytes` ([`VideoSource::reopen`]); `None` if the backend cannot make one.
    pub fn reopen(&self, cache_bytes: usize) -> Option<Video> {
        let source = self.source.reopen()?;
        let same =
            (source.info().width, source.info().height) == (self.info().width, self.info().height);
        same.then(|| Video::from_source(source, cache_bytes))
    }

    /// How many frames of the current size the cache holds at most.
    pub fn cache_capacity_frames(&self) -> usize {
        self.cache.capacity_frames()
    }

    /// Bytes currently held by the frame cache.
    pub fn cached_bytes(&self) -> usize {
        self.cache.used_bytes()
    }
}

#[cfg(feature = "ffmpeg")]
fn open_file(path: &Path, threads: Option<usize>) -> Result<Box<dyn VideoSource>, VideoError> {
    Ok(Box::new(FfmpegSource::open_with_threads(path, threads)?))
}

#[cfg(not(feature = "ffmpeg"))]
fn open_file(path: &Path, _threads: Option<usize>) -> Result<Box<dyn VideoSource>, VideoError> {
    Err(VideoError::FfmpegDisabled {
        path: path.to_owned(),
    })
}

/// Rotates an image clockwise by a multiple of 90 degrees (display rotation of phone videos).
pub fn rotate_clockwise(image: RgbImage, degrees: u32) -> RgbImage {
    match degrees % 360 {
        90 => image::imageops::rotate90(&image),
        180 => image::imageops::rotate180(&image),
        270 => image::imageops::rotate270(&image),
        _ => image,
    }
}
