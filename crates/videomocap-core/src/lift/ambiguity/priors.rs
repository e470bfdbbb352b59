//! The priors each group's candidates pay per frame (the joints' ranges of motion, the gait's
//! swing, staying out of the body, the image's depth evidence), in the key triangle's or the
//! pelvis's frame.

use super::{AmbiguityWeights, GROUPS, Group, HIPS_GROUP, LEG_GROUPS, Prior, lift_order, placed};
use crate::formats::NetworkBody;
use crate::skeleton::Joint::*;
use crate::skeleton::{BodyPart, Bone, Joint, PerJoint, SubjectModel, segment_distance};
use nalgebra::{Point3, Vector3};

/// How far a resting arm and leg hang outwards from straight down, radians: arms clear the
/// hips; thighs lean a little inwards, knees nearer each other than the hips. The references'
/// thighs, in the pelvis's frame, lean 0.02 to 0.09 inwards at the median on the suite's six
/// motion-capture clips (0.16 to 0.23 at their tenth percentile), 0.06 to 0.08 outwards on the
/// procedural bodies and 0.12 outwards on the real sample. The suite from exact 2D with true
/// lengths (legs in the pelvis's frame) at 0.05 / 0 / −0.05 / −0.1: wrong roots 4.52 / 4.44 /
/// 4.44 / 4.44 % (walk_across_side 9.4 / 8.8 / 8.8 / 8.8 %); the real sample unchanged.
pub(super) const REST_ABDUCTION: [f64; 2] = [0.15, -0.05];

/// How much further outwards than [`REST_ABDUCTION`] a hanging upper arm rests per unit of its
/// forward tilt (the sine of each angle): an arm swung back comes in towards the body, swung
/// forward it moves out. The references' hanging arms (pointing more than 0.7 down), fitted
/// per clip, give slopes of 0.11 to 0.53 on all six motion-capture clips (walk_across_side's
/// arm hangs 0.14 inwards swung 0.41 back, where the fixed rest pose preferred its mirror root
/// 0.21 outwards). The suite from exact 2D with true lengths at 0.3 / 0.5: wrong roots 4.7 →
/// 4.6 % either way (walk_across_side 11.6 → 10.5 %). Counted only for an arm hanging within
/// [`REST_SWING_HANG`] of straight down: applied to any arm, it turned jumping_jacks_frontal's
/// raised arms forwards (2.0 → 23.1 %). At 0.3 `bench lift` (refined): exact 2D 11.3 → 11.3 mm
/// (PA 10.6 → 10.5), wrong roots 4.8 → 4.6 %, from the height 36.9 → 36.8, 2 px noise 47.7 →
/// 47.7 (from the height 62.6 → 62.7), from the tracker 93.9 → 93.9; the real sample
/// unchanged.
pub(super) const REST_SWING: f64 = 0.3;

/// How far down (the sine of the angle from horizontal) an upper arm must hang for
/// [`REST_SWING`] to count at all; it counts fully straight down. At 0.3 (as for the elbow's
/// prior, [`ELBOW_HANG`]) the real sample's wrong roots rose 5.4 → 6.1 %; at 0.8 they stay.
pub(super) const REST_SWING_HANG: f64 = 0.8;

/// How far down an upper arm must hang for [`AmbiguityWeights::elbow`] to count at all (the
/// sine of the angle from horizontal); it counts fully straight down.
pub(super) const ELBOW_HANG: f64 = 0.3;

/// How far an upper arm or thigh may cross inwards of straight down before [`AmbiguityWeights::
/// medial`] counts it (the sine of the angle).
pub(super) const MEDIAL_FREE: f64 = 0.1;

/// How far behind the key triangle's down direction the pelvis hangs from the chest (the sine
/// of the angle), for [`AmbiguityWeights::trunk_up`]'s spine: the chest sits forward of the
/// pelvis on a standing body. The references put the pelvis 0.07 to 0.11 behind on the suite's
/// motion capture, 0.23 (± 0.10) on the real sample, and exactly on the line on the suite's
/// procedural bodies. `bench lift`'s suite from exact 2D with true lengths at 0 / 0.1 / 0.15 /
/// 0.2 / 0.25 / 0.3 / 0.35: 18.1 / 16.7 / 14.0 / 14.2 / 14.0 / 14.2 / 14.2 mm; at 0.2
/// walk_toward_frontal 51.4 → 31.4, dance_turns_frontal 35.7 → 21.3, dribble_oblique 30.3 →
/// 20.6, run_side 20.1 → 12.9, worse sit_down_frontal 17.7 → 19.1 and walk_across_side 20.3 →
/// 20.8; the real sample's 67.9 mm is the same throughout. (The same lean for the neck above
/// the chest made the real sample worse, 67.9 → 71.4 mm.) Later, with the other priors as they
/// are now, 0.3 cut the suite's wrong roots 4.6 → 4.4 % (11.3 → 10.9 mm), all of it on
/// walk_across_side, but was worse with 2 px of noise (one seed: 44.8 → 46.4 mm), from the
/// height (40.4 → 41.0 mm with the real sample), on the reference's key triangle (8.7 → 9.1 mm)
/// and on run_side; 0.1 gave 6.6 %.
pub(super) const SPINE_BACK: f64 = 0.2;

/// How far forward of the key triangle's up direction the head top sits above the neck (the
/// sine of the angle), for [`AmbiguityWeights::trunk_up`]'s head: a head carried upright still
/// leans forwards of the shoulders. The references: 0.15 to 0.67 (median over each clip) on the
/// suite's motion capture (dribbling looks down at the ball), −0.04 on the side-view run, 0.62 on
/// the real sample, exactly upright on the procedural bodies. `bench lift`'s exact 2D at 0 / 0.1 /
/// 0.15 / 0.2 / 0.25: the suite with true lengths 14.2 / 14.2 / 14.2 / 14.2 / 14.8 mm (from the
/// height 39.0 throughout but 39.5 at 0.25: an upright procedural head tips over), the real
/// sample 67.9 / 67.9 / 67.9 / 67.3 / 67.3 (from the height 107.0 / 107.0 / 103.9 / 103.9 /
/// 103.9). At 0.2 the full `bench lift` also moved the real sample from the tracker's output
/// 179.5 → 172.3 mm, and the suite's 2 px noise 48.1 → 48.5, from the tracker 94.3 → 95.1.
pub(super) const HEAD_FORWARD: f64 = 0.2;

/// How much more a head tilted sideways pays in [`AmbiguityWeights::trunk_up`] than one
/// tilted forwards (on top of the tilt both pay): the neck bends forwards far more than
/// sideways. The references tilt the head sideways by a sine of 0.18 at most (0.13 at the
/// median of the most tilted clip), forwards by up to 0.78 (dribbling looks down at the ball);
/// a head leaning well forward in an oblique view has a mirror root less forward but tilted
/// sideways, which the isotropic prior preferred on every frame of dribble_oblique. `bench
/// lift`'s suite from exact 2D with true lengths at 0 / 1 / 2 / 3 / 10: wrong roots 5.0 / 4.7 /
/// 4.7 / 4.9 / 5.1 % (dribble_oblique 9.4 / 4.6 / 4.2 / 4.2 / 4.2 %; from 3 walk_across_side's
/// head, seen from the side, follows the key triangle's small errors sideways).
pub(super) const HEAD_SIDEWAYS: f64 = 2.0;

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

/// [`AmbiguityWeights::image_facing`]'s cost of a key path (unweighted, squared metres): each
/// frame's shoulders' depth step (left minus right) against the network's, squared, times
/// the network's confidence in both shoulders; `None` without any network body.
pub fn image_facing_cost(key: &[[Point3<f64>; 3]], bodies: &[Option<NetworkBody>]) -> Option<f64> {
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

/// The key triangle's directions in one frame: left, up, forward (unit vectors).
#[derive(Clone)]
pub(super) struct TrunkFrame {
    pub(super) left: Vector3<f64>,
    pub(super) up: Vector3<f64>,
    pub(super) forward: Vector3<f64>,
}

impl TrunkFrame {
    pub(super) fn of(points: &PerJoint<Point3<f64>>) -> TrunkFrame {
        let left = (points[LeftShoulder] - points[RightShoulder]).normalize();
        let mid = nalgebra::center(&points[LeftShoulder], &points[RightShoulder]);
        let down = points[Chest] - mid;
        let up = -(down - left * left.dot(&down)).normalize();
        // Subject's left × up = forward (right-handed camera space, Y down).
        TrunkFrame {
            left,
            up,
            forward: left.cross(&up),
        }
    }

    /// How far the bone from `from` to `to` points forwards (the forward component of its unit
    /// direction, the sine of its swing from the trunk's plane; 0 where the joints coincide):
    /// a thigh's swing, read by [`arm_swing`] and the gait's lag.
    pub(super) fn forward_sine(&self, from: &Point3<f64>, to: &Point3<f64>) -> f64 {
        (to - from)
            .try_normalize(f64::EPSILON)
            .map_or(0.0, |d| d.dot(&self.forward))
    }

    /// The pelvis's frame: left along the hip line (solved before the legs), up the key
    /// triangle's up made square to it. The shoulders turn against the pelvis as the body
    /// walks, and a thigh's lean and its knee's hinge belong to the pelvis: in the key
    /// triangle's frame walk_across_side's right knee, bent as its thigh swung back, seemed to
    /// bend sideways (0.020 against 0.0005 for the mirror thigh), and 41 frames in a row took
    /// the mirror root. The suite from exact 2D with true lengths: wrong roots 4.65 → 4.52 %
    /// (walk_across_side 10.6 → 9.4 %, dance_oblique 10.8 → 9.4 %, dribble_oblique 4.2 → 4.0
    /// %; worse run_side 4.0 → 5.0 %, whose knees in the pelvis's frame go wrong for 16 frames
    /// each). Half and half is worse than either: the hinge in the key triangle's frame and the
    /// lean in the pelvis's 4.74 %, the other way round 5.16 %. With the thighs' inward rest
    /// lean ([`REST_ABDUCTION`]), `bench lift` (refined; before → after): exact 2D with true
    /// lengths 11.3 → 11.0 mm, wrong roots 4.6 → 4.4 % (on the reference's key triangle 4.2 →
    /// 3.9 %), 2 px noise 47.7 → 46.7 (from the height 62.7 → 61.3), from the tracker 94.2 →
    /// 90.5 (walk_across_side 137.4 → 108.2, run_side 94.9 → 89.9), from the tracker and the
    /// height 104.2 → 100.1; worse: exact 2D from the height 36.8 → 39.0 (dribble_oblique 66.6
    /// → 101.9: the proportions fitted to its tracks read these priors' costs, and its fitted
    /// forearm came out 0.244 m, not 0.248, against a true 0.257; with them its right arm took the
    /// mirror root on 91 of its 100 frames, 9 before, with or without the arm-swing prior) and
    /// `--estimate-focal`'s median error a factor of 1.22 → 1.48 (walk_across_side 716 → 1351
    /// px against 600). The real sample is unchanged. Where the hips coincide or their line
    /// runs along the trunk, the key triangle's frame stands in.
    pub(super) fn pelvis(&self, points: &PerJoint<Point3<f64>>) -> TrunkFrame {
        let hip_left = (points[LeftHip] - points[RightHip]).try_normalize(f64::EPSILON);
        let frame = hip_left.and_then(|left| {
            let up = (self.up - left * left.dot(&self.up)).try_normalize(0.1)?;
            Some(TrunkFrame {
                left,
                up,
                forward: left.cross(&up),
            })
        });
        frame.unwrap_or_else(|| self.clone())
    }
}

/// The unit direction `base` tilted towards the perpendicular unit direction `toward` by the
/// angle whose sine is `sine`.
pub(super) fn tilted(base: Vector3<f64>, toward: Vector3<f64>, sine: f64) -> Vector3<f64> {
    base * (1.0 - sine * sine).sqrt() + toward * sine
}

/// An arm's [`AmbiguityWeights::arm_swing`] term (squared metres, weighted; 0 for the other
/// groups).
pub(super) fn swing_cost(
    group: &Group,
    p: &PerJoint<Point3<f64>>,
    trunk: &TrunkFrame,
    w: &AmbiguityWeights,
) -> f64 {
    if group.prior != Prior::Arm || w.arm_swing == 0.0 {
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

/// A group's posture prior for one candidate (squared metres, weighted): everything but the
/// arms' swing.
pub(super) fn posture_cost(
    group: &Group,
    p: &PerJoint<Point3<f64>>,
    trunk: &TrunkFrame,
    subject: &SubjectModel,
    w: &AmbiguityWeights,
) -> f64 {
    // How far a bone's solved end lies from where the unit direction `dir` would put it.
    let along = |bone: Bone, dir: Vector3<f64>| {
        let (from, to) = lift_order(bone);
        let len = subject.bone_length(bone);
        (p[to] - (p[from] + dir * len)).norm_squared()
    };
    // How far a bone's solved end lies behind the trunk's forward direction, as the sine of
    // the angle, times its length: backward bending of the head or spine.
    let behind = |bone: Bone| {
        let (from, to) = lift_order(bone);
        let len = subject.bone_length(bone);
        let d = (p[to] - p[from]) / len;
        // The pelvis hangs below the chest: it lies behind the chest's frame when the spine
        // arches backwards.
        let sign = if to == Pelvis { 1.0 } else { -1.0 };
        (sign * d.dot(&trunk.forward)).max(0.0).powi(2) * len * len
    };
    match group.prior {
        Prior::Head => {
            let head = tilted(trunk.up, trunk.forward, HEAD_FORWARD);
            let sideways = (p[HeadTop] - p[Neck]).dot(&trunk.left).powi(2);
            w.trunk_up
                * (along(Bone::new(Chest, Neck), trunk.up)
                    + 0.5 * (along(Bone::new(Neck, HeadTop), head) + HEAD_SIDEWAYS * sideways))
                + w.extension * behind(Bone::new(Neck, HeadTop))
        }
        Prior::Spine => {
            let down = tilted(-trunk.up, -trunk.forward, SPINE_BACK);
            w.trunk_up * along(Bone::new(Pelvis, Chest), down)
                + w.extension * behind(Bone::new(Pelvis, Chest))
        }
        Prior::Hips => {
            let off_line =
                (p[LeftHip].coords + p[RightHip].coords - p[Pelvis].coords * 2.0).norm_squared();
            let across = p[LeftHip] - p[RightHip];
            let half = across.norm() / 2.0;
            let parallel = if half > 0.0 {
                (across / (2.0 * half) - trunk.left).norm_squared() * half * half
            } else {
                0.0
            };
            w.hips_collinear * off_line + w.hips_parallel * parallel
        }
        Prior::Arm | Prior::Leg => {
            let pelvis;
            let trunk = if group.prior == Prior::Leg {
                pelvis = trunk.pelvis(p);
                &pelvis
            } else {
                trunk
            };
            let root = group.bones[0].parent;
            let middle = group.bones[0].child;
            let end = group.bones[1].child;
            let is_leg = group.prior == Prior::Leg;
            // The subject's own outward direction on this limb's side.
            let outward = if matches!(root, LeftShoulder | LeftHip) {
                trunk.left
            } else {
                -trunk.left
            };
            let upper = (p[middle] - p[root]).normalize();
            let lower = p[end] - p[middle];
            // How the lower bone leaves the upper bone's line.
            let bend = lower - upper * upper.dot(&lower);
            let upper_len = (p[middle] - p[root]).norm();
            let abduction = if is_leg {
                REST_ABDUCTION[1]
            } else {
                // A hanging arm swung back rests further in, swung forward further out.
                let hanging = hanging_share(&upper, trunk, REST_SWING_HANG);
                REST_ABDUCTION[0] + REST_SWING * upper.dot(&trunk.forward) * hanging
            };
            let rest_dir = -trunk.up * abduction.cos() + outward * abduction.sin();
            let rest = w.hanging * ((upper - rest_dir) * upper_len).norm_squared();
            let medial =
                w.medial * ((-upper.dot(&outward) - MEDIAL_FREE).max(0.0) * upper_len).powi(2);
            let common = rest + medial;
            if is_leg {
                // A knee bends backwards: its bend must not point forwards, nor sideways (the
                // hinge's axis is the trunk's left-right line turned square to the thigh).
                let axis = trunk.left - upper * upper.dot(&trunk.left);
                let side = if axis.norm() > 0.3 {
                    bend.dot(&axis.normalize()).powi(2)
                } else {
                    0.0
                };
                common + w.knee * bend.dot(&trunk.forward).max(0.0).powi(2) + w.knee_side * side
            } else {
                // An elbow of an arm hanging down bends forwards; the weight fades as the arm
                // rises (a raised arm can bend its elbow any way by turning the upper arm).
                let hanging = hanging_share(&upper, trunk, ELBOW_HANG);
                common
                    + w.contact * inside_body(&p[end], p, subject)
                    + w.elbow * hanging * (-bend.dot(&trunk.forward)).max(0.0).powi(2)
                    + w.straight * bend.norm_squared()
                    + w.frontal * (upper.dot(&trunk.forward) * upper_len).powi(2)
            }
        }
    }
}

/// How far the unit direction `upper` hangs down, from 0 when it points less than `from` down
/// (the sine of its angle below the trunk's horizontal) to 1 straight down.
pub(super) fn hanging_share(upper: &Vector3<f64>, trunk: &TrunkFrame, from: f64) -> f64 {
    ((-upper.dot(&trunk.up) - from) / (1.0 - from)).clamp(0.0, 1.0)
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
/// prior of the hips plus each leg at its best roots below them (unweighted, squared metres).
/// A joint's miss off its ray is left out: badly tracked legs would otherwise decide for the
/// pelvis.
pub(super) fn hanging_cost(
    p: &PerJoint<Point3<f64>>,
    rays: &PerJoint<Vector3<f64>>,
    trunk: &TrunkFrame,
    subject: &SubjectModel,
    w: &AmbiguityWeights,
) -> f64 {
    let least = |g: usize, p: &PerJoint<Point3<f64>>| {
        (0..1usize << GROUPS[g].bones.len())
            .map(|combo| {
                posture_cost(
                    &GROUPS[g],
                    &placed(g, combo, p, rays, subject),
                    trunk,
                    subject,
                    w,
                )
            })
            .fold(f64::INFINITY, f64::min)
    };
    (0..1usize << GROUPS[HIPS_GROUP].bones.len())
        .map(|combo| {
            let q = placed(HIPS_GROUP, combo, p, rays, subject);
            posture_cost(&GROUPS[HIPS_GROUP], &q, trunk, subject, w)
                + LEG_GROUPS.iter().map(|&g| least(g, &q)).sum::<f64>()
        })
        .fold(f64::INFINITY, f64::min)
}
