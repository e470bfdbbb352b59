//! The one error type of the file formats: every variant names the file.

use super::FrameIndex;
use crate::skeleton::Joint;
use std::path::PathBuf;

/// A file could not be read, parsed, checked or written.
#[derive(Debug, thiserror::Error)]
pub enum FormatError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not valid JSON for this file: {source}")]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error("{path}: this is a \"{found}\" file, expected \"{expected}\"")]
    WrongFormat {
        path: PathBuf,
        found: String,
        expected: &'static str,
    },
    #[error(
        "{path}: version {version} is not supported (this build reads up to version {supported}; was it written by a newer videomocap?)"
    )]
    UnsupportedVersion {
        path: PathBuf,
        version: u32,
        supported: u32,
    },
    #[error("{path}: unknown joint \"{name}\" (see docs/formats.md for the 16 joint names)")]
    UnknownJoint { path: PathBuf, name: String },
    #[error("{path}: joint {joint} is listed twice")]
    DuplicateJoint { path: PathBuf, joint: Joint },
    #[error("{path}: joint {joint} is missing{}", frame_suffix(*.frame))]
    MissingJoint {
        path: PathBuf,
        joint: Joint,
        frame: Option<FrameIndex>,
    },
    #[error("{path}: joint {joint} has a non-finite coordinate{}", frame_suffix(*.frame))]
    NonFinite {
        path: PathBuf,
        joint: Joint,
        frame: Option<FrameIndex>,
    },
    #[error(
        "{path}: joint {joint} at ({x:.1}, {y:.1}) is outside the {width}×{height} frame{}",
        frame_suffix(*.frame)
    )]
    OutsideFrame {
        path: PathBuf,
        joint: Joint,
        x: f64,
        y: f64,
        width: u32,
        height: u32,
        frame: Option<FrameIndex>,
    },
    #[error("{path}: frame {frame}: \"{field}\" has {found} entries, expected {expected}")]
    WrongLength {
        path: PathBuf,
        frame: FrameIndex,
        field: &'static str,
        found: usize,
        expected: usize,
    },
    #[error("{path}: {problem}")]
    Invalid { path: PathBuf, problem: String },
}

fn frame_suffix(frame: Option<FrameIndex>) -> String {
    frame.map_or_else(String::new, |f| format!(" in frame {f}"))
}
