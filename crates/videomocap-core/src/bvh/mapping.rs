//! Mapping a motion-capture rig onto the 16-joint model, driven by a table of joint names so that
//! new rigs need a line of data, not code.
//!
//! Rules (chosen to match the definitions in `skeleton::Joint::definition` and the real sample's
//! reference):
//! - limbs and neck: the first joint of the table that the file has;
//! - pelvis: midpoint of the two hip joints;
//! - chest: `0.6·neck + 0.4·pelvis` on the trunk's middle line (the same definition as the real
//!   sample's reference, and 0.397 of the way down by the proportions table);
//! - head_top: the rig's head joint moved along the head's own neck→head direction (as it was in
//!   the rest pose, so it turns with the head) until it is `neck-head_top` of the proportions
//!   table away from the neck in the rest pose.
//!
//! Units: the scale among metres, centimetres, inches and millimetres that makes the rest-pose
//! stature closest to 1.7 m (in ratio) is chosen; positions come out in metres.

use super::{Bvh, BvhError};
use crate::skeleton::{Bone, JOINT_COUNT, Joint, PerJoint, Proportions};
use nalgebra::{Point3, Vector3};
use std::path::Path;

/// Names (case-insensitive) tried in turn for each joint taken directly from the rig.
/// Covers the CMU Poser conversion, the Character Creator (iClone) rig, the CMU/Mixamo-style
/// `LeftUpLeg` naming and the original CMU ASF names.
const NAME_TABLE: &[(Joint, &[&str])] = &[
    (
        Joint::Neck,
        &[
            "neck",
            "CC_Base_NeckTwist01",
            "Neck",
            "Neck1",
            "neck_01",
            "lowerneck",
        ],
    ),
    (
        Joint::LeftShoulder,
        &[
            "lShldr",
            "CC_Base_L_Upperarm",
            "LeftArm",
            "LeftUpArm",
            "lhumerus",
            "upperarm_l",
        ],
    ),
    (
        Joint::LeftElbow,
        &[
            "lForeArm",
            "CC_Base_L_Forearm",
            "LeftForeArm",
            "LeftLowArm",
            "lradius",
            "lowerarm_l",
        ],
    ),
    (
        Joint::LeftWrist,
        &["lHand", "CC_Base_L_Hand", "LeftHand", "lwrist", "hand_l"],
    ),
    (
        Joint::RightShoulder,
        &[
            "rShldr",
            "CC_Base_R_Upperarm",
            "RightArm",
            "RightUpArm",
            "rhumerus",
            "upperarm_r",
        ],
    ),
    (
        Joint::RightElbow,
        &[
            "rForeArm",
            "CC_Base_R_Forearm",
            "RightForeArm",
            "RightLowArm",
            "rradius",
            "lowerarm_r",
        ],
    ),
    (
        Joint::RightWrist,
        &["rHand", "CC_Base_R_Hand", "RightHand", "rwrist", "hand_r"],
    ),
    (
        Joint::LeftHip,
        &[
            "lThigh",
            "CC_Base_L_Thigh",
            "LeftUpLeg",
            "LeftHip",
            "lfemur",
            "thigh_l",
        ],
    ),
    (
        Joint::LeftKnee,
        &[
            "lShin",
            "CC_Base_L_Calf",
            "LeftLeg",
            "LeftKnee",
            "ltibia",
            "calf_l",
        ],
    ),
    (
        Joint::LeftAnkle,
        &["lFoot", "CC_Base_L_Foot", "LeftFoot", "LeftAnkle", "foot_l"],
    ),
    (
        Joint::RightHip,
        &[
            "rThigh",
            "CC_Base_R_Thigh",
            "RightUpLeg",
            "RightHip",
            "rfemur",
            "thigh_r",
        ],
    ),
    (
        Joint::RightKnee,
        &[
            "rShin",
            "CC_Base_R_Calf",
            "RightLeg",
            "RightKnee",
            "rtibia",
            "calf_r",
        ],
    ),
    (
        Joint::RightAnkle,
        &[
            "rFoot",
            "CC_Base_R_Foot",
            "RightFoot",
            "RightAnkle",
            "foot_r",
        ],
    ),
];

/// Names tried for the rig's head joint (used to place head_top).
const HEAD_NAMES: &[&str] = &["head", "CC_Base_Head", "Head", "head_01"];

/// Candidate unit scales to metres: metres, centimetres, inches, millimetres.
const UNIT_SCALES: [f64; 4] = [1.0, 0.01, 0.0254, 0.001];

/// Stature the unit guess aims at, metres.
const TYPICAL_STATURE_M: f64 = 1.7;

/// A rig's motion expressed as the 16 joints, in metres, in the file's world axes.
#[derive(Debug, Clone)]
pub struct MappedMotion {
    /// Frames per second of the file.
    pub fps: f64,
    /// Joint positions per frame, metres, file axes.
    pub frames: Vec<PerJoint<Point3<f64>>>,
    /// The metres-per-file-unit factor chosen.
    pub unit_scale: f64,
    /// Which rig joint fed each directly mapped joint (for the record).
    pub sources: Vec<(Joint, String)>,
}

fn find_any(bvh: &Bvh, names: &[&str]) -> Option<usize> {
    names.iter().find_map(|n| bvh.find(n))
}

/// Maps every frame of a BVH onto the 16 joints.
pub fn map_to_model(bvh: &Bvh, path: &Path) -> Result<MappedMotion, BvhError> {
    let missing = |joint: &str, names: &[&str]| BvhError::MissingJoint {
        path: path.to_owned(),
        joint: joint.to_owned(),
        candidates: names.join(", "),
    };
    let mut direct = [usize::MAX; JOINT_COUNT];
    let mut sources = Vec::new();
    for (joint, names) in NAME_TABLE {
        let j = find_any(bvh, names).ok_or_else(|| missing(joint.name(), names))?;
        direct[joint.index()] = j;
        sources.push((*joint, bvh.joints[j].name.clone()));
    }
    let head = find_any(bvh, HEAD_NAMES).ok_or_else(|| missing("head", HEAD_NAMES))?;
    let neck = direct[Joint::Neck.index()];

    // Rest pose: units and the head's up direction in its own frame.
    let rest = bvh.rest_positions();
    let rest_at = |joint: Joint| rest[direct[joint.index()]];
    let proportions = Proportions::default();
    let frac = |a: Joint, b: Joint| proportions.bone_fraction[Bone::new(a, b).index()];
    let leg = (rest_at(Joint::LeftKnee) - rest_at(Joint::LeftAnkle)).norm()
        + (rest_at(Joint::LeftHip) - rest_at(Joint::LeftKnee)).norm();
    let rest_pelvis = nalgebra::center(&rest_at(Joint::LeftHip), &rest_at(Joint::RightHip));
    let trunk = (rest[neck] - rest_pelvis).norm();
    let fraction = frac(Joint::LeftHip, Joint::LeftKnee)
        + frac(Joint::LeftKnee, Joint::LeftAnkle)
        + frac(Joint::Pelvis, Joint::Chest)
        + frac(Joint::Chest, Joint::Neck);
    let stature_units = (leg + trunk) / fraction;
    let unit_scale = UNIT_SCALES
        .into_iter()
        .min_by(|a, b| {
            let da = (stature_units * a / TYPICAL_STATURE_M).ln().abs();
            let db = (stature_units * b / TYPICAL_STATURE_M).ln().abs();
            da.total_cmp(&db)
        })
        .unwrap_or(1.0);
    let stature_m = stature_units * unit_scale;
    let head_len_m = frac(Joint::Neck, Joint::HeadTop) * stature_m;
    let neck_to_head_m = (rest[head] - rest[neck]).norm() * unit_scale;
    // Rest-pose neck→head direction. In the BVH rest pose every global rotation is the
    // identity, so this is also the direction in the head joint's own frame.
    let up_in_head = (rest[head] - rest[neck])
        .try_normalize(1e-9)
        .unwrap_or_else(Vector3::y);
    let top_offset_m = (head_len_m - neck_to_head_m).max(0.3 * head_len_m);

    let mut frames = Vec::with_capacity(bvh.frame_count());
    for f in 0..bvh.frame_count() {
        let globals = bvh.global_transforms(f);
        let pos = |j: usize| Point3::from(globals[j].translation.vector * unit_scale);
        let mut points = PerJoint([Point3::origin(); JOINT_COUNT]);
        for (joint, _) in NAME_TABLE {
            points[*joint] = pos(direct[joint.index()]);
        }
        points[Joint::Pelvis] = nalgebra::center(&points[Joint::LeftHip], &points[Joint::RightHip]);
        points[Joint::Chest] =
            Point3::from(points[Joint::Neck].coords * 0.6 + points[Joint::Pelvis].coords * 0.4);
        let head_up = globals[head].rotation * up_in_head;
        points[Joint::HeadTop] = pos(head) + head_up * top_offset_m;
        frames.push(points);
    }
    Ok(MappedMotion {
        fps: bvh.fps(),
        frames,
        unit_scale,
        sources,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_bundled_rigs_map_to_plausible_metric_bodies() {
        for (file, scale) in [
            ("tests/data/cmu_61_05_dance.bvh", 1.0),
            ("tests/data/cmu_02_01_walk.bvh", 0.01),
        ] {
            let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../..")
                .join(file);
            let bvh = Bvh::load(&path).unwrap();
            let m = map_to_model(&bvh, &path).unwrap();
            assert_eq!(m.unit_scale, scale, "{file}");
            assert_eq!(m.frames.len(), bvh.frame_count());
            let p = &m.frames[0];
            let shank = (p[Joint::LeftKnee] - p[Joint::LeftAnkle]).norm();
            let upper_arm = (p[Joint::LeftShoulder] - p[Joint::LeftElbow]).norm();
            assert!((0.3..0.55).contains(&shank), "{file}: shank {shank}");
            assert!(
                (0.2..0.4).contains(&upper_arm),
                "{file}: upper arm {upper_arm}"
            );
            // The head top is above the neck, which is above the pelvis (up = trunk direction).
            let up = (p[Joint::Neck] - p[Joint::Pelvis]).normalize();
            assert!(
                (p[Joint::HeadTop] - p[Joint::Neck]).dot(&up) > 0.1,
                "{file}"
            );
            // The subject's left is on the left: (left − right) · (up × forward) ...
            // checked indirectly: left and right hips are distinct and about a hip width apart.
            let hips = (p[Joint::LeftHip] - p[Joint::RightHip]).norm();
            assert!((0.1..0.3).contains(&hips), "{file}: hips {hips}");
        }
    }
}
