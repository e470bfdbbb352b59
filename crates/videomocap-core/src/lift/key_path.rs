//! Beyond the paper: the key triangle's path over the whole clip, fitted at once.
//!
//! Eqs. 10–11 place the key triangle frame by frame from three image points, and a small
//! triangle far away turns a pixel of noise into centimetres of depth and degrees of turn. The
//! path chosen frame by frame is therefore refitted over all frames by least squares: every key
//! joint's reprojection onto its (smoothed) track, the triangle's three sides at their lengths,
//! and every key joint's acceleration, each divided by its expected size:
//! - reprojection, `σ` = half the key joints' white noise
//!   ([`super::smoothing::median_noise_px`], at least [`MIN_NOISE_PX`]; the tracks are already
//!   smoothed), weighted by the track's confidence;
//! - sides, `σ` = 1 mm;
//! - acceleration, `σ` = [`KEY_ACCELERATION_TIMES_NOISE`] over the noise, at least
//!   [`MIN_KEY_ACCELERATION_MPS2`]: exact tracks are barely moved, noisy ones firmly;
//! - the trunk's pitch towards the camera (the chest's depth behind the shoulders' midpoint) at
//!   its median over the clip, `σ` = [`KEY_TILT_TIMES_NOISE`] over the noise: what a pixel of
//!   noise hides best in a triangle facing the camera.
//!
//! Each frame's triangle is then put rigidly where it best fits the result (Kabsch), so its
//! sides keep their lengths exactly and the BVH export stays exact.

use super::least_squares::{Residuals, Row, frame_interval_s, minimise};
use crate::camera::PinholeCamera;
use nalgebra::{DVector, Matrix3, Point2, Point3, Rotation3, UnitQuaternion, Vector3};

/// The key joints' acceleration deviation (m/s²) is this over their tracks' noise (pixels).
/// Swept on the synthetic suite with true lengths (four draws of 2 px noise, exact tracks, the
/// tracker's output, the real sample with its reference 2D and with noise; the noise then taken
/// over all joints): 5 gave 61.6, 20.5,
/// 113.2, 69.3 and 70.7 mm; 10 gave 61.6, 20.3, 113.1, 69.2, 70.7; 20 gave 62.6, 20.4, 112.9,
/// 69.2, 71.9.
pub(super) const KEY_ACCELERATION_TIMES_NOISE: f64 = 10.0;

/// The firmest key acceleration deviation, m/s² (reached at 2 px of noise): tracks of 5 px
/// noise would otherwise be smoothed to a standstill (the tracker's output on a dance clip). At
/// 3 the same sweep gave 61.7, 20.3, 113.6, 69.2, 70.7 mm; at 8 62.4, 20.3, 112.5, 69.2, 71.3.
pub(super) const MIN_KEY_ACCELERATION_MPS2: f64 = 5.0;

/// Deviation (metres) of a frame's trunk pitch towards the camera (the chest's depth behind the
/// shoulders' midpoint) from the clip's median is this over the key joints' noise (pixels): 15 mm
/// at 2 px, about 6° of pitch for an adult's key triangle. A frontal triangle's pitch is what
/// noise hides best: with 2 px on a triangle 50 px across, a frame's pitch is uncertain by about
/// 15°, and the triangle tipped the wrong way turns the priors of every limb with it. Swept on
/// the synthetic suite with true lengths (four draws of 2 px noise; the real sample with noise;
/// the tracker's output): off 61.9, 70.3, 111.8 mm; 0.04 gave 58.0, 70.4, 112.0; 0.03 gave 56.8,
/// 70.5, 112.0; 0.02 gave 55.6, 71.2; 0.01 gave 54.8, 72.1 (the real sample's subject sways).
pub(super) const KEY_TILT_TIMES_NOISE: f64 = 0.03;

/// Below this noise (pixels) the path is left as it is (exact tracks stay exact); above it, the
/// least noise assumed.
pub(super) const MIN_NOISE_PX: f64 = 0.1;

/// Deviation of a side from its length, metres.
const SIDE_SIGMA_M: f64 = 0.001;

/// Levenberg–Marquardt steps at most.
const MAX_ITERATIONS: usize = 30;

/// The key triangle's sides as `(joint, joint)` indices into its three points.
const SIDES: [(usize, usize); 3] = [(0, 1), (2, 0), (2, 1)];

/// The problem's data.
struct KeyPath<'a> {
    cam: &'a PinholeCamera,
    /// Each frame's three key points in the image.
    observed: &'a [[Point2<f64>; 3]],
    /// Each point's weight (its track's confidence).
    weights: &'a [[f64; 3]],
    sides: [f64; 3],
    sigma_px: f64,
    /// Acceleration deviation, metres per frame².
    sigma_accel_m: f64,
    /// The clip's typical depth of the chest behind the shoulders' midpoint ([`tilt_m`]),
    /// metres.
    tilt_m: f64,
    /// Deviation of each frame's [`tilt_m`] from the clip's, metres.
    sigma_tilt_m: f64,
}

impl Residuals for KeyPath<'_> {
    fn rows(&self, x: &DVector<f64>, emit: &mut dyn FnMut(Row)) {
        let n = self.observed.len();
        let f = self.cam.focal_px;
        let col = |t: usize, k: usize| 9 * t + 3 * k;
        for t in 0..n {
            for k in 0..3 {
                let c = col(t, k);
                let (px, py, z) = (x[c], x[c + 1], x[c + 2].max(1e-3));
                let s = self.weights[t][k].sqrt() / self.sigma_px;
                let o = self.observed[t][k];
                emit(
                    Row::new(s * (f * px / z + self.cam.cx - o.x))
                        .with(c, s * f / z)
                        .with(c + 2, -s * f * px / (z * z)),
                );
                emit(
                    Row::new(s * (f * py / z + self.cam.cy - o.y))
                        .with(c + 1, s * f / z)
                        .with(c + 2, -s * f * py / (z * z)),
                );
            }
            let s = 1.0 / SIDE_SIGMA_M;
            for (&(a, b), &length) in SIDES.iter().zip(&self.sides) {
                let (ca, cb) = (col(t, a), col(t, b));
                let d = Vector3::new(x[cb] - x[ca], x[cb + 1] - x[ca + 1], x[cb + 2] - x[ca + 2]);
                let len = d.norm().max(1e-9);
                let u = d / len;
                emit(
                    Row::new(s * (len - length))
                        .with(cb, s * u.x)
                        .with(cb + 1, s * u.y)
                        .with(cb + 2, s * u.z)
                        .with(ca, -s * u.x)
                        .with(ca + 1, -s * u.y)
                        .with(ca + 2, -s * u.z),
                );
            }
            let s = 1.0 / self.sigma_tilt_m;
            let (l, r, c) = (col(t, 0) + 2, col(t, 1) + 2, col(t, 2) + 2);
            emit(
                Row::new(s * (x[c] - 0.5 * (x[l] + x[r]) - self.tilt_m))
                    .with(c, s)
                    .with(l, -0.5 * s)
                    .with(r, -0.5 * s),
            );
            if t >= 1 && t + 1 < n {
                let s = 1.0 / self.sigma_accel_m;
                for i in 0..9 {
                    let (a, b, c) = (9 * (t - 1) + i, 9 * t + i, 9 * (t + 1) + i);
                    emit(
                        Row::new(s * (x[a] - 2.0 * x[b] + x[c]))
                            .with(a, s)
                            .with(b, -2.0 * s)
                            .with(c, s),
                    );
                }
            }
        }
    }
}

/// The pitch prior for chaining the key poses frame by frame, `(weight, reference pitch)`:
/// a squared pitch deviation (metres², [`tilt_m`] from `reference`'s) weighs against a squared
/// acceleration of the key joints (metres² per frame², unweighted) by the ratio of their
/// variances in the refit, so both steps weigh the two alike (0.14 at 30 frames/s whatever the
/// noise: both deviations scale with it). `None` where the refit leaves the path alone (below
/// [`MIN_NOISE_PX`]).
pub(crate) fn chain_pitch_prior(
    noise_px: f64,
    fps: f64,
    reference: &[Point3<f64>; 3],
) -> Option<(f64, f64)> {
    if noise_px < MIN_NOISE_PX {
        return None;
    }
    let dt = frame_interval_s(fps);
    let weight = (key_acceleration_mps2(noise_px) * dt * dt / key_tilt_sigma_m(noise_px)).powi(2);
    Some((weight, tilt_m(reference)))
}

/// The deviation of a frame's pitch from the clip's for tracks of `noise_px` white noise, m.
fn key_tilt_sigma_m(noise_px: f64) -> f64 {
    KEY_TILT_TIMES_NOISE / noise_px.max(MIN_NOISE_PX)
}

/// The key acceleration deviation for tracks of `noise_px` white noise, m/s².
fn key_acceleration_mps2(noise_px: f64) -> f64 {
    (KEY_ACCELERATION_TIMES_NOISE / noise_px.max(MIN_NOISE_PX)).max(MIN_KEY_ACCELERATION_MPS2)
}

/// Refits the key triangle's path `key` (both shoulders and the chest per frame, camera space)
/// to the key joints' image points `observed` (with weights `weights`) over the whole clip, for
/// tracks of `noise_px` white noise at `fps` (below [`MIN_NOISE_PX`], `key` is returned as it
/// is); every frame's result is the rigid `model` triangle.
pub(super) fn smooth_key_path(
    cam: &PinholeCamera,
    key: &[[Point3<f64>; 3]],
    observed: &[[Point2<f64>; 3]],
    weights: &[[f64; 3]],
    model: &[Point3<f64>; 3],
    noise_px: f64,
    fps: f64,
) -> Vec<[Point3<f64>; 3]> {
    if noise_px < MIN_NOISE_PX {
        // Tracks without measurable noise: the path from eqs. 10–11 is already exact.
        return key.to_vec();
    }
    let dt = frame_interval_s(fps);
    // The trunk's typical pitch towards the camera: the median over the path chosen frame by
    // frame (a frame whose noise tipped its triangle the wrong way moves a median little).
    let mut tilts: Vec<f64> = key.iter().map(tilt_m).collect();
    tilts.sort_by(f64::total_cmp);
    let median_tilt_m = tilts.get(tilts.len() / 2).copied().unwrap_or(0.0);
    let problem = KeyPath {
        tilt_m: median_tilt_m,
        sigma_tilt_m: key_tilt_sigma_m(noise_px),
        cam,
        observed,
        weights,
        sides: SIDES.map(|(a, b)| (model[b] - model[a]).norm()),
        sigma_px: 0.5 * noise_px.max(MIN_NOISE_PX),
        sigma_accel_m: key_acceleration_mps2(noise_px) * dt * dt,
    };
    let x = DVector::from_iterator(
        9 * key.len(),
        key.iter()
            .flat_map(|k| k.iter().flat_map(|p| [p.x, p.y, p.z])),
    );
    // No cancel between steps: the whole fit takes milliseconds.
    let Some(minimum) = minimise(&problem, x, MAX_ITERATIONS, &mut |_| true) else {
        return key.to_vec();
    };
    let x = minimum.x;
    let cm = centroid(model);
    (0..key.len())
        .map(|t| {
            let fitted = [0, 1, 2].map(|k| {
                let c = 9 * t + 3 * k;
                Point3::new(x[c], x[c + 1], x[c + 2])
            });
            let r = rigid_rotation(model, &fitted);
            let c = centroid(&fitted);
            model.map(|m| Point3::from(r * (m.coords - cm) + c))
        })
        .collect()
}

/// How far the chest lies behind the shoulders' midpoint along the camera's axis, metres: the
/// trunk's pitch towards (negative) or away from the camera.
pub(crate) fn tilt_m(key: &[Point3<f64>; 3]) -> f64 {
    key[2].z - 0.5 * (key[0].z + key[1].z)
}

/// The centroid of three points (the key triangle's).
pub(crate) fn centroid(p: &[Point3<f64>; 3]) -> Vector3<f64> {
    (p[0].coords + p[1].coords + p[2].coords) / 3.0
}

/// The rotation taking `model` onto `target` about their centroids, in the least-squares sense
/// (Kabsch 1976).
fn rigid_rotation(model: &[Point3<f64>; 3], target: &[Point3<f64>; 3]) -> UnitQuaternion<f64> {
    let (cm, ct) = (centroid(model), centroid(target));
    let mut h = Matrix3::zeros();
    for (m, t) in model.iter().zip(target) {
        h += (m.coords - cm) * (t.coords - ct).transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return UnitQuaternion::identity();
    };
    let mut d = Matrix3::identity();
    if (v_t.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = v_t.transpose() * d * u.transpose();
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r))
}

#[cfg(test)]
mod tests {
    use super::super::least_squares::assert_rows_match_finite_differences;
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn the_rigid_rotation_finds_a_turned_triangle() {
        let model = [
            Point3::new(0.18, 0.0, 0.0),
            Point3::new(-0.18, 0.0, 0.0),
            Point3::new(0.0, 0.12, 0.03),
        ];
        let r = UnitQuaternion::from_euler_angles(0.4, -0.9, 0.2);
        let target = model.map(|p| Point3::from(r * p.coords + Vector3::new(0.3, -0.2, 4.0)));
        let found = rigid_rotation(&model, &target);
        assert!(found.angle_to(&r) < 1e-9);
    }

    /// A walk: the camera, the model triangle, its true path and its image points.
    type Walk = (
        PinholeCamera,
        [Point3<f64>; 3],
        Vec<[Point3<f64>; 3]>,
        Vec<[Point2<f64>; 3]>,
    );

    /// A triangle turning and walking away from the camera, its image points with white noise.
    fn walk(noise_px: f64) -> Walk {
        let cam = PinholeCamera::centred(600.0, 640, 480);
        let model = [
            Point3::new(0.18, 0.0, 0.0),
            Point3::new(-0.18, 0.0, 0.0),
            Point3::new(0.0, 0.2, 0.0),
        ];
        let truth: Vec<[Point3<f64>; 3]> = (0..90)
            .map(|t| {
                let t = t as f64 / 30.0;
                let r = UnitQuaternion::from_euler_angles(0.1, 0.6 * (1.5 * t).sin(), 0.0);
                let d = Vector3::new(0.2 * t - 0.3, -0.3, 4.0 + 0.5 * t);
                model.map(|p| Point3::from(r * p.coords + d))
            })
            .collect();
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let normal = Normal::new(0.0, noise_px.max(1e-12)).unwrap();
        let observed = truth
            .iter()
            .map(|k| {
                k.map(|p| {
                    let u = cam.project(&p).unwrap();
                    let mut jitter = || {
                        if noise_px > 0.0 {
                            normal.sample(&mut rng)
                        } else {
                            0.0
                        }
                    };
                    Point2::new(u.x + jitter(), u.y + jitter())
                })
            })
            .collect();
        (cam, model, truth, observed)
    }

    fn mean_error(a: &[[Point3<f64>; 3]], b: &[[Point3<f64>; 3]]) -> f64 {
        let sum: f64 = a
            .iter()
            .zip(b)
            .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).norm()).sum::<f64>())
            .sum();
        sum / (3 * a.len()) as f64
    }

    /// Central finite differences of every residual against the analytic rows, off the
    /// solution (noisy points, a start moved away from them).
    #[test]
    fn analytic_rows_match_finite_differences() {
        let (cam, model, truth, observed) = walk(2.0);
        let (truth, observed) = (&truth[..5], &observed[..5]);
        let weights: Vec<[f64; 3]> = (0..5).map(|t| [1.0, 0.5, 0.2 + 0.1 * t as f64]).collect();
        let problem = KeyPath {
            cam: &cam,
            observed,
            weights: &weights,
            sides: SIDES.map(|(a, b)| 1.02 * (model[b] - model[a]).norm()),
            sigma_px: 0.7,
            sigma_accel_m: 0.01,
            tilt_m: 0.02,
            sigma_tilt_m: 0.03,
        };
        let x = DVector::from_iterator(
            45,
            truth
                .iter()
                .flat_map(|k| k.iter().flat_map(|p| [p.x + 0.01, p.y - 0.02, p.z + 0.05])),
        );
        assert_rows_match_finite_differences(&problem, &x);
    }

    #[test]
    fn an_exact_path_stays_and_every_frame_keeps_the_triangle() {
        let (cam, model, truth, observed) = walk(0.0);
        let weights = vec![[1.0; 3]; truth.len()];
        // Without noise the path is returned as it is; at the least noise assumed it barely
        // moves.
        let fit =
            |noise: f64| smooth_key_path(&cam, &truth, &observed, &weights, &model, noise, 30.0);
        assert_eq!(fit(0.0), truth);
        let out = fit(MIN_NOISE_PX);
        assert!(
            mean_error(&out, &truth) < 1e-4,
            "{}",
            mean_error(&out, &truth)
        );
        for k in &out {
            for (a, b) in SIDES {
                let want = (model[b] - model[a]).norm();
                assert!(((k[b] - k[a]).norm() - want).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn a_noisy_path_comes_closer_to_the_truth() {
        // Start from the truth pushed about by the noise the way eqs. 10–11 would: the rigid
        // fit to each frame's noisy points, found here by assuming exact tracks (reprojection
        // tight, acceleration loose) from a start along the true path.
        let (cam, model, truth, observed) = walk(2.0);
        let weights = vec![[1.0; 3]; truth.len()];
        let fit = |start: &[[Point3<f64>; 3]], noise: f64| {
            smooth_key_path(&cam, start, &observed, &weights, &model, noise, 30.0)
        };
        let per_frame = fit(&truth, MIN_NOISE_PX);
        let before = mean_error(&per_frame, &truth);
        let after = mean_error(&fit(&per_frame, 2.0), &truth);
        // Measured: 224 → 86 mm.
        assert!(before > 0.1, "before {before}");
        assert!(after < 0.5 * before, "{before} → {after}");
    }

    #[test]
    fn the_pitch_term_steadies_the_trunks_pitch_towards_the_camera() {
        // The walk nearly keeps its pitch (the chest 16–20 mm behind the shoulders' midpoint as
        // it turns); the same fit as the path's with the pitch term at 2 px and turned off.
        let (cam, model, truth, observed) = walk(2.0);
        let weights = vec![[1.0; 3]; truth.len()];
        let per_frame = smooth_key_path(
            &cam,
            &truth,
            &observed,
            &weights,
            &model,
            MIN_NOISE_PX,
            30.0,
        );
        let pitch_error = |sigma_tilt_m: f64| {
            let problem = KeyPath {
                cam: &cam,
                observed: &observed,
                weights: &weights,
                sides: SIDES.map(|(a, b)| (model[b] - model[a]).norm()),
                sigma_px: 1.0,
                sigma_accel_m: key_acceleration_mps2(2.0) / 900.0,
                tilt_m: tilt_m(&truth[0]),
                sigma_tilt_m,
            };
            let x = DVector::from_iterator(
                9 * per_frame.len(),
                per_frame
                    .iter()
                    .flat_map(|k| k.iter().flat_map(|p| [p.x, p.y, p.z])),
            );
            let x = minimise(&problem, x, MAX_ITERATIONS, &mut |_| true)
                .expect("the fit runs")
                .x;
            truth
                .iter()
                .enumerate()
                .map(|(t, k)| {
                    let p = |i: usize| Point3::new(x[9 * t + 3 * i], 0.0, x[9 * t + 3 * i + 2]);
                    (tilt_m(&[p(0), p(1), p(2)]) - tilt_m(k)).abs()
                })
                .sum::<f64>()
                / truth.len() as f64
        };
        let (off, on) = (pitch_error(1e3), pitch_error(key_tilt_sigma_m(2.0)));
        // Measured: 20.1 → 4.4 mm.
        assert!(on < 0.5 * off, "pitch error {off} → {on} m");
    }
}
