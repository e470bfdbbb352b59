//! The exported rig: its joints (BVH names, parents, where each sits on the 16-joint skeleton and
//! which rule gives its local X axis) and its rest pose.
//!
//! Every rig joint that has children aims its Z axis at exactly one of them; its other children
//! sit at its own position (zero offset) and carry their own rotation, as CMU's `LHipJoint` does.
//! That keeps every bone free to move as the reconstruction moved it, so forward kinematics of
//! the BVH gives back every joint exactly when the bone lengths are constant.

use crate::skeleton::Joint;
use Place::{At, Between, Toe};
use nalgebra::{Point3, Vector3};

/// Where a rig joint sits on the 16-joint skeleton.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Place {
    /// At a joint of the model.
    At(Joint),
    /// On the line from the first joint to the second, at this fraction of the way (beyond
    /// the second when above 1: the hand's end continues the forearm).
    Between(Joint, Joint, f64),
    /// The toes of the leg whose knee and ankle these are: in front of the ankle, square to the
    /// shank and towards the body's front, and down towards the floor ([`TOE_FORWARD_PER_SHANK`]
    /// and [`TOE_DOWN_PER_SHANK`] of the shank's length), so a standing foot lies flat. It sets
    /// the rest pose; in motion the foot turns with the shank ([`XRule::Rigid`]).
    Toe {
        /// The leg's knee.
        knee: Joint,
        /// The leg's ankle.
        ankle: Joint,
    },
}

impl Place {
    /// The position given the model's joint positions.
    pub fn position(self, joint: impl Fn(Joint) -> Point3<f64>) -> Point3<f64> {
        match self {
            Place::At(j) => joint(j),
            Place::Between(a, b, t) => joint(a) + t * (joint(b) - joint(a)),
            Place::Toe { knee, ankle } => {
                let shank = joint(ankle) - joint(knee);
                let length = shank.norm();
                let down = shank.try_normalize(1e-9).unwrap_or_else(Vector3::zeros);
                // The body's front: (left − right) × up, the same in camera space and the
                // world (both right-handed).
                let front = (joint(Joint::LeftHip) - joint(Joint::RightHip))
                    .cross(&(joint(Joint::Neck) - joint(Joint::Pelvis)));
                let forward = (front - front.dot(&down) * down)
                    .try_normalize(1e-9)
                    .unwrap_or_else(Vector3::zeros);
                joint(ankle)
                    + length * (TOE_FORWARD_PER_SHANK * forward + TOE_DOWN_PER_SHANK * down)
            }
        }
    }
}

/// How far the hand's end (the middle fingertip) lies beyond the wrist, as a share of the
/// forearm: Winter's hand 0.108 H over his forearm 0.146 H.
pub const HAND_PER_FOREARM: f64 = 0.108 / 0.146;

/// How far the toes lie in front of the ankle, as a share of the shank: the foot reaches about
/// 0.11 H in front of the ankle (Winter's foot 0.152 H less the heel behind the ankle), over the
/// shank's 0.246 H (knee 0.285 H, ankle 0.039 H).
pub const TOE_FORWARD_PER_SHANK: f64 = 0.11 / 0.246;

/// How far the toes lie below the ankle, as a share of the shank: the ankle's 0.039 H over the
/// floor (Winter), so a standing foot's toes touch the floor.
pub const TOE_DOWN_PER_SHANK: f64 = 0.039 / 0.246;

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
    /// A part that is not tracked (a hand, a foot): at rest its X is its parent's, and in
    /// motion it turns with its parent (its own rotation stays zero), keeping the rest pose's
    /// angle to the parent's bone: a hand continues its forearm, a foot stays square to its
    /// shank and turns with the knee's plane, so it never flips.
    Rigid,
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

const fn end(parent: usize, place: Place) -> RigJoint {
    joint("End Site", Some(parent), place, None, XRule::ParentX)
}

/// The exported rig, parents before children. Names follow the CMU/Mixamo conventions Blender
/// users know (see [`RigNames`] for the Mixamo set); the spine's middle joint sits halfway from
/// pelvis to chest; the hands continue the forearms and the feet point at the toes (neither is
/// tracked: a hand turns with its forearm, a foot stays square to its shank).
pub const RIG: [RigJoint; 26] = {
    use Joint::*;
    use XRule::*;
    [
        /* 0 */ joint("Hips", None, At(Pelvis), Some(1), Across(LeftHip, RightHip)),
        /* 1 */
        joint(
            "Spine",
            Some(0),
            Between(Pelvis, Chest, 0.5),
            Some(2),
            FromParent,
        ),
        /* 2 */
        joint(
            "Chest",
            Some(1),
            At(Chest),
            Some(3),
            Across(LeftShoulder, RightShoulder),
        ),
        /* 3 */ joint("Neck", Some(2), At(Neck), Some(4), FromParent),
        /* 4 */
        joint(
            "Head",
            Some(3),
            Between(Neck, HeadTop, HEAD_JOINT_FRACTION),
            Some(5),
            FromParent,
        ),
        /* 5 */ end(4, At(HeadTop)),
        /* 6 */ joint("LeftShoulder", Some(2), At(Chest), Some(7), FromParent),
        /* 7 */
        joint(
            "LeftArm",
            Some(6),
            At(LeftShoulder),
            Some(8),
            Hinge(Limb::LeftArm),
        ),
        /* 8 */ joint("LeftForeArm", Some(7), At(LeftElbow), Some(9), ParentX),
        /* 9 */ joint("LeftHand", Some(8), At(LeftWrist), Some(10), Rigid),
        /* 10 */ end(9, Between(LeftElbow, LeftWrist, 1.0 + HAND_PER_FOREARM)),
        /* 11 */ joint("RightShoulder", Some(2), At(Chest), Some(12), FromParent),
        /* 12 */
        joint(
            "RightArm",
            Some(11),
            At(RightShoulder),
            Some(13),
            Hinge(Limb::RightArm),
        ),
        /* 13 */ joint("RightForeArm", Some(12), At(RightElbow), Some(14), ParentX),
        /* 14 */ joint("RightHand", Some(13), At(RightWrist), Some(15), Rigid),
        /* 15 */ end(14, Between(RightElbow, RightWrist, 1.0 + HAND_PER_FOREARM)),
        /* 16 */ joint("LHipJoint", Some(0), At(Pelvis), Some(17), FromParent),
        /* 17 */
        joint(
            "LeftUpLeg",
            Some(16),
            At(LeftHip),
            Some(18),
            Hinge(Limb::LeftLeg),
        ),
        /* 18 */ joint("LeftLeg", Some(17), At(LeftKnee), Some(19), ParentX),
        /* 19 */ joint("LeftFoot", Some(18), At(LeftAnkle), Some(20), Rigid),
        /* 20 */
        end(
            19,
            Toe {
                knee: LeftKnee,
                ankle: LeftAnkle,
            },
        ),
        /* 21 */ joint("RHipJoint", Some(0), At(Pelvis), Some(22), FromParent),
        /* 22 */
        joint(
            "RightUpLeg",
            Some(21),
            At(RightHip),
            Some(23),
            Hinge(Limb::RightLeg),
        ),
        /* 23 */ joint("RightLeg", Some(22), At(RightKnee), Some(24), ParentX),
        /* 24 */ joint("RightFoot", Some(23), At(RightAnkle), Some(25), Rigid),
        /* 25 */
        end(
            24,
            Toe {
                knee: RightKnee,
                ankle: RightAnkle,
            },
        ),
    ]
};

/// Which bone names the BVH carries; the joints, offsets and motion are the same.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RigNames {
    /// The CMU motion-capture names (`Hips`, `LHipJoint`, `LeftUpLeg`, `LeftForeArm`, …), as
    /// the CMU database's BVH conversions carry them.
    #[default]
    Cmu,
    /// Mixamo's names (`mixamorig:Hips`, `mixamorig:Spine2`, `mixamorig:LeftUpLeg`, …), which
    /// Blender's retargeting add-ons map onto Mixamo characters by name. The chest is
    /// `Spine2` (Mixamo's top spine bone, that carries neck and shoulders); the hip joints,
    /// which Mixamo does not have, are `LeftHipJoint`/`RightHipJoint`.
    Mixamo,
}

impl RigNames {
    /// Both sets, the default first.
    pub const ALL: [RigNames; 2] = [RigNames::Cmu, RigNames::Mixamo];

    /// The BVH name of rig joint `i` (End Sites have none).
    pub fn name(self, i: usize) -> String {
        let cmu = RIG[i].name;
        match self {
            RigNames::Cmu => cmu.to_owned(),
            RigNames::Mixamo => {
                let name = match cmu {
                    "Chest" => "Spine2",
                    "LHipJoint" => "LeftHipJoint",
                    "RHipJoint" => "RightHipJoint",
                    other => other,
                };
                format!("mixamorig:{name}")
            }
        }
    }

    /// The word a user types (`--rig cmu|mixamo`).
    pub fn key(self) -> &'static str {
        match self {
            RigNames::Cmu => "cmu",
            RigNames::Mixamo => "mixamo",
        }
    }
}

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
