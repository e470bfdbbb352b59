//! `skeleton3d.json`: the reconstructed 3D skeleton per frame, in camera coordinates
//! (metres, X right, Y down, Z forward), with the camera and the bone lengths used.

use super::{
    FORMAT_VERSION, FormatError, FrameIndex, check_frame_order, check_header, joint_columns,
    joint_names, parse_json, read_text, save_json,
};
use crate::camera::PinholeCamera;
use crate::skeleton::{Bone, Joint, PerJoint};
use nalgebra::Point3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The `format` tag of skeleton3d files.
pub const SKELETON3D_FORMAT: &str = "videomocap.skeleton3d";

/// The prefix of the frame flag that marks a joint whose 2D track was off the frame
/// (`off_frame:left_wrist`): its 3D position rests on the tracker's estimate.
pub const OFF_FRAME_FLAG: &str = "off_frame:";

/// The frame flag for a frame where the pose network saw no body while it did on others (the
/// depth choices there rest on the geometry alone).
pub const NO_IMAGE_DEPTH_FLAG: &str = "no_image_depth";

/// The frame flag for a pose the learned pose prior has (almost) never seen (a contortionist,
/// a fall): the depth choices there rest on the image and smooth motion, not on what bodies
/// usually do.
pub const UNUSUAL_POSE_FLAG: &str = "unusual_pose";

/// The prefix of the frame flag that marks a joint whose 2D track was lost (in a weak run too
/// long to interpolate, `lost:left_wrist`): its 3D position rests on the tracker's guess.
pub const LOST_FLAG: &str = "lost:";

/// The prefix of the frame flag that marks a planted foot (`contact:left_ankle`): the lift
/// found the foot on the floor there and held it still. A state, not a problem: not counted
/// by [`Frame3d::flagged`].
pub const CONTACT_FLAG: &str = "contact:";

/// The 16 joints of one frame in camera space.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame3d {
    /// Frame number in the video (0-based).
    pub index: FrameIndex,
    /// Joint positions in camera space, metres.
    pub points: PerJoint<Point3<f64>>,
    /// What the reconstruction noticed on this frame (e.g. `too_long:left_elbow-left_wrist`,
    /// `key_triangle_not_converged`); empty when all went well. Optional in the file.
    pub flags: Vec<String>,
}

/// A reconstructed 3D skeleton sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton3d {
    /// The camera the points are expressed in.
    pub camera: PinholeCamera,
    /// Frame rate of the source video (frames per second); `None` in files written before it was
    /// recorded, in which case exports ask for it.
    pub fps: Option<f64>,
    /// Length of each bone in metres, keyed `"parent-child"`.
    pub bone_lengths_m: BTreeMap<String, f64>,
    /// Frames in increasing index order.
    pub frames: Vec<Frame3d>,
}

impl Frame3d {
    /// Whether the reconstruction noticed something on this frame (any flag but a foot's
    /// contact).
    pub fn flagged(&self) -> bool {
        self.flags.iter().any(|f| !f.starts_with(CONTACT_FLAG))
    }

    /// Per joint, whether the frame has the flag `<prefix><joint>` (e.g. [`OFF_FRAME_FLAG`]).
    pub fn joint_flags(&self, prefix: &str) -> PerJoint<bool> {
        let mut out = PerJoint::from_fn(|_| false);
        for flag in &self.flags {
            if let Some(joint) = flag.strip_prefix(prefix).and_then(Joint::from_name) {
                out[joint] = true;
            }
        }
        out
    }
}

#[derive(Serialize, Deserialize)]
struct FrameFile {
    index: FrameIndex,
    points: Vec<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    flags: Vec<String>,
}

#[derive(Serialize, Deserialize)]
struct SkeletonFile {
    #[serde(default)]
    format: Option<String>,
    #[serde(default)]
    version: Option<u32>,
    camera: PinholeCamera,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fps: Option<f64>,
    joints: Vec<String>,
    bone_lengths_m: BTreeMap<String, f64>,
    frames: Vec<FrameFile>,
}

impl Skeleton3d {
    /// Reads and checks a skeleton3d file.
    pub fn load(path: &Path) -> Result<Self, FormatError> {
        Self::parse(&read_text(path)?, path)
    }

    /// Parses a skeleton from JSON text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, FormatError> {
        let raw: SkeletonFile = parse_json(text, path)?;
        check_header(path, SKELETON3D_FORMAT, raw.format.as_deref(), raw.version)?;
        let columns = joint_columns(path, &raw.joints)?;
        let cam = raw.camera;
        check_header_values(path, &cam, raw.fps, &raw.bone_lengths_m)?;
        let mut frames = Vec::with_capacity(raw.frames.len());
        let mut previous: Option<FrameIndex> = None;
        for f in raw.frames {
            frames.push(parse_frame(
                path,
                f,
                &columns,
                raw.joints.len(),
                &mut previous,
            )?);
        }
        Ok(Skeleton3d {
            camera: cam,
            fps: raw.fps,
            bone_lengths_m: raw.bone_lengths_m,
            frames,
        })
    }

    /// Saves atomically, joints in model order.
    pub fn save(&self, path: &Path) -> Result<(), FormatError> {
        save_json(&self.file(), path)
    }

    /// The file's JSON (to embed in a project file).
    pub fn to_json_value(&self) -> serde_json::Value {
        // Serialising plain numbers, strings and maps cannot fail.
        serde_json::to_value(self.file()).unwrap_or(serde_json::Value::Null)
    }

    /// Reads the JSON of [`Self::to_json_value`] (or of a file); `path` names it in errors.
    pub fn from_json_value(value: serde_json::Value, path: &Path) -> Result<Self, FormatError> {
        Self::parse(&value.to_string(), path)
    }

    fn file(&self) -> SkeletonFile {
        SkeletonFile {
            format: Some(SKELETON3D_FORMAT.to_owned()),
            version: Some(FORMAT_VERSION),
            camera: self.camera,
            fps: self.fps,
            joints: joint_names(),
            bone_lengths_m: self.bone_lengths_m.clone(),
            frames: self
                .frames
                .iter()
                .map(|f| FrameFile {
                    index: f.index,
                    points: f.points.0.iter().map(|p| [p.x, p.y, p.z]).collect(),
                    flags: f.flags.clone(),
                })
                .collect(),
        }
    }
}

/// Refuses a camera without a positive finite focal length or a finite centre, a frame rate
/// that is not positive, an unknown bone or a length that is not positive.
fn check_header_values(
    path: &Path,
    cam: &PinholeCamera,
    fps: Option<f64>,
    bone_lengths_m: &BTreeMap<String, f64>,
) -> Result<(), FormatError> {
    let camera_ok =
        cam.focal_px.is_finite() && cam.focal_px > 0.0 && cam.cx.is_finite() && cam.cy.is_finite();
    if !camera_ok {
        return Err(FormatError::Invalid {
            path: path.to_owned(),
            problem: format!(
                "camera focal_px must be positive and finite and cx, cy finite (got {}, {}, {})",
                cam.focal_px, cam.cx, cam.cy
            ),
        });
    }
    if let Some(fps) = fps
        && !(fps.is_finite() && fps > 0.0)
    {
        return Err(FormatError::Invalid {
            path: path.to_owned(),
            problem: format!("fps must be positive and finite (got {fps})"),
        });
    }
    for (key, &len) in bone_lengths_m {
        if Bone::from_key(key).is_none() {
            return Err(FormatError::Invalid {
                path: path.to_owned(),
                problem: format!("unknown bone \"{key}\" in bone_lengths_m"),
            });
        }
        if !(len.is_finite() && len > 0.0) {
            return Err(FormatError::Invalid {
                path: path.to_owned(),
                problem: format!("bone \"{key}\" has length {len}; it must be positive"),
            });
        }
    }
    Ok(())
}

/// One frame of the file (`n` joints in the file's `columns`), after `previous`, every point
/// finite.
fn parse_frame(
    path: &Path,
    f: FrameFile,
    columns: &[usize; crate::skeleton::JOINT_COUNT],
    n: usize,
    previous: &mut Option<FrameIndex>,
) -> Result<Frame3d, FormatError> {
    if f.points.len() != n {
        return Err(FormatError::WrongLength {
            path: path.to_owned(),
            frame: f.index,
            field: "points",
            found: f.points.len(),
            expected: n,
        });
    }
    check_frame_order(path, previous, f.index)?;
    for joint in Joint::ALL {
        if !f.points[columns[joint.index()]]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(FormatError::NonFinite {
                path: path.to_owned(),
                joint,
                frame: Some(f.index),
            });
        }
    }
    Ok(Frame3d {
        index: f.index,
        points: PerJoint::from_fn(|j| {
            let [x, y, z] = f.points[columns[j.index()]];
            Point3::new(x, y, z)
        }),
        flags: f.flags,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Skeleton3d {
        Skeleton3d {
            camera: PinholeCamera::centred(1000.0, 640, 480),
            fps: Some(30.0),
            bone_lengths_m: [("left_knee-left_ankle".to_owned(), 0.42)].into(),
            frames: vec![Frame3d {
                index: FrameIndex(0),
                points: PerJoint::from_fn(|j| Point3::new(j.index() as f64 * 0.1, -0.5, 3.0)),
                flags: vec!["too_long:left_elbow-left_wrist".to_owned()],
            }],
        }
    }

    #[test]
    fn save_and_load_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("skeleton3d.json");
        sample().save(&path).unwrap();
        assert_eq!(Skeleton3d::load(&path).unwrap(), sample());
    }

    #[test]
    fn a_bad_focal_length_or_unknown_bone_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.json");
        sample().save(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let bad = text.replace("\"focal_px\": 1000.0", "\"focal_px\": -1.0");
        assert!(
            Skeleton3d::parse(&bad, &path)
                .unwrap_err()
                .to_string()
                .contains("focal_px")
        );
        let bad = text.replace("left_knee-left_ankle", "knee-ankle");
        assert!(
            Skeleton3d::parse(&bad, &path)
                .unwrap_err()
                .to_string()
                .contains("knee-ankle")
        );
    }
}
