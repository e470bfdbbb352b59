//! `tracks2d.json`: the tracker's output, every joint's image position per frame with its
//! reliability and its state: tracked, interpolated, off the frame or lost.

use super::{
    FormatError, FrameIndex, check_frame_order, check_header_up_to, joint_columns, joint_names,
    parse_json, read_text, save_json,
};
use crate::camera::point_in_frame;
use crate::skeleton::{Joint, PerJoint};
use nalgebra::{Point2, Vector3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The `format` tag of tracks2d files.
pub const TRACKS2D_FORMAT: &str = "videomocap.tracks2d";

/// The tracks2d version this build writes (it reads 1 to 4). Version 2 added `off_frame` (a
/// version 1 reader would refuse its points outside the frame) and `lost`; version 3 added
/// `gait` (a far limb completed from the gait by versions before 2026-11-28; read as
/// interpolated, no longer written); version 4 added `body3d` (the pose network's 3D body).
pub const TRACKS2D_VERSION: u32 = 4;

/// The video the tracks belong to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SourceInfo {
    /// The video file or image directory, as given when tracking.
    pub path: PathBuf,
    /// Frame width in pixels (after display rotation).
    pub width: u32,
    /// Frame height in pixels (after display rotation).
    pub height: u32,
    /// Frames per second.
    pub fps: f64,
    /// Number of frames in the video.
    pub frame_count: usize,
}

/// How a tracked point was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PointSource {
    /// Found in the image (or marked by hand).
    Tracked,
    /// Filled in between reliable frames (occlusion handling).
    Interpolated,
    /// Outside the image: the position is the tracker's estimate (the limb held at its last
    /// seen angle to its parent), its confidence 0; never interpolated across the frame.
    OffFrame,
    /// In a weak run too long to interpolate (or at an end of the video): the position is the
    /// tracker's guess, to be checked (a long occlusion, or a lost joint).
    Lost,
}

/// One joint in one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackedPoint {
    /// Position in image pixels (outside the frame only for [`PointSource::OffFrame`]).
    pub pos: Point2<f64>,
    /// Reliability in `[0, 1]` (the block similarity mapped to this range).
    pub confidence: f32,
    /// Tracked, interpolated, off the frame or lost.
    pub source: PointSource,
}

/// The pose network's 3D body on one frame: evidence for the lift's depth order, never the
/// answer.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkBody {
    /// Each joint in the network's body frame: metres, origin between the hips, x to the
    /// image's right, y down, z away from the camera.
    pub points: PerJoint<Vector3<f64>>,
    /// How sure the network is that each joint is there and seen, 0–1.
    pub confidence: PerJoint<f32>,
}

/// All 16 joints in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameTracks {
    /// Frame number in the video (0-based).
    pub index: FrameIndex,
    /// The joints.
    pub points: PerJoint<TrackedPoint>,
    /// The pose network's 3D body on this frame (`None`: tracked without the network, or it
    /// saw no person here). Boxed: most frames of most files have none.
    pub body3d: Option<Box<NetworkBody>>,
}

impl FrameTracks {
    /// The trunk's image length, neck to pelvis, pixels: the body's scale in this frame.
    pub fn torso_px(&self) -> f64 {
        (self.points[Joint::Neck].pos - self.points[Joint::Pelvis].pos).norm()
    }
}

/// A whole tracking result.
#[derive(Debug, Clone, PartialEq)]
pub struct Tracks2d {
    /// The video tracked.
    pub source: SourceInfo,
    /// Tracked frames in increasing index order.
    pub frames: Vec<FrameTracks>,
}

#[derive(Serialize, Deserialize)]
struct FrameFile {
    index: FrameIndex,
    points: Vec<[f64; 2]>,
    confidence: Vec<f32>,
    interpolated: Vec<bool>,
    /// Version 2; omitted when no joint of the frame is off it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    off_frame: Option<Vec<bool>>,
    /// Version 2; omitted when no joint of the frame is lost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lost: Option<Vec<bool>>,
    /// Version 3, read only: a far limb completed from the gait by versions before
    /// 2026-11-28, seen nowhere, migrated on load to an interpolated point.
    #[serde(default, skip_serializing)]
    gait: Option<Vec<bool>>,
    /// Version 4; omitted on frames without the network's body: per joint x, y, z (metres)
    /// and the network's confidence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    body3d: Option<Vec<[f64; 4]>>,
}

#[derive(Serialize, Deserialize)]
struct TracksFile {
    #[serde(default)]
    format: Option<String>,
    #[serde(default)]
    version: Option<u32>,
    source: SourceInfo,
    joints: Vec<String>,
    frames: Vec<FrameFile>,
}

impl Tracks2d {
    /// Reads and checks a tracks2d file.
    pub fn load(path: &Path) -> Result<Self, FormatError> {
        Self::parse(&read_text(path)?, path)
    }

    /// Parses tracks from JSON text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, FormatError> {
        let raw: TracksFile = parse_json(text, path)?;
        check_header_up_to(
            path,
            TRACKS2D_FORMAT,
            raw.format.as_deref(),
            raw.version,
            TRACKS2D_VERSION,
        )?;
        let columns = joint_columns(path, &raw.joints)?;
        let src = raw.source;
        check_source(path, &src)?;
        let mut frames = Vec::with_capacity(raw.frames.len());
        let mut previous: Option<FrameIndex> = None;
        for f in raw.frames {
            let flags = FrameFlags::of(path, &f, raw.joints.len())?;
            check_frame_order(path, &mut previous, f.index)?;
            let mut points = Vec::with_capacity(raw.joints.len());
            for joint in Joint::ALL {
                points.push(parse_point(
                    path,
                    &f,
                    &flags,
                    &src,
                    joint,
                    columns[joint.index()],
                )?);
            }
            frames.push(FrameTracks {
                index: f.index,
                points: PerJoint::from_fn(|j| points[j.index()]),
                body3d: parse_body3d(path, &f, &columns)?,
            });
        }
        Ok(Tracks2d {
            source: src,
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

    fn file(&self) -> TracksFile {
        TracksFile {
            format: Some(TRACKS2D_FORMAT.to_owned()),
            version: Some(TRACKS2D_VERSION),
            source: self.source.clone(),
            joints: joint_names(),
            frames: self
                .frames
                .iter()
                .map(|f| FrameFile {
                    index: f.index,
                    points: f.points.0.iter().map(|p| [p.pos.x, p.pos.y]).collect(),
                    confidence: f.points.0.iter().map(|p| p.confidence).collect(),
                    interpolated: f
                        .points
                        .0
                        .iter()
                        .map(|p| p.source == PointSource::Interpolated)
                        .collect(),
                    off_frame: flags(f, PointSource::OffFrame),
                    lost: flags(f, PointSource::Lost),
                    gait: None,
                    body3d: f.body3d.as_ref().map(|b| {
                        Joint::ALL
                            .map(|j| {
                                let p = b.points[j];
                                [p.x, p.y, p.z, f64::from(b.confidence[j])]
                            })
                            .to_vec()
                    }),
                })
                .collect(),
        }
    }
}

/// Per joint, whether its point has `source`; `None` when no point has it (the array is then
/// left out of the file).
fn flags(frame: &FrameTracks, source: PointSource) -> Option<Vec<bool>> {
    let flags: Vec<bool> = frame.points.0.iter().map(|p| p.source == source).collect();
    flags.contains(&true).then_some(flags)
}

/// Refuses a source with no size or no frame rate.
fn check_source(path: &Path, src: &SourceInfo) -> Result<(), FormatError> {
    if src.width == 0 || src.height == 0 || !(src.fps.is_finite() && src.fps > 0.0) {
        return Err(FormatError::Invalid {
            path: path.to_owned(),
            problem: format!(
                "source has size {}×{} at {} fps; both sides and the frame rate must be positive",
                src.width, src.height, src.fps
            ),
        });
    }
    Ok(())
}

/// A frame's per-joint flags, absent ones all false, every list checked to hold one entry per
/// joint.
struct FrameFlags {
    off_frame: Vec<bool>,
    lost: Vec<bool>,
    gait: Vec<bool>,
}

impl FrameFlags {
    fn of(path: &Path, f: &FrameFile, n: usize) -> Result<Self, FormatError> {
        let or_none = |v: &Option<Vec<bool>>| v.clone().unwrap_or_else(|| vec![false; n]);
        let flags = FrameFlags {
            off_frame: or_none(&f.off_frame),
            lost: or_none(&f.lost),
            gait: or_none(&f.gait),
        };
        for (field, found) in [
            ("points", f.points.len()),
            ("confidence", f.confidence.len()),
            ("interpolated", f.interpolated.len()),
            ("off_frame", flags.off_frame.len()),
            ("lost", flags.lost.len()),
            ("gait", flags.gait.len()),
            ("body3d", f.body3d.as_ref().map_or(n, Vec::len)),
        ] {
            if found != n {
                return Err(FormatError::WrongLength {
                    path: path.to_owned(),
                    frame: f.index,
                    field,
                    found,
                    expected: n,
                });
            }
        }
        Ok(flags)
    }
}

/// One joint's point of a frame (the file's column `col`), checked: finite, its confidence in
/// [0, 1], on the frame unless marked off it, and its flags consistent.
fn parse_point(
    path: &Path,
    f: &FrameFile,
    flags: &FrameFlags,
    src: &SourceInfo,
    joint: Joint,
    col: usize,
) -> Result<TrackedPoint, FormatError> {
    let [x, y] = f.points[col];
    let confidence = f.confidence[col];
    if !(x.is_finite() && y.is_finite() && confidence.is_finite()) {
        return Err(FormatError::NonFinite {
            path: path.to_owned(),
            joint,
            frame: Some(f.index),
        });
    }
    if !(0.0..=1.0).contains(&confidence) {
        return Err(FormatError::Invalid {
            path: path.to_owned(),
            problem: format!(
                "joint {joint} in frame {}: confidence {confidence} is outside [0, 1]",
                f.index
            ),
        });
    }
    let pos = Point2::new(x, y);
    let inside = point_in_frame(&pos, src.width, src.height);
    let (off_frame, lost, gait) = (flags.off_frame[col], flags.lost[col], flags.gait[col]);
    let interpolated = f.interpolated[col];
    if !inside && !off_frame {
        return Err(FormatError::OutsideFrame {
            path: path.to_owned(),
            joint,
            x,
            y,
            width: src.width,
            height: src.height,
            frame: Some(f.index),
        });
    }
    let problem = if off_frame && inside {
        Some("is marked off_frame but lies on the frame")
    } else if off_frame && interpolated {
        Some("is marked both off_frame and interpolated")
    } else if off_frame && confidence != 0.0 {
        Some("is marked off_frame with a confidence other than 0")
    } else if lost && (off_frame || interpolated) {
        Some("is marked lost and also off_frame or interpolated")
    } else if gait && (off_frame || interpolated || lost) {
        Some("is marked gait and also off_frame, interpolated or lost")
    } else {
        None
    };
    if let Some(problem) = problem {
        return Err(FormatError::Invalid {
            path: path.to_owned(),
            problem: format!(
                "joint {joint} in frame {} at ({x:.1}, {y:.1}) {problem}",
                f.index
            ),
        });
    }
    Ok(TrackedPoint {
        pos,
        confidence,
        source: if off_frame {
            PointSource::OffFrame
        } else if lost {
            PointSource::Lost
        } else if gait || interpolated {
            PointSource::Interpolated
        } else {
            PointSource::Tracked
        },
    })
}

/// The network's 3D body of a frame (version 4), when the file has one; a non-number refused.
fn parse_body3d(
    path: &Path,
    f: &FrameFile,
    columns: &[usize; crate::skeleton::JOINT_COUNT],
) -> Result<Option<Box<NetworkBody>>, FormatError> {
    let Some(b) = &f.body3d else {
        return Ok(None);
    };
    if b.iter().flatten().any(|v| !v.is_finite()) {
        return Err(FormatError::Invalid {
            path: path.to_owned(),
            problem: format!("frame {}: body3d holds a non-number", f.index),
        });
    }
    let at = |j: Joint| b[columns[j.index()]];
    Ok(Some(Box::new(NetworkBody {
        points: PerJoint::from_fn(|j| Vector3::new(at(j)[0], at(j)[1], at(j)[2])),
        confidence: PerJoint::from_fn(|j| at(j)[3].clamp(0.0, 1.0) as f32),
    })))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Tracks2d {
        Tracks2d {
            source: SourceInfo {
                path: PathBuf::from("clip.mp4"),
                width: 640,
                height: 480,
                fps: 30.0,
                frame_count: 2,
            },
            frames: (0..2)
                .map(|i| FrameTracks {
                    index: FrameIndex(i),
                    body3d: None,
                    points: PerJoint::from_fn(|j| TrackedPoint {
                        pos: Point2::new(100.0 + j.index() as f64, 50.0 + i as f64),
                        confidence: 0.75,
                        source: if j == Joint::LeftWrist && i == 1 {
                            PointSource::Interpolated
                        } else {
                            PointSource::Tracked
                        },
                    }),
                })
                .collect(),
        }
    }

    #[test]
    fn save_and_load_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tracks2d.json");
        sample().save(&path).unwrap();
        assert_eq!(Tracks2d::load(&path).unwrap(), sample());
    }

    /// Tracks saved to `t.json` in a fresh folder (kept alive by the first value), and the
    /// file read back as plain JSON.
    fn saved_json(t: &Tracks2d) -> (tempfile::TempDir, std::path::PathBuf, serde_json::Value) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.json");
        t.save(&path).unwrap();
        let v = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        (dir, path, v)
    }

    #[test]
    fn joints_may_come_in_another_order() {
        let (_dir, path, mut v) = saved_json(&sample());
        // Swap the first two columns everywhere.
        v["joints"].as_array_mut().unwrap().swap(0, 1);
        for f in v["frames"].as_array_mut().unwrap() {
            for key in ["points", "confidence", "interpolated"] {
                f[key].as_array_mut().unwrap().swap(0, 1);
            }
        }
        let t = Tracks2d::parse(&v.to_string(), &path).unwrap();
        assert_eq!(t, sample());
    }

    /// The sample with the left wrist off the frame (left of the image) in frame 1, the
    /// right wrist lost in frame 0.
    fn with_off_frame() -> Tracks2d {
        let mut t = sample();
        t.frames[0].points[Joint::RightWrist].source = PointSource::Lost;
        t.frames[1].points[Joint::LeftWrist] = TrackedPoint {
            pos: Point2::new(-40.0, 200.0),
            confidence: 0.0,
            source: PointSource::OffFrame,
        };
        t
    }

    #[test]
    fn off_frame_and_lost_points_round_trip() {
        let (_dir, path, v) = saved_json(&with_off_frame());
        assert_eq!(v["version"], TRACKS2D_VERSION);
        // Only the frame with an off-frame (lost) joint carries the array.
        assert!(v["frames"][0].get("off_frame").is_none());
        assert_eq!(v["frames"][1]["off_frame"][6], true);
        assert_eq!(v["frames"][1]["off_frame"][5], false);
        assert!(v["frames"][1].get("lost").is_none());
        assert_eq!(v["frames"][0]["lost"][9], true);
        assert!(v["frames"][0].get("gait").is_none());
        assert_eq!(Tracks2d::load(&path).unwrap(), with_off_frame());
    }

    /// The network's 3D body rides with the frame it was seen on (version 4), in the file's
    /// joint order; frames without it carry no array; a wrong length is refused.
    #[test]
    fn the_network_body_round_trips_and_is_checked() {
        let mut t = sample();
        t.frames[1].body3d = Some(Box::new(NetworkBody {
            points: PerJoint::from_fn(|j| Vector3::new(j.index() as f64 * 0.01, -0.5, 0.25)),
            confidence: PerJoint::from_fn(|j| if j == Joint::LeftWrist { 0.25 } else { 1.0 }),
        }));
        let (_dir, path, mut v) = saved_json(&t);
        assert!(v["frames"][0].get("body3d").is_none());
        assert_eq!(v["frames"][1]["body3d"][6][3], 0.25);
        assert_eq!(Tracks2d::load(&path).unwrap(), t);
        v["frames"][1]["body3d"].as_array_mut().unwrap().pop();
        let err = Tracks2d::parse(&v.to_string(), &path).unwrap_err();
        assert!(err.to_string().contains("body3d"), "{err}");
    }

    /// Files from versions before 2026-11-28 may mark a point completed from the gait: it is
    /// read as interpolated (seen nowhere, half weight in the lift) and not written back.
    #[test]
    fn gait_points_of_older_files_are_read_as_interpolated() {
        let (_dir, path, mut v) = saved_json(&sample());
        let mut gait = vec![false; 16];
        gait[14] = true;
        v["frames"][0]["gait"] = serde_json::json!(gait);
        let t = Tracks2d::parse(&v.to_string(), &path).unwrap();
        assert_eq!(
            t.frames[0].points[Joint::RightKnee].source,
            PointSource::Interpolated
        );
        assert_eq!(
            t.frames[0].points[Joint::LeftKnee].source,
            sample().frames[0].points[Joint::LeftKnee].source
        );
        let again = serde_json::to_value(t.to_json_value()).unwrap();
        assert!(again["frames"][0].get("gait").is_none());
    }

    #[test]
    fn version_1_is_read_and_a_newer_version_refused() {
        let (_dir, path, mut v) = saved_json(&sample());
        v["version"] = serde_json::json!(1);
        assert_eq!(Tracks2d::parse(&v.to_string(), &path).unwrap(), sample());
        v["version"] = serde_json::json!(5);
        let err = Tracks2d::parse(&v.to_string(), &path)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("t.json") && err.contains("version 5") && err.contains("up to version 4"),
            "{err}"
        );
    }

    #[test]
    fn off_frame_marks_must_agree_with_the_point() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.json");
        with_off_frame().save(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let base: serde_json::Value = serde_json::from_str(&text).unwrap();
        let cases: [(&str, serde_json::Value, &str); 5] = [
            (
                "points",
                serde_json::json!([100.0, 200.0]),
                "lies on the frame",
            ),
            (
                "confidence",
                serde_json::json!(0.5),
                "confidence other than 0",
            ),
            (
                "interpolated",
                serde_json::json!(true),
                "both off_frame and interpolated",
            ),
            ("lost", serde_json::json!(true), "lost and also off_frame"),
            ("gait", serde_json::json!(true), "gait and also off_frame"),
        ];
        for (field, value, says) in cases {
            let mut v = base.clone();
            if field == "lost" || field == "gait" {
                v["frames"][1][field] = serde_json::json!(vec![false; 16]);
            }
            v["frames"][1][field][6] = value;
            let err = Tracks2d::parse(&v.to_string(), &path)
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("t.json") && err.contains("left_wrist") && err.contains(says),
                "{field}: {err}"
            );
        }
        // Unmarked, the same point is simply outside the frame.
        let mut v = base.clone();
        v["frames"][1]["off_frame"][6] = serde_json::json!(false);
        let err = Tracks2d::parse(&v.to_string(), &path)
            .unwrap_err()
            .to_string();
        assert!(err.contains("outside the 640×480 frame"), "{err}");
    }

    #[test]
    fn short_arrays_and_points_off_the_frame_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.json");
        sample().save(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["frames"][1]["confidence"].as_array_mut().unwrap().pop();
        let err = Tracks2d::parse(&v.to_string(), &path)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("frame 1") && err.contains("confidence"),
            "{err}"
        );

        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["frames"][0]["points"][6] = serde_json::json!([900.0, 10.0]);
        let err = Tracks2d::parse(&v.to_string(), &path)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("left_wrist") && err.contains("outside"),
            "{err}"
        );
    }
}
