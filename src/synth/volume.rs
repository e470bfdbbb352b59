//! Synthetic point volumes: the posed synthetic body voxelised on a fixed world lattice (voxel
//! centres at multiples of the voxel size), with optional noise voxels near the body and holes,
//! written as one binary PLY per frame and the true joints as `truth.skeleton3d.json`. This is
//! the ground truth of the volume pipeline's tests and benchmark.

use super::motion::{Motion, stature_of};
use super::render::Body;
use crate::camera::PinholeCamera;
use crate::formats::{Frame3d, Skeleton3d};
use crate::skeleton::{Bone, PerJoint};
use crate::volume::VolumeError;
use crate::volume::cloud::write_ply;
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use std::collections::BTreeMap;
use std::path::Path;

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
    std::fs::create_dir_all(dir).map_err(|e| VolumeError::Io {
        path: dir.to_owned(),
        source: e,
    })?;
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
                index,
                points: *points,
                flags: Vec::new(),
            })
            .collect(),
    }
}
