//! Synthetic point volumes: the posed synthetic body voxelised on a fixed world lattice (voxel
//! centres at multiples of the voxel size), with optional noise voxels near the body and holes,
//! written as one binary PLY per frame and the true joints as `truth.skeleton3d.json`. This is
//! the ground truth of the volume pipeline's tests and benchmark.

use super::capsules::Body;
use super::faults::SilhouetteFaults;
use super::motion::{Motion, stature_of};
use super::render::Surface;
use image::GrayImage;
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::formats::{Frame3d, FrameIndex, Skeleton3d};
use videomocap_core::skeleton::{Bone, PerJoint};
use videomocap_volume::VolumeError;
use videomocap_volume::carve::{CalibratedCamera, CamerasFile};
use videomocap_volume::cloud::write_ply;

/// How to voxelise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoxelParams {
    /// Voxel edge, metres (the paper used 50 mm).
    pub voxel_m: f64,
    /// Spurious voxels per frame, scattered within 0.3 m of the body's box (the paper's "ghost
    /// voxels"); isolated ones vanish in the largest connected component.
    pub noise_voxels: usize,
    /// Share of the body's voxels removed at random (holes).
    pub hole_fraction: f64,
    /// Random seed.
    pub seed: u64,
}

impl Default for VoxelParams {
    fn default() -> Self {
        VoxelParams {
            voxel_m: 0.04,
            noise_voxels: 0,
            hole_fraction: 0.0,
            seed: 1,
        }
    }
}

/// The voxel centres of the body posed by `joints` (world frame).
pub fn voxelise(
    joints: &PerJoint<Point3<f64>>,
    stature_m: f64,
    params: &VoxelParams,
    rng: &mut impl Rng,
) -> Vec<Point3<f64>> {
    let body = Body::new(joints, stature_m);
    let v = params.voxel_m;
    let (lo, hi) = body.bounds();
    let cell = |x: f64| (x / v).floor() as i64;
    let (x0, y0, z0) = (cell(lo.x), cell(lo.y), cell(lo.z));
    let (x1, y1, z1) = (cell(hi.x) + 1, cell(hi.y) + 1, cell(hi.z) + 1);
    let mut out = Vec::new();
    for z in z0..=z1 {
        for y in y0..=y1 {
            for x in x0..=x1 {
                let p = Point3::new(x as f64, y as f64, z as f64) * v;
                if body.contains(&p)
                    && (params.hole_fraction <= 0.0 || rng.random::<f64>() >= params.hole_fraction)
                {
                    out.push(p);
                }
            }
        }
    }
    let span = (hi - lo) + Vector3::repeat(0.6);
    for _ in 0..params.noise_voxels {
        let r = Vector3::new(
            rng.random::<f64>(),
            rng.random::<f64>(),
            rng.random::<f64>(),
        );
        let p = lo - Vector3::repeat(0.3) + span.component_mul(&r);
        out.push(Point3::new(cell(p.x) as f64, cell(p.y) as f64, cell(p.z) as f64) * v);
    }
    out
}

/// Writes `frame_NNNN.ply` per frame and `truth.skeleton3d.json` (the true 16 joints in the
/// same world frame, metres, Y up) into `dir`; `progress(done, total)` after each frame.
pub fn write_volume_sequence(
    motion: &Motion,
    dir: &Path,
    params: &VoxelParams,
    mut progress: impl FnMut(usize, usize),
) -> Result<usize, VolumeError> {
    std::fs::create_dir_all(dir).map_err(VolumeError::io(dir))?;
    let stature = stature_of(motion);
    let mut rng = rand::rngs::StdRng::seed_from_u64(params.seed);
    let mut points_total = 0;
    for (i, joints) in motion.frames.iter().enumerate() {
        let pts = voxelise(joints, stature, params, &mut rng);
        points_total += pts.len();
        write_ply(&dir.join(format!("frame_{i:04}.ply")), &pts)?;
        progress(i + 1, motion.frames.len());
    }
    truth(motion).save(&dir.join("truth.skeleton3d.json"))?;
    Ok(points_total)
}

/// Cameras around `centre`, looking down at it at 20° from `distance` metres, their directions
/// spread evenly over half a turn from straight in front (+Z): a camera opposite another sees
/// nearly the same silhouette, so half a turn gives the carving the most; `width`×`height`
/// pixels, 60° horizontal field of view.
pub fn ring_cameras(
    views: usize,
    centre: Point3<f64>,
    distance: f64,
    width: u32,
    height: u32,
) -> Vec<CalibratedCamera> {
    let f = f64::from(width) / 2.0 / (30f64.to_radians()).tan();
    (0..views)
        .map(|k| {
            let a = k as f64 * std::f64::consts::PI / views as f64;
            let e = 20f64.to_radians();
            let eye =
                centre + Vector3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos()) * distance;
            CalibratedCamera::look_at(format!("cam{k}"), eye, centre, (width, height), f)
        })
        .collect()
}

/// The silhouette of a body given as voxel centres of edge `voxel_m` (255 = person): each
/// centre drawn as a disc as wide as its voxel's projected half-diagonal.
pub fn silhouette(points: &[Point3<f64>], voxel_m: f64, cam: &CalibratedCamera) -> GrayImage {
    let mut img = GrayImage::new(cam.width, cam.height);
    for p in points {
        let z = cam.to_camera(p).z;
        let Some((u, v)) = cam.project(p) else {
            continue;
        };
        let rad = (cam.fx * 0.87 * voxel_m / z).max(0.5);
        let (x0, x1) = ((u - rad).floor().max(0.0), (u + rad).ceil());
        let (y0, y1) = ((v - rad).floor().max(0.0), (v + rad).ceil());
        let mut y = y0;
        while y <= y1 && y < f64::from(cam.height) {
            let mut x = x0;
            while x <= x1 && x < f64::from(cam.width) {
                if (x - u).hypot(y - v) <= rad {
                    img.put_pixel(x as u32, y as u32, image::Luma([255]));
                }
                x += 1.0;
            }
            y += 1.0;
        }
    }
    img
}

/// Writes a carving set-up of `motion` into `dir` for `videomocap carve`: `views` cameras of
/// `width`×`height` pixels on a ring around the space the body moves in (see [`ring_cameras`]),
/// `cameras.json` with that box, and `masks/<camera>/frame_NNNN.png`, the body's silhouettes
/// (from 10 mm voxels), frames in parallel, with `faults` drawn in (a second person widens the
/// box to hold them); `progress(done, total)` after each frame.
pub fn write_carving_setup(
    motion: &Motion,
    dir: &Path,
    views: usize,
    size: (u32, u32),
    faults: &SilhouetteFaults,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(), VolumeError> {
    write_carving_setup_of(
        motion,
        dir,
        views,
        size,
        faults,
        Surface::Capsules,
        progress,
    )
}

/// The person's silhouette in `cam`: the capsule body's voxel centres `pts` (the forearm left
/// out when `no_forearm`), or MakeHuman's mesh posed on `joints` (the capsule forearm's
/// silhouette then cut from it).
fn person_mask(
    surface: Surface,
    pts: &[Point3<f64>],
    joints: &PerJoint<Point3<f64>>,
    stature: f64,
    no_forearm: Option<&SilhouetteFaults>,
    cam: &CalibratedCamera,
    voxel_m: f64,
) -> Result<GrayImage, VolumeError> {
    let forearm = |p: &&Point3<f64>| no_forearm.is_some_and(|f| f.is_forearm(joints, p));
    match surface {
        Surface::Capsules => {
            let kept: Vec<Point3<f64>> = pts.iter().filter(|p| !forearm(p)).copied().collect();
            Ok(silhouette(&kept, voxel_m, cam))
        }
        Surface::Mesh => {
            let pinhole = PinholeCamera {
                focal_px: cam.fx,
                cx: cam.cx,
                cy: cam.cy,
                width: cam.width,
                height: cam.height,
            };
            let in_camera = joints.map(|_, p| Point3::from(cam.to_camera(p)));
            let mut img = image::RgbImage::new(cam.width, cam.height);
            let depth = super::mesh::paint(
                &pinhole,
                &in_camera,
                stature,
                &super::appearance::Appearance::default(),
                &mut img,
            )
            .map_err(|e| VolumeError::Invalid {
                path: std::path::PathBuf::from("mesh"),
                problem: e.to_string(),
            })?;
            let mut mask = GrayImage::from_fn(cam.width, cam.height, |x, y| {
                let d = depth[(y * cam.width + x) as usize];
                image::Luma([if d.is_finite() { 255 } else { 0 }])
            });
            if no_forearm.is_some() {
                let cut: Vec<Point3<f64>> = pts.iter().filter(forearm).copied().collect();
                let hole = silhouette(&cut, voxel_m, cam);
                for (m, h) in mask.pixels_mut().zip(hole.pixels()) {
                    if h.0[0] > 0 {
                        m.0[0] = 0;
                    }
                }
            }
            Ok(mask)
        }
    }
}

/// The box to carve: every frame's body (and the second person `second` to its side, when
/// there is one), 20 cm around.
fn carving_box(
    motion: &Motion,
    stature: f64,
    second: Option<Vector3<f64>>,
) -> (Point3<f64>, Point3<f64>) {
    let (mut lo, mut hi) = (
        Point3::from(Vector3::repeat(f64::MAX)),
        Point3::from(Vector3::repeat(f64::MIN)),
    );
    for j in &motion.frames {
        let (a, b) = Body::new(j, stature).bounds();
        lo = lo.inf(&a);
        hi = hi.sup(&b);
        if let Some(second) = second {
            lo = lo.inf(&(a + second));
            hi = hi.sup(&(b + second));
        }
    }
    let margin = Vector3::repeat(0.2);
    (lo - margin, hi + margin)
}

/// [`write_carving_setup`] with the person drawn as `surface`: the capsule body, or MakeHuman's
/// skinned mesh (suite v4's people) rasterised into each view.
pub fn write_carving_setup_of(
    motion: &Motion,
    dir: &Path,
    views: usize,
    (width, height): (u32, u32),
    faults: &SilhouetteFaults,
    surface: Surface,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(), VolumeError> {
    let stature = stature_of(motion);
    let second = Vector3::x() * faults.second_person_m.unwrap_or(0.0);
    let (lo, hi) = carving_box(motion, stature, faults.second_person_m.map(|_| second));
    let centre = nalgebra::center(&lo, &hi);
    // Far enough that the box's bounding sphere fills at most 90 % of the shorter image side.
    let radius = (hi - lo).norm() / 2.0;
    let half_fov =
        (f64::from(height.min(width)) / f64::from(width) * 30f64.to_radians().tan()).atan();
    let distance = radius / (0.9 * half_fov).sin();
    let cameras = ring_cameras(views, centre, distance, width, height);
    for c in &cameras {
        let d = dir.join("masks").join(&c.name);
        std::fs::create_dir_all(&d).map_err(VolumeError::io(&d))?;
    }
    CamerasFile::new(cameras.clone(), Some([lo.coords.into(), hi.coords.into()]))
        .save(&dir.join("cameras.json"))?;
    let fine = VoxelParams {
        voxel_m: 0.01,
        ..VoxelParams::default()
    };
    let done = std::sync::atomic::AtomicUsize::new(0);
    motion
        .frames
        .par_iter()
        .enumerate()
        .try_for_each(|(i, joints)| {
            // No noise or holes: the generator is never drawn from.
            let mut rng = rand::rngs::StdRng::seed_from_u64(fine.seed);
            let pts = voxelise(joints, stature, &fine, &mut rng);
            // Faults drawn on every view: the shadow, the second person.
            let mut extra = Vec::new();
            if faults.shadow {
                let floor = pts.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
                extra.extend(SilhouetteFaults::shadow_points(joints, floor, fine.voxel_m));
            }
            if faults.second_person_m.is_some() {
                let other = &motion.frames[(i + motion.frames.len() / 2) % motion.frames.len()];
                let other: PerJoint<Point3<f64>> = PerJoint::from_fn(|j| other[j] + second);
                extra.extend(voxelise(&other, stature, &fine, &mut rng));
            }
            for (view, c) in cameras.iter().enumerate() {
                let path = dir
                    .join("masks")
                    .join(&c.name)
                    .join(format!("frame_{i:04}.png"));
                let no_forearm = (faults.missing_forearm_view == Some(view)).then_some(faults);
                let mut mask =
                    person_mask(surface, &pts, joints, stature, no_forearm, c, fine.voxel_m)?;
                if !extra.is_empty() {
                    let other = silhouette(&extra, fine.voxel_m, c);
                    for (m, o) in mask.pixels_mut().zip(other.pixels()) {
                        m.0[0] = m.0[0].max(o.0[0]);
                    }
                }
                let mask = faults.edges(view, mask);
                mask.save(&path).map_err(|e| VolumeError::Invalid {
                    path: path.clone(),
                    problem: format!("cannot write the mask: {e}"),
                })?;
            }
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(n, motion.frames.len());
            Ok::<(), VolumeError>(())
        })?;
    Ok(())
}

/// The motion's joints as a skeleton3d (world frame; the camera is nominal).
pub fn truth(motion: &Motion) -> Skeleton3d {
    let first = motion.frames.first();
    let bone_lengths_m: BTreeMap<String, f64> = first
        .map(|p| {
            Bone::ALL
                .iter()
                .map(|b| (b.key(), (p[b.child] - p[b.parent]).norm().max(1e-6)))
                .collect()
        })
        .unwrap_or_default();
    Skeleton3d {
        camera: PinholeCamera::centred(1000.0, 1000, 1000),
        fps: Some(motion.fps),
        bone_lengths_m,
        frames: motion
            .frames
            .iter()
            .enumerate()
            .map(|(index, points)| Frame3d {
                index: FrameIndex(index),
                points: *points,
                flags: Vec::new(),
            })
            .collect(),
    }
}
