//! Bones of the 16-joint tree and the body parts (tracking blocks) laid along them.

use super::joint::Joint;

/// A bone: the segment from a joint's parent to the joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Bone {
    /// The end nearer the pelvis.
    pub parent: Joint,
    /// The end farther from the pelvis.
    pub child: Joint,
}

/// Number of bones (one per joint but the root).
pub const BONE_COUNT: usize = 15;

impl Bone {
    /// All bones, ordered so that every bone comes after the bone of its parent joint
    /// (centre outwards, as the VBA reconstruction visits them).
    pub const ALL: [Bone; BONE_COUNT] = [
        Bone::new(Joint::Pelvis, Joint::Chest),
        Bone::new(Joint::Chest, Joint::Neck),
        Bone::new(Joint::Neck, Joint::HeadTop),
        Bone::new(Joint::Chest, Joint::LeftShoulder),
        Bone::new(Joint::LeftShoulder, Joint::LeftElbow),
        Bone::new(Joint::LeftElbow, Joint::LeftWrist),
        Bone::new(Joint::Chest, Joint::RightShoulder),
        Bone::new(Joint::RightShoulder, Joint::RightElbow),
        Bone::new(Joint::RightElbow, Joint::RightWrist),
        Bone::new(Joint::Pelvis, Joint::LeftHip),
        Bone::new(Joint::LeftHip, Joint::LeftKnee),
        Bone::new(Joint::LeftKnee, Joint::LeftAnkle),
        Bone::new(Joint::Pelvis, Joint::RightHip),
        Bone::new(Joint::RightHip, Joint::RightKnee),
        Bone::new(Joint::RightKnee, Joint::RightAnkle),
    ];

    /// A bone between two joints (no check that they are adjacent).
    pub const fn new(parent: Joint, child: Joint) -> Bone {
        Bone { parent, child }
    }

    /// The bone ending at `child`, `None` for the pelvis.
    pub fn to(child: Joint) -> Option<Bone> {
        child.parent().map(|parent| Bone { parent, child })
    }

    /// The key used in files: `"parent-child"`, e.g. `"left_knee-left_ankle"`.
    pub fn key(self) -> String {
        format!("{}-{}", self.parent.name(), self.child.name())
    }

    /// Parses a `"parent-child"` key of one of the 15 bones.
    pub fn from_key(key: &str) -> Option<Bone> {
        Bone::ALL.into_iter().find(|b| b.key() == key)
    }

    /// The bone in a user's words: "left forearm", "right shin", "neck".
    pub fn plain_name(self) -> String {
        let side = |j: Joint| {
            if j.name().starts_with("left") {
                "left "
            } else {
                "right "
            }
        };
        let (side, part) = match self.child {
            Joint::Chest => ("", "spine"),
            Joint::Neck => ("", "neck"),
            Joint::HeadTop => ("", "head"),
            Joint::LeftShoulder | Joint::RightShoulder => (side(self.child), "collarbone"),
            Joint::LeftElbow | Joint::RightElbow => (side(self.child), "upper arm"),
            Joint::LeftWrist | Joint::RightWrist => (side(self.child), "forearm"),
            Joint::LeftHip | Joint::RightHip => (side(self.child), "hip"),
            Joint::LeftKnee | Joint::RightKnee => (side(self.child), "thigh"),
            Joint::LeftAnkle | Joint::RightAnkle => (side(self.child), "shin"),
            Joint::Pelvis => ("", "pelvis"),
        };
        format!("{side}{part}")
    }

    /// Position of the bone in [`Bone::ALL`].
    pub fn index(self) -> usize {
        Bone::ALL.iter().position(|b| *b == self).unwrap_or(0)
    }
}

/// A body part tracked as one morph-block (Pan et al., Fig. 2b): its middle line is a bone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BodyPart {
    Head,
    Trunk,
    LeftUpperArm,
    LeftForearm,
    RightUpperArm,
    RightForearm,
    LeftThigh,
    LeftShank,
    RightThigh,
    RightShank,
}

/// Which breadth of the proportions table sizes a body part.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Breadth {
    Head,
    Trunk,
    UpperArm,
    Forearm,
    Thigh,
    Shank,
}

impl BodyPart {
    /// All parts, top to bottom in the order the VBA tracker visits them.
    pub const ALL: [BodyPart; 10] = [
        BodyPart::Head,
        BodyPart::Trunk,
        BodyPart::LeftUpperArm,
        BodyPart::LeftForearm,
        BodyPart::RightUpperArm,
        BodyPart::RightForearm,
        BodyPart::LeftThigh,
        BodyPart::LeftShank,
        BodyPart::RightThigh,
        BodyPart::RightShank,
    ];

    /// The two joints at the ends of the part's middle line (the end nearer the root first).
    pub fn ends(self) -> (Joint, Joint) {
        use Joint::*;
        match self {
            BodyPart::Head => (Neck, HeadTop),
            BodyPart::Trunk => (Neck, Pelvis),
            BodyPart::LeftUpperArm => (LeftShoulder, LeftElbow),
            BodyPart::LeftForearm => (LeftElbow, LeftWrist),
            BodyPart::RightUpperArm => (RightShoulder, RightElbow),
            BodyPart::RightForearm => (RightElbow, RightWrist),
            BodyPart::LeftThigh => (LeftHip, LeftKnee),
            BodyPart::LeftShank => (LeftKnee, LeftAnkle),
            BodyPart::RightThigh => (RightHip, RightKnee),
            BodyPart::RightShank => (RightKnee, RightAnkle),
        }
    }

    /// Which breadth of the proportions table gives this part's width.
    pub fn breadth(self) -> Breadth {
        match self {
            BodyPart::Head => Breadth::Head,
            BodyPart::Trunk => Breadth::Trunk,
            BodyPart::LeftUpperArm | BodyPart::RightUpperArm => Breadth::UpperArm,
            BodyPart::LeftForearm | BodyPart::RightForearm => Breadth::Forearm,
            BodyPart::LeftThigh | BodyPart::RightThigh => Breadth::Thigh,
            BodyPart::LeftShank | BodyPart::RightShank => Breadth::Shank,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_joint_but_the_pelvis_ends_exactly_one_bone() {
        for j in Joint::ALL {
            let n = Bone::ALL.iter().filter(|b| b.child == j).count();
            assert_eq!(n, usize::from(j != Joint::Pelvis), "{j}");
        }
    }

    #[test]
    fn bones_are_listed_centre_outwards() {
        for (i, b) in Bone::ALL.iter().enumerate() {
            if let Some(pb) = Bone::to(b.parent) {
                assert!(pb.index() < i, "{} before its parent bone", b.key());
            }
        }
    }

    #[test]
    fn keys_round_trip() {
        for b in Bone::ALL {
            assert_eq!(Bone::from_key(&b.key()), Some(b));
        }
        assert_eq!(Bone::from_key("neck-pelvis"), None);
    }
}
