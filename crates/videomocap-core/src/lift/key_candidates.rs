//! The key triangle's candidate poses on every frame (eqs. 6–11 solved on each frame's three
//! points, up to four poses each) and the smoothest path through them over the clip.

use super::calibrate::{
    CALIBRATION_TOLERANCE_PX, KeyTriangle, Residuals, calibrate_all, calibrate_from, starting_poses,
};
use super::job::LiftJob;
use super::key_path::{centroid, tilt_m};
use super::propagate::{PROPAGATION_TOLERANCE_M, key_depths};
use crate::camera::PinholeCamera;
use crate::skeleton::{Joint, PerJoint, SubjectModel};
use nalgebra::{Point2, Point3};

/// How deep the trunk can be and still look as long as it does in the image: a segment of
/// length `L` at depth `Z` spans at most about `f·L/Z` pixels, so `Z ≤ f·L/l` for the trunk
/// (neck to pelvis, `l` pixels), with half as much again for perspective and tracking error;
/// unbounded when the trunk's image is under a pixel.
pub(super) fn deepest_trunk(
    cam: &PinholeCamera,
    subject: &SubjectModel,
    image: &PerJoint<Point2<f64>>,
) -> f64 {
    let trunk_m = subject.trunk_m();
    let trunk_px = (image[Joint::Neck] - image[Joint::Pelvis]).norm();
    if trunk_px < 1.0 {
        f64::INFINITY
    } else {
        1.5 * cam.focal_px * trunk_m / trunk_px
    }
}

/// The nearest a key joint may be to the camera, metres: no one films a trunk from closer.
pub(super) const NEAREST_KEY_M: f64 = 0.2;

/// Whether a key pose may be kept: its centroid no deeper than `max_depth`, every joint at
/// least [`NEAREST_KEY_M`] in front of the camera. A pinhole images a triangle with every point
/// negated (behind the camera) exactly as the triangle itself, so calibration can land there.
pub(super) fn plausible_key(key: &[Point3<f64>; 3], max_depth: f64) -> bool {
    centroid(key).z <= max_depth && key.iter().all(|p| p.z >= NEAREST_KEY_M)
}

/// Every pose of the key triangle that fits one frame (a three-point pose has up to four), each
/// made exact by eqs. 10–11; when none fits within tolerance, the closest fit, and `false`.
/// Poses whose centroid lies deeper than `max_depth` are dropped: a thin image triangle (a side
/// view) is also fitted by a tiny far-away triangle whose key lines pass near the marked points,
/// and on the synthetic suite with 2 px noise such fits, chained over frames, carried the trunk
/// thousands of kilometres away. So are poses with a key joint nearer than [`NEAREST_KEY_M`]
/// (behind the camera, too): three rays are also met by such a triangle, and on the suite from
/// the tracker's output one of them, chained in, tipped a bending trunk seen from the side over
/// (bend_side, true lengths: 136.0 → 115.4 mm). When every pose is dropped, the closest point
/// fit (its twin in front when it lies behind the camera), brought along its rays to
/// `max_depth` at most (and `false`).
pub(super) fn key_candidates(
    job: &LiftJob<'_>,
    triangle: &KeyTriangle,
    sides: &[f64; 3],
    image: &[Point2<f64>; 3],
    max_depth: f64,
) -> (Vec<[Point3<f64>; 3]>, bool) {
    let cam = &job.camera;
    let fits = calibrate_all(cam, triangle, image, CALIBRATION_TOLERANCE_PX);
    let closest_point_fit = || {
        starting_poses(cam, triangle, image)
            .into_iter()
            .map(|start| calibrate_from(cam, triangle, image, start, Residuals::Points))
            .min_by(|a, b| a.rms_px.total_cmp(&b.rms_px))
            .map(|c| c.pose)
    };
    let converged = !fits.is_empty();
    let poses: Vec<_> = if converged {
        fits.iter().map(|c| c.pose).collect()
    } else {
        closest_point_fit().into_iter().collect()
    };
    let depth = |k: &[Point3<f64>; 3]| centroid(k).z;
    let mut out: Vec<[Point3<f64>; 3]> = Vec::new();
    for pose in poses {
        let k = triangle.points.map(|p| pose.apply(&p));
        let snapped = key_depths(cam, image, sides, k.map(|p| p.z));
        let k = if snapped.rms_m < PROPAGATION_TOLERANCE_M {
            snapped.points
        } else {
            k
        };
        if plausible_key(&k, max_depth)
            && !out
                .iter()
                .any(|o| (0..3).all(|i| (o[i] - k[i]).norm() < 1e-3))
        {
            out.push(k);
        }
    }
    if out.is_empty() {
        if let Some(pose) = closest_point_fit() {
            let k = triangle.points.map(|p| pose.apply(&p));
            // A fit behind the camera is turned to its twin in front (the same image).
            let k = if depth(&k) < 0.0 {
                k.map(|p| Point3::from(-p.coords))
            } else {
                k
            };
            let scale = (max_depth / depth(&k)).min(1.0);
            out.push(k.map(|p| Point3::from(p.coords * scale)));
        }
        return (out, false);
    }
    (out, converged)
}

/// Squared acceleration of the key joints over three frames.
fn key_acceleration(a: &[Point3<f64>; 3], b: &[Point3<f64>; 3], c: &[Point3<f64>; 3]) -> f64 {
    (0..3)
        .map(|i| (c[i].coords - b[i].coords * 2.0 + a[i].coords).norm_squared())
        .sum()
}

/// The smoothest sequence of key-triangle poses through the per-frame candidates (Viterbi over
/// pairs of frames, least squared acceleration): where two solutions of eqs. 10–11 meet and
/// part again, the one continuing the motion is kept. `pitch`, `(weight, reference)`, adds each
/// pose's squared pitch deviation ([`tilt_m`] from `reference`) times `weight`.
pub(super) fn smoothest_key_path(
    candidates: &[Vec<[Point3<f64>; 3]>],
    pitch: Option<(f64, f64)>,
) -> Vec<[Point3<f64>; 3]> {
    // Each candidate's pitch cost, once.
    let pitch_cost: Vec<Vec<f64>> = candidates
        .iter()
        .map(|frame| {
            frame
                .iter()
                .map(|k| {
                    pitch.map_or(0.0, |(weight, reference)| {
                        weight * (tilt_m(k) - reference).powi(2)
                    })
                })
                .collect()
        })
        .collect();
    let n = candidates.len();
    if n == 0 {
        return Vec::new();
    }
    if n == 1 {
        return vec![candidates[0][0]];
    }
    // cost[(a, b)]: best with frame t−1 at a and frame t at b.
    let mut cost: Vec<Vec<f64>> = candidates[0]
        .iter()
        .zip(&pitch_cost[0])
        .map(|(a, pitch_a)| {
            candidates[1]
                .iter()
                .zip(&pitch_cost[1])
                .map(|(b, pitch_b)| {
                    pitch_a + pitch_b + (0..3).map(|i| (b[i] - a[i]).norm_squared()).sum::<f64>()
                })
                .collect()
        })
        .collect();
    let mut back: Vec<Vec<Vec<usize>>> = Vec::new();
    for t in 2..n {
        let (kb, kc) = (candidates[t - 1].len(), candidates[t].len());
        let mut next = vec![vec![f64::INFINITY; kc]; kb];
        let mut from = vec![vec![0usize; kc]; kb];
        for b in 0..kb {
            for c in 0..kc {
                let pitch_c = pitch_cost[t][c];
                for (a, row) in cost.iter().enumerate() {
                    let total = row[b]
                        + pitch_c
                        + key_acceleration(
                            &candidates[t - 2][a],
                            &candidates[t - 1][b],
                            &candidates[t][c],
                        );
                    if total < next[b][c] {
                        next[b][c] = total;
                        from[b][c] = a;
                    }
                }
            }
        }
        cost = next;
        back.push(from);
    }
    let mut best = (0, 0, f64::INFINITY);
    for (a, row) in cost.iter().enumerate() {
        for (b, &v) in row.iter().enumerate() {
            if v < best.2 {
                best = (a, b, v);
            }
        }
    }
    let mut path = vec![0usize; n];
    path[n - 2] = best.0;
    path[n - 1] = best.1;
    for t in (2..n).rev() {
        path[t - 2] = back[t - 2][path[t - 1]][path[t]];
    }
    path.iter()
        .enumerate()
        .map(|(t, &k)| candidates[t][k])
        .collect()
}
