//! What is read when a video opens: the container and its decoder, the index of every packet,
//! the frames' order, their rate and the display rotation.

use super::not_a_video;
use crate::video::VideoError;
use ff::packet::Ref as _;
use ffmpeg_next as ff;
use std::path::Path;

/// Reads the display rotation (clockwise degrees, multiple of 90) from a stream's display matrix.
#[allow(unsafe_code)] // FFmpeg's C data, read beside a SAFETY comment
pub(super) fn display_rotation(stream: &ff::format::stream::Stream) -> u32 {
    for side in stream.side_data() {
        if side.kind() == ff::codec::packet::side_data::Type::DisplayMatrix
            && side.data().len() >= 36
        {
            let mut m = [0i32; 9];
            for (k, chunk) in side.data().chunks_exact(4).take(9).enumerate() {
                m[k] = i32::from_ne_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
            }
            // SAFETY: `m` holds the 9 entries av_display_rotation_get reads.
            let ccw = unsafe { ff::ffi::av_display_rotation_get(m.as_ptr()) };
            if !ccw.is_finite() {
                return 0;
            }
            // As FFmpeg's own autorotate: the display matrix angle is counter-clockwise.
            let cw = (-ccw).rem_euclid(360.0);
            return ((cw / 90.0).round() as u32 % 4) * 90;
        }
    }
    0
}

/// The longest run of frames from a keyframe to the next one, or to the end.
pub(super) fn longest_interval(keyframes: &[usize], frame_count: usize) -> usize {
    keyframes
        .iter()
        .zip(keyframes.iter().skip(1).chain([&frame_count]))
        .map(|(a, b)| b.saturating_sub(*a))
        .max()
        .unwrap_or(frame_count)
}

/// Frame rate reported when the file gives none and has a single frame.
const DEFAULT_FPS_WHEN_UNKNOWN: f64 = 30.0;

/// Median interval between consecutive timestamps, if there are at least two.
pub(super) fn median_interval(pts: &[i64]) -> Option<i64> {
    let mut d: Vec<i64> = pts.windows(2).map(|w| w[1] - w[0]).collect();
    d.sort_unstable();
    d.get(d.len() / 2).copied().filter(|&m| m > 0)
}

/// Whether frame intervals differ from the median by more than 10% of it (variable frame rate).
pub(super) fn is_variable(pts: &[i64]) -> bool {
    let Some(median) = median_interval(pts) else {
        return false;
    };
    pts.windows(2)
        .any(|w| ((w[1] - w[0]) - median).abs() as f64 > 0.1 * median as f64)
}

/// Opens the container, naming an MP4/MOV recording cut short before its index was written.
pub(super) fn open_input(path: &Path) -> Result<ff::format::context::Input, VideoError> {
    ff::format::input(path).map_err(|e| {
        let mp4 = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| ["mp4", "mov", "m4v"].contains(&e.to_ascii_lowercase().as_str()));
        if mp4 && e == ff::Error::InvalidData {
            not_a_video(
                path,
                format!("{e}; an MP4/MOV recording cut short, before its index was written, reads like this"),
            )
        } else {
            not_a_video(path, e)
        }
    })
}

/// The stream's decoder, decoding frames on `threads` (`None`: as many as the process may use).
pub(super) fn open_decoder(
    path: &Path,
    parameters: ff::codec::Parameters,
    threads: Option<usize>,
) -> Result<ff::decoder::Video, VideoError> {
    let mut ctx =
        ff::codec::Context::from_parameters(parameters).map_err(|e| not_a_video(path, e))?;
    ctx.set_threading(ff::codec::threading::Config {
        kind: ff::codec::threading::Type::Frame,
        count: threads
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(2, |n| n.get()))
            .max(1),
        ..Default::default()
    });
    ctx.decoder().video().map_err(|e| not_a_video(path, e))
}

/// The index: every packet of the stream, in file order (its timestamp, whether a keyframe),
/// discarded and corrupt packets left out.
#[allow(unsafe_code)] // FFmpeg's C data, read beside a SAFETY comment
pub(super) fn index_packets(
    input: &mut ff::format::context::Input,
    stream_index: usize,
) -> Vec<(i64, bool)> {
    let mut packets: Vec<(i64, bool)> = Vec::new();
    let mut ordinal = 0i64;
    for (s, packet) in input.packets() {
        if s.index() != stream_index {
            continue;
        }
        // SAFETY: reading the flags field of a valid packet.
        let discard = unsafe { (*packet.as_ptr()).flags } & ff::ffi::AV_PKT_FLAG_DISCARD != 0;
        if discard || packet.is_corrupt() {
            continue;
        }
        let ts = packet.pts().or(packet.dts()).unwrap_or(ordinal);
        packets.push((ts, packet.is_key()));
        ordinal += 1;
    }
    packets
}

/// The frames' timestamps in display order and the keyframes' frame numbers (frame 0 always
/// one); `packets` is not empty.
pub(super) fn frame_order(packets: &[(i64, bool)]) -> (Vec<i64>, Vec<usize>) {
    let mut pts: Vec<i64> = packets.iter().map(|p| p.0).collect();
    pts.sort_unstable();
    pts.dedup();
    let mut keyframes: Vec<usize> = packets
        .iter()
        .filter(|p| p.1)
        .filter_map(|p| pts.binary_search(&p.0).ok())
        .collect();
    keyframes.sort_unstable();
    keyframes.dedup();
    if keyframes.first() != Some(&0) {
        keyframes.insert(0, 0);
    }
    (pts, keyframes)
}

/// The frame rate, the span from the first frame to the last (seconds) and whether the rate
/// varies. Constant rate: the median frame interval (exact, whatever the container's average
/// says); variable rate: frames over span; a single frame: the container's average.
pub(super) fn frame_rate(pts: &[i64], time_base: f64, avg_rate: ff::Rational) -> (f64, f64, bool) {
    let frame_count = pts.len();
    let span = (pts[frame_count - 1] - pts[0]) as f64 * time_base;
    let variable_frame_rate = is_variable(pts);
    let fps = match median_interval(pts) {
        Some(d) if !variable_frame_rate => 1.0 / (d as f64 * time_base),
        _ if span > 0.0 => (frame_count - 1) as f64 / span,
        _ if avg_rate.numerator() > 0 && avg_rate.denominator() > 0 => {
            f64::from(avg_rate.numerator()) / f64::from(avg_rate.denominator())
        }
        _ => DEFAULT_FPS_WHEN_UNKNOWN,
    };
    (fps, span, variable_frame_rate)
}
