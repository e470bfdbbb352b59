//! Errors of the frame sources; every variant names the file.

use std::path::PathBuf;

/// A video or image sequence could not be opened or decoded.
#[derive(Debug, thiserror::Error)]
pub enum VideoError {
    #[error("{path}: cannot open: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a video FFmpeg can read ({reason})")]
    NotAVideo { path: PathBuf, reason: String },
    #[error("{path}: the file has no video stream")]
    NoVideoStream { path: PathBuf },
    #[error("{path}: the video has no frames")]
    NoFrames { path: PathBuf },
    #[error("{path}: frame {index} does not exist (the video has {count} frames)")]
    FrameOutOfRange {
        path: PathBuf,
        index: usize,
        count: usize,
    },
    #[error("{path}: cannot decode frame {index}: {reason}")]
    Decode {
        path: PathBuf,
        index: usize,
        reason: String,
    },
    #[error("{path}: no PNG or JPEG images in this directory")]
    NoImages { path: PathBuf },
    #[error(
        "{path}: images differ in size: {first_file} is {first_width}×{first_height} but {other_file} is {other_width}×{other_height}"
    )]
    MixedSizes {
        path: PathBuf,
        first_file: String,
        first_width: u32,
        first_height: u32,
        other_file: String,
        other_width: u32,
        other_height: u32,
    },
    #[error("{path}: cannot read image: {reason}")]
    Image { path: PathBuf, reason: String },
    #[error("{path}: cannot write video: {reason}")]
    Encode { path: PathBuf, reason: String },
    #[error(
        "{path}: this build has no FFmpeg support (feature \"ffmpeg\"); use a directory of images"
    )]
    FfmpegDisabled { path: PathBuf },
}
