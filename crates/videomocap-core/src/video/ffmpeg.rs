//! Video files through FFmpeg (ffmpeg-next) with frame-accurate random access.
//!
//! On open, the demuxer is run once over the whole file (packets only, no decoding) to list every
//! frame's presentation timestamp and every keyframe. Frame `i` is then the `i`-th timestamp in
//! presentation order, whatever the B-frames or the keyframe spacing. To decode it we seek to the
//! last keyframe at or before it, flush the decoder and decode forward until that timestamp comes
//! out; a request for the frame right after the last one decoded just decodes on, with no seek.

use super::{VideoError, VideoInfo, VideoSource, rotate_clockwise};
use ffmpeg_next as ff;
use image::RgbImage;
use std::path::{Path, PathBuf};
use std::sync::Once;

mod open;

use open::{
    display_rotation, frame_order, frame_rate, index_packets, longest_interval, open_decoder,
    open_input,
};

static INIT: Once = Once::new();

/// Initialises FFmpeg once and silences its log (errors reach the user through our own types).
pub(super) fn init() {
    INIT.call_once(|| {
        // Only fails if FFmpeg's global init fails, which it does not in versions ≥ 4.
        let _ = ff::init();
        ff::util::log::set_level(ff::util::log::Level::Fatal);
    });
}

/// Frames between the last decoded frame and a later request beyond which a seek is cheaper
/// than decoding on (a seek costs up to one GOP of decoding; most GOPs are ≤ 250 frames).
const DECODE_ON_LIMIT: usize = 48;

/// Keyframes a seek steps back at most when the frame does not come out after the nearest
/// one (inexact keyframe flags); beyond that the frame counts as damaged.
const STEP_BACK_KEYFRAMES: usize = 2;

/// A video file read through FFmpeg.
pub struct FfmpegSource {
    input: ff::format::context::Input,
    decoder: ff::decoder::Video,
    stream_index: usize,
    time_base: f64,
    /// Presentation timestamps (stream time base) of all frames, ascending: frame i has `pts[i]`.
    pts: Vec<i64>,
    /// Indexes (into `pts`) of the keyframes, ascending.
    keyframes: Vec<usize>,
    /// The converter from the decoder's pixels to RGB at the output size.
    converter: Option<Converter>,
    /// Output size before rotation, if frames are shrunk ([`FfmpegSource::shrink_to`]).
    shrunk: Option<(u32, u32)>,
    /// The displayed size at full scale (what [`VideoSource::output_size`] goes back to).
    full_size: (u32, u32),
    /// The coded size of the first frame: a shrunk frame of another size is refused rather
    /// than scaled to fit (unshrunk, its size tells the caller).
    coded_size: (u32, u32),
    /// Index of the last frame the decoder produced, if it is positioned after it.
    last_decoded: Option<usize>,
    /// Whether end of stream was sent to the decoder since the last seek.
    eof_sent: bool,
    /// While seeking: the target's timestamp. Until its packet is sent the decoder skips
    /// non-reference frames, which no later frame needs (exact, and about half the work on
    /// clips with B-frames).
    skip_until_pts: Option<i64>,
    info: VideoInfo,
}

fn not_a_video(path: &Path, e: impl std::fmt::Display) -> VideoError {
    VideoError::NotAVideo {
        path: path.to_owned(),
        reason: e.to_string(),
    }
}

impl FfmpegSource {
    /// Opens a video file and indexes its frames, decoding on as many threads as the process
    /// may use.
    pub fn open(path: &Path) -> Result<FfmpegSource, VideoError> {
        Self::open_with_threads(path, None)
    }

    /// [`FfmpegSource::open`] with the decoder's threads given (`None`: as many as the process
    /// may use; 1: none besides the caller's).
    pub fn open_with_threads(
        path: &Path,
        threads: Option<usize>,
    ) -> Result<FfmpegSource, VideoError> {
        init();
        std::fs::File::open(path).map_err(|source| VideoError::Io {
            path: path.to_owned(),
            source,
        })?;
        let mut input = open_input(path)?;
        let stream = input
            .streams()
            .best(ff::media::Type::Video)
            .ok_or_else(|| VideoError::NoVideoStream {
                path: path.to_owned(),
            })?;
        let stream_index = stream.index();
        let tb = stream.time_base();
        let time_base = f64::from(tb.numerator()) / f64::from(tb.denominator().max(1));
        let rotation_deg = display_rotation(&stream);
        let avg_rate = stream.avg_frame_rate();
        let decoder = open_decoder(path, stream.parameters(), threads)?;
        let codec = decoder
            .codec()
            .map_or_else(|| "unknown".to_owned(), |c| c.name().to_owned());
        let (coded_w, coded_h) = (decoder.width(), decoder.height());
        let packets = index_packets(&mut input, stream_index);
        if packets.is_empty() || coded_w == 0 || coded_h == 0 {
            return Err(VideoError::NoFrames {
                path: path.to_owned(),
            });
        }
        let (pts, keyframes) = frame_order(&packets);
        let (fps, span, variable_frame_rate) = frame_rate(&pts, time_base, avg_rate);
        let (width, height) = if rotation_deg % 180 == 90 {
            (coded_h, coded_w)
        } else {
            (coded_w, coded_h)
        };
        let info = VideoInfo {
            path: path.to_owned(),
            width,
            height,
            fps,
            frame_count: pts.len(),
            duration_s: span + 1.0 / fps,
            rotation_deg,
            codec,
            variable_frame_rate,
            keyframe_interval: longest_interval(&keyframes, pts.len()),
        };
        // Back to the start for decoding.
        input.seek(i64::MIN + 1, ..).ok();
        let mut me = FfmpegSource {
            input,
            decoder,
            stream_index,
            time_base,
            pts,
            keyframes,
            converter: None,
            shrunk: None,
            full_size: (info.width, info.height),
            coded_size: (coded_w, coded_h),
            last_decoded: None,
            eof_sent: false,
            skip_until_pts: None,
            info,
        };
        me.seek_to_keyframe_before(0)?;
        Ok(me)
    }

    /// Makes every later frame come out `width × height` (as displayed, after rotation)
    /// instead of full size: the video is scaled while its pixels are converted to RGB, which
    /// costs less than converting at full size. The info reports the new size.
    pub fn shrink_to(&mut self, width: u32, height: u32) {
        let (width, height) = (width.max(1), height.max(1));
        self.shrunk = Some(if self.info.rotation_deg % 180 == 90 {
            (height, width)
        } else {
            (width, height)
        });
        self.info.width = width;
        self.info.height = height;
    }

    fn path(&self) -> PathBuf {
        self.info.path.clone()
    }

    fn decode_error(&self, index: usize, e: impl std::fmt::Display) -> VideoError {
        VideoError::Decode {
            path: self.path(),
            index,
            reason: e.to_string(),
        }
    }

    /// Positions the demuxer at the keyframe `k`-th in `self.keyframes` and resets the decoder.
    fn seek_to_keyframe(&mut self, k: usize) -> Result<(), VideoError> {
        let frame = self.keyframes.get(k).copied().unwrap_or(0);
        let target = self.pts[frame];
        // avformat_seek_file with stream -1 takes AV_TIME_BASE (µs); round down so the seek
        // never lands after the keyframe.
        let ts_us = (target as f64 * self.time_base * 1e6).floor() as i64;
        let result = if k == 0 {
            self.input.seek(i64::MIN + 1, ..)
        } else {
            self.input.seek(ts_us, ..ts_us)
        };
        result.map_err(|e| self.decode_error(frame, format!("seek failed: {e}")))?;
        self.decoder.flush();
        self.last_decoded = None;
        self.eof_sent = false;
        self.set_skip_until(None);
        Ok(())
    }

    /// Skips non-reference frames until the packet with timestamp `pts` (or a later one) is sent;
    /// `None` decodes everything.
    fn set_skip_until(&mut self, pts: Option<i64>) {
        self.skip_until_pts = pts;
        self.decoder.skip_frame(if pts.is_some() {
            ff::Discard::NonReference
        } else {
            ff::Discard::Default
        });
    }

    /// Seeks to the last keyframe at or before frame `index`.
    fn seek_to_keyframe_before(&mut self, index: usize) -> Result<usize, VideoError> {
        let k = self
            .keyframes
            .partition_point(|&f| f <= index)
            .saturating_sub(1);
        self.seek_to_keyframe(k)?;
        Ok(k)
    }

    /// Decodes the next frame in presentation order; `None` at end of stream.
    fn next_decoded(&mut self, for_index: usize) -> Result<Option<ff::frame::Video>, VideoError> {
        let mut frame = ff::frame::Video::empty();
        loop {
            match self.decoder.receive_frame(&mut frame) {
                Ok(()) => return Ok(Some(frame)),
                Err(ff::Error::Eof) => return Ok(None),
                Err(ff::Error::Other { errno }) if errno == ff::util::error::EAGAIN => {}
                Err(e) => return Err(self.decode_error(for_index, e)),
            }
            if self.eof_sent {
                return Ok(None);
            }
            // Feed the next packet of our stream, or end of stream.
            let mut fed = false;
            while let Some((s, packet)) = self.input.packets().next() {
                if s.index() != self.stream_index {
                    continue;
                }
                if let Some(until) = self.skip_until_pts
                    && packet.pts().or(packet.dts()).is_none_or(|ts| ts >= until)
                {
                    self.set_skip_until(None);
                }
                // A damaged packet is skipped; the decoder conceals or drops its frame.
                let _ = self.decoder.send_packet(&packet);
                fed = true;
                break;
            }
            if !fed {
                self.decoder
                    .send_eof()
                    .map_err(|e| self.decode_error(for_index, e))?;
                self.eof_sent = true;
            }
        }
    }

    /// Index of a decoded frame from its timestamp (nearest listed timestamp).
    fn index_of(&self, frame: &ff::frame::Video) -> Option<usize> {
        let ts = frame.timestamp().or(frame.pts())?;
        match self.pts.binary_search(&ts) {
            Ok(i) => Some(i),
            Err(i) => {
                // Not listed (should not happen): take the nearest neighbour.
                let before = i.checked_sub(1);
                let after = (i < self.pts.len()).then_some(i);
                match (before, after) {
                    (Some(b), Some(a)) => Some(if ts - self.pts[b] <= self.pts[a] - ts {
                        b
                    } else {
                        a
                    }),
                    (Some(b), None) => Some(b),
                    (None, a) => a,
                }
            }
        }
    }

    /// Decodes forward until frame `index` comes out. Returns `None` if it was passed or the
    /// stream ended first.
    fn decode_forward_to(&mut self, index: usize) -> Result<Option<ff::frame::Video>, VideoError> {
        while let Some(frame) = self.next_decoded(index)? {
            let Some(i) = self.index_of(&frame) else {
                continue;
            };
            self.last_decoded = Some(i);
            if i == index {
                return Ok(Some(frame));
            }
            if i > index {
                return Ok(None);
            }
        }
        Ok(None)
    }

    fn convert_to_rgb(
        &mut self,
        frame: &ff::frame::Video,
        index: usize,
    ) -> Result<RgbImage, VideoError> {
        let (fmt, sw, sh) = (frame.format(), frame.width(), frame.height());
        if self.shrunk.is_some() && (sw, sh) != self.coded_size {
            return Err(self.decode_error(
                index,
                format!(
                    "the frame is {sw}×{sh}, the video's first frame {}×{}",
                    self.coded_size.0, self.coded_size.1
                ),
            ));
        }
        let (w, h) = self.shrunk.unwrap_or((sw, sh));
        let key = (fmt, sw, sh, w, h);
        if !matches!(&self.converter, Some(c) if c.key == key) {
            let converter = Converter::new(key).map_err(|e| self.decode_error(index, e))?;
            self.converter = Some(converter);
        }
        let mut rgb = ff::frame::Video::empty();
        if let Some(converter) = self.converter.as_mut() {
            converter
                .run(frame, &mut rgb)
                .map_err(|e| VideoError::Decode {
                    path: self.info.path.clone(),
                    index,
                    reason: e.to_string(),
                })?;
        }
        // Rows carry padding: copy them one by one.
        let stride = rgb.stride(0);
        let data = rgb.data(0);
        let row_bytes = w as usize * 3;
        let mut out = Vec::with_capacity(row_bytes * h as usize);
        for y in 0..h as usize {
            let start = y * stride;
            let row = data.get(start..start + row_bytes).ok_or_else(|| {
                self.decode_error(index, "converted frame is smaller than expected")
            })?;
            out.extend_from_slice(row);
        }
        let image = RgbImage::from_raw(w, h, out)
            .ok_or_else(|| self.decode_error(index, "converted frame has the wrong size"))?;
        Ok(rotate_clockwise(image, self.info.rotation_deg))
    }
}

/// What a converter converts: source pixel format and size, output size.
type ConverterKey = (ff::format::Pixel, u32, u32, u32, u32);

/// Decoded frames to RGB24 at the output size. A smaller output is shrunk in the decoder's own
/// pixel format first and then converted at its size: FFmpeg's planar scaling and its unscaled
/// YUV → RGB conversion are both fast paths, while scaling and converting in one step is not
/// (the 1080×1920 sample shrunk to 540×960: 300 → 400 frames/s decoded and converted). The
/// unscaled conversion repeats each 4:2:0 chroma sample over its 2×2 pixels instead of
/// interpolating it; shrinking to 4:4:4 first would interpolate, but is no faster than one step.
struct Converter {
    /// Source format, source size, output size.
    key: ConverterKey,
    /// The shrinking stage and its output frame (reused), when the output is smaller.
    shrink: Option<(ff::software::scaling::Context, ff::frame::Video)>,
    /// To RGB24 at the output size.
    to_rgb: ff::software::scaling::Context,
}

impl Converter {
    fn new(key: ConverterKey) -> Result<Converter, ff::Error> {
        use ff::software::scaling::{Context, Flags};
        let (fmt, sw, sh, w, h) = key;
        let shrink = if (w, h) != (sw, sh) {
            let ctx = Context::get(fmt, sw, sh, fmt, w, h, Flags::BILINEAR)?;
            Some((ctx, ff::frame::Video::empty()))
        } else {
            None
        };
        let to_rgb = Context::get(fmt, w, h, ff::format::Pixel::RGB24, w, h, Flags::BILINEAR)?;
        Ok(Converter {
            key,
            shrink,
            to_rgb,
        })
    }

    fn run(
        &mut self,
        frame: &ff::frame::Video,
        rgb: &mut ff::frame::Video,
    ) -> Result<(), ff::Error> {
        match self.shrink.as_mut() {
            Some((ctx, small)) => {
                ctx.run(frame, small)?;
                self.to_rgb.run(small, rgb)
            }
            None => self.to_rgb.run(frame, rgb),
        }
    }
}

// SAFETY: every FFmpeg object in `FfmpegSource` (demuxer, decoder, scaler) is owned by it alone
// and only touched through `&mut self`; FFmpeg contexts may move between threads as long as they
// are not used from two at once, which `&mut` rules out.
#[allow(unsafe_code)]
unsafe impl Send for FfmpegSource {}

impl VideoSource for FfmpegSource {
    fn output_size(&mut self, size: Option<(u32, u32)>) -> bool {
        // Asking for the full size is asking for no scaling (and no check of the coded size).
        match size.filter(|s| *s != self.full_size) {
            Some((w, h)) => self.shrink_to(w, h),
            None => {
                self.shrunk = None;
                (self.info.width, self.info.height) = self.full_size;
            }
        }
        true
    }

    fn reopen(&self) -> Option<Box<dyn VideoSource>> {
        let mut other = FfmpegSource::open_with_threads(&self.info.path, None).ok()?;
        if other.pts != self.pts {
            return None;
        }
        if self.shrunk.is_some() {
            other.shrink_to(self.info.width, self.info.height);
        }
        Some(Box::new(other))
    }

    fn info(&self) -> &VideoInfo {
        &self.info
    }

    fn time_of(&self, index: usize) -> f64 {
        match (self.pts.get(index), self.pts.first()) {
            (Some(p), Some(p0)) => (p - p0) as f64 * self.time_base,
            _ => index as f64 / self.info.fps,
        }
    }

    fn decode(&mut self, index: usize) -> Result<RgbImage, VideoError> {
        if index >= self.pts.len() {
            return Err(VideoError::FrameOutOfRange {
                path: self.path(),
                index,
                count: self.pts.len(),
            });
        }
        // Decode on from the current position when the target is a little ahead, or anywhere
        // ahead in the same group of pictures (a seek would restart at the same keyframe).
        let gop_start = self.keyframes[self
            .keyframes
            .partition_point(|&f| f <= index)
            .saturating_sub(1)];
        let ahead = self.last_decoded.is_some_and(|last| {
            index > last && (index - last <= DECODE_ON_LIMIT || last >= gop_start)
        });
        if ahead && let Some(frame) = self.decode_forward_to(index)? {
            return self.convert_to_rgb(&frame, index);
        }
        // Seek to the keyframe before; if that lands too late (inexact index), step back.
        // Stepping back is bounded: a damaged frame must fail fast, not decode the whole file
        // back to its start.
        let mut k = self.seek_to_keyframe_before(index)?;
        let lowest = k.saturating_sub(STEP_BACK_KEYFRAMES);
        self.set_skip_until(Some(self.pts[index]));
        loop {
            if let Some(frame) = self.decode_forward_to(index)? {
                return self.convert_to_rgb(&frame, index);
            }
            if k == lowest {
                return Err(self.decode_error(
                    index,
                    "the frame could not be decoded (damaged or truncated file?)",
                ));
            }
            k -= 1;
            self.seek_to_keyframe(k)?;
            self.set_skip_until(Some(self.pts[index]));
        }
    }
}
