//! Body proportions (bone lengths and breadths as fractions of stature) and the per-subject model.
//!
//! The defaults live in `assets/proportions.json` (with their anthropometric source) and are
//! compiled in; a subject overrides them with a height or with measured bone lengths.

use super::bone::{BONE_COUNT, BodyPart, Bone, Breadth};
use super::joint::Joint;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The compiled-in default proportions file.
const DEFAULT_PROPORTIONS_JSON: &str = include_str!("../../../../assets/proportions.json");

/// Stature used when the user gives none: 1.70 m, close to the adult mean of both sexes
/// (NCD-RisC 2016: 1.76 m men, 1.63 m women in high-income countries).
pub const DEFAULT_HEIGHT_M: f64 = 1.70;

/// Errors reading or checking a proportions or subject file.
#[derive(Debug, thiserror::Error)]
pub enum ProportionsError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a valid proportions file: {source}")]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error(
        "{path}: unknown bone \"{key}\" (bones are written \"parent-child\", e.g. \"left_knee-left_ankle\")"
    )]
    UnknownBone { path: PathBuf, key: String },
    #[error("{path}: bone \"{key}\" is missing")]
    MissingBone { path: PathBuf, key: String },
    #[error("{path}: value of \"{key}\" must be a positive finite number, got {value}")]
    NotPositive {
        path: PathBuf,
        key: String,
        value: f64,
    },
    #[error("height must be a positive finite number of metres, got {0}")]
    BadHeight(f64),
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct ProportionsFile {
    #[serde(default)]
    source: String,
    bones: BTreeMap<String, f64>,
    shoulder_width: f64,
    widths: BreadthsFile,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
struct BreadthsFile {
    head: f64,
    trunk: f64,
    upper_arm: f64,
    forearm: f64,
    thigh: f64,
    shank: f64,
}

/// Proportions of a body as fractions of its stature.
#[derive(Debug, Clone, PartialEq)]
pub struct Proportions {
    /// Length of each bone of [`Bone::ALL`], as a fraction of stature.
    pub bone_fraction: [f64; BONE_COUNT],
    /// Distance between the two shoulder joints (the key triangle's third side), fraction of stature.
    pub shoulder_width_fraction: f64,
    /// Breadth of each body part, fraction of stature.
    breadths: BreadthsFile,
    /// Where the numbers come from.
    pub source: String,
}

impl Default for Proportions {
    /// The compiled-in table of `assets/proportions.json`.
    fn default() -> Self {
        // Invariant: the embedded asset is checked by the unit test below.
        #[allow(clippy::expect_used)]
        Proportions::from_json(
            DEFAULT_PROPORTIONS_JSON,
            Path::new("assets/proportions.json"),
        )
        .expect("embedded assets/proportions.json is valid")
    }
}

impl Proportions {
    /// Reads a proportions file (same layout as `assets/proportions.json`).
    pub fn load(path: &Path) -> Result<Self, ProportionsError> {
        let text = std::fs::read_to_string(path).map_err(|source| ProportionsError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::from_json(&text, path)
    }

    fn from_json(text: &str, path: &Path) -> Result<Self, ProportionsError> {
        let file: ProportionsFile =
            serde_json::from_str(text).map_err(|source| ProportionsError::Json {
                path: path.to_owned(),
                source,
            })?;
        let positive = |key: &str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(value)
            } else {
                Err(ProportionsError::NotPositive {
                    path: path.to_owned(),
                    key: key.to_owned(),
                    value,
                })
            }
        };
        for key in file.bones.keys() {
            if Bone::from_key(key).is_none() {
                return Err(ProportionsError::UnknownBone {
                    path: path.to_owned(),
                    key: key.clone(),
                });
            }
        }
        let mut bone_fraction = [0.0; BONE_COUNT];
        for (i, bone) in Bone::ALL.iter().enumerate() {
            let key = bone.key();
            let value = *file
                .bones
                .get(&key)
                .ok_or_else(|| ProportionsError::MissingBone {
                    path: path.to_owned(),
                    key: key.clone(),
                })?;
            bone_fraction[i] = positive(&key, value)?;
        }
        let w = file.widths;
        for (key, value) in [
            ("widths.head", w.head),
            ("widths.trunk", w.trunk),
            ("widths.upper_arm", w.upper_arm),
            ("widths.forearm", w.forearm),
            ("widths.thigh", w.thigh),
            ("widths.shank", w.shank),
        ] {
            positive(key, value)?;
        }
        Ok(Proportions {
            bone_fraction,
            shoulder_width_fraction: positive("shoulder_width", file.shoulder_width)?,
            breadths: w,
            source: file.source,
        })
    }

    /// Length of the bone joining two joints (in either order) as a fraction of stature; 0 when
    /// no bone joins them.
    pub fn fraction_between(&self, a: Joint, b: Joint) -> f64 {
        Bone::ALL
            .iter()
            .position(|bone| {
                (bone.parent == a && bone.child == b) || (bone.parent == b && bone.child == a)
            })
            .map_or(0.0, |i| self.bone_fraction[i])
    }

    /// Breadth of a body part as a fraction of stature.
    pub fn breadth_fraction(&self, breadth: Breadth) -> f64 {
        let w = &self.breadths;
        match breadth {
            Breadth::Head => w.head,
            Breadth::Trunk => w.trunk,
            Breadth::UpperArm => w.upper_arm,
            Breadth::Forearm => w.forearm,
            Breadth::Thigh => w.thigh,
            Breadth::Shank => w.shank,
        }
    }
}

/// One subject's body: stature and metric bone lengths, from proportions or measurements.
#[derive(Debug, Clone, PartialEq)]
pub struct SubjectModel {
    /// Stature in metres.
    pub height_m: f64,
    /// Length of each bone of [`Bone::ALL`] in metres.
    pub bone_length_m: [f64; BONE_COUNT],
    /// Distance between the shoulder joints in metres.
    pub shoulder_width_m: f64,
    /// How uncertain each bone's length is, as a share of it (0: known exactly). The lift leans
    /// an uncertain bone towards lying square to its viewing ray: it solves with the bone this
    /// share shorter and gives it back its length along the direction found
    /// ([`SubjectModel::leaning`]).
    pub length_doubt: [f64; BONE_COUNT],
    /// The proportions the lengths were scaled from (for breadths).
    pub proportions: Proportions,
}

impl SubjectModel {
    /// A subject of the given stature with the given proportions.
    pub fn from_height(height_m: f64, proportions: Proportions) -> Result<Self, ProportionsError> {
        if !(height_m.is_finite() && height_m > 0.0) {
            return Err(ProportionsError::BadHeight(height_m));
        }
        Ok(SubjectModel {
            height_m,
            bone_length_m: proportions.bone_fraction.map(|f| f * height_m),
            shoulder_width_m: proportions.shoulder_width_fraction * height_m,
            length_doubt: [0.0; BONE_COUNT],
            proportions,
        })
    }

    /// Replaces some bone lengths by measured ones (metres), keyed like [`Bone::key`].
    pub fn with_bone_lengths(
        mut self,
        lengths: &BTreeMap<String, f64>,
        origin: &Path,
    ) -> Result<Self, ProportionsError> {
        for (key, &value) in lengths {
            let Some(bone) = Bone::from_key(key) else {
                return Err(ProportionsError::UnknownBone {
                    path: origin.to_owned(),
                    key: key.clone(),
                });
            };
            if !(value.is_finite() && value > 0.0) {
                return Err(ProportionsError::NotPositive {
                    path: origin.to_owned(),
                    key: key.clone(),
                    value,
                });
            }
            self.bone_length_m[bone.index()] = value;
        }
        Ok(self)
    }

    /// Length of one bone in metres.
    pub fn bone_length(&self, bone: Bone) -> f64 {
        self.bone_length_m[bone.index()]
    }

    /// The trunk's length, neck to pelvis, in metres: chest–neck plus pelvis–chest (the chest
    /// lies on the line between neck and pelvis by its definition).
    pub fn trunk_m(&self) -> f64 {
        self.length_to(Joint::Neck) + self.length_to(Joint::Chest)
    }

    /// Length of the bone ending at `child` in metres (0 for the pelvis).
    pub fn length_to(&self, child: Joint) -> f64 {
        Bone::to(child).map_or(0.0, |b| self.bone_length(b))
    }

    /// Breadth of a body part in metres.
    pub fn breadth_m(&self, part: BodyPart) -> f64 {
        self.proportions.breadth_fraction(part.breadth()) * self.height_m
    }

    /// The subject the lift solves with: every bone shorter by its [`SubjectModel::length_doubt`]
    /// (and no doubt left).
    pub fn leaning(&self) -> SubjectModel {
        let mut out = self.clone();
        for (l, d) in out.bone_length_m.iter_mut().zip(&self.length_doubt) {
            *l *= 1.0 - d;
        }
        out.length_doubt = [0.0; BONE_COUNT];
        out
    }

    /// Bone lengths keyed `"parent-child"`, as written in skeleton3d files.
    pub fn bone_lengths_by_key(&self) -> BTreeMap<String, f64> {
        Bone::ALL
            .iter()
            .map(|b| (b.key(), self.bone_length(*b)))
            .collect()
    }
}

impl Default for SubjectModel {
    /// A subject of [`DEFAULT_HEIGHT_M`] with the default proportions.
    fn default() -> Self {
        let proportions = Proportions::default();
        SubjectModel {
            height_m: DEFAULT_HEIGHT_M,
            bone_length_m: proportions.bone_fraction.map(|f| f * DEFAULT_HEIGHT_M),
            shoulder_width_m: proportions.shoulder_width_fraction * DEFAULT_HEIGHT_M,
            length_doubt: [0.0; BONE_COUNT],
            proportions,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_table_loads_and_stacks_to_a_plausible_stature() {
        let p = Proportions::default();
        let len = |a, b| p.bone_fraction[Bone::new(a, b).index()];
        // Standing straight: ankle up to head top along one leg and the spine.
        let stack = len(Joint::LeftKnee, Joint::LeftAnkle)
            + len(Joint::LeftHip, Joint::LeftKnee)
            + len(Joint::Pelvis, Joint::Chest)
            + len(Joint::Chest, Joint::Neck)
            + len(Joint::Neck, Joint::HeadTop);
        // Winter: ankle height is 0.039 H, so the stack is about 0.961 H.
        assert!((stack - 0.961).abs() < 0.005, "stack {stack}");
    }

    #[test]
    fn height_scales_every_bone() {
        let s = SubjectModel::from_height(2.0, Proportions::default()).unwrap();
        let b = Bone::new(Joint::LeftShoulder, Joint::LeftElbow);
        assert!((s.bone_length(b) - 0.372).abs() < 1e-12);
        assert!(SubjectModel::from_height(0.0, Proportions::default()).is_err());
        assert!(SubjectModel::from_height(f64::NAN, Proportions::default()).is_err());
    }

    #[test]
    fn measured_lengths_override_and_bad_keys_are_named() {
        let mut m = BTreeMap::new();
        m.insert("left_knee-left_ankle".to_owned(), 0.5);
        let s = SubjectModel::default()
            .with_bone_lengths(&m, Path::new("subject.json"))
            .unwrap();
        assert_eq!(s.length_to(Joint::LeftAnkle), 0.5);
        m.insert("knee-ankle".to_owned(), 0.5);
        let err = SubjectModel::default()
            .with_bone_lengths(&m, Path::new("subject.json"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("subject.json") && err.contains("knee-ankle"),
            "{err}"
        );
    }
}
