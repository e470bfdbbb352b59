//! The priors each group's candidates pay per frame (the joints' ranges of motion, the gait's
//! swing, staying out of the body, the image's depth evidence), in the key triangle's or the
//! pelvis's frame.

use super::super::prior::{PosePrior, PriorGroup, TrunkFrame};
use super::{AmbiguityWeights, GROUPS, Group, HIPS_GROUP, LEG_GROUPS, lift_order, placed};
use crate::formats::NetworkBody;
use crate::skeleton::Joint::*;
use crate::skeleton::{BodyPart, Joint, PerJoint, SubjectModel, segment_distance};
use nalgebra::{Point3, Vector3};

/// How far the thighs must split for a stride to count fully in [`AmbiguityWeights::
/// arm_swing`]: the product of their forward components, one forward and one back (0.2 each
/// way). At 0.02 and 0.08 `bench lift`'s suite from exact 2D was within 0.3 mm of 0.04.
pub(super) const GAIT_SPLIT: f64 = 0.04;

/// The radius of the trunk around the spine that [`AmbiguityWeights::contact`] keeps a wrist
/// out of, as a share of the trunk's (frontal) breadth: a round capsule stands for a trunk
/// less deep than broad, so its radius is nearer half the depth than half the breadth (0.35 of
/// the default 1.75 m subject's 0.35 m is 0.12 m).
pub(super) const TRUNK_DEPTH: f64 = 0.35;

/// The radius of a thigh around its bone that [`AmbiguityWeights::contact`] keeps a wrist out
/// of, as a share of the thigh's breadth (0.45 of the default subject's 0.16 m is 0.07 m).
pub(super) const THIGH_DEPTH: f64 = 0.45;

/// The facing's cost of a key path, weighed by [`AmbiguityWeights::image_depth`] (unweighted, squared metres): each
/// frame's shoulders' depth step (left minus right) against the network's, squared, times
/// the network's confidence in both shoulders; `None` without any network body.
pub(crate) fn image_facing_cost(
    key: &[[Point3<f64>; 3]],
    bodies: &[Option<NetworkBody>],
) -> Option<f64> {
    let mut seen = false;
    let cost = key
        .iter()
        .zip(bodies)
        .filter_map(|(k, b)| Some((k, b.as_ref()?)))
        .map(|(k, b)| {
            seen = true;
            let ours = k[0].z - k[1].z;
            let net = b.points[LeftShoulder].z - b.points[RightShoulder].z;
            let sure = f64::from(b.confidence[LeftShoulder].min(b.confidence[RightShoulder]));
            sure * (ours - net).powi(2)
        })
        .sum();
    seen.then_some(cost)
}

/// [`AmbiguityWeights::image_depth`]'s cost of a group's candidate placed in `p` (unweighted,
/// squared metres): each bone's depth step against the network's (scaled to the bone's
/// length), times the network's confidence in both its ends.
pub(super) fn image_depth_cost(
    group: &Group,
    p: &PerJoint<Point3<f64>>,
    body: &NetworkBody,
) -> f64 {
    group
        .bones
        .iter()
        .map(|bone| {
            let (known, solved) = lift_order(*bone);
            // The network's step at our bone's length (its body has its own proportions).
            let ours = p[solved].z - p[known].z;
            let theirs = body.points[solved] - body.points[known];
            let net = theirs.z * (p[solved] - p[known]).norm() / theirs.norm().max(1e-6);
            let sure = f64::from(body.confidence[known].min(body.confidence[solved]));
            sure * (ours - net).powi(2)
        })
        .sum()
}

/// An arm's [`AmbiguityWeights::arm_swing`] term (squared metres, weighted; 0 for the other
/// groups).
pub(super) fn swing_cost(
    group: &Group,
    p: &PerJoint<Point3<f64>>,
    trunk: &TrunkFrame,
    w: &AmbiguityWeights,
) -> f64 {
    if !matches!(group.prior, PriorGroup::Arm(_)) || w.arm_swing == 0.0 {
        return 0.0;
    }
    let (root, middle) = (group.bones[0].parent, group.bones[0].child);
    let upper = p[middle] - p[root];
    let len = upper.norm();
    match upper.try_normalize(f64::EPSILON) {
        Some(dir) => w.arm_swing * arm_swing(p, trunk, root, dir) * len * len,
        None => 0.0,
    }
}

/// How deep a wrist lies inside the trunk or a thigh, squared (metres squared), for
/// [`AmbiguityWeights::contact`]. The spine and both legs are solved before the arms.
pub(super) fn inside_body(
    wrist: &Point3<f64>,
    p: &PerJoint<Point3<f64>>,
    subject: &SubjectModel,
) -> f64 {
    let trunk = TRUNK_DEPTH * subject.breadth_m(BodyPart::Trunk);
    let thigh = THIGH_DEPTH * subject.breadth_m(BodyPart::LeftThigh);
    let depth = |radius: f64, a: Joint, b: Joint| {
        (radius - segment_distance(wrist, &p[a], &p[b]))
            .max(0.0)
            .powi(2)
    };
    depth(trunk, Chest, Pelvis)
        + depth(thigh, LeftHip, LeftKnee)
        + depth(thigh, RightHip, RightKnee)
}

/// How far an arm swings with its own thigh rather than against it, scaled by how far
/// the stride is split, for [`AmbiguityWeights::arm_swing`]: `stride · (1 + a·t)`, where `a`
/// and `t` are the forward components (sines of the angles from straight down) of the upper
/// arm (`upper`, from the shoulder `root`) and of the same side's thigh, and `stride` grows
/// from 0 with the thighs side by side to 1 when they split forwards and backwards by
/// [`GAIT_SPLIT`]. Between 0 (the arm fully against its thigh) and 2; the same for both of a
/// bone's roots when the legs stand together.
pub(super) fn arm_swing(
    p: &PerJoint<Point3<f64>>,
    trunk: &TrunkFrame,
    root: Joint,
    upper: Vector3<f64>,
) -> f64 {
    let forward = |hip: Joint, knee: Joint| trunk.forward_sine(&p[hip], &p[knee]);
    let (left, right) = (forward(LeftHip, LeftKnee), forward(RightHip, RightKnee));
    let stride = (-left * right / GAIT_SPLIT).clamp(0.0, 1.0);
    let own = if root == LeftShoulder { left } else { right };
    stride * (1.0 + upper.dot(&trunk.forward) * own)
}

/// [`AmbiguityWeights::lookahead`]'s cost for a pelvis placed in `p` on one frame: the least
/// pose-prior cost (nats) of the hips plus each leg at its best roots below them. A joint's
/// miss off its ray is left out: badly tracked legs would otherwise decide for the pelvis.
pub(super) fn hanging_cost(
    p: &PerJoint<Point3<f64>>,
    rays: &PerJoint<Vector3<f64>>,
    trunk: &TrunkFrame,
    subject: &SubjectModel,
    prior: &PosePrior,
) -> f64 {
    let least = |g: usize, p: &PerJoint<Point3<f64>>| {
        (0..1usize << GROUPS[g].bones.len())
            .map(|combo| prior.cost(GROUPS[g].prior, &placed(g, combo, p, rays, subject), trunk))
            .fold(f64::INFINITY, f64::min)
    };
    (0..1usize << GROUPS[HIPS_GROUP].bones.len())
        .map(|combo| {
            let q = placed(HIPS_GROUP, combo, p, rays, subject);
            prior.cost(GROUPS[HIPS_GROUP].prior, &q, trunk)
                + LEG_GROUPS.iter().map(|&g| least(g, &q)).sum::<f64>()
        })
        .fold(f64::INFINITY, f64::min)
}
