//! The joints of a standing body built outwards from its bone lengths: the one place that lays
//! out a skeleton in space, shared by the BVH rig's rest pose and the synthetic motions.

use super::{Bone, JOINT_COUNT, Joint, PerJoint};
use nalgebra::{Point3, Vector3};

/// Unit directions of one side's limb segments: upper arm, forearm, thigh, shank.
pub type LimbDirections = [Vector3<f64>; 4];

/// Places the 16 joints of a body standing at `pelvis` (metres, Y up, facing +Z, the subject's
/// left at +X): the spine straight up, the shoulders `shoulder_width` apart (lower if a clavicle
/// is too short to reach: then it lies flat), the hips straight out from the pelvis, and each
/// limb along the directions `limbs(sign)` gives for its side (`sign` +1 left, −1 right).
pub fn standing_pose(
    length: impl Fn(Bone) -> f64,
    shoulder_width: f64,
    pelvis: Point3<f64>,
    limbs: impl Fn(f64) -> LimbDirections,
) -> PerJoint<Point3<f64>> {
    let len = |a: Joint, b: Joint| length(Bone::new(a, b));
    let up = Vector3::y();
    let mut p = PerJoint([Point3::origin(); JOINT_COUNT]);
    p[Joint::Pelvis] = pelvis;
    p[Joint::Chest] = pelvis + up * len(Joint::Pelvis, Joint::Chest);
    p[Joint::Neck] = p[Joint::Chest] + up * len(Joint::Chest, Joint::Neck);
    p[Joint::HeadTop] = p[Joint::Neck] + up * len(Joint::Neck, Joint::HeadTop);
    for sign in [1.0, -1.0] {
        // The left side's joints, mirrored for the right.
        let on_side = |j: Joint| if sign > 0.0 { j } else { j.mirrored() };
        let [shoulder, elbow, wrist, hip, knee, ankle] = [
            Joint::LeftShoulder,
            Joint::LeftElbow,
            Joint::LeftWrist,
            Joint::LeftHip,
            Joint::LeftKnee,
            Joint::LeftAnkle,
        ]
        .map(on_side);
        let clavicle = len(Joint::Chest, shoulder);
        let out = (0.5 * shoulder_width).min(clavicle);
        let rise = (clavicle * clavicle - out * out).max(0.0).sqrt();
        let [upper, lower, thigh, shank] = limbs(sign);
        p[shoulder] = p[Joint::Chest] + Vector3::new(sign * out, rise, 0.0);
        p[elbow] = p[shoulder] + upper * len(shoulder, elbow);
        p[wrist] = p[elbow] + lower * len(elbow, wrist);
        p[hip] = pelvis + Vector3::new(sign * len(Joint::Pelvis, hip), 0.0, 0.0);
        p[knee] = p[hip] + thigh * len(hip, knee);
        p[ankle] = p[knee] + shank * len(knee, ankle);
    }
    p
}
