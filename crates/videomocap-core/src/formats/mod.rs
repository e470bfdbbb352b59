//! The project's versioned JSON files (documented in `docs/formats.md`): marks, keys, known
//! lengths, tracks2d and skeleton3d, with one error type that always names the file, and atomic saving.

mod atomic;
mod error;
mod frame_index;
mod keys;
mod lengths;
mod marks;
mod skeleton3d;
mod tracks2d;

pub use atomic::write_atomically;
pub use error::FormatError;
pub use frame_index::FrameIndex;
pub(crate) use keys::KeyEntry;
pub use keys::{KEYS_FORMAT, KeyFrames};
pub use lengths::{KnownLengths, LENGTH_RANGE_M, LENGTHS_FORMAT, SHOULDER_WIDTH_KEY, TapeLengths};
pub use marks::{MARKS_FORMAT, Marks};
pub use skeleton3d::{
    CONTACT_FLAG, Frame3d, LOST_FLAG, NO_IMAGE_DEPTH_FLAG, OFF_FRAME_FLAG, SKELETON3D_FORMAT,
    Skeleton3d, UNUSUAL_POSE_FLAG,
};
pub use tracks2d::{
    FrameTracks, NetworkBody, PointSource, SourceInfo, TRACKS2D_FORMAT, TRACKS2D_VERSION,
    TrackedPoint, Tracks2d,
};

use crate::skeleton::{JOINT_COUNT, Joint};
use serde::Deserialize;
use std::path::Path;

/// A tracks2d or a skeleton3d file, told apart by its `format` tag (or, in files without one,
/// by its fields).
#[derive(Debug, Clone, PartialEq)]
pub enum AnyFile {
    Tracks2d(Tracks2d),
    Skeleton3d(Skeleton3d),
}

/// Reads a tracks2d or skeleton3d file, whichever it is.
pub fn load_any(path: &Path) -> Result<AnyFile, FormatError> {
    #[derive(Deserialize)]
    struct Peek {
        #[serde(default)]
        format: Option<String>,
        #[serde(default)]
        camera: Option<serde_json::Value>,
    }
    let text = read_text(path)?;
    let peek: Peek = parse_json(&text, path)?;
    match peek.format.as_deref() {
        Some(TRACKS2D_FORMAT) => Tracks2d::parse(&text, path).map(AnyFile::Tracks2d),
        Some(SKELETON3D_FORMAT) => Skeleton3d::parse(&text, path).map(AnyFile::Skeleton3d),
        Some(other) => Err(FormatError::WrongFormat {
            path: path.to_owned(),
            found: other.to_owned(),
            expected: "videomocap.tracks2d or videomocap.skeleton3d",
        }),
        None if peek.camera.is_some() => Skeleton3d::parse(&text, path).map(AnyFile::Skeleton3d),
        None => Tracks2d::parse(&text, path).map(AnyFile::Tracks2d),
    }
}

/// The version this build writes and reads of marks, skeleton3d, projects and voxel grids.
pub const FORMAT_VERSION: u32 = 1;

/// Reads a whole file as text, naming it in the error.
pub fn read_text(path: &Path) -> Result<String, FormatError> {
    std::fs::read_to_string(path).map_err(|source| FormatError::Io {
        path: path.to_owned(),
        source,
    })
}

/// Parses JSON, naming the file and the line in the error.
pub fn parse_json<T: for<'de> Deserialize<'de>>(text: &str, path: &Path) -> Result<T, FormatError> {
    serde_json::from_str(text).map_err(|source| FormatError::Json {
        path: path.to_owned(),
        source,
    })
}

/// Checks that a hand-placed point of `joint` on `frame` lies on a `width × height` image.
pub(crate) fn check_on_image(
    path: &Path,
    joint: Joint,
    p: &nalgebra::Point2<f64>,
    (width, height): (u32, u32),
    frame: FrameIndex,
) -> Result<(), FormatError> {
    if crate::camera::point_in_frame(p, width, height) {
        return Ok(());
    }
    Err(FormatError::OutsideFrame {
        path: path.to_owned(),
        joint,
        x: p.x,
        y: p.y,
        width,
        height,
        frame: Some(frame),
    })
}

/// Checks the optional `format` and `version` fields of a file (version 1 only).
pub fn check_header(
    path: &Path,
    expected: &'static str,
    format: Option<&str>,
    version: Option<u32>,
) -> Result<(), FormatError> {
    check_header_up_to(path, expected, format, version, FORMAT_VERSION)
}

/// Checks the optional `format` and `version` fields of a file whose format has reached
/// version `newest` (every version from 1 to `newest` is read).
pub(crate) fn check_header_up_to(
    path: &Path,
    expected: &'static str,
    format: Option<&str>,
    version: Option<u32>,
    newest: u32,
) -> Result<(), FormatError> {
    if let Some(found) = format
        && found != expected
    {
        return Err(FormatError::WrongFormat {
            path: path.to_owned(),
            found: found.to_owned(),
            expected,
        });
    }
    if let Some(v) = version
        && !(1..=newest).contains(&v)
    {
        return Err(FormatError::UnsupportedVersion {
            path: path.to_owned(),
            version: v,
            supported: newest,
        });
    }
    Ok(())
}

/// Maps a file's list of joint names onto the model: for each model joint, its column in the file.
fn joint_columns(path: &Path, names: &[String]) -> Result<[usize; JOINT_COUNT], FormatError> {
    let mut columns = [usize::MAX; JOINT_COUNT];
    for (col, name) in names.iter().enumerate() {
        let joint = Joint::from_name(name).ok_or_else(|| FormatError::UnknownJoint {
            path: path.to_owned(),
            name: name.clone(),
        })?;
        if columns[joint.index()] != usize::MAX {
            return Err(FormatError::DuplicateJoint {
                path: path.to_owned(),
                joint,
            });
        }
        columns[joint.index()] = col;
    }
    for joint in Joint::ALL {
        if columns[joint.index()] == usize::MAX {
            return Err(FormatError::MissingJoint {
                path: path.to_owned(),
                joint,
                frame: None,
            });
        }
    }
    Ok(columns)
}

/// Checks that frame indexes strictly increase; `previous` carries the last index seen.
fn check_frame_order(
    path: &Path,
    previous: &mut Option<FrameIndex>,
    index: FrameIndex,
) -> Result<(), FormatError> {
    if previous.is_some_and(|p| index <= p) {
        return Err(FormatError::Invalid {
            path: path.to_owned(),
            problem: format!("frame {index} is out of order or repeated"),
        });
    }
    *previous = Some(index);
    Ok(())
}

/// The 16 joint names in file order, as written in the `joints` field.
fn joint_names() -> Vec<String> {
    Joint::ALL.iter().map(|j| j.name().to_owned()).collect()
}

/// Serialises to pretty JSON and saves atomically.
pub fn save_json<T: serde::Serialize>(value: &T, path: &Path) -> Result<(), FormatError> {
    let mut text = serde_json::to_string_pretty(value).map_err(|source| FormatError::Json {
        path: path.to_owned(),
        source,
    })?;
    text.push('\n');
    write_atomically(path, text.as_bytes())
}

/// The JSON example under the heading that starts with `heading` in `docs/formats.md`, for the
/// tests that hold the documented settings to the code's defaults.
#[cfg(test)]
pub(crate) fn documented_json(heading: &str) -> &'static str {
    include_str!("../../../../docs/formats.md")
        .split(heading)
        .nth(1)
        .and_then(|section| section.split("```json").nth(1))
        .and_then(|block| block.split("```").next())
        .unwrap_or_else(|| panic!("docs/formats.md has a JSON block under {heading:?}"))
}
