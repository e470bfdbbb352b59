//! The exported rig: its joints (BVH names, parents, where each sits on the 16-joint skeleton and
//! which rule gives its local X axis) and its rest pose.
//!
//! Every rig joint that has children aims its Z axis at exactly one of them; its other children
//! sit at its own position (zero offset) and carry their own rotation, as CMU's `LHipJoint` does.
//! That keeps every bone free to move as the reconstruction moved it, so forward kinematics of
//! the BVH gives back every joint exactly when the bone lengths are constant.

use crate::skeleton::Joint;
use nalgebra::{Point3, Vector3};

/// Where a rig joint sits on the 16-joint skeleton.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Place {
    /// At a joint of the model.
    At(Joint),
    /// On the segment from the first joint to the second, at this fraction of the way.
    Between(Joint, Joint, f64),
}

impl Place {
    /// The position given the model's joint positions.
    pub fn position(self, joint: impl Fn(Joint) -> Point3<f64>) -> Point3<f64> {
        match self {
            Place::At(j) => joint(j),
            Place::Between(a, b, t) => joint(a) + t * (joint(b) - joint(a)),
        }
    }
}

/// How a rig joint's local X axis is found (after Chu et al. §4: "the X axis of the torso is
/// the cross product of the Z axis and the vector formed between the two shoulder points …
/// child bodies … determine their X axes by the cross product of X axis of their parent and
/// their own Z axis").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum XRule {
    /// Z × (left − right) of this joint pair (the shoulders for the chest, the hips for the
    /// pelvis).
    Across(Joint, Joint),
    /// The parent's X crossed with this joint's Z; when the two are parallel the parent's Y
    /// (the parent's X turned 90° about its Z, the paper's "offset of the parent X axis").
    FromParent,
    /// The hinge axis of the limb whose upper bone starts here (elbow or knee), found over the
    /// whole sequence so it keeps its plane (see `kinematics::hinge_axes`).
    Hinge(Limb),
    /// The parent's X (the lower bone of a hinge turns about the same axis as the upper one).
    ParentX,
}

/// The four two-bone limbs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Limb {
    LeftArm,
    RightArm,
    LeftLeg,
    RightLeg,
}

impl Limb {
    /// All four limbs.
    pub const ALL: [Limb; 4] = [Limb::LeftArm, Limb::RightArm, Limb::LeftLeg, Limb::RightLeg];

    /// Root, middle (hinge) and end joints.
    pub fn joints(self) -> [Joint; 3] {
        match self {
            Limb::LeftArm => [Joint::LeftShoulder, Joint::LeftElbow, Joint::LeftWrist],
            Limb::RightArm => [Joint::RightShoulder, Joint::RightElbow, Joint::RightWrist],
            Limb::LeftLeg => [Joint::LeftHip, Joint::LeftKnee, Joint::LeftAnkle],
            Limb::RightLeg => [Joint::RightHip, Joint::RightKnee, Joint::RightAnkle],
        }
    }

    /// Whether the hinge flexes towards the body's front (elbows) or its back (knees).
    pub fn flexes_forward(self) -> bool {
        matches!(self, Limb::LeftArm | Limb::RightArm)
    }
}

/// One joint of the exported rig.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigJoint {
    /// BVH name (`"End Site"` ends are written without one).
    pub name: &'static str,
    /// Index of the parent in [`RIG`], `None` for the root.
    pub parent: Option<usize>,
    /// Where it sits.
    pub place: Place,
    /// The child its Z axis points at (`None` for End Sites).
    pub aim: Option<usize>,
    /// How its X axis is found (unused for End Sites).
    pub x_rule: XRule,
}

impl RigJoint {
    /// Whether this is an End Site (no channels).
    pub fn is_end(&self) -> bool {
        self.aim.is_none()
    }
}

/// Fraction of the way from neck to head_top where the `Head` joint (the skull's base) sits:
/// Winter's chin at 0.870 H and eyes at 0.936 H put the skull base near 0.90 H; the neck is at
/// 0.845 H and head_top at 1.0 H, so (0.90 − 0.845) / 0.155 ≈ 0.35.
pub const HEAD_JOINT_FRACTION: f64 = 0.35;

const fn joint(
    name: &'static str,
    parent: Option<usize>,
    place: Place,
    aim: Option<usize>,
    x_rule: XRule,
) -> RigJoint {
    RigJoint {
        name,
        parent,
        place,
        aim,
        x_rule,
    }
}

const fn end(parent: usize, at: Joint) -> RigJoint {
    joint(
        "End Site",
        Some(parent),
        Place::At(at),
        None,
        XRule::ParentX,
    )
}

/// The exported rig, parents before children. Names follow the CMU/Mixamo conventions Blender
/// users know; the spine's middle joint sits halfway from pelvis to chest.
pub const RIG: [RigJoint; 22] = {
    use Joint::*;
    use XRule::*;
    [
        /* 0 */
        joint(
            "Hips",
            None,
            Place::At(Pelvis),
            Some(1),
            Across(LeftHip, RightHip),
        ),
        /* 1 */
        joint(
            "Spine",
            Some(0),
            Place::Between(Pelvis, Chest, 0.5),
            Some(2),
            FromParent,
        ),
        /* 2 */
        joint(
            "Chest",
            Some(1),
            Place::At(Chest),
            Some(3),
            Across(LeftShoulder, RightShoulder),
        ),
        /* 3 */ joint("Neck", Some(2), Place::At(Neck), Some(4), FromParent),
        /* 4 */
        joint(
            "Head",
            Some(3),
            Place::Between(Neck, HeadTop, HEAD_JOINT_FRACTION),
            Some(5),
            FromParent,
        ),
        /* 5 */ end(4, HeadTop),
        /* 6 */
        joint(
            "LeftShoulder",
            Some(2),
            Place::At(Chest),
            Some(7),
            FromParent,
        ),
        /* 7 */
        joint(
            "LeftArm",
            Some(6),
            Place::At(LeftShoulder),
            Some(8),
            Hinge(Limb::LeftArm),
        ),
        /* 8 */
        joint(
            "LeftForeArm",
            Some(7),
            Place::At(LeftElbow),
            Some(9),
            ParentX,
        ),
        /* 9 */ end(8, LeftWrist),
        /* 10 */
        joint(
            "RightShoulder",
            Some(2),
            Place::At(Chest),
            Some(11),
            FromParent,
        ),
        /* 11 */
        joint(
            "RightArm",
            Some(10),
            Place::At(RightShoulder),
            Some(12),
            Hinge(Limb::RightArm),
        ),
        /* 12 */
        joint(
            "RightForeArm",
            Some(11),
            Place::At(RightElbow),
            Some(13),
            ParentX,
        ),
        /* 13 */ end(12, RightWrist),
        /* 14 */
        joint(
            "LHipJoint",
            Some(0),
            Place::At(Pelvis),
            Some(15),
            FromParent,
        ),
        /* 15 */
        joint(
            "LeftUpLeg",
            Some(14),
            Place::At(LeftHip),
            Some(16),
            Hinge(Limb::LeftLeg),
        ),
        /* 16 */ joint("LeftLeg", Some(15), Place::At(LeftKnee), Some(17), ParentX),
        /* 17 */ end(16, LeftAnkle),
        /* 18 */
        joint(
            "RHipJoint",
            Some(0),
            Place::At(Pelvis),
            Some(19),
            FromParent,
        ),
        /* 19 */
        joint(
            "RightUpLeg",
            Some(18),
            Place::At(RightHip),
            Some(20),
            Hinge(Limb::RightLeg),
        ),
        /* 20 */
        joint(
            "RightLeg",
            Some(19),
            Place::At(RightKnee),
            Some(21),
            ParentX,
        ),
        /* 21 */ end(20, RightAnkle),
    ]
};

/// The rig joint (or End Site) that sits on each model joint, for reading positions back.
pub fn rig_index_of(joint: Joint) -> usize {
    // Invariant: every model joint has exactly one rig joint placed at it that is the aim of
    // its parent (or the root); the test `every_model_joint_has_one_rig_joint` checks it.
    RIG.iter()
        .enumerate()
        .position(|(i, r)| {
            r.place == Place::At(joint)
                && match r.parent {
                    None => true,
                    Some(p) => RIG[p].aim == Some(i),
                }
        })
        .unwrap_or(0)
}

/// The model's rest pose in the world (metres, Y up, facing +Z, the subject's left at +X):
/// standing straight, arms out sideways (T-pose), every bone at the given length. `lengths`
/// holds the 15 model bones' lengths in [`crate::skeleton::Bone::ALL`] order; `shoulder_width`
/// sets the clavicles' slope.
pub fn rest_pose(
    lengths: &[f64; crate::skeleton::BONE_COUNT],
    shoulder_width: f64,
) -> crate::skeleton::PerJoint<Point3<f64>> {
    let (out, down) = (Vector3::x(), -Vector3::y());
    crate::skeleton::standing_pose(
        |b| lengths[b.index()],
        shoulder_width,
        Point3::origin(),
        |sign| [sign * out, sign * out, down, down],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_model_joint_has_one_rig_joint() {
        for j in Joint::ALL {
            let i = rig_index_of(j);
            assert_eq!(RIG[i].place, Place::At(j), "{j:?}");
        }
    }

    #[test]
    fn only_the_aimed_child_is_offset() {
        // Every child that is not its parent's aim sits where its parent sits.
        for (i, r) in RIG.iter().enumerate() {
            assert!(r.parent.is_none_or(|p| p < i), "parents come first");
            if let Some(p) = r.parent
                && RIG[p].aim != Some(i)
            {
                assert_eq!(r.place, RIG[p].place, "{} must sit on its parent", r.name);
            }
            if let Some(a) = r.aim {
                assert_eq!(RIG[a].parent, Some(i), "{} aims at a child", r.name);
            }
        }
    }
}
