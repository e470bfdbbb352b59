//! `keys.json`: joints placed by hand on any frames, the marks and every correction made since.
//!
//! `{"format":"videomocap.keys","version":1,"keys":[{"frame":0,"joints":{"head_top":[x,y],…}},
//! {"frame":42,"joints":{"left_wrist":[x,y]}}]}`. A key may hold any subset of the 16 joints;
//! the first key holding all 16 starts the track. A project file keeps its keys in the same
//! shape (its `keys` field).

use super::{
    FORMAT_VERSION, FormatError, FrameIndex, Marks, check_header, check_on_image, parse_json,
    read_text,
};
use crate::skeleton::{JOINT_COUNT, Joint, PerJoint};
use nalgebra::Point2;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The `format` tag of key files.
pub const KEYS_FORMAT: &str = "videomocap.keys";

/// Hand-placed joints per frame: the marks, and every correction made since.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KeyFrames {
    /// Per frame index, the joints placed by hand there.
    pub frames: BTreeMap<FrameIndex, PerJoint<Option<Point2<f64>>>>,
}

/// One key as files write it: a frame and the joints placed on it, by name.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct KeyEntry {
    pub(crate) frame: FrameIndex,
    pub(crate) joints: BTreeMap<String, [f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeysIn {
    format: Option<String>,
    version: Option<u32>,
    keys: Vec<KeyEntry>,
}

#[derive(Serialize)]
struct KeysOut {
    format: &'static str,
    version: u32,
    keys: Vec<KeyEntry>,
}

impl KeyFrames {
    /// Key frames from marks (all 16 joints on one frame).
    pub fn from_marks(marks: &Marks) -> KeyFrames {
        let mut frames = BTreeMap::new();
        frames.insert(marks.frame, marks.points.map(|_, p| Some(*p)));
        KeyFrames { frames }
    }

    /// Places one joint by hand on a frame (that frame becomes a key frame for the joint).
    pub fn set(&mut self, frame: FrameIndex, joint: Joint, pos: Point2<f64>) {
        self.frames
            .entry(frame)
            .or_insert_with(|| PerJoint([None; JOINT_COUNT]))[joint] = Some(pos);
    }

    /// Whether a joint was placed by hand on a frame.
    pub fn is_key(&self, frame: FrameIndex, joint: Joint) -> bool {
        self.frames
            .get(&frame)
            .is_some_and(|joints| joints[joint].is_some())
    }

    /// The first frame holding all 16 joints, and its pose: where tracking starts.
    pub fn first_full(&self) -> Option<(FrameIndex, PerJoint<Point2<f64>>)> {
        self.frames.iter().find_map(|(f, joints)| {
            let all: Option<Vec<Point2<f64>>> = joints.0.iter().copied().collect();
            all.map(|v| (*f, PerJoint::from_fn(|j| v[j.index()])))
        })
    }

    /// Reads and checks a keys file (format, version, joint names, finite numbers, no joint
    /// placed twice on one frame at two places).
    pub fn load(path: &Path) -> Result<KeyFrames, FormatError> {
        KeyFrames::parse(&read_text(path)?, path)
    }

    /// Parses keys JSON; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<KeyFrames, FormatError> {
        let raw: KeysIn = parse_json(text, path)?;
        check_header(path, KEYS_FORMAT, raw.format.as_deref(), raw.version)?;
        KeyFrames::from_entries(raw.keys, path)
    }

    /// Keys from their file entries, checked: known joints, finite numbers, and a joint listed
    /// again on a frame only at the same place.
    pub(crate) fn from_entries(
        entries: Vec<KeyEntry>,
        path: &Path,
    ) -> Result<KeyFrames, FormatError> {
        let mut keys = KeyFrames::default();
        for k in entries {
            for (name, [x, y]) in k.joints {
                let joint = Joint::from_name(&name).ok_or_else(|| FormatError::UnknownJoint {
                    path: path.to_owned(),
                    name: name.clone(),
                })?;
                if !(x.is_finite() && y.is_finite()) {
                    return Err(FormatError::NonFinite {
                        path: path.to_owned(),
                        joint,
                        frame: Some(k.frame),
                    });
                }
                let pos = Point2::new(x, y);
                if let Some(was) = keys.frames.get(&k.frame).and_then(|f| f[joint])
                    && (was - pos).norm() > 1e-9
                {
                    return Err(FormatError::Invalid {
                        path: path.to_owned(),
                        problem: format!(
                            "frame {}: joint {joint} is placed twice, at ({:.1}, {:.1}) and ({x:.1}, {y:.1})",
                            k.frame, was.x, was.y
                        ),
                    });
                }
                keys.set(k.frame, joint, pos);
            }
        }
        Ok(keys)
    }

    /// The keys as file entries, frames ascending, joints by name.
    pub(crate) fn entries(&self) -> Vec<KeyEntry> {
        self.frames
            .iter()
            .map(|(&frame, joints)| KeyEntry {
                frame,
                joints: joints
                    .iter()
                    .filter_map(|(j, p)| p.map(|p| (j.name().to_owned(), [p.x, p.y])))
                    .collect(),
            })
            .collect()
    }

    /// Checks the keys against a video of `frames` frames of `width × height`: every key on a
    /// frame of the video, every point on the image, and one key holding all 16 joints.
    pub fn check_in_video(
        &self,
        path: &Path,
        width: u32,
        height: u32,
        frames: usize,
    ) -> Result<(), FormatError> {
        for (&frame, joints) in &self.frames {
            if frame.get() >= frames {
                return Err(FormatError::Invalid {
                    path: path.to_owned(),
                    problem: format!(
                        "a key is on frame {frame} but the video has {frames} frames (0–{})",
                        frames.saturating_sub(1)
                    ),
                });
            }
            for (joint, p) in joints.iter() {
                if let Some(p) = p {
                    check_on_image(path, joint, p, (width, height), frame)?;
                }
            }
        }
        if self.first_full().is_none() {
            return Err(FormatError::Invalid {
                path: path.to_owned(),
                problem: "no key holds all 16 joints (the first full key starts the track)".into(),
            });
        }
        Ok(())
    }

    /// The JSON text of a keys file.
    pub fn to_json(&self) -> String {
        let out = KeysOut {
            format: KEYS_FORMAT,
            version: FORMAT_VERSION,
            keys: self.entries(),
        };
        // Invariant: string keys and f64 values always serialise.
        let mut text = serde_json::to_string_pretty(&out).unwrap_or_default();
        text.push('\n');
        text
    }

    /// Saves atomically.
    pub fn save(&self, path: &Path) -> Result<(), FormatError> {
        super::write_atomically(path, self.to_json().as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn full(frame: usize) -> String {
        let joints: Vec<String> = Joint::ALL
            .iter()
            .map(|j| format!("\"{}\": [{}, {}]", j.name(), 10 + j.index(), 20 + j.index()))
            .collect();
        format!(
            "{{\"frame\": {frame}, \"joints\": {{{}}}}}",
            joints.join(", ")
        )
    }

    fn file(keys: &[String]) -> String {
        format!(
            "{{\"format\": \"videomocap.keys\", \"version\": 1, \"keys\": [{}]}}",
            keys.join(", ")
        )
    }

    #[test]
    fn keys_round_trip_and_a_partial_key_adds_to_a_frame() {
        let p = Path::new("keys.json");
        let text = file(&[
            full(3),
            "{\"frame\": 42, \"joints\": {\"left_wrist\": [5.5, 6.25]}}".into(),
        ]);
        let keys = KeyFrames::parse(&text, p).expect("valid keys");
        assert_eq!(keys.frames.len(), 2);
        assert_eq!(keys.first_full().map(|k| k.0), Some(FrameIndex(3)));
        assert!(
            keys.is_key(FrameIndex(42), Joint::LeftWrist)
                && !keys.is_key(FrameIndex(42), Joint::Neck)
        );
        let again = KeyFrames::parse(&keys.to_json(), p).expect("written keys read back");
        assert_eq!(again, keys);
        keys.check_in_video(p, 100, 100, 50).expect("keys fit");
    }

    #[test]
    fn bad_keys_are_errors_that_name_the_file_and_the_problem() {
        let p = Path::new("k.json");
        let err = |text: String| {
            KeyFrames::parse(&text, p)
                .and_then(|k| k.check_in_video(p, 100, 100, 50).map(|_| k))
                .expect_err("refused")
                .to_string()
        };
        let unknown = err(file(&[
            full(0),
            "{\"frame\": 2, \"joints\": {\"nose\": [1, 2]}}".into(),
        ]));
        assert!(
            unknown.contains("k.json") && unknown.contains("nose"),
            "{unknown}"
        );
        let late = err(file(&[
            full(0),
            "{\"frame\": 50, \"joints\": {\"neck\": [1, 2]}}".into(),
        ]));
        assert!(
            late.contains("frame 50") && late.contains("50 frames"),
            "{late}"
        );
        let outside = err(file(&[
            full(0),
            "{\"frame\": 5, \"joints\": {\"neck\": [1, 200]}}".into(),
        ]));
        assert!(
            outside.contains("outside") && outside.contains("frame 5"),
            "{outside}"
        );
        let twice = err(file(&[
            full(0),
            "{\"frame\": 5, \"joints\": {\"neck\": [1, 2]}}".into(),
            "{\"frame\": 5, \"joints\": {\"neck\": [3, 2]}}".into(),
        ]));
        assert!(
            twice.contains("placed twice") && twice.contains("neck"),
            "{twice}"
        );
        let no_full = err(file(&[
            "{\"frame\": 5, \"joints\": {\"neck\": [1, 2]}}".into()
        ]));
        assert!(no_full.contains("all 16"), "{no_full}");
        let wrong = err("{\"format\": \"videomocap.marks\", \"version\": 1, \"keys\": []}".into());
        assert!(wrong.contains("videomocap.keys"), "{wrong}");
    }
}
