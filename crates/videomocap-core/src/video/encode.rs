//! Writing RGB frames to an H.264 MP4 through FFmpeg's encoder (used by `synth` and the tests
//! that need real compressed video with B-frames and long GOPs).

use super::VideoError;
use ffmpeg_next as ff;
use image::RgbImage;
use std::path::{Path, PathBuf};

/// Encoder settings.
#[derive(Debug, Clone)]
pub struct EncodeParams {
    /// Frames per second (integer: the time base is 1/fps).
    pub fps: u32,
    /// Keyframe interval in frames.
    pub gop: u32,
    /// Maximum consecutive B-frames.
    pub max_b_frames: usize,
    /// x264 constant rate factor (0 lossless … 51 worst; 18 is visually lossless).
    pub crf: u32,
}

impl Default for EncodeParams {
    fn default() -> Self {
        EncodeParams {
            fps: 30,
            gop: 60,
            max_b_frames: 2,
            crf: 18,
        }
    }
}

/// An MP4 file being written frame by frame. Call [`Mp4Writer::finish`] at the end.
pub struct Mp4Writer {
    path: PathBuf,
    output: ff::format::context::Output,
    encoder: ff::encoder::Video,
    scaler: ff::software::scaling::Context,
    encoder_time_base: ff::Rational,
    width: u32,
    height: u32,
    next_pts: i64,
}

fn encode_error(path: &Path, e: impl std::fmt::Display) -> VideoError {
    VideoError::Encode {
        path: path.to_owned(),
        reason: e.to_string(),
    }
}

impl Mp4Writer {
    /// Creates the file and opens an H.264 encoder for `width × height` frames (both even).
    pub fn create(
        path: &Path,
        width: u32,
        height: u32,
        params: &EncodeParams,
    ) -> Result<Mp4Writer, VideoError> {
        super::ffmpeg::init();
        if !width.is_multiple_of(2)
            || !height.is_multiple_of(2)
            || width == 0
            || height == 0
            || params.fps == 0
        {
            return Err(encode_error(
                path,
                format!(
                    "{width}×{height} at {} fps: sides must be even and positive",
                    params.fps
                ),
            ));
        }
        let err = |e: ff::Error| encode_error(path, e);
        let mut output = ff::format::output(path).map_err(err)?;
        let global_header = output
            .format()
            .flags()
            .contains(ff::format::Flags::GLOBAL_HEADER);
        let codec = ff::encoder::find(ff::codec::Id::H264)
            .ok_or_else(|| encode_error(path, "FFmpeg has no H.264 encoder (install libx264)"))?;
        let mut stream = output.add_stream(codec).map_err(err)?;
        let mut enc = ff::codec::context::Context::new_with_codec(codec)
            .encoder()
            .video()
            .map_err(err)?;
        let fps = i32::try_from(params.fps).unwrap_or(30);
        let time_base = ff::Rational::new(1, fps);
        enc.set_width(width);
        enc.set_height(height);
        enc.set_format(ff::format::Pixel::YUV420P);
        enc.set_time_base(time_base);
        enc.set_frame_rate(Some(ff::Rational::new(fps, 1)));
        enc.set_gop(params.gop);
        enc.set_max_b_frames(params.max_b_frames);
        if global_header {
            enc.set_flags(ff::codec::Flags::GLOBAL_HEADER);
        }
        let mut opts = ff::Dictionary::new();
        opts.set("preset", "veryfast");
        opts.set("crf", &params.crf.to_string());
        // Fixed GOP: no scene-cut keyframes, so the keyframe spacing is exactly `gop`.
        opts.set(
            "x264-params",
            &format!("scenecut=0:keyint={}:min-keyint={}", params.gop, params.gop),
        );
        let encoder = enc.open_with(opts).map_err(err)?;
        stream.set_parameters(&encoder);
        stream.set_time_base(time_base);
        output.write_header().map_err(err)?;
        let scaler = ff::software::scaling::Context::get(
            ff::format::Pixel::RGB24,
            width,
            height,
            ff::format::Pixel::YUV420P,
            width,
            height,
            ff::software::scaling::Flags::BILINEAR,
        )
        .map_err(err)?;
        Ok(Mp4Writer {
            path: path.to_owned(),
            output,
            encoder,
            scaler,
            encoder_time_base: time_base,
            width,
            height,
            next_pts: 0,
        })
    }

    /// Encodes one frame (same size as given to [`Mp4Writer::create`]).
    pub fn write(&mut self, image: &RgbImage) -> Result<(), VideoError> {
        if image.dimensions() != (self.width, self.height) {
            return Err(encode_error(
                &self.path,
                format!(
                    "frame is {}×{}, the video is {}×{}",
                    image.width(),
                    image.height(),
                    self.width,
                    self.height
                ),
            ));
        }
        let mut rgb = ff::frame::Video::new(ff::format::Pixel::RGB24, self.width, self.height);
        let stride = rgb.stride(0);
        let row_bytes = self.width as usize * 3;
        {
            let data = rgb.data_mut(0);
            for (y, row) in image.as_raw().chunks_exact(row_bytes).enumerate() {
                data[y * stride..y * stride + row_bytes].copy_from_slice(row);
            }
        }
        let mut yuv = ff::frame::Video::empty();
        self.scaler
            .run(&rgb, &mut yuv)
            .map_err(|e| encode_error(&self.path, e))?;
        yuv.set_pts(Some(self.next_pts));
        self.next_pts += 1;
        self.encoder
            .send_frame(&yuv)
            .map_err(|e| encode_error(&self.path, e))?;
        self.drain()
    }

    fn drain(&mut self) -> Result<(), VideoError> {
        let stream_tb = self
            .output
            .stream(0)
            .map_or(self.encoder_time_base, |s| s.time_base());
        let mut packet = ff::Packet::empty();
        while self.encoder.receive_packet(&mut packet).is_ok() {
            packet.set_stream(0);
            packet.set_duration(1);
            packet.rescale_ts(self.encoder_time_base, stream_tb);
            packet
                .write_interleaved(&mut self.output)
                .map_err(|e| encode_error(&self.path, e))?;
        }
        Ok(())
    }

    /// Flushes the encoder and writes the file trailer.
    pub fn finish(mut self) -> Result<(), VideoError> {
        self.encoder
            .send_eof()
            .map_err(|e| encode_error(&self.path, e))?;
        self.drain()?;
        self.output
            .write_trailer()
            .map_err(|e| encode_error(&self.path, e))
    }
}
