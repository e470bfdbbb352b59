//! `gt.json`: the ground truth of a clip — per frame the 2D points, 3D camera-space points and
//! per-joint visibility; the camera intrinsics; the true bone lengths. The real sample's
//! reference uses the same layout (without bone lengths).

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::formats::{FormatError, FrameIndex, write_atomically};
use videomocap_core::skeleton::{Joint, PerJoint};

/// One frame of ground truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroundTruthFrame {
    /// Frame index.
    pub index: usize,
    /// Image positions of the 16 joints, pixels.
    pub points2d: Vec<[f64; 2]>,
    /// Camera-space positions of the 16 joints, metres (X right, Y down, Z forward).
    pub points3d: Vec<[f64; 3]>,
    /// Whether each joint is seen (on the image and not hidden by another body part).
    pub visible: Vec<bool>,
}

/// A whole clip's ground truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroundTruth {
    /// How the clip was made.
    pub source: String,
    /// Frames per second.
    pub fps: f64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length, pixels.
    pub focal_px: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// Joint names in column order (the 16 in model order).
    pub joints: Vec<String>,
    /// Joints computed from others rather than measured (not to be scored).
    #[serde(default)]
    pub derived_joints: Vec<String>,
    /// The subject's height as a person would state it (sole to vertex), metres: for a
    /// synthetic clip the rendered body's, for a real clip the one its source gives.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stated_height_m: Option<f64>,
    /// True bone lengths, metres, keyed "parent-child" (mean over frames).
    #[serde(default)]
    pub bone_lengths_m: BTreeMap<String, f64>,
    /// Per-frame truth.
    pub frames: Vec<GroundTruthFrame>,
}

impl GroundTruth {
    /// The joints computed from others rather than measured ([`GroundTruth::derived_joints`]
    /// by name), which are never scored.
    pub fn derived(&self) -> Vec<Joint> {
        self.derived_joints
            .iter()
            .filter_map(|n| Joint::from_name(n))
            .collect()
    }

    /// Reads a gt.json file and checks that it lists the 16 joints in model order.
    pub fn load(path: &Path) -> Result<GroundTruth, FormatError> {
        let text = std::fs::read_to_string(path).map_err(|source| FormatError::Io {
            path: path.to_owned(),
            source,
        })?;
        let gt: GroundTruth = serde_json::from_str(&text).map_err(|source| FormatError::Json {
            path: path.to_owned(),
            source,
        })?;
        for (i, joint) in Joint::ALL.iter().enumerate() {
            if gt.joints.get(i).map(String::as_str) != Some(joint.name()) {
                return Err(FormatError::Invalid {
                    path: path.to_owned(),
                    problem: format!(
                        "joints must list the 16 joints in model order; column {i} is not {joint}"
                    ),
                });
            }
        }
        for f in &gt.frames {
            for (field, n) in [
                ("points2d", f.points2d.len()),
                ("points3d", f.points3d.len()),
                ("visible", f.visible.len()),
            ] {
                if n != Joint::ALL.len() {
                    return Err(FormatError::WrongLength {
                        path: path.to_owned(),
                        frame: FrameIndex(f.index),
                        field,
                        found: n,
                        expected: Joint::ALL.len(),
                    });
                }
            }
        }
        Ok(gt)
    }

    /// Saves atomically.
    pub fn save(&self, path: &Path) -> Result<(), FormatError> {
        let mut text = serde_json::to_string(self).map_err(|source| FormatError::Json {
            path: path.to_owned(),
            source,
        })?;
        text.push('\n');
        write_atomically(path, text.as_bytes())
    }
}

impl GroundTruth {
    /// The camera the clip was filmed (or rendered) with.
    pub fn camera(&self) -> PinholeCamera {
        PinholeCamera {
            focal_px: self.focal_px,
            cx: self.cx,
            cy: self.cy,
            width: self.width,
            height: self.height,
        }
    }
}

impl GroundTruthFrame {
    /// The 2D points as typed values.
    pub fn points2d(&self) -> PerJoint<Point2<f64>> {
        PerJoint::from_fn(|j| {
            let [x, y] = self
                .points2d
                .get(j.index())
                .copied()
                .unwrap_or([f64::NAN; 2]);
            Point2::new(x, y)
        })
    }

    /// The 3D points as typed values.
    pub fn points3d(&self) -> PerJoint<Point3<f64>> {
        PerJoint::from_fn(|j| {
            let [x, y, z] = self
                .points3d
                .get(j.index())
                .copied()
                .unwrap_or([f64::NAN; 3]);
            Point3::new(x, y, z)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_real_reference_loads() {
        let path = crate::repo_root().join("sample_videos/pose2sim_balancing_cam01/gt.json");
        let gt = GroundTruth::load(&path).unwrap();
        assert_eq!(gt.frames.len(), 100);
        assert_eq!((gt.width, gt.height), (1080, 1920));
        assert_eq!(gt.derived_joints, vec!["chest".to_owned()]);
    }
}
