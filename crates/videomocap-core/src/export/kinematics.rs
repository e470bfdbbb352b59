//! Kinematic posture (Chu et al. §4): a local frame on every rig joint (Z along its bone, X by
//! the rules of [`XRule`], Y = Z × X) and each joint's rotation relative to its parent, from
//! world-space joint positions. Shared by the BVH export and the volume pipeline.

use super::ExportError;
use super::rig::{Limb, RIG, XRule, rest_pose};
use crate::skeleton::{BONE_COUNT, Bone, Joint, PerJoint};
use nalgebra::{Matrix3, Point3, Rotation3, Vector3};

/// A bone bent less than this (degrees) has no hinge plane of its own; the plane is carried over
/// from the neighbouring frames.
pub const STRAIGHT_LIMB_DEG: f64 = 10.0;

/// The rig's motion: rest offsets and, per frame, the root's position and every joint's rotation
/// relative to its parent.
#[derive(Debug, Clone, PartialEq)]
pub struct RigMotion {
    /// Rest offset of each rig joint from its parent in the parent's frame, metres (the root's
    /// is zero).
    pub offsets: Vec<Vector3<f64>>,
    /// Seconds per frame.
    pub frame_time_s: f64,
    /// One pose per frame.
    pub frames: Vec<RigPose>,
}

/// One frame of [`RigMotion`].
#[derive(Debug, Clone, PartialEq)]
pub struct RigPose {
    /// World position of the root (the pelvis), metres.
    pub root: Point3<f64>,
    /// Rotation of each rig joint relative to its parent (the root's is global); identity for
    /// End Sites and the untracked parts ([`XRule::Rigid`]).
    pub local: Vec<Rotation3<f64>>,
}

impl RigMotion {
    /// Forward kinematics: every rig joint's world position in frame `f`.
    pub fn positions(&self, f: usize) -> Vec<Point3<f64>> {
        self.forward(&self.frames[f])
    }

    /// Every rig joint's position in the rest pose (every rotation zero, the root at the
    /// origin).
    #[cfg(test)]
    fn positions_at_rest(&self) -> Vec<Point3<f64>> {
        self.forward(&RigPose {
            root: Point3::origin(),
            local: vec![Rotation3::identity(); RIG.len()],
        })
    }

    fn forward(&self, pose: &RigPose) -> Vec<Point3<f64>> {
        let mut global: Vec<Rotation3<f64>> = Vec::with_capacity(RIG.len());
        let mut pos: Vec<Point3<f64>> = Vec::with_capacity(RIG.len());
        for (i, r) in RIG.iter().enumerate() {
            match r.parent {
                None => {
                    global.push(pose.local[i]);
                    pos.push(pose.root);
                }
                Some(p) => {
                    pos.push(pos[p] + global[p] * self.offsets[i]);
                    global.push(global[p] * pose.local[i]);
                }
            }
        }
        pos
    }
}

/// Median length of every model bone over the frames, and the median shoulder width.
pub fn median_lengths(frames: &[PerJoint<Point3<f64>>]) -> ([f64; BONE_COUNT], f64) {
    let median = |f: &dyn Fn(&PerJoint<Point3<f64>>) -> f64| {
        let mut v: Vec<f64> = frames.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    let lengths = Bone::ALL.map(|b| median(&|p| (p[b.child] - p[b.parent]).norm()));
    let width = median(&|p| (p[Joint::LeftShoulder] - p[Joint::RightShoulder]).norm());
    (lengths, width)
}

/// Local frames and joint rotations for a world-space sequence (metres, Y up). The rest pose is
/// the T-pose of [`rest_pose`] with the median bone lengths; a joint's global rotation is its
/// frame times the transpose of its rest frame, so the rest pose has every rotation zero and
/// each bone's offset turns onto the bone.
pub fn solve(
    frames: &[PerJoint<Point3<f64>>],
    frame_time_s: f64,
) -> Result<RigMotion, ExportError> {
    if frames.is_empty() {
        return Err(ExportError::NoFrames);
    }
    let (lengths, width) = median_lengths(frames);
    if let Some(b) = Bone::ALL.iter().zip(&lengths).find(|(_, l)| **l <= 1e-6) {
        return Err(ExportError::ZeroBone(b.0.key()));
    }
    let rest = rest_pose(&lengths, width);
    let rest_rig = rig_positions(&rest);
    let rest_hinges = Limb::ALL.map(|l| reference_axis(l, &rest, None));
    let rest_frames = body_frames(&rest_rig, &rest, &rest_hinges);
    let offsets = RIG
        .iter()
        .enumerate()
        .map(|(i, r)| {
            r.parent
                .map_or(Vector3::zeros(), |p| rest_rig[i] - rest_rig[p])
        })
        .collect();
    let hinges = hinge_axes(frames);
    let poses = frames
        .iter()
        .zip(&hinges)
        .map(|(p, h)| {
            let rig = rig_positions(p);
            let body = body_frames(&rig, p, h);
            let global: Vec<Matrix3<f64>> = body
                .iter()
                .zip(&rest_frames)
                .map(|(b, r)| b * r.transpose())
                .collect();
            let local = RIG
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    let m = match r.parent {
                        _ if r.is_end() || r.x_rule == XRule::Rigid => Matrix3::identity(),
                        None => global[i],
                        Some(parent) => global[parent].transpose() * global[i],
                    };
                    Rotation3::from_matrix(&m)
                })
                .collect();
            RigPose {
                root: rig[0],
                local,
            }
        })
        .collect();
    Ok(RigMotion {
        offsets,
        frame_time_s,
        frames: poses,
    })
}

/// Positions of the rig joints on a model pose.
pub fn rig_positions(p: &PerJoint<Point3<f64>>) -> Vec<Point3<f64>> {
    RIG.iter().map(|r| r.place.position(|j| p[j])).collect()
}

/// Each rig joint's frame as a matrix whose columns are its X, Y and Z axes (identity for End
/// Sites). `hinges` holds the four limbs' hinge axes in [`Limb::ALL`] order.
fn body_frames(
    rig: &[Point3<f64>],
    model: &PerJoint<Point3<f64>>,
    hinges: &[Vector3<f64>; 4],
) -> Vec<Matrix3<f64>> {
    let mut out: Vec<Matrix3<f64>> = Vec::with_capacity(RIG.len());
    for (i, r) in RIG.iter().enumerate() {
        let Some(aim) = r.aim else {
            out.push(Matrix3::identity());
            continue;
        };
        let parent = r.parent.map(|p| out[p]);
        let parent_axis = |k: usize| parent.map_or(Vector3::ith(k, 1.0), |m| m.column(k).into());
        let z = (rig[aim] - rig[i])
            .try_normalize(1e-9)
            .unwrap_or_else(|| parent_axis(2));
        let x_wanted = match r.x_rule {
            XRule::Across(left, right) => z.cross(&(model[left] - model[right])),
            XRule::FromParent => {
                let x = parent_axis(0).cross(&z);
                if x.norm() > 1e-6 {
                    x
                } else {
                    parent_axis(1).cross(&z)
                }
            }
            XRule::Hinge(limb) => hinges[limb_index(limb)],
            XRule::ParentX | XRule::Rigid => parent_axis(0),
        };
        let x = perpendicular(x_wanted, z)
            .or_else(|| perpendicular(parent_axis(0), z))
            .or_else(|| perpendicular(parent_axis(1), z))
            .unwrap_or_else(|| z.cross(&Vector3::x()).normalize());
        let y = z.cross(&x);
        out.push(Matrix3::from_columns(&[x, y, z]));
    }
    out
}

/// `v` made perpendicular to the unit vector `z` and normalised, `None` when (nearly) parallel.
fn perpendicular(v: Vector3<f64>, z: Vector3<f64>) -> Option<Vector3<f64>> {
    (v - v.dot(&z) * z).try_normalize(1e-6 * v.norm().max(1e-12))
}

fn limb_index(limb: Limb) -> usize {
    Limb::ALL.iter().position(|l| *l == limb).unwrap_or(0)
}

/// The axis a normal flexion of `limb` would turn about: upper bone × the body's front (elbows)
/// or back (knees). The front is (left − right) × up of the shoulders and trunk for arms, of
/// the hips and spine for legs. With `upper` given it replaces the limb's own upper direction.
fn reference_axis(
    limb: Limb,
    p: &PerJoint<Point3<f64>>,
    upper: Option<Vector3<f64>>,
) -> Vector3<f64> {
    let [root, mid, _] = limb.joints();
    let (left, right, low, high) = if limb.flexes_forward() {
        (
            Joint::LeftShoulder,
            Joint::RightShoulder,
            Joint::Pelvis,
            Joint::Neck,
        )
    } else {
        (Joint::LeftHip, Joint::RightHip, Joint::Pelvis, Joint::Chest)
    };
    let front = (p[left] - p[right]).cross(&(p[high] - p[low]));
    let flex = if limb.flexes_forward() { front } else { -front };
    let upper = upper.unwrap_or(p[mid] - p[root]);
    match (upper.try_normalize(1e-12), flex.try_normalize(1e-12)) {
        (Some(u), Some(f)) => u.cross(&f),
        // No direction to speak of: the frame builder falls back to the parent's axes.
        _ => Vector3::zeros(),
    }
}

/// The hinge axis of each limb on each frame, so that elbows and knees keep their plane and
/// twist does not flip: where the limb is bent by more than [`STRAIGHT_LIMB_DEG`] the axis is
/// upper × lower bone, its sign kept continuous with the axis carried from the bent frame
/// before; on a run of nearly straight frames the axes of the bent frames on either side are
/// carried in frame by frame (kept perpendicular to the upper bone) and blended linearly over
/// the run, so twist that happened while the limb was straight turns smoothly (leading and
/// trailing runs take the one axis they have). Finally the whole limb's sign is
/// chosen so that most bent frames flex the anatomical way (elbows forwards, knees backwards);
/// a limb never bent uses the anatomical axis itself.
pub fn hinge_axes(frames: &[PerJoint<Point3<f64>>]) -> Vec<[Vector3<f64>; 4]> {
    let mut out = vec![[Vector3::zeros(); 4]; frames.len()];
    let min_sin = STRAIGHT_LIMB_DEG.to_radians().sin();
    for (k, limb) in Limb::ALL.into_iter().enumerate() {
        let [root, mid, end] = limb.joints();
        let upper: Vec<Vector3<f64>> = frames
            .iter()
            .map(|p| {
                (p[mid] - p[root])
                    .try_normalize(1e-12)
                    .unwrap_or_else(Vector3::y)
            })
            .collect();
        let bent: Vec<Option<Vector3<f64>>> = frames
            .iter()
            .zip(&upper)
            .map(|(p, u)| {
                let a = u.cross(&(p[end] - p[mid]).try_normalize(1e-12)?);
                (a.norm() >= min_sin).then(|| a.normalize())
            })
            .collect();
        let n = frames.len();
        // Forward: bent frames keep the sign of the axis carried from before; `forward[t]` is
        // the last bent frame's axis carried frame by frame (kept perpendicular to the upper
        // bone) up to t.
        let mut axis: Vec<Option<Vector3<f64>>> = vec![None; n];
        let mut forward: Vec<Option<Vector3<f64>>> = vec![None; n];
        let mut carried: Option<Vector3<f64>> = None;
        for t in 0..n {
            carried = carried.and_then(|v| perpendicular(v, upper[t]));
            if let Some(a) = bent[t] {
                let a = match carried {
                    Some(c) if a.dot(&c) < 0.0 => -a,
                    _ => a,
                };
                axis[t] = Some(a);
                carried = Some(a);
            }
            forward[t] = carried;
        }
        // Backward: the next bent frame's axis carried back; straight runs blend the two so a
        // twist that happened while the limb was straight is spread over the run.
        let mut back: Option<(usize, Vector3<f64>)> = None;
        for t in (0..n).rev() {
            if let Some(a) = axis[t] {
                back = Some((t, a));
                continue;
            }
            back = back.and_then(|(q, v)| Some((q, perpendicular(v, upper[t])?)));
            let last_bent = (0..t).rev().find(|&p| axis[p].is_some());
            axis[t] = match (forward[t], back, last_bent) {
                (Some(f), Some((q, b)), Some(p)) => {
                    let s = (t - p) as f64 / (q - p) as f64;
                    perpendicular((1.0 - s) * f + s * b, upper[t]).or(Some(f))
                }
                (Some(f), _, _) => Some(f),
                (None, Some((_, b)), _) => Some(b),
                (None, None, _) => None,
            };
        }
        let vote: f64 = (0..frames.len())
            .filter_map(|t| {
                let a = axis[t]?;
                bent[t]?;
                Some(a.dot(&reference_axis(limb, &frames[t], Some(upper[t]))))
            })
            .sum();
        let sign = if vote < 0.0 { -1.0 } else { 1.0 };
        for t in 0..frames.len() {
            out[t][k] = match axis[t] {
                Some(a) => sign * a,
                None => reference_axis(limb, &frames[t], Some(upper[t])),
            };
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::rig::rig_index_of;
    use crate::skeleton::SubjectModel;

    /// A pose with every bone turned a different way.
    fn pose(seed: f64) -> PerJoint<Point3<f64>> {
        let s = SubjectModel::default();
        let rest = rest_pose(&Bone::ALL.map(|b| s.bone_length(b)), 0.35);
        let mut p = rest;
        for (k, b) in Bone::ALL.iter().enumerate() {
            let k = k as f64 + seed;
            let turn = Rotation3::new(Vector3::new(
                0.3 * k.sin(),
                0.5 * k.cos(),
                0.2 * (2.0 * k).sin(),
            ));
            p[b.child] = p[b.parent] + turn * (rest[b.child] - rest[b.parent]);
        }
        p
    }

    #[test]
    fn forward_kinematics_gives_back_every_joint() {
        let frames: Vec<_> = (0..5).map(|t| pose(t as f64 * 0.1)).collect();
        let motion = solve(&frames, 0.04).unwrap();
        for (f, p) in frames.iter().enumerate() {
            let fk = motion.positions(f);
            let want = rig_positions(p);
            // The toes turn with the shank: they keep the rest pose's angle to it.
            let (knee, ankle) = (
                rig_index_of(Joint::LeftKnee),
                rig_index_of(Joint::LeftAnkle),
            );
            let toe = RIG
                .iter()
                .position(|r| r.parent == Some(ankle))
                .expect("the foot's End Site");
            let angle_at = |q: &[Point3<f64>]| (q[ankle] - q[knee]).angle(&(q[toe] - q[ankle]));
            let rest_angle = angle_at(&motion.positions_at_rest());
            let angle = angle_at(&fk);
            assert!(
                (angle - rest_angle).abs() < 1e-9,
                "{angle} against {rest_angle}"
            );
            for (i, (a, b)) in fk.iter().zip(&want).enumerate() {
                if matches!(RIG[i].place, crate::export::rig::Place::Toe { .. }) {
                    continue;
                }
                assert!(
                    (a - b).norm() < 1e-9,
                    "frame {f} {}: {a} vs {b}",
                    RIG[i].name
                );
            }
        }
    }
}
