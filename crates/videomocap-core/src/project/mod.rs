//! A project: the video, every joint placed by hand (marks and corrections), the settings, the
//! depth choices the user flipped, and the results (tracks, 3D skeleton). The desktop app edits
//! one; it is saved atomically as `videomocap.project` JSON (documented in `docs/formats.md`) and
//! autosaved beside the work. [`History`] gives undo and redo over whole projects.

mod history;

pub use history::History;

use crate::formats::{
    FORMAT_VERSION, FormatError, FrameIndex, KeyEntry, KeyFrames, LENGTH_RANGE_M, Skeleton3d,
    TapeLengths, Tracks2d, parse_json, read_text, write_atomically,
};
use crate::lift::{DepthOverrides, LiftParams, Root};
use crate::skeleton::Bone;
use crate::track::TrackerParams;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The `format` tag of project files.
pub const PROJECT_FORMAT: &str = "videomocap.project";

/// Default stature of the subject when none is given, metres.
pub const DEFAULT_HEIGHT_M: f64 = 1.70;

/// Settings a project keeps with it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Tracker settings.
    pub tracker: TrackerParams,
    /// Focal length in pixels; `None` = the default (60° across the longer image side).
    pub focal_px: Option<f64>,
    /// The subject's stature, metres (scales the bone lengths).
    pub height_m: f64,
    /// Lift settings, as in the command line's `--lift-settings` file.
    pub lift: LiftParams,
    /// Lengths the user measured on the subject (as the command line's `--lengths` file).
    pub lengths: TapeLengths,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            tracker: TrackerParams::default(),
            focal_px: None,
            height_m: DEFAULT_HEIGHT_M,
            lift: LiftParams::default(),
            lengths: TapeLengths::default(),
        }
    }
}

/// Everything the user made for one video. Cheap to clone (results are shared), so undo keeps
/// whole projects.
#[derive(Debug, Clone, PartialEq)]
pub struct Project {
    /// The video or image folder.
    pub video: PathBuf,
    /// Joints placed by hand, per frame.
    pub keys: KeyFrames,
    /// Settings.
    pub settings: Settings,
    /// Depth choices forced by the user (clicking a limb in the 3D view).
    pub overrides: DepthOverrides,
    /// The tracks, once tracked.
    pub tracks: Option<Arc<Tracks2d>>,
    /// The 3D skeleton, once lifted.
    pub skeleton: Option<Arc<Skeleton3d>>,
}

impl Project {
    /// An empty project on a video.
    pub fn new(video: PathBuf) -> Project {
        Project {
            video,
            keys: KeyFrames::default(),
            settings: Settings::default(),
            overrides: DepthOverrides::default(),
            tracks: None,
            skeleton: None,
        }
    }

    /// The first frame with all 16 joints placed (the marks), if any.
    pub fn marks(&self) -> Option<crate::formats::Marks> {
        self.keys
            .first_full()
            .map(|(frame, points)| crate::formats::Marks { frame, points })
    }

    /// Reads a project file.
    pub fn load(path: &Path) -> Result<Project, FormatError> {
        Project::parse(&read_text(path)?, path)
    }

    /// Parses project JSON; `path` names the file in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Project, FormatError> {
        let raw: ProjectFile = parse_json(text, path)?;
        check_header(path, &raw)?;
        let keys = KeyFrames::from_entries(raw.keys, path)?;
        let overrides = parse_overrides(path, raw.depth_overrides)?;
        check_settings(path, &raw.settings)?;
        let tracks = raw
            .tracks
            .map(|v| Tracks2d::from_json_value(v, path).map(Arc::new))
            .transpose()?;
        let skeleton = raw
            .skeleton
            .map(|v| Skeleton3d::from_json_value(v, path).map(Arc::new))
            .transpose()?;
        Ok(Project {
            video: raw.video,
            keys,
            settings: raw.settings,
            overrides,
            tracks,
            skeleton,
        })
    }

    /// The project as JSON text.
    pub fn to_json(&self) -> String {
        let file = ProjectFile {
            format: PROJECT_FORMAT.to_owned(),
            version: FORMAT_VERSION,
            video: self.video.clone(),
            settings: self.settings,
            keys: self.keys.entries(),
            depth_overrides: self
                .overrides
                .iter()
                .map(|(&(frame, bone), root)| OverrideFile {
                    frame,
                    bone: bone.key(),
                    root: match root {
                        Root::Near => "near",
                        Root::Far => "far",
                    }
                    .to_owned(),
                })
                .collect(),
            tracks: self.tracks.as_ref().map(|t| t.to_json_value()),
            skeleton: self.skeleton.as_ref().map(|s| s.to_json_value()),
        };
        // Plain numbers, strings, maps: serialising cannot fail.
        let mut text = serde_json::to_string_pretty(&file).unwrap_or_default();
        text.push('\n');
        text
    }

    /// Saves atomically (temporary file, fsync, rename): a crash leaves the old or the new file.
    pub fn save(&self, path: &Path) -> Result<(), FormatError> {
        write_atomically(path, self.to_json().as_bytes())
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProjectFile {
    format: String,
    version: u32,
    video: PathBuf,
    #[serde(default)]
    settings: Settings,
    #[serde(default)]
    keys: Vec<KeyEntry>,
    #[serde(default)]
    depth_overrides: Vec<OverrideFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tracks: Option<serde_json::Value>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    skeleton: Option<serde_json::Value>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct OverrideFile {
    frame: FrameIndex,
    bone: String,
    root: String,
}

/// Refuses another format or version.
fn check_header(path: &Path, raw: &ProjectFile) -> Result<(), FormatError> {
    if raw.format != PROJECT_FORMAT {
        return Err(FormatError::WrongFormat {
            path: path.to_owned(),
            found: raw.format.clone(),
            expected: PROJECT_FORMAT,
        });
    }
    if raw.version != FORMAT_VERSION {
        return Err(FormatError::UnsupportedVersion {
            path: path.to_owned(),
            version: raw.version,
            supported: FORMAT_VERSION,
        });
    }
    Ok(())
}

/// A problem with the project file's contents.
fn invalid(path: &Path, problem: String) -> FormatError {
    FormatError::Invalid {
        path: path.to_owned(),
        problem,
    }
}

/// The "flip this limb" choices, each a known bone and `near` or `far`.
fn parse_overrides(path: &Path, entries: Vec<OverrideFile>) -> Result<DepthOverrides, FormatError> {
    let mut overrides = DepthOverrides::default();
    for o in entries {
        let bone = Bone::from_key(&o.bone).ok_or_else(|| {
            invalid(
                path,
                format!("unknown bone \"{}\" in depth_overrides", o.bone),
            )
        })?;
        let root = match o.root.as_str() {
            "near" => Root::Near,
            "far" => Root::Far,
            other => {
                return Err(invalid(
                    path,
                    format!("depth override root must be \"near\" or \"far\", not \"{other}\""),
                ));
            }
        };
        overrides.insert((o.frame, bone), root);
    }
    Ok(overrides)
}

/// Refuses a height, a known length or a focal length out of range, and tracker or lift
/// settings their own checks refuse.
fn check_settings(path: &Path, settings: &Settings) -> Result<(), FormatError> {
    let height = settings.height_m;
    if !(height.is_finite() && (0.5..=2.8).contains(&height)) {
        return Err(invalid(
            path,
            format!("settings.height_m must be between 0.5 and 2.8 m (got {height})"),
        ));
    }
    let mut tape = settings.lengths;
    for (name, value) in tape.fields_mut() {
        if let Some(v) = *value
            && !(v.is_finite() && (LENGTH_RANGE_M.0..=LENGTH_RANGE_M.1).contains(&v))
        {
            return Err(invalid(
                path,
                format!(
                    "settings.lengths: the {name} must be between {} and {} m (got {v})",
                    LENGTH_RANGE_M.0, LENGTH_RANGE_M.1
                ),
            ));
        }
    }
    if let Some(f) = settings.focal_px
        && !(f.is_finite() && f > 0.0)
    {
        return Err(invalid(
            path,
            format!("settings.focal_px must be positive (got {f})"),
        ));
    }
    settings
        .tracker
        .validate()
        .map_err(|e| invalid(path, format!("settings.tracker: {e}")))?;
    settings
        .lift
        .validate()
        .map_err(|e| invalid(path, format!("settings.lift: {e}")))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::Joint;
    use nalgebra::Point2;

    #[test]
    fn a_project_round_trips_through_its_file() {
        let mut p = Project::new(PathBuf::from("clip.mp4"));
        p.keys
            .set(FrameIndex(0), Joint::Neck, Point2::new(10.5, 20.25));
        p.keys
            .set(FrameIndex(7), Joint::LeftWrist, Point2::new(1.0, 2.0));
        p.overrides.insert(
            (FrameIndex(3), Bone::new(Joint::LeftElbow, Joint::LeftWrist)),
            Root::Far,
        );
        p.settings.height_m = 1.82;
        p.settings.focal_px = Some(900.0);
        p.settings.lift.refine = false;
        p.settings.lift.hands_outside_body = 3.0;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.json");
        p.save(&path).unwrap();
        assert_eq!(Project::load(&path).unwrap(), p);
    }

    /// A project saved before the lift's settings were cut to eight opens: the kept ones
    /// carried over under their new names, the retired ones dropped.
    #[test]
    fn a_project_with_the_old_lift_settings_opens() {
        let mut p = Project::new(PathBuf::from("clip.mp4"));
        p.settings.lift.hands_outside_body = 3.0;
        p.settings.lift.steady_trunk = false;
        let new = p.to_json();
        let lift = new.index_of_lift();
        let old = format!(
            "{}{}{}",
            &new[..lift.0],
            r#""lift": {"refine": true, "calibration_tolerance_px": 1.0, "key_path_smoothing": false,
               "adaptive_smoothing": true, "ambiguity": {"elbow": 5.0, "contact": 3.0},
               "refinement": {"max_iterations": 20}}"#,
            &new[lift.1..]
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("old.json");
        std::fs::write(&path, old).unwrap();
        assert_eq!(Project::load(&path).unwrap(), p);
    }

    /// Where the `"lift": {…}` entry lies in a project's text.
    trait LiftEntry {
        fn index_of_lift(&self) -> (usize, usize);
    }

    impl LiftEntry for String {
        fn index_of_lift(&self) -> (usize, usize) {
            let start = self.find("\"lift\":").unwrap();
            let open = start + self[start..].find('{').unwrap();
            let mut depth = 0;
            for (k, c) in self[open..].char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            return (start, open + k + 1);
                        }
                    }
                    _ => {}
                }
            }
            panic!("unclosed lift entry");
        }
    }

    #[test]
    fn bad_projects_are_named() {
        let path = Path::new("bad.videomocap");
        let base = Project::new(PathBuf::from("clip.mp4")).to_json();
        let cases = [
            (base.replace("1.7", "9.0"), "height_m"),
            (
                base.replace("videomocap.project", "videomocap.tracks2d"),
                "videomocap.tracks2d",
            ),
            (
                base.replace(
                    "\"keys\": []",
                    "\"keys\": [{\"frame\": 1, \"joints\": {\"nose\": [1, 2]}}]",
                ),
                "nose",
            ),
            ("{".to_owned(), "bad.videomocap"),
            // A weight below 0 would reward the posture its prior forbids.
            (
                base.replace(
                    "\"hands_outside_body\": 10.0",
                    "\"hands_outside_body\": -1.0",
                ),
                "hands_outside_body",
            ),
            // The tracker's settings are checked too (a reliability threshold above 1 would
            // make every joint weak).
            (
                base.replace("\"weak_reliability\": 0.45", "\"weak_reliability\": 1.5"),
                "settings.tracker: tracker setting \"weak_reliability\"",
            ),
        ];
        for (text, needle) in cases {
            let err = Project::parse(&text, path).unwrap_err().to_string();
            assert!(
                err.contains(needle) && err.contains("bad.videomocap"),
                "{err}"
            );
        }
    }
}
