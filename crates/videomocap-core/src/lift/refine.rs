//! Beyond the paper: one nonlinear least-squares pass over all frames at once.
//!
//! Unknowns: every joint of every frame (camera space) and the 15 bone lengths plus the
//! shoulder width. Residuals, each divided by its expected size:
//! - reprojection of every joint onto its track, weighted by the track's confidence (an
//!   interpolated point counts half), `σ = reprojection_sigma_px`;
//! - every bone (and the shoulder line) at its length, `σ = length_sigma_m`;
//! - the pelvis halfway between the hips (the model's definition), `σ = length_sigma_m`;
//! - every joint's acceleration, `σ = a · Δt²` with `a` from the tracks' noise (adaptive, the
//!   default) or `acceleration_sigma_mps2`;
//! - each length near its starting value (`σ = length_prior` of it) and their sum at its
//!   starting value (a monocular camera cannot see scale: the subject's height sets it);
//! - every joint near where the per-frame solve put it, `σ = anchor_sigma_m` (a trust region:
//!   one camera sees depth poorly, and without it a few 2D points the skeleton cannot reach
//!   re-posed whole bodies to reach them).
//!
//! Solved by Levenberg–Marquardt; the normal equations are sparse (banded over frames plus
//! the length columns) and factored with `nalgebra-sparse`'s Cholesky.

use super::error::LiftError;
use super::least_squares::{Residuals, Row, frame_interval_s, minimise};
use crate::camera::PinholeCamera;
use crate::formats::{NetworkBody, PointSource, TrackedPoint};
use crate::skeleton::{BONE_COUNT, Bone, JOINT_COUNT, Joint, PerJoint, SubjectModel};
use nalgebra::{DVector, Point2, Point3, Rotation3, Vector3};
use std::sync::atomic::{AtomicBool, Ordering};

/// Weights of the refinement: fitted constants (`docs/method.md`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineParams {
    /// Expected 2D error of a fully trusted track point, pixels (default 20: the tracker's
    /// errors are drift and jumps of several to tens of pixels, and the per-frame solve already
    /// lies on the smoothed tracks' rays, so the pass mostly smooths and evens the lengths).
    /// Measured in `docs/method.md` ("Fitted constants of the lift").
    pub reprojection_sigma_px: f64,
    /// Allowed deviation of a bone from its length, metres (default 0.005).
    pub length_sigma_m: f64,
    /// Typical joint acceleration when `adaptive` is off, m/s² (default 100: only jitter is
    /// smoothed; at 20 the refinement bent fast motions such as jumping jacks out of shape on
    /// the suite).
    pub acceleration_sigma_mps2: f64,
    /// Allowed relative change of each bone length from its start (default 0.01: one camera
    /// cannot tell a longer bone from a bone turned towards it, and at 0.1 the refinement traded
    /// lengths for depth and tilted whole poses on the suite).
    pub length_prior: f64,
    /// Levenberg–Marquardt iterations at most (default 6: on the dev split 6, 10 and 20 gave the
    /// same figures to 0.1 mm, and each step costs a factorisation).
    pub max_iterations: usize,
    /// How far (metres, standard deviation per axis) a joint may move from the per-frame solve
    /// (default 0.03; 0 turns the anchor off). Measured in `docs/method.md` ("Fitted constants
    /// of the lift").
    pub anchor_sigma_m: f64,
    /// Set the acceleration deviation from the tracks' own noise (default true): it is
    /// `ACCELERATION_TIMES_NOISE` over the median white-noise deviation of the joints' tracks
    /// (`super::smoothing::median_noise_px`), so noisy tracks are smoothed firmly and exact
    /// ones barely. Measured in `docs/method.md` ("Fitted constants of the lift").
    pub adaptive: bool,
    /// How far (metres along the child's viewing ray, at full confidence) a bone's child may sit
    /// from where the pose network's direction for the bone puts it at the bone's length
    /// (default 0.025; 0 turns the pull off): the network sees the limbs' depth better than the
    /// rays and the priors alone, and the image places the bone across the ray. Measured in
    /// `docs/method.md` ("The network's bone directions in the refinement").
    pub network_direction_sigma_m: f64,
}

impl Default for RefineParams {
    fn default() -> Self {
        RefineParams {
            reprojection_sigma_px: 20.0,
            length_sigma_m: 0.005,
            acceleration_sigma_mps2: 100.0,
            length_prior: 0.01,
            max_iterations: 6,
            anchor_sigma_m: 0.03,
            adaptive: true,
            network_direction_sigma_m: 0.025,
        }
    }
}

/// The adaptive refinement's acceleration deviation (m/s²) is this over the tracks' noise
/// (pixels): jitter needs a firm hand, exact tracks almost none. On the synthetic suite with true
/// lengths and before the anchor ([`RefineParams::anchor_sigma_m`]) it gave 63.5 → 61.5 mm
/// MPJPE with 2 px noise and 20.4 → 21.6 mm with exact tracks
/// (without the floor below, 30 gave 66.3 and 23.5 and 100 gave 63.1 and 20.9; the fixed
/// 100 m/s² gives 64.2 and 24.4).
pub(super) const ACCELERATION_TIMES_NOISE: f64 = 60.0;

/// The firmest acceleration deviation the adaptive refinement uses, m/s² (reached at 2 px of
/// noise): at 20 m/s² it bent fast motions such as jumping jacks out of shape on the suite.
pub(super) const MIN_ACCELERATION_MPS2: f64 = 30.0;

/// The least noise the adaptive refinement assumes, pixels (exact tracks read 0.1–1 px: fast
/// motion is not quite smooth at the frame rate).
pub(super) const MIN_NOISE_PX: f64 = 0.1;

/// What the refinement did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineSummary {
    /// Iterations run.
    pub iterations: usize,
    /// Weighted cost before.
    pub cost_before: f64,
    /// Weighted cost at the least-squares minimum (before the bones are snapped to their
    /// lengths).
    pub cost_after: f64,
    /// RMS reprojection error before, pixels.
    pub reprojection_px_before: f64,
    /// RMS reprojection error of the returned (snapped) points, pixels.
    pub reprojection_px_after: f64,
}

/// The refined sequence.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Refined {
    /// Joints per frame.
    pub points: Vec<PerJoint<Point3<f64>>>,
    /// Bone lengths (indexed like [`Bone::ALL`]), metres.
    pub bone_lengths: [f64; BONE_COUNT],
    /// Shoulder width, metres.
    pub shoulder_width: f64,
    /// Summary.
    pub summary: RefineSummary,
}

/// The weight of a track point in the reprojection term: its confidence (at least 0.05), halved
/// when it was interpolated (not seen there).
pub(super) fn track_weight(p: &TrackedPoint) -> f64 {
    let c = f64::from(p.confidence).clamp(0.05, 1.0);
    if p.source == PointSource::Interpolated {
        0.5 * c
    } else {
        c
    }
}

/// Lengths held: the 15 bones then the shoulder width.
const LENGTHS: usize = BONE_COUNT + 1;
// The scale row has one entry per length.
const _: () = assert!(LENGTHS <= super::least_squares::MAX_ENTRIES);
const PER_FRAME: usize = 3 * JOINT_COUNT;

/// The pairs of joints held at a length, in [`Bone::ALL`] order then the shoulders.
fn length_pairs() -> [(Joint, Joint); LENGTHS] {
    let mut pairs = [(Joint::LeftShoulder, Joint::RightShoulder); LENGTHS];
    for (k, b) in Bone::ALL.iter().enumerate() {
        pairs[k] = (b.parent, b.child);
    }
    pairs
}

/// The problem's data.
struct Problem<'a> {
    cam: &'a PinholeCamera,
    images: &'a [PerJoint<Point2<f64>>],
    weights: &'a [PerJoint<f64>],
    /// The per-frame solve, where the anchor rows hold the joints.
    start: &'a [PerJoint<Point3<f64>>],
    start_lengths: [f64; LENGTHS],
    params: RefineParams,
    /// Acceleration deviation, metres per frame² ([`acceleration_sigma_m`]).
    accel_sigma_m: f64,
    /// Per frame, the bones the pose network saw ([`network_directions`]).
    directions: Vec<Vec<SeenBone>>,
}

/// The subject's lengths in refinement order: the 15 bones, then the shoulder width.
fn subject_lengths(subject: &SubjectModel) -> [f64; LENGTHS] {
    let mut lengths = [subject.shoulder_width_m; LENGTHS];
    lengths[..BONE_COUNT].copy_from_slice(&subject.bone_length_m);
    lengths
}

impl Problem<'_> {
    /// The unknowns as one vector: every frame's joints, then the lengths.
    fn pack(points: &[PerJoint<Point3<f64>>], lengths: &[f64; LENGTHS]) -> DVector<f64> {
        let n = points.len();
        let mut x = DVector::zeros(n * PER_FRAME + LENGTHS);
        for (t, frame) in points.iter().enumerate() {
            for j in Joint::ALL {
                let c = Self::col(t, j);
                x[c] = frame[j].x;
                x[c + 1] = frame[j].y;
                x[c + 2] = frame[j].z;
            }
        }
        for (k, l) in lengths.iter().enumerate() {
            x[n * PER_FRAME + k] = *l;
        }
        x
    }

    fn col(t: usize, j: Joint) -> usize {
        t * PER_FRAME + 3 * j.index()
    }

    fn point(x: &DVector<f64>, t: usize, j: Joint) -> Point3<f64> {
        let c = Self::col(t, j);
        Point3::new(x[c], x[c + 1], x[c + 2])
    }

    fn reprojection_rms(&self, x: &DVector<f64>) -> f64 {
        let mut sum = 0.0;
        let mut count = 0.0f64;
        for (t, image) in self.images.iter().enumerate() {
            for j in Joint::ALL {
                if let Some(p) = self.cam.project(&Self::point(x, t, j)) {
                    sum += (p - image[j]).norm_squared();
                    count += 1.0;
                }
            }
        }
        (sum / count.max(1.0)).sqrt()
    }
}

impl Residuals for Problem<'_> {
    fn rows(&self, x: &DVector<f64>, emit: &mut dyn FnMut(Row)) {
        for t in 0..self.images.len() {
            self.image_rows(x, t, emit);
            self.length_rows(x, t, emit);
            self.network_rows(x, t, emit);
            self.acceleration_rows(x, t, emit);
        }
        self.global_rows(x, emit);
    }
}

impl Problem<'_> {
    /// Frame `t`'s reprojection rows and its anchor to the per-frame solve.
    fn image_rows(&self, x: &DVector<f64>, t: usize, emit: &mut dyn FnMut(Row)) {
        let p = &self.params;
        let f = self.cam.focal_px;
        for j in Joint::ALL {
            let c = Self::col(t, j);
            let q = Self::point(x, t, j);
            let z = q.z.max(1e-3);
            let s = self.weights[t][j].sqrt() / p.reprojection_sigma_px;
            let u = f * q.x / z + self.cam.cx - self.images[t][j].x;
            let v = f * q.y / z + self.cam.cy - self.images[t][j].y;
            emit(
                Row::new(s * u)
                    .with(c, s * f / z)
                    .with(c + 2, -s * f * q.x / (z * z)),
            );
            emit(
                Row::new(s * v)
                    .with(c + 1, s * f / z)
                    .with(c + 2, -s * f * q.y / (z * z)),
            );
        }
        if p.anchor_sigma_m > 0.0 {
            let s = 1.0 / p.anchor_sigma_m;
            for j in Joint::ALL {
                let c = Self::col(t, j);
                let q = Self::point(x, t, j) - self.start[t][j];
                for axis in 0..3 {
                    emit(Row::new(s * q[axis]).with(c + axis, s));
                }
            }
        }
    }

    /// Frame `t`'s bones (and shoulder line) at their lengths, the pelvis between the hips.
    fn length_rows(&self, x: &DVector<f64>, t: usize, emit: &mut dyn FnMut(Row)) {
        let p = &self.params;
        let lcol = self.images.len() * PER_FRAME;
        let pairs = length_pairs();
        let s = 1.0 / p.length_sigma_m;
        for (k, &(a, b)) in pairs.iter().enumerate() {
            let d = Self::point(x, t, b) - Self::point(x, t, a);
            let len = d.norm().max(1e-9);
            let u = d / len;
            let (ca, cb) = (Self::col(t, a), Self::col(t, b));
            emit(
                Row::new(s * (len - x[lcol + k]))
                    .with(cb, s * u.x)
                    .with(cb + 1, s * u.y)
                    .with(cb + 2, s * u.z)
                    .with(ca, -s * u.x)
                    .with(ca + 1, -s * u.y)
                    .with(ca + 2, -s * u.z)
                    .with(lcol + k, -s),
            );
        }
        let (cl, cr, cp) = (
            Self::col(t, Joint::LeftHip),
            Self::col(t, Joint::RightHip),
            Self::col(t, Joint::Pelvis),
        );
        for axis in 0..3 {
            emit(
                Row::new(s * (x[cl + axis] + x[cr + axis] - 2.0 * x[cp + axis]))
                    .with(cl + axis, s)
                    .with(cr + axis, s)
                    .with(cp + axis, -2.0 * s),
            );
        }
    }

    /// Frame `t`'s pull towards the network's bone directions, along the children's rays.
    fn network_rows(&self, x: &DVector<f64>, t: usize, emit: &mut dyn FnMut(Row)) {
        let p = &self.params;
        let pairs = length_pairs();
        if p.network_direction_sigma_m > 0.0 {
            for &(k, u, sure) in &self.directions[t] {
                let (a, b) = pairs[k];
                let s = sure.sqrt() / p.network_direction_sigma_m;
                let d = Self::point(x, t, b) - Self::point(x, t, a);
                let target = u * self.start_lengths[k];
                let (ca, cb) = (Self::col(t, a), Self::col(t, b));
                // Along the child's ray only: the image places the bone across it.
                let e = self.start[t][b]
                    .coords
                    .try_normalize(1e-9)
                    .unwrap_or_else(Vector3::z);
                emit(
                    Row::new(s * (d - target).dot(&e))
                        .with(cb, s * e.x)
                        .with(cb + 1, s * e.y)
                        .with(cb + 2, s * e.z)
                        .with(ca, -s * e.x)
                        .with(ca + 1, -s * e.y)
                        .with(ca + 2, -s * e.z),
                );
            }
        }
    }

    /// Frame `t`'s joints' accelerations (frames inside the clip).
    fn acceleration_rows(&self, x: &DVector<f64>, t: usize, emit: &mut dyn FnMut(Row)) {
        let n = self.images.len();
        if t >= 1 && t + 1 < n {
            let s = 1.0 / self.accel_sigma_m;
            for j in Joint::ALL {
                for axis in 0..3 {
                    let (a, b, c) = (
                        Self::col(t - 1, j) + axis,
                        Self::col(t, j) + axis,
                        Self::col(t + 1, j) + axis,
                    );
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

    /// The lengths near their start and their sum at its start (the scale).
    fn global_rows(&self, x: &DVector<f64>, emit: &mut dyn FnMut(Row)) {
        let p = &self.params;
        let lcol = self.images.len() * PER_FRAME;
        let mut sum = 0.0;
        let mut start_sum = 0.0;
        for k in 0..LENGTHS {
            let l0 = self.start_lengths[k];
            let s = 1.0 / (p.length_prior * l0);
            emit(Row::new(s * (x[lcol + k] - l0)).with(lcol + k, s));
            sum += x[lcol + k];
            start_sum += l0;
        }
        // Scale: the sum of the lengths stays at its start, within 0.1 %.
        let s = 1.0 / (0.001 * start_sum);
        let mut row = Row::new(s * (sum - start_sum));
        for k in 0..LENGTHS {
            row = row.with(lcol + k, s);
        }
        emit(row);
    }
}

/// The pose with every bone at exactly its length: from the pelvis outwards ([`Bone::ALL`] lists
/// parents first), each child is put at its bone's length from its (already placed) parent along
/// the direction the refinement gave the bone. The least-squares pass holds lengths only within
/// `length_sigma_m`, and a BVH's offsets are fixed: without this the exported file would not
/// give the skeleton back exactly (0.75 mm off on the bundled synthetic clip). A bone the
/// refinement shrank to nothing takes its direction from `fallback` (the per-frame solve), or
/// straight down (+Y) when that one is nothing too.
pub(super) fn snap_to_lengths(
    free: &PerJoint<Point3<f64>>,
    fallback: &PerJoint<Point3<f64>>,
    lengths: &[f64; BONE_COUNT],
) -> PerJoint<Point3<f64>> {
    let mut snapped = *free;
    for (bone, &len) in Bone::ALL.iter().zip(lengths) {
        let dir = (free[bone.child] - free[bone.parent])
            .try_normalize(1e-9)
            .or_else(|| (fallback[bone.child] - fallback[bone.parent]).try_normalize(1e-12))
            .unwrap_or_else(Vector3::y);
        snapped[bone.child] = snapped[bone.parent] + len * dir;
    }
    snapped
}

/// The acceleration deviation in metres per frame²: from the tracks' noise when
/// `params.adaptive`, else `params.acceleration_sigma_mps2`.
fn acceleration_sigma_m(track_noise_px: f64, params: &RefineParams, dt: f64) -> f64 {
    let accel = if params.adaptive {
        (ACCELERATION_TIMES_NOISE / track_noise_px.max(MIN_NOISE_PX)).max(MIN_ACCELERATION_MPS2)
    } else {
        params.acceleration_sigma_mps2
    };
    accel * dt * dt
}

/// The network's directions are averaged over this many frames either side (weighted by its
/// confidence): frame by frame they jitter. On the dev split the averaging took the motion's
/// jitter from exact 2D 1146 → 804 m/s³ (from the tracker's output 599 → 558) and left MPJPE
/// as it was (`docs/method.md`, "The network's bone directions in the refinement").
const NETWORK_DIRECTION_FRAMES: usize = 2;

/// One bone as the network saw it on one frame: its direction in the camera's axes and the
/// network's confidence in both ends.
type Seen = (Vector3<f64>, f64);

/// A bone's index (in [`Bone::ALL`]) with how the network saw it, averaged over frames.
type SeenBone = (usize, Vector3<f64>, f64);

/// The least confidence (both ends) at which the network's direction of a bone is used.
const MIN_NETWORK_CONFIDENCE: f32 = 0.5;

/// Per frame, the bones the pose network saw surely enough ([`MIN_NETWORK_CONFIDENCE`]): each
/// bone's index, its direction in the camera's axes (averaged over
/// [`NETWORK_DIRECTION_FRAMES`] either side) and the network's confidence in both ends.
/// The network's axes are the view's (x right, y down, z away), a view centred on the body:
/// each frame's directions are turned from the optical axis onto the ray through the pelvis.
fn network_directions(
    start: &[PerJoint<Point3<f64>>],
    bodies: &[Option<NetworkBody>],
) -> Vec<Vec<SeenBone>> {
    // Each frame's bone directions in the camera's axes, where the network was sure.
    let seen: Vec<[Option<Seen>; BONE_COUNT]> = start
        .iter()
        .enumerate()
        .map(|(t, points)| {
            let Some(Some(body)) = bodies.get(t) else {
                return [None; BONE_COUNT];
            };
            let turn = points[Joint::Pelvis]
                .coords
                .try_normalize(1e-9)
                .and_then(|ray| Rotation3::rotation_between(&Vector3::z(), &ray))
                .unwrap_or_else(Rotation3::identity);
            std::array::from_fn(|k| {
                let bone = Bone::ALL[k];
                let sure = body.confidence[bone.parent].min(body.confidence[bone.child]);
                let d = body.points[bone.child] - body.points[bone.parent];
                let u = d.try_normalize(1e-6)?;
                (sure >= MIN_NETWORK_CONFIDENCE).then(|| (turn * u, f64::from(sure)))
            })
        })
        .collect();
    let radius = NETWORK_DIRECTION_FRAMES;
    (0..seen.len())
        .map(|t| {
            (0..BONE_COUNT)
                .filter_map(|k| {
                    let (_, sure) = seen[t][k]?;
                    let lo = t.saturating_sub(radius);
                    let hi = (t + radius).min(seen.len() - 1);
                    let sum: Vector3<f64> = (lo..=hi)
                        .filter_map(|s| seen[s][k].map(|(u, c)| u * c))
                        .sum();
                    Some((k, sum.try_normalize(1e-9)?, sure))
                })
                .collect()
        })
        .collect()
}

/// Refines a sequence; `start` is the per-frame solve, `bodies` the pose network's per frame
/// (empty: none), `fps` sets Δt, and `track_noise_px` is the tracks' white noise
/// ([`super::smoothing::median_noise_px`]) for the adaptive acceleration term.
#[allow(clippy::too_many_arguments)]
pub(super) fn refine(
    cam: &PinholeCamera,
    images: &[PerJoint<Point2<f64>>],
    weights: &[PerJoint<f64>],
    start: &[PerJoint<Point3<f64>>],
    bodies: &[Option<NetworkBody>],
    subject: &SubjectModel,
    fps: f64,
    track_noise_px: f64,
    params: &RefineParams,
    progress: &mut dyn FnMut(usize, usize),
    cancel: &AtomicBool,
) -> Result<Refined, LiftError> {
    let n = start.len();
    let start_lengths = subject_lengths(subject);
    let dt = frame_interval_s(fps);
    let directions = network_directions(start, bodies);
    let problem = Problem {
        cam,
        images,
        weights,
        start,
        start_lengths,
        params: *params,
        accel_sigma_m: acceleration_sigma_m(track_noise_px, params, dt),
        directions,
    };
    let x = Problem::pack(start, &start_lengths);
    let reprojection_px_before = problem.reprojection_rms(&x);
    let minimum = minimise(&problem, x, params.max_iterations, &mut |i| {
        progress(i, params.max_iterations);
        !cancel.load(Ordering::Relaxed)
    })
    .ok_or(LiftError::Cancelled)?;
    let x = minimum.x;
    progress(params.max_iterations, params.max_iterations);
    let mut lengths = [0.0; LENGTHS];
    lengths.copy_from_slice(&x.as_slice()[n * PER_FRAME..]);
    let mut bone_lengths = [0.0; BONE_COUNT];
    bone_lengths.copy_from_slice(&lengths[..BONE_COUNT]);
    let points: Vec<PerJoint<Point3<f64>>> = (0..n)
        .map(|t| {
            let free = PerJoint::from_fn(|j| Problem::point(&x, t, j));
            snap_to_lengths(&free, &start[t], &bone_lengths)
        })
        .collect();
    // The reprojection reported is that of the snapped points, which are what is returned.
    let reprojection_px_after = problem.reprojection_rms(&Problem::pack(&points, &lengths));
    Ok(Refined {
        points,
        bone_lengths,
        shoulder_width: lengths[BONE_COUNT],
        summary: RefineSummary {
            iterations: minimum.iterations,
            cost_before: minimum.cost_before,
            cost_after: minimum.cost_after,
            reprojection_px_before,
            reprojection_px_after,
        },
    })
}

#[cfg(test)]
mod tests;
