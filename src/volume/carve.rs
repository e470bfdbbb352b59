//! Voxel carving (paper §2, after Penny et al.): calibrated cameras and one silhouette mask per
//! camera; each voxel's pixel in every camera is looked up once (the paper's lookup table), a
//! voxel is kept when enough silhouettes contain it, and only the largest connected component
//! survives (§5's clean-up).

use super::VolumeError;
use super::voxel::VoxelGrid;
use crate::formats::{check_header, parse_json, read_text};
use image::GrayImage;
use nalgebra::{Matrix3, Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `format` tag of camera calibration files.
pub const CAMERAS_FORMAT: &str = "videomocap.cameras";

/// One calibrated camera: world → camera `X_c = R·X_w + t` (metres; camera X right, Y down,
/// Z forward), then `u = fx·X/Z + cx`, `v = fy·Y/Z + cy`. Lens distortion is assumed removed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibratedCamera {
    /// Name; its masks live in `masks/<name>/`.
    pub name: String,
    /// Image size in pixels.
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// Focal lengths in pixels.
    pub fx: f64,
    /// See `fx`.
    pub fy: f64,
    /// Principal point in pixels.
    pub cx: f64,
    /// See `cx`.
    pub cy: f64,
    /// Rotation world → camera, rows.
    pub rotation: [[f64; 3]; 3],
    /// Translation world → camera, metres.
    pub translation: [f64; 3],
}

impl CalibratedCamera {
    /// The pixel (x right, y down) a world point projects to, if in front of the camera.
    pub fn project(&self, p: &Point3<f64>) -> Option<(f64, f64)> {
        let r = Matrix3::from_fn(|i, j| self.rotation[i][j]);
        let c = r * p.coords + Vector3::from(self.translation);
        (c.z > 1e-6).then(|| (self.fx * c.x / c.z + self.cx, self.fy * c.y / c.z + self.cy))
    }
}

#[derive(Serialize, Deserialize)]
struct CamerasFile {
    #[serde(default)]
    format: Option<String>,
    #[serde(default)]
    version: Option<u32>,
    cameras: Vec<CalibratedCamera>,
}

/// Reads and checks a `cameras.json` file.
pub fn load_cameras(path: &Path) -> Result<Vec<CalibratedCamera>, VolumeError> {
    let raw: CamerasFile = parse_json(&read_text(path)?, path)?;
    check_header(path, CAMERAS_FORMAT, raw.format.as_deref(), raw.version)?;
    let invalid = |problem: String| VolumeError::Invalid {
        path: path.to_owned(),
        problem,
    };
    if raw.cameras.is_empty() {
        return Err(invalid("no cameras listed".into()));
    }
    for c in &raw.cameras {
        let finite = [c.fx, c.fy, c.cx, c.cy]
            .iter()
            .chain(c.rotation.iter().flatten())
            .chain(&c.translation)
            .all(|v| v.is_finite());
        if !finite || c.fx <= 0.0 || c.fy <= 0.0 || c.width == 0 || c.height == 0 {
            return Err(invalid(format!(
                "camera \"{}\" needs positive focal lengths and size and finite numbers",
                c.name
            )));
        }
    }
    Ok(raw.cameras)
}

/// A carving set-up: the grid and, per camera, the pixel each voxel centre falls on.
#[derive(Debug, Clone)]
pub struct Carver {
    template: VoxelGrid,
    /// Per camera, per voxel: pixel index `y·width + x`, or `u32::MAX` when outside the image.
    lookup: Vec<Vec<u32>>,
    widths: Vec<u32>,
}

impl Carver {
    /// Precomputes the lookup table of `grid` (its occupancy is ignored) in every camera.
    pub fn new(grid: VoxelGrid, cameras: &[CalibratedCamera]) -> Carver {
        let [nx, ny, nz] = grid.dims;
        let lookup = cameras
            .iter()
            .map(|cam| {
                let mut t = Vec::with_capacity(nx * ny * nz);
                for z in 0..nz {
                    for y in 0..ny {
                        for x in 0..nx {
                            let px = cam.project(&grid.centre(x, y, z)).and_then(|(u, v)| {
                                let (u, v) = (u.round(), v.round());
                                let inside = u >= 0.0
                                    && v >= 0.0
                                    && u < f64::from(cam.width)
                                    && v < f64::from(cam.height);
                                inside.then(|| v as u32 * cam.width + u as u32)
                            });
                            t.push(px.unwrap_or(u32::MAX));
                        }
                    }
                }
                t
            })
            .collect();
        Carver {
            widths: cameras.iter().map(|c| c.width).collect(),
            template: grid,
            lookup,
        }
    }

    /// Carves one frame: a voxel is occupied when at least `min_votes` masks (one per camera,
    /// same order, non-zero = person) contain its centre; then the largest component is kept.
    pub fn carve(&self, masks: &[GrayImage], min_votes: usize) -> VoxelGrid {
        let mut grid = self.template.clone();
        for (i, o) in grid.occupied.iter_mut().enumerate() {
            let votes = self
                .lookup
                .iter()
                .zip(masks)
                .zip(&self.widths)
                .filter(|((lut, mask), w)| {
                    let px = lut[i];
                    px != u32::MAX
                        && mask.width() == **w
                        && mask
                            .get_pixel_checked(px % **w, px / **w)
                            .is_some_and(|p| p[0] > 0)
                })
                .count();
            *o = votes >= min_votes;
        }
        grid.keep_largest_component();
        grid
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 30 cm ball seen by four cameras around it: carving gives the ball (its visual hull),
    /// a little fatter than the ball but never missing any of it.
    #[test]
    fn four_views_carve_a_ball() {
        let centre = Point3::new(0.0, 1.0, 0.0);
        let radius = 0.3;
        let cams: Vec<CalibratedCamera> = (0..4)
            .map(|k| {
                let a = k as f64 * std::f64::consts::FRAC_PI_2;
                let eye = Point3::new(3.0 * a.sin(), 1.0, 3.0 * a.cos());
                let fwd = (centre - eye).normalize();
                let right = fwd.cross(&Vector3::y()).normalize();
                let down = fwd.cross(&right);
                let r = Matrix3::from_rows(&[right.transpose(), down.transpose(), fwd.transpose()]);
                let t = -(r * eye.coords);
                CalibratedCamera {
                    name: format!("c{k}"),
                    width: 200,
                    height: 200,
                    fx: 300.0,
                    fy: 300.0,
                    cx: 100.0,
                    cy: 100.0,
                    rotation: [
                        [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
                        [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
                        [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
                    ],
                    translation: [t.x, t.y, t.z],
                }
            })
            .collect();
        // Silhouettes: pixels whose ray passes within `radius` of the centre.
        let masks: Vec<GrayImage> = cams
            .iter()
            .map(|c| {
                let (cu, cv) = c.project(&centre).unwrap();
                let dist = 3.0;
                let r_px = c.fx * radius / (dist * dist - radius * radius).sqrt();
                GrayImage::from_fn(c.width, c.height, |x, y| {
                    let inside = (f64::from(x) - cu).hypot(f64::from(y) - cv) <= r_px;
                    image::Luma([if inside { 255 } else { 0 }])
                })
            })
            .collect();
        let v = 0.05;
        let grid = VoxelGrid::new(Point3::new(-0.5, 0.5, -0.5), v, [21, 21, 21]);
        let carved = Carver::new(grid.clone(), &cams).carve(&masks, 4);
        let [nx, ny, nz] = grid.dims;
        let (mut missed, mut extra) = (0, 0);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let inside = (grid.centre(x, y, z) - centre).norm() <= radius;
                    let got = carved.occupied[grid.index(x, y, z)];
                    if inside && !got {
                        missed += 1;
                    }
                    if got && !inside {
                        extra += 1;
                    }
                }
            }
        }
        let ball = (4.0 / 3.0 * std::f64::consts::PI * radius.powi(3) / v.powi(3)) as usize;
        assert_eq!(missed, 0);
        assert!(
            extra < ball / 2,
            "{extra} extra voxels for a ball of {ball}"
        );
    }
}
