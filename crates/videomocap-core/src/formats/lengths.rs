//! `lengths.json`: bone lengths the user knows (measured on the subject, or read off a previous
//! lift), in metres, any subset.
//!
//! `{"pelvis-chest": 0.30, "left_knee-left_ankle": 0.42, "shoulder_width": 0.36}`: each key a
//! bone as skeleton3d files name it (`"parent-child"`), or `shoulder_width` (between the
//! shoulder joints); an optional `"format": "videomocap.lengths"` and `"version": 1`.

use super::{FormatError, check_header, parse_json, read_text};
use crate::skeleton::Bone;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The `format` tag of lengths files.
pub const LENGTHS_FORMAT: &str = "videomocap.lengths";

/// The key of the shoulder width in a lengths file.
pub const SHOULDER_WIDTH_KEY: &str = "shoulder_width";

/// The shortest and longest length a file may give, metres: a value outside is a slip of the
/// unit (centimetres or millimetres for metres), not a body.
pub const LENGTH_RANGE_M: (f64, f64) = (0.02, 1.2);

/// Lengths the user knows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KnownLengths {
    /// Bones, metres.
    pub bones: BTreeMap<Bone, f64>,
    /// The distance between the shoulder joints, metres.
    pub shoulder_width_m: Option<f64>,
}

impl KnownLengths {
    /// Whether nothing is known.
    pub fn is_empty(&self) -> bool {
        self.bones.is_empty() && self.shoulder_width_m.is_none()
    }

    /// Reads and checks a lengths file: known keys only, every value a length in metres within
    /// [`LENGTH_RANGE_M`].
    pub fn load(path: &Path) -> Result<Self, FormatError> {
        Self::parse(&read_text(path)?, path)
    }

    /// Parses lengths from JSON text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, FormatError> {
        let raw: serde_json::Map<String, serde_json::Value> = parse_json(text, path)?;
        let invalid = |problem: String| FormatError::Invalid {
            path: path.to_owned(),
            problem,
        };
        let format = match raw.get("format") {
            None => None,
            Some(v) => Some(
                v.as_str()
                    .ok_or_else(|| invalid("\"format\" must be a string".into()))?,
            ),
        };
        let version = match raw.get("version") {
            None => None,
            Some(v) => Some(
                v.as_u64()
                    .and_then(|v| u32::try_from(v).ok())
                    .ok_or_else(|| invalid("\"version\" must be a whole number".into()))?,
            ),
        };
        check_header(path, LENGTHS_FORMAT, format, version)?;
        let mut out = KnownLengths::default();
        for (key, value) in &raw {
            if key == "format" || key == "version" {
                continue;
            }
            let metres = value.as_f64().ok_or_else(|| {
                invalid(format!("\"{key}\" must be a length in metres, got {value}"))
            })?;
            if !(LENGTH_RANGE_M.0..=LENGTH_RANGE_M.1).contains(&metres) {
                return Err(invalid(format!(
                    "\"{key}\" is {metres} m: a bone's length in metres lies between {} and {} \
                     (centimetres written as metres?)",
                    LENGTH_RANGE_M.0, LENGTH_RANGE_M.1
                )));
            }
            if key == SHOULDER_WIDTH_KEY {
                out.shoulder_width_m = Some(metres);
            } else if let Some(bone) = Bone::from_key(key) {
                out.bones.insert(bone, metres);
            } else {
                return Err(invalid(format!(
                    "unknown bone \"{key}\" (a bone is \"parent-child\" as in skeleton3d files, \
                     e.g. \"left_knee-left_ankle\", or \"{SHOULDER_WIDTH_KEY}\"; see \
                     docs/formats.md)"
                )));
            }
        }
        Ok(out)
    }
}

/// The lengths a user can measure on a person with a tape (each side's, both sides alike), as
/// the desktop app keeps them in a project's settings: metres, `None` when not known.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TapeLengths {
    /// Neck to the top of the head.
    pub head: Option<f64>,
    /// Shoulder joint to elbow.
    pub upper_arm: Option<f64>,
    /// Elbow to wrist.
    pub forearm: Option<f64>,
    /// Hip joint to knee.
    pub thigh: Option<f64>,
    /// Knee to ankle.
    pub shank: Option<f64>,
    /// Between the two shoulder joints.
    pub shoulder_width: Option<f64>,
}

impl TapeLengths {
    /// Each field with its plain name, for a form.
    pub fn fields_mut(&mut self) -> [(&'static str, &mut Option<f64>); 6] {
        [
            ("head", &mut self.head),
            ("upper arm", &mut self.upper_arm),
            ("forearm", &mut self.forearm),
            ("thigh", &mut self.thigh),
            ("shank", &mut self.shank),
            ("shoulders apart", &mut self.shoulder_width),
        ]
    }

    /// The same lengths keyed by bone, both sides.
    pub fn known(&self) -> KnownLengths {
        use crate::skeleton::Joint::*;
        let mut out = KnownLengths {
            shoulder_width_m: self.shoulder_width,
            ..KnownLengths::default()
        };
        let pairs: [(Option<f64>, [Bone; 2]); 5] = [
            (self.head, [Bone::new(Neck, HeadTop); 2]),
            (
                self.upper_arm,
                [
                    Bone::new(LeftShoulder, LeftElbow),
                    Bone::new(RightShoulder, RightElbow),
                ],
            ),
            (
                self.forearm,
                [
                    Bone::new(LeftElbow, LeftWrist),
                    Bone::new(RightElbow, RightWrist),
                ],
            ),
            (
                self.thigh,
                [Bone::new(LeftHip, LeftKnee), Bone::new(RightHip, RightKnee)],
            ),
            (
                self.shank,
                [
                    Bone::new(LeftKnee, LeftAnkle),
                    Bone::new(RightKnee, RightAnkle),
                ],
            ),
        ];
        for (value, bones) in pairs {
            if let Some(v) = value {
                for b in bones {
                    out.bones.insert(b, v);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::Joint;

    #[test]
    fn a_subset_of_bones_and_the_shoulder_width_are_read() {
        let k = KnownLengths::parse(
            r#"{"format":"videomocap.lengths","version":1,"pelvis-chest":0.3,
                "left_knee-left_ankle":0.42,"shoulder_width":0.36}"#,
            Path::new("l.json"),
        )
        .unwrap();
        assert_eq!(k.bones.len(), 2);
        assert_eq!(k.bones[&Bone::new(Joint::Pelvis, Joint::Chest)], 0.3);
        assert_eq!(k.shoulder_width_m, Some(0.36));
        assert!(
            KnownLengths::parse("{}", Path::new("l.json"))
                .unwrap()
                .is_empty()
        );
    }

    #[test]
    fn tape_lengths_give_both_sides() {
        let tape = TapeLengths {
            thigh: Some(0.44),
            shoulder_width: Some(0.37),
            ..TapeLengths::default()
        };
        let k = tape.known();
        assert_eq!(k.bones[&Bone::new(Joint::LeftHip, Joint::LeftKnee)], 0.44);
        assert_eq!(k.bones[&Bone::new(Joint::RightHip, Joint::RightKnee)], 0.44);
        assert_eq!(k.bones.len(), 2);
        assert_eq!(k.shoulder_width_m, Some(0.37));
        assert!(TapeLengths::default().known().is_empty());
    }

    #[test]
    fn bad_files_name_the_file_and_the_problem() {
        for (text, needle) in [
            (r#"{"neck-pelvis":0.5}"#, "unknown bone \"neck-pelvis\""),
            (r#"{"pelvis-chest":30}"#, "centimetres"),
            (r#"{"pelvis-chest":"long"}"#, "must be a length in metres"),
            (
                r#"{"format":"videomocap.marks","pelvis-chest":0.3}"#,
                "expected",
            ),
            (r#"[0.3]"#, "not valid JSON"),
        ] {
            let e = KnownLengths::parse(text, Path::new("my_lengths.json")).unwrap_err();
            let msg = e.to_string();
            assert!(
                msg.contains("my_lengths.json") && msg.contains(needle),
                "{msg}"
            );
        }
    }
}
