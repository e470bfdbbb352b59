//! The 16 joints of the VBA human model (Pan et al., Fig. 2a), in the project's fixed order.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::ops::{Index, IndexMut};

/// One of the 16 joints. Left and right are the subject's own.
///
/// The order of the variants is the order used by every file format and every per-joint array.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Joint {
    HeadTop,
    Neck,
    Chest,
    Pelvis,
    LeftShoulder,
    LeftElbow,
    LeftWrist,
    RightShoulder,
    RightElbow,
    RightWrist,
    LeftHip,
    LeftKnee,
    LeftAnkle,
    RightHip,
    RightKnee,
    RightAnkle,
}

/// Number of joints in the model.
pub const JOINT_COUNT: usize = 16;

/// Which side of the subject the camera sees while the joints are marked by hand: some joints'
/// landmarks are on the front of the body, some on the back ([`Joint::definition`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkingView {
    /// The subject faces the camera (or is seen from the side).
    Front,
    /// The subject has their back to the camera.
    Behind,
}

impl Joint {
    /// All joints in file order.
    pub const ALL: [Joint; JOINT_COUNT] = [
        Joint::HeadTop,
        Joint::Neck,
        Joint::Chest,
        Joint::Pelvis,
        Joint::LeftShoulder,
        Joint::LeftElbow,
        Joint::LeftWrist,
        Joint::RightShoulder,
        Joint::RightElbow,
        Joint::RightWrist,
        Joint::LeftHip,
        Joint::LeftKnee,
        Joint::LeftAnkle,
        Joint::RightHip,
        Joint::RightKnee,
        Joint::RightAnkle,
    ];

    /// The joint's position in file order (0..16).
    pub fn index(self) -> usize {
        self as usize
    }

    /// The joint's name as written in files (`head_top`, `left_wrist`, …).
    pub fn name(self) -> &'static str {
        match self {
            Joint::HeadTop => "head_top",
            Joint::Neck => "neck",
            Joint::Chest => "chest",
            Joint::Pelvis => "pelvis",
            Joint::LeftShoulder => "left_shoulder",
            Joint::LeftElbow => "left_elbow",
            Joint::LeftWrist => "left_wrist",
            Joint::RightShoulder => "right_shoulder",
            Joint::RightElbow => "right_elbow",
            Joint::RightWrist => "right_wrist",
            Joint::LeftHip => "left_hip",
            Joint::LeftKnee => "left_knee",
            Joint::LeftAnkle => "left_ankle",
            Joint::RightHip => "right_hip",
            Joint::RightKnee => "right_knee",
            Joint::RightAnkle => "right_ankle",
        }
    }

    /// Parses a file name of a joint; `None` for anything else.
    pub fn from_name(name: &str) -> Option<Joint> {
        Joint::ALL.into_iter().find(|j| j.name() == name)
    }

    /// The order a user marks the joints in by hand: down the middle to the chest, each arm,
    /// both hips before the pelvis (their midpoint, which cannot be placed before them), then
    /// each leg.
    pub const MARKING_ORDER: [Joint; JOINT_COUNT] = [
        Joint::HeadTop,
        Joint::Neck,
        Joint::Chest,
        Joint::LeftShoulder,
        Joint::LeftElbow,
        Joint::LeftWrist,
        Joint::RightShoulder,
        Joint::RightElbow,
        Joint::RightWrist,
        Joint::LeftHip,
        Joint::RightHip,
        Joint::Pelvis,
        Joint::LeftKnee,
        Joint::LeftAnkle,
        Joint::RightKnee,
        Joint::RightAnkle,
    ];

    /// Where exactly to put the joint when marking it by hand (shown in the GUI and the docs),
    /// in words for what the camera sees: from behind, the landmarks on the back (the chest's
    /// breastbone cannot be seen; the same height on the spine can).
    pub fn definition(self, view: MarkingView) -> &'static str {
        match (self, view) {
            (Joint::Neck, MarkingView::Behind) => {
                "base of the neck: the bump of the 7th cervical vertebra at the back of the base of the neck, midway between the shoulders"
            }
            (Joint::Chest, MarkingView::Behind) => {
                "on the spine, level with the lower tips of the shoulder blades (the height of the nipple line in front), about a third of the way from neck to pelvis"
            }
            (Joint::LeftElbow | Joint::RightElbow, MarkingView::Behind) => {
                "centre of the elbow joint: level with the elbow's point (olecranon), midway between the bony points either side"
            }
            (Joint::LeftKnee | Joint::RightKnee, MarkingView::Behind) => {
                "centre of the knee joint: level with the crease at the back of the knee, midway across the leg"
            }
            (joint, _) => joint.front_definition(),
        }
    }

    /// The definition seen from the front (and from behind where the same words hold).
    fn front_definition(self) -> &'static str {
        match self {
            Joint::HeadTop => "top of the skull (vertex), on the head's middle line",
            Joint::Neck => {
                "base of the neck: midpoint between the shoulders at the level of the 7th cervical vertebra (the bump at the back of the base of the neck)"
            }
            Joint::Chest => {
                "sternum (breastbone), on the trunk's middle line about a third of the way from neck to pelvis"
            }
            Joint::Pelvis => "midpoint of the two hip joints: halfway between the two hips",
            Joint::LeftShoulder | Joint::RightShoulder => {
                "centre of the shoulder joint (head of the humerus), under the acromion (the bony tip of the shoulder)"
            }
            Joint::LeftElbow | Joint::RightElbow => {
                "centre of the elbow joint, between the epicondyles (the bony points either side of the elbow)"
            }
            Joint::LeftWrist | Joint::RightWrist => {
                "centre of the wrist, between the styloid processes (the two bony knobs either side of the wrist)"
            }
            Joint::LeftHip | Joint::RightHip => {
                "centre of the hip joint (head of the femur), at the level of the greater trochanter (the bony point on the side of the hip)"
            }
            Joint::LeftKnee | Joint::RightKnee => {
                "centre of the knee joint, between the femoral condyles (the rounded ends of the thigh bone)"
            }
            Joint::LeftAnkle | Joint::RightAnkle => {
                "centre of the ankle joint, between the malleoli (the ankle bones that stick out either side)"
            }
        }
    }

    /// The parent in the bone tree rooted at the pelvis; `None` for the pelvis.
    pub fn parent(self) -> Option<Joint> {
        use Joint::*;
        Some(match self {
            Pelvis => return None,
            Chest => Pelvis,
            Neck => Chest,
            HeadTop => Neck,
            LeftShoulder | RightShoulder => Chest,
            LeftElbow => LeftShoulder,
            LeftWrist => LeftElbow,
            RightElbow => RightShoulder,
            RightWrist => RightElbow,
            LeftHip | RightHip => Pelvis,
            LeftKnee => LeftHip,
            LeftAnkle => LeftKnee,
            RightKnee => RightHip,
            RightAnkle => RightKnee,
        })
    }

    /// The same joint on the other side of the body (itself for joints on the middle line).
    pub fn mirrored(self) -> Joint {
        use Joint::*;
        match self {
            LeftShoulder => RightShoulder,
            LeftElbow => RightElbow,
            LeftWrist => RightWrist,
            RightShoulder => LeftShoulder,
            RightElbow => LeftElbow,
            RightWrist => LeftWrist,
            LeftHip => RightHip,
            LeftKnee => RightKnee,
            LeftAnkle => RightAnkle,
            RightHip => LeftHip,
            RightKnee => LeftKnee,
            RightAnkle => LeftAnkle,
            other => other,
        }
    }
}

impl fmt::Display for Joint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One value per joint, indexed by [`Joint`]: positions, confidences, flags.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct PerJoint<T>(pub [T; JOINT_COUNT]);

impl<T> PerJoint<T> {
    /// Builds the array by calling `f` for each joint in file order.
    pub fn from_fn(mut f: impl FnMut(Joint) -> T) -> Self {
        PerJoint(std::array::from_fn(|i| f(Joint::ALL[i])))
    }

    /// Maps every value, keeping the joint order.
    pub fn map<U>(&self, mut f: impl FnMut(Joint, &T) -> U) -> PerJoint<U> {
        PerJoint::from_fn(|j| f(j, &self.0[j.index()]))
    }

    /// Joints paired with their values, in file order.
    pub fn iter(&self) -> impl Iterator<Item = (Joint, &T)> {
        Joint::ALL.into_iter().zip(self.0.iter())
    }
}

impl<T: Default> Default for PerJoint<T> {
    fn default() -> Self {
        PerJoint::from_fn(|_| T::default())
    }
}

impl<T> Index<Joint> for PerJoint<T> {
    type Output = T;
    fn index(&self, joint: Joint) -> &T {
        &self.0[joint.index()]
    }
}

impl<T> IndexMut<Joint> for PerJoint<T> {
    fn index_mut(&mut self, joint: Joint) -> &mut T {
        &mut self.0[joint.index()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_in_file_order() {
        let names: Vec<&str> = Joint::ALL.iter().map(|j| j.name()).collect();
        assert_eq!(
            names.join(","),
            "head_top,neck,chest,pelvis,left_shoulder,left_elbow,left_wrist,right_shoulder,\
             right_elbow,right_wrist,left_hip,left_knee,left_ankle,right_hip,right_knee,right_ankle"
        );
        for (i, j) in Joint::ALL.iter().enumerate() {
            assert_eq!(j.index(), i);
            assert_eq!(Joint::from_name(j.name()), Some(*j));
        }
        assert_eq!(Joint::from_name("nose"), None);
    }

    #[test]
    fn every_joint_but_the_pelvis_reaches_the_pelvis() {
        for j in Joint::ALL {
            let mut cur = j;
            let mut steps = 0;
            while let Some(p) = cur.parent() {
                cur = p;
                steps += 1;
                assert!(steps < JOINT_COUNT, "cycle at {j}");
            }
            assert_eq!(cur, Joint::Pelvis);
        }
    }

    /// Every joint is asked once, and each hip before the pelvis, their midpoint.
    #[test]
    fn marking_asks_each_joint_once_and_the_hips_before_their_midpoint() {
        let mut seen: Vec<Joint> = Joint::MARKING_ORDER.to_vec();
        seen.sort();
        assert_eq!(seen, Joint::ALL);
        let at = |j: Joint| Joint::MARKING_ORDER.iter().position(|&k| k == j);
        assert!(at(Joint::LeftHip) < at(Joint::Pelvis));
        assert!(at(Joint::RightHip) < at(Joint::Pelvis));
    }

    /// From behind, no joint is defined by a landmark on the front of the body.
    #[test]
    fn from_behind_no_definition_names_the_breastbone() {
        for j in Joint::ALL {
            let words = j.definition(MarkingView::Behind);
            assert!(
                !words.contains("sternum") && !words.contains("breastbone"),
                "{j}: {words}"
            );
        }
        assert!(
            Joint::Chest
                .definition(MarkingView::Front)
                .contains("breastbone")
        );
        assert!(
            Joint::Chest
                .definition(MarkingView::Behind)
                .contains("shoulder blades")
        );
    }

    #[test]
    fn mirroring_twice_is_identity() {
        for j in Joint::ALL {
            assert_eq!(j.mirrored().mirrored(), j);
        }
        assert_eq!(Joint::LeftKnee.mirrored(), Joint::RightKnee);
    }
}
