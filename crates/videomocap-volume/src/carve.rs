//! Voxel carving (paper §2, after Penny et al.): calibrated cameras and one silhouette mask per
//! camera; each voxel's pixel in every camera is looked up once (the paper's lookup table), a
//! voxel is kept when enough silhouettes contain it, and only one connected component survives
//! (§5's clean-up: the largest, or the marked person's, followed over the clip). A carving set-up on disk is a directory holding `cameras.json`
//! (with the box to carve) and `masks/<camera name>/`, one mask image per frame.

use super::VolumeError;
use super::follow::follow;
use super::voxel::{Kept, VoxelGrid};
use image::GrayImage;
use nalgebra::{Matrix3, Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use videomocap_core::formats::{check_header, parse_json, read_text};

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
    /// A camera at `eye` looking at `target` with the world's +Y up in its image (Y-up world),
    /// `focal_px` on both axes, the principal point at the image centre.
    pub fn look_at(
        name: String,
        eye: Point3<f64>,
        target: Point3<f64>,
        (width, height): (u32, u32),
        focal_px: f64,
    ) -> CalibratedCamera {
        let fwd = (target - eye).normalize();
        let right = fwd.cross(&Vector3::y()).normalize();
        let down = fwd.cross(&right);
        let r = Matrix3::from_rows(&[right.transpose(), down.transpose(), fwd.transpose()]);
        let t = -(r * eye.coords);
        CalibratedCamera {
            name,
            width,
            height,
            fx: focal_px,
            fy: focal_px,
            cx: (f64::from(width) - 1.0) / 2.0,
            cy: (f64::from(height) - 1.0) / 2.0,
            rotation: std::array::from_fn(|i| std::array::from_fn(|j| r[(i, j)])),
            translation: [t.x, t.y, t.z],
        }
    }

    /// A world point in this camera's space (metres; X right, Y down, Z forward).
    pub fn to_camera(&self, p: &Point3<f64>) -> Vector3<f64> {
        Matrix3::from_fn(|i, j| self.rotation[i][j]) * p.coords + Vector3::from(self.translation)
    }

    /// The pixel (x right, y down) a world point projects to, if in front of the camera.
    pub fn project(&self, p: &Point3<f64>) -> Option<(f64, f64)> {
        let c = self.to_camera(p);
        (c.z > 1e-6).then(|| (self.fx * c.x / c.z + self.cx, self.fy * c.y / c.z + self.cy))
    }
}

/// A `cameras.json` file: the cameras and, for carving, the box the person moves in.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CamerasFile {
    /// Always [`CAMERAS_FORMAT`] when written.
    #[serde(default)]
    pub format: Option<String>,
    /// Format version (1).
    #[serde(default)]
    pub version: Option<u32>,
    /// The calibrated cameras.
    pub cameras: Vec<CalibratedCamera>,
    /// The box to carve: its lowest and highest corners, world metres (needed by `carve`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounds_m: Option<[[f64; 3]; 2]>,
}

impl CamerasFile {
    /// A file of the current format and version.
    pub fn new(cameras: Vec<CalibratedCamera>, bounds_m: Option<[[f64; 3]; 2]>) -> CamerasFile {
        CamerasFile {
            format: Some(CAMERAS_FORMAT.to_owned()),
            version: Some(1),
            cameras,
            bounds_m,
        }
    }

    /// Writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<(), VolumeError> {
        Ok(videomocap_core::formats::save_json(self, path)?)
    }
}

/// Reads and checks a `cameras.json` file.
pub fn load_cameras(path: &Path) -> Result<CamerasFile, VolumeError> {
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
    if let Some([lo, hi]) = raw.bounds_m
        && !(lo.iter().chain(&hi).all(|v| v.is_finite()) && (0..3).all(|k| lo[k] < hi[k]))
    {
        return Err(invalid(
            "bounds_m must be [[lowest x, y, z], [highest x, y, z]], finite, lowest < highest"
                .into(),
        ));
    }
    Ok(raw)
}

/// A mask pixel at or above this grey level is the person (JPEG masks blur their edges).
const MASK_ON: u8 = 128;

/// The most voxels a carving grid may have (as in `.voxels.json`).
const MAX_VOXELS: usize = 1 << 28;

/// A carving set-up read from disk: cameras, the box, and each frame's mask files.
#[derive(Debug, Clone)]
pub struct CarvingSetup {
    /// The `cameras.json` it was read from (named in errors).
    pub cameras_path: PathBuf,
    /// The cameras, in `cameras.json` order.
    pub cameras: Vec<CalibratedCamera>,
    /// The box to carve (lowest, highest corner).
    pub bounds: [Point3<f64>; 2],
    /// Per frame, one mask file per camera (same order as `cameras`).
    pub frames: Vec<Vec<PathBuf>>,
}

/// Mask images: PNG or JPEG (what the `image` build reads).
fn is_mask(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["png", "jpg", "jpeg"].contains(&e.to_ascii_lowercase().as_str()))
}

/// Reads a carving set-up: `dir/cameras.json` (with `bounds_m`) and `dir/masks/<name>/` per
/// camera, the same number of masks in each (natural name order: frame k is the k-th file).
pub fn open_setup(dir: &Path) -> Result<CarvingSetup, VolumeError> {
    let cameras_path = dir.join("cameras.json");
    let file = load_cameras(&cameras_path)?;
    let [lo, hi] = file.bounds_m.ok_or_else(|| VolumeError::Invalid {
        path: cameras_path.clone(),
        problem: "no bounds_m: carving needs the box to carve, \"bounds_m\": [[x0, y0, z0], [x1, y1, z1]] (metres)".into(),
    })?;
    let mut per_camera: Vec<Vec<PathBuf>> = Vec::new();
    for cam in &file.cameras {
        let d = dir.join("masks").join(&cam.name);
        let entries = std::fs::read_dir(&d).map_err(VolumeError::io(&d))?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && is_mask(p))
            .collect();
        files.sort_by(|a, b| natord::compare(&a.to_string_lossy(), &b.to_string_lossy()));
        if files.is_empty() {
            return Err(VolumeError::Invalid {
                path: d,
                problem: "no mask images here (PNG or JPEG; grey level ≥ 128 = person)".into(),
            });
        }
        if let Some(first) = per_camera.first()
            && first.len() != files.len()
        {
            return Err(VolumeError::Invalid {
                path: d,
                problem: format!(
                    "{} masks, but camera \"{}\" has {}: every camera needs one per frame",
                    files.len(),
                    file.cameras[0].name,
                    first.len()
                ),
            });
        }
        per_camera.push(files);
    }
    let frames = (0..per_camera.first().map_or(0, Vec::len))
        .map(|k| per_camera.iter().map(|f| f[k].clone()).collect())
        .collect();
    Ok(CarvingSetup {
        cameras_path,
        cameras: file.cameras,
        bounds: [Point3::from(lo), Point3::from(hi)],
        frames,
    })
}

impl CarvingSetup {
    /// The empty grid covering the box at `voxel_m`; refused when it would exceed 2^28 voxels.
    pub fn grid(&self, voxel_m: f64) -> Result<VoxelGrid, VolumeError> {
        let [lo, hi] = self.bounds;
        let n = |k: usize| ((hi[k] - lo[k]) / voxel_m).ceil().max(1.0);
        let dims = [n(0), n(1), n(2)];
        if voxel_m.is_nan() || voxel_m <= 0.0 || dims.iter().product::<f64>() > MAX_VOXELS as f64 {
            return Err(VolumeError::Invalid {
                path: self.cameras_path.clone(),
                problem: format!(
                    "a {:.0} mm grid over bounds_m would have {:.0} voxels (at most {MAX_VOXELS})",
                    voxel_m * 1000.0,
                    dims.iter().product::<f64>()
                ),
            });
        }
        let origin = lo + Vector3::repeat(voxel_m / 2.0);
        Ok(VoxelGrid::new(origin, voxel_m, dims.map(|d| d as usize)))
    }

    /// Frame `k`'s masks, one per camera; a mask that cannot be read or is not its camera's
    /// size is an error naming it.
    pub fn read_masks(&self, k: usize) -> Result<Vec<GrayImage>, VolumeError> {
        self.frames[k]
            .iter()
            .zip(&self.cameras)
            .map(|(path, cam)| {
                let img = image::open(path)
                    .map_err(|e| VolumeError::Invalid {
                        path: path.clone(),
                        problem: format!("cannot read the mask: {e}"),
                    })?
                    .into_luma8();
                if img.dimensions() != (cam.width, cam.height) {
                    return Err(VolumeError::Invalid {
                        path: path.clone(),
                        problem: format!(
                            "the mask is {}×{}, camera \"{}\" is {}×{}",
                            img.width(),
                            img.height(),
                            cam.name,
                            cam.width,
                            cam.height
                        ),
                    });
                }
                Ok(img)
            })
            .collect()
    }
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
    /// same order, grey level ≥ 128 = person) contain its centre; then one component is kept:
    /// the one nearest `person` (a point the person stays near), or the largest.
    pub fn carve(
        &self,
        masks: &[GrayImage],
        min_votes: usize,
        person: Option<Point3<f64>>,
    ) -> (VoxelGrid, Kept) {
        let mut grid = self.occupancy(masks, min_votes);
        let kept = grid.keep_component(person);
        (grid, kept)
    }

    /// The voxels at least `min_votes` masks contain, every component kept.
    fn occupancy(&self, masks: &[GrayImage], min_votes: usize) -> VoxelGrid {
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
                            .is_some_and(|p| p[0] >= MASK_ON)
                })
                .count();
            *o = votes >= min_votes;
        }
        grid
    }
}

/// Carves every frame of `setup` at `voxel_m` (a voxel stays when `min_votes` masks contain it;
/// `None` = all cameras; one component kept per frame: the person marked at `person` followed
/// through the clip (see the `follow` module), or the largest) into
/// `out_dir/<first camera's mask name>.voxels.json`, frames in parallel, calling
/// `progress(done, total)` as frames are carved; returns what each frame kept and dropped. Stops at the first
/// unreadable or wrongly sized mask, naming it; `cancel` stops between frames.
pub fn carve_sequence(
    setup: &CarvingSetup,
    voxel_m: f64,
    min_votes: Option<usize>,
    person: Option<Point3<f64>>,
    out_dir: &Path,
    progress: &(dyn Fn(usize, usize) + Sync),
    cancel: &std::sync::atomic::AtomicBool,
) -> Result<Vec<Kept>, VolumeError> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let cameras = setup.cameras.len();
    let votes = min_votes.unwrap_or(cameras);
    if votes == 0 || votes > cameras {
        return Err(VolumeError::Invalid {
            path: setup.cameras_path.clone(),
            problem: format!(
                "the vote threshold must be 1 to {cameras} (one per camera), got {votes}"
            ),
        });
    }
    let carver = Carver::new(setup.grid(voxel_m)?, &setup.cameras);
    std::fs::create_dir_all(out_dir).map_err(VolumeError::io(out_dir))?;
    let done = AtomicUsize::new(0);
    let total = setup.frames.len();
    let blobs: Vec<Vec<Vec<usize>>> = (0..total)
        .into_par_iter()
        .map(|k| {
            if cancel.load(Ordering::Relaxed) {
                return Err(VolumeError::Invalid {
                    path: out_dir.to_owned(),
                    problem: "cancelled".into(),
                });
            }
            let blobs = carver.occupancy(&setup.read_masks(k)?, votes).components();
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            Ok(blobs)
        })
        .collect::<Result<_, _>>()?;
    let chosen: Vec<Option<usize>> = match person {
        Some(p) => follow(&carver.template, &blobs, &p),
        None => blobs
            .iter()
            .map(|b| {
                b.iter()
                    .enumerate()
                    .max_by_key(|(_, c)| c.len())
                    .map(|(k, _)| k)
            })
            .collect(),
    };
    (0..total)
        .into_par_iter()
        .map(|k| {
            let mut grid = carver.template.clone();
            for &i in blobs[k].iter().flatten() {
                grid.occupied[i] = true;
            }
            let kept = grid.keep_only(&blobs[k], chosen[k]);
            let stem = setup.frames[k][0].file_stem().map_or_else(
                || format!("frame_{k:04}"),
                |s| s.to_string_lossy().into_owned(),
            );
            grid.save(&out_dir.join(format!("{stem}.voxels.json")))?;
            Ok(kept)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 30 cm ball seen by four cameras around it: carving gives the ball (its visual hull),
    /// a little fatter than the ball but never missing any of it.
    use std::f64::consts::FRAC_1_SQRT_2;

    /// JPEG masks count as frames (the documented PNG or JPEG); other files do not.
    #[test]
    fn a_set_up_with_jpeg_masks_opens() {
        let dir = tempfile::tempdir().unwrap();
        let cam = CalibratedCamera::look_at(
            "c0".into(),
            Point3::new(0.0, 1.0, 3.0),
            Point3::new(0.0, 1.0, 0.0),
            (40, 30),
            50.0,
        );
        CamerasFile::new(vec![cam], Some([[-1.0, 0.0, -1.0], [1.0, 2.0, 1.0]]))
            .save(&dir.path().join("cameras.json"))
            .unwrap();
        let masks = dir.path().join("masks/c0");
        std::fs::create_dir_all(&masks).unwrap();
        GrayImage::new(40, 30).save(masks.join("f1.jpg")).unwrap();
        GrayImage::new(40, 30).save(masks.join("f2.JPEG")).unwrap();
        std::fs::write(masks.join("notes.txt"), "x").unwrap();
        let setup = open_setup(dir.path()).unwrap();
        assert_eq!(setup.frames.len(), 2);
        assert_eq!(setup.read_masks(1).unwrap()[0].dimensions(), (40, 30));
    }

    #[test]
    fn four_views_carve_a_ball() {
        let centre = Point3::new(0.0, 1.0, 0.0);
        let radius = 0.3;
        let cams: Vec<CalibratedCamera> = (0..4)
            .map(|k| {
                let a = k as f64 * std::f64::consts::FRAC_PI_2;
                let eye = Point3::new(3.0 * a.sin(), 1.0, 3.0 * a.cos());
                CalibratedCamera::look_at(format!("c{k}"), eye, centre, (200, 200), 300.0)
            })
            .collect();
        // Silhouettes: pixels whose square touches the ball's disc (the carver looks up the
        // pixel a voxel centre rounds to, so a pixel counts when any of it is inside).
        let masks: Vec<GrayImage> = cams
            .iter()
            .map(|c| {
                let (cu, cv) = c.project(&centre).unwrap();
                let dist = 3.0;
                let r_px = c.fx * radius / (dist * dist - radius * radius).sqrt();
                GrayImage::from_fn(c.width, c.height, |x, y| {
                    let inside =
                        (f64::from(x) - cu).hypot(f64::from(y) - cv) <= r_px + FRAC_1_SQRT_2;
                    image::Luma([if inside { 255 } else { 0 }])
                })
            })
            .collect();
        let v = 0.05;
        let grid = VoxelGrid::new(Point3::new(-0.5, 0.5, -0.5), v, [21, 21, 21]);
        let (carved, _) = Carver::new(grid.clone(), &cams).carve(&masks, 4, None);
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
