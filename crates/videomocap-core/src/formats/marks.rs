//! `marks.json`: the 16 joints placed by hand on one frame, the tracker's starting point.
//!
//! `{"format":"videomocap.marks","version":1,"frame":0,"joints":{"head_top":[x,y],…}}`

use super::{
    FORMAT_VERSION, FormatError, FrameIndex, check_header, check_on_image, parse_json, read_text,
    write_atomically,
};
use crate::skeleton::{JOINT_COUNT, Joint, PerJoint};
use nalgebra::Point2;
use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize, Serializer};
use std::collections::BTreeMap;
use std::path::Path;

/// The `format` tag of marks files.
pub const MARKS_FORMAT: &str = "videomocap.marks";

/// Hand-placed image positions of all 16 joints on one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Marks {
    /// The frame the marks were placed on (0-based).
    pub frame: FrameIndex,
    /// Each joint's position in image pixels.
    pub points: PerJoint<Point2<f64>>,
}

#[derive(Deserialize)]
struct MarksIn {
    format: Option<String>,
    version: Option<u32>,
    #[serde(default)]
    frame: FrameIndex,
    joints: BTreeMap<String, [f64; 2]>,
}

#[derive(Serialize)]
struct MarksOut<'a> {
    format: &'static str,
    version: u32,
    frame: FrameIndex,
    joints: JointsInOrder<'a>,
}

/// Writes the joints as a JSON object in model order (not alphabetical).
struct JointsInOrder<'a>(&'a PerJoint<Point2<f64>>);

impl Serialize for JointsInOrder<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(JOINT_COUNT))?;
        for (joint, p) in self.0.iter() {
            map.serialize_entry(joint.name(), &[p.x, p.y])?;
        }
        map.end()
    }
}

impl Marks {
    /// Reads and checks a marks file: known format and version, all 16 joints, finite numbers.
    pub fn load(path: &Path) -> Result<Self, FormatError> {
        Self::parse(&read_text(path)?, path)
    }

    /// Parses marks from JSON text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, FormatError> {
        let raw: MarksIn = parse_json(text, path)?;
        check_header(path, MARKS_FORMAT, raw.format.as_deref(), raw.version)?;
        for name in raw.joints.keys() {
            if Joint::from_name(name).is_none() {
                return Err(FormatError::UnknownJoint {
                    path: path.to_owned(),
                    name: name.clone(),
                });
            }
        }
        let mut points = PerJoint([Point2::origin(); JOINT_COUNT]);
        for joint in Joint::ALL {
            let [x, y] =
                *raw.joints
                    .get(joint.name())
                    .ok_or_else(|| FormatError::MissingJoint {
                        path: path.to_owned(),
                        joint,
                        frame: None,
                    })?;
            if !(x.is_finite() && y.is_finite()) {
                return Err(FormatError::NonFinite {
                    path: path.to_owned(),
                    joint,
                    frame: None,
                });
            }
            points[joint] = Point2::new(x, y);
        }
        Ok(Marks {
            frame: raw.frame,
            points,
        })
    }

    /// Checks that every mark lies on a `width × height` frame; names the first one that does not.
    pub fn check_in_frame(&self, path: &Path, width: u32, height: u32) -> Result<(), FormatError> {
        for (joint, p) in self.points.iter() {
            check_on_image(path, joint, p, (width, height), self.frame)?;
        }
        Ok(())
    }

    /// The JSON text of the file (joints in model order).
    pub fn to_json(&self) -> String {
        let out = MarksOut {
            format: MARKS_FORMAT,
            version: FORMAT_VERSION,
            frame: self.frame,
            joints: JointsInOrder(&self.points),
        };
        // Invariant: string keys and f64 values always serialise (non-finite ones as null).
        serde_json::to_string_pretty(&out).unwrap_or_default()
    }

    /// Saves atomically.
    pub fn save(&self, path: &Path) -> Result<(), FormatError> {
        let mut text = self.to_json();
        text.push('\n');
        write_atomically(path, text.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Marks {
        Marks {
            frame: FrameIndex(3),
            points: PerJoint::from_fn(|j| Point2::new(10.0 + j.index() as f64, 20.5)),
        }
    }

    #[test]
    fn save_and_load_round_trip_in_model_order() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("marks.json");
        sample().save(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.find("head_top").unwrap() < text.find("right_ankle").unwrap());
        assert!(text.contains("\"version\": 1"));
        assert_eq!(Marks::load(&path).unwrap(), sample());
    }

    #[test]
    fn header_fields_are_optional_on_read() {
        let mut joints = serde_json::Map::new();
        for j in Joint::ALL {
            joints.insert(j.name().into(), serde_json::json!([1.0, 2.0]));
        }
        let text = serde_json::json!({ "joints": joints }).to_string();
        let m = Marks::parse(&text, Path::new("m.json")).unwrap();
        assert_eq!(m.frame, FrameIndex(0));
    }

    #[test]
    fn a_missing_joint_is_named() {
        let text = sample()
            .to_json()
            .replace("\"left_knee\"", "\"left_knee_x\"");
        let err = Marks::parse(&text, Path::new("m.json"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("m.json") && err.contains("left_knee_x"),
            "{err}"
        );
        let mut m: serde_json::Value = serde_json::from_str(&sample().to_json()).unwrap();
        m["joints"].as_object_mut().unwrap().remove("neck");
        let err = Marks::parse(&m.to_string(), Path::new("m.json"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("joint neck is missing"), "{err}");
    }

    #[test]
    fn wrong_format_or_version_is_refused() {
        let t = sample()
            .to_json()
            .replace("videomocap.marks", "videomocap.tracks2d");
        assert!(matches!(
            Marks::parse(&t, Path::new("m.json")),
            Err(FormatError::WrongFormat { .. })
        ));
        let t = sample()
            .to_json()
            .replace("\"version\": 1", "\"version\": 7");
        assert!(matches!(
            Marks::parse(&t, Path::new("m.json")),
            Err(FormatError::UnsupportedVersion { version: 7, .. })
        ));
    }

    #[test]
    fn a_point_outside_the_frame_is_named() {
        let mut m = sample();
        m.points[Joint::RightWrist] = Point2::new(700.0, 10.0);
        let err = m
            .check_in_frame(Path::new("m.json"), 640, 480)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("right_wrist") && err.contains("640×480"),
            "{err}"
        );
        assert!(
            sample()
                .check_in_frame(Path::new("m.json"), 640, 480)
                .is_ok()
        );
    }
}
