//! The forward/backward depth ambiguity of every bone, resolved over the whole sequence.
//!
//! Each bone solved from its parent has two roots ([`super::backproject`]). Bones are taken in
//! groups (the head and neck, the spine, the two hips, each arm, each leg); for each group every
//! combination of its bones' roots is a candidate, scored per frame by a prior built on the joints'
//! ranges of motion (the neck and spine lie along the key triangle's up direction, the pelvis a
//! little behind it and the head top a little forward of it, and bend forwards rather than
//! backwards, the head rather than sideways; the hips are collinear with the pelvis and parallel to
//! the shoulders; knees bend backwards, in the leg's own plane; hanging elbows bend forwards; upper
//! arms and thighs do not cross the body's middle, and weakly prefer to hang a little outwards
//! (an arm swung back less so) or, thighs, a little inwards; the legs' priors are taken in the
//! pelvis's frame, the arms' in the key triangle's; of two arms that fit equally, the
//! straighter and the one nearer the trunk's frontal plane; in a stride each arm swings against
//! its own thigh; a wrist stays out of the trunk and the thighs; the pelvis also pays the least
//! prior the hips and legs can take below it; in a gait each arm follows the other's swing,
//! mirrored, half a stride away), and the candidates are chained
//! over the frames by dynamic programming (Viterbi over pairs of consecutive choices) that
//! minimises the joints' 3D acceleration in camera space plus the priors. Groups
//! are solved centre outwards, each on the trajectory chosen for its root. A user's choice for a
//! bone on a frame ([`DepthOverrides`]) is a hard constraint.
mod gait;
mod margins;

use super::backproject::{Root, bone_roots};
use super::error::{LiftError, check_setting};
use crate::formats::{FrameIndex, NetworkBody};
use crate::skeleton::{
    BONE_COUNT, BodyPart, Bone, Joint, PerJoint, SubjectModel, segment_distance,
};
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// How strongly each prior counts against the acceleration term (both in squared metres).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AmbiguityWeights {
    /// Neck, head and spine along the key triangle's up direction.
    pub trunk_up: f64,
    /// The head and the spine bent backwards (extension reaches about a third of flexion).
    pub extension: f64,
    /// Hips collinear with the pelvis.
    pub hips_collinear: f64,
    /// Hip line parallel to the shoulder line.
    pub hips_parallel: f64,
    /// Knees bend backwards.
    pub knee: f64,
    /// Knees bend in the leg's own plane, not sideways (the knee is a hinge; hip rotation
    /// turns its plane only a little).
    pub knee_side: f64,
    /// Elbows of hanging arms bend forwards. As firm as an elbow that cannot bend backwards:
    /// at 5 (was 0.5) `bench lift` measured the suite from the tracker's output 104.5 → 102.2 mm
    /// (115.7 from the height, was 118.8), 2 px noise 48.0 → 47.8, exact 2D from the height
    /// 57.3 → 55.7, the real sample from the tracker's output 181.9 → 179.5; worse only on the
    /// real sample's exact 2D from the height, 105.5 → 107.7.
    pub elbow: f64,
    /// Upper arms and thighs hang along the trunk, a little outwards (a weak preference for
    /// the rest pose).
    pub hanging: f64,
    /// Upper arms and thighs crossing the body's middle (adduction beyond the rest pose).
    pub medial: f64,
    /// Elbows bent (a weak preference for the straighter of two otherwise equal arms; knees
    /// are left out: a seated shank hangs, and its mirror is the straighter).
    pub straight: f64,
    /// Upper arms out of the trunk's frontal plane, forwards or backwards (a weak preference,
    /// for two arms that fit otherwise equally: an arm raised sideways lies near the image
    /// plane of a frontal view, where its two roots differ by a small forward or backward tilt
    /// that nothing else tells apart). `bench lift`'s suite, exact 2D and true lengths (before
    /// the spine's lean, `SPINE_BACK`), at 0.05 / 0.1 / 0.2 / 0.3: 19.3 / 18.1 / 18.0 / 19.1 mm
    /// (0 gives 20.3; at 0.3 the side view's bow, whose hanging arms point along the trunk's
    /// forward direction, turns its arms backwards). What it gets wrong: sit_down_frontal's arms
    /// reach forwards as the body sits (0.6 rad at the seat), and the mirror root, tilted 0.3
    /// back, pays less here (0.0009 against 0.0031 on the deepest frame) and in
    /// [`AmbiguityWeights::hanging`] (0.0006 against 0.0017), so 45 of its 88 elbow-frames per arm are
    /// wrong. Tried and not kept (the suite from exact 2D with true lengths, wrong roots
    /// against 4.65 %):
    /// - This prior for raised arms only (fading out as the arm hangs, from sines of 0.3 /
    ///   0.5 / 0.7 / 0.9): 4.85 / 4.78 / 4.80 / 4.74 %, sit_down_frontal unchanged.
    /// - An extra cost on upper arms swung behind the trunk's frontal plane, at 0.1 / 0.3 / 1:
    ///   5.03 / 5.56 / 8.63 %. At 1 sit_down_frontal went 19.4 → 1.7 mm, but
    ///   jumping_jacks_frontal went 7.8 → 32.8 and walk_toward_frontal 14.9 → 29.1. Counted only
    ///   beyond a sine of 0.3, it gave 5.23 %, sit_down_frontal unchanged.
    /// - Forward tilts cheaper than backward ones (forward ×0.5 / ×0.3; forward ×0.3 and
    ///   backward ×3), against 722 wrong bone-frames: 874 / 1024 / 1069, jumping_jacks_frontal
    ///   26 → 178–328, sit_down_frontal unchanged (its mirror hangs along the trunk at frames
    ///   40–49 and 70–79, where the truth reaches 0.48 forward).
    pub frontal: f64,
    /// In a walking or running stride (the thighs split forwards and backwards), each arm
    /// swings against its own thigh (the left arm forward with the right leg): the arm
    /// whose forward tilt has the same sign as its thigh's pays, in proportion to how far the
    /// thighs split (fully from 0.2 forwards and backwards), tilt times tilt. Walking arms
    /// seen from the front or obliquely hang a little forward or back of the image plane, where
    /// nothing else tells their two roots apart. The suite from exact 2D with true lengths at
    /// 0 / 0.7 / 1 / 1.5 / 2: 14.2 / 12.2 / 11.7 / 11.8 / 12.1 mm, wrong roots 7.6 / 6.2 / 5.5 /
    /// 5.5 / 5.7 %. At 1 `bench lift` (refined; before → after): exact 2D 14.2 → 11.7 mm
    /// (treadmill_oblique 11.3 → 2.0, walk_toward_frontal 31.4 → 14.9, dribble_oblique 20.6 →
    /// 16.3; worse only walk_across_side, 20.8 → 20.9), from the height 39.0 → 36.7, 2 px noise
    /// 48.5 → 47.9, from the tracker 95.1 → 93.9; the real sample (balancing, no stride) 67.3 →
    /// 66.7 from its reference 2D, 103.9 → 98.1 from the height, the rest unchanged.
    pub arm_swing: f64,
    /// A wrist inside the body: nearer the spine (chest to pelvis) than 0.35 of the trunk's
    /// breadth, or a thigh than 0.45 of the thigh's, pays the squared depth it went in. A hand
    /// hanging beside the hips seen from the side, or in front of the body seen obliquely, has a
    /// mirror root inside the hip or the thigh (walk_across_side's left forearm was wrong on 96 of
    /// 120 frames). On the suite's references (0.12 m round the spine, 0.07 m round a thigh), of
    /// 2685 wrist-frames whose two roots differ, the true wrist is inside on 8 (one dance) and the
    /// mirror root alone on 229. The suite from exact 2D with true lengths at 0 / 2 / 5 / 10 / 30:
    /// wrong roots 5.5 / 5.2 / 5.0 / 5.0 / 5.0 %. At 10 `bench lift` (refined; before → after):
    /// exact 2D 11.7 → 11.5 mm, wrong roots 5.6 → 5.1 % (walk_across_side 20.9 → 19.8 mm,
    /// dance_oblique 23.3 → 21.9), from the height 36.7 → 36.7, 2 px noise 47.9 → 48.0, from the
    /// tracker 93.9 → 94.1 (run_side 124.6 → 127.6: its swinging hands pass close by the trunk),
    /// from the tracker and the height 109.5 → 109.4; the real sample unchanged.
    pub contact: f64,
    /// A joint off its viewing ray (its bone too short for its 2D image).
    pub miss: f64,
    /// The spine's look ahead: each of the pelvis's two roots also pays the least prior the
    /// hips and the legs can take hanging from it on that frame (each leg at its best roots).
    /// The spine's own prior often cannot tell a pelvis a little in front of the chest from one
    /// a little behind (a side view, a trunk bent towards the camera); the legs hung from the
    /// wrong one must bend or splay. Like the arms' swing it steers the choice but stays out of
    /// the group's reported cost (the hips and legs report their own). `bench lift` (refined;
    /// before → after) at 0.3: exact 2D with true lengths 10.9 → 10.5 mm, wrong roots 828 → 817
    /// bone-frames (walk_across_side 195 → 184), from the height 39.0 → 37.9; 2 px noise 46.0 →
    /// 44.4 (from the height 60.9 → 59.1); from the tracker 82.0 → 80.6 (from the height 88.7 →
    /// 87.9); the real sample unchanged (with noise, from the height, 103.9 → 103.7); the
    /// per-frame solve 2249 → 2009 frames/s. The suite's wrong roots from exact 2D at 0.1 / 0.3 /
    /// 1 / 3: 820 / 817 / 826 / 841. Looking ahead from the hips to the legs as well cut exact
    /// 2D to 799, but from the tracker's output it took the badly tracked legs' side:
    /// treadmill_raised 105.9 → 169.3 mm, the real sample 153.9 → 168.4.
    pub lookahead: f64,
    /// In a gait (the thighs swinging alternately, repeating each other half a stride apart),
    /// each arm's upper arm and forearm pay their squared distance (times the bone's length
    /// squared) from the other arm's, mirrored left to right in the key triangle's frame, half a
    /// stride before and after: two more passes over the arms, each steered by the other arm's
    /// previous choice. Walking and running arms swing alike half a stride apart, while a mirror
    /// root moves an arm towards or away from the camera: outwards for the near arm, say, and
    /// inwards for the far one, at another phase of the stride, so the two arms' mirror roots
    /// seldom agree. An arm that does not follow its partner (a dribbling hand: the median
    /// discrepancy of its first pass above a fixed gate) is left as it is. Like the arms' swing
    /// it steers the choice and stays out of the reported cost. The suite from exact 2D with true
    /// lengths at 0 / 0.1 / 0.2 / 0.3 / 0.5 / 1: wrong roots 817 / 744 / 721 / 722 / 719 / 754
    /// bone-frames (at 0.3 walk_across_side 184 → 102, run_side 110 → 104, treadmill_oblique
    /// 8 → 1; the others unchanged). The same for the legs as well gave 724. At 0.3 `bench lift`
    /// (refined; before → after): exact 2D with true lengths 10.5 → 10.3 mm, wrong roots 817 →
    /// 722 bone-frames (4.2 → 3.7 %; on the reference's key triangle 3.3 → 2.9 %), from the
    /// height 37.9 → 36.8; 2 px noise 44.4 → 44.2 (from the height 59.1 → 59.2); from the
    /// tracker 80.6 → 80.5 (from the height 87.9 → 88.0); the real sample (balancing, no gait)
    /// unchanged; the per-frame solve 2009 → 1820 frames/s (the arms solved three times).
    pub gait_symmetry: f64,
    /// The image's depth evidence: where the pose network saw the body (the tracks' `body3d`),
    /// each bone pays the squared difference between its depth step (child minus parent, along
    /// the camera's axis) and the network's, times the network's confidence in both ends. It
    /// steers the choice and stays out of the reported cost. Measured in `docs/method.md`.
    pub image_depth: f64,
    /// The image's evidence for which way the body faces: how strongly the shoulders' depth
    /// order against the network's (each frame's squared difference of the two depth steps,
    /// times the network's confidence, summed over the clip) counts in the choice of the key
    /// triangle's pose and facing, as one more part of the fit's sum of logarithms (0: not at
    /// all). Measured in `docs/method.md`.
    pub image_facing: f64,
}

impl Default for AmbiguityWeights {
    fn default() -> Self {
        AmbiguityWeights {
            trunk_up: 0.3,
            extension: 1.0,
            hips_collinear: 10.0,
            hips_parallel: 1.0,
            knee: 2.0,
            knee_side: 1.0,
            elbow: 5.0,
            hanging: 0.05,
            medial: 1.0,
            straight: 0.05,
            frontal: 0.1,
            arm_swing: 1.0,
            contact: 10.0,
            miss: 10.0,
            lookahead: 0.3,
            gait_symmetry: 0.3,
            image_depth: IMAGE_DEPTH,
            image_facing: IMAGE_FACING,
        }
    }
}

impl AmbiguityWeights {
    /// Checks every weight is finite and not negative (a negative weight would reward the
    /// posture its prior forbids).
    pub fn validate(&self) -> Result<(), LiftError> {
        // Destructured so that a new weight cannot be left unchecked.
        let AmbiguityWeights {
            trunk_up,
            extension,
            hips_collinear,
            hips_parallel,
            knee,
            knee_side,
            elbow,
            hanging,
            medial,
            straight,
            frontal,
            arm_swing,
            contact,
            miss,
            lookahead,
            gait_symmetry,
            image_depth,
            image_facing,
        } = *self;
        [
            ("ambiguity.trunk_up", trunk_up),
            ("ambiguity.extension", extension),
            ("ambiguity.hips_collinear", hips_collinear),
            ("ambiguity.hips_parallel", hips_parallel),
            ("ambiguity.knee", knee),
            ("ambiguity.knee_side", knee_side),
            ("ambiguity.elbow", elbow),
            ("ambiguity.hanging", hanging),
            ("ambiguity.medial", medial),
            ("ambiguity.straight", straight),
            ("ambiguity.frontal", frontal),
            ("ambiguity.arm_swing", arm_swing),
            ("ambiguity.contact", contact),
            ("ambiguity.miss", miss),
            ("ambiguity.lookahead", lookahead),
            ("ambiguity.gait_symmetry", gait_symmetry),
            ("ambiguity.image_depth", image_depth),
            ("ambiguity.image_facing", image_facing),
        ]
        .into_iter()
        .try_for_each(|(name, value)| check_setting(name, value, false))
    }
}

/// How far a resting arm and leg hang outwards from straight down, radians: arms clear the
/// hips; thighs lean a little inwards, knees nearer each other than the hips. The references'
/// thighs, in the pelvis's frame, lean 0.02 to 0.09 inwards at the median on the suite's six
/// motion-capture clips (0.16 to 0.23 at their tenth percentile), 0.06 to 0.08 outwards on the
/// procedural bodies and 0.12 outwards on the real sample. The suite from exact 2D with true
/// lengths (legs in the pelvis's frame) at 0.05 / 0 / −0.05 / −0.1: wrong roots 4.52 / 4.44 /
/// 4.44 / 4.44 % (walk_across_side 9.4 / 8.8 / 8.8 / 8.8 %); the real sample unchanged.
const REST_ABDUCTION: [f64; 2] = [0.15, -0.05];

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
const REST_SWING: f64 = 0.3;

/// How far down (the sine of the angle from horizontal) an upper arm must hang for
/// [`REST_SWING`] to count at all; it counts fully straight down. At 0.3 (as for the elbow's
/// prior, [`ELBOW_HANG`]) the real sample's wrong roots rose 5.4 → 6.1 %; at 0.8 they stay.
const REST_SWING_HANG: f64 = 0.8;

/// How far down an upper arm must hang for [`AmbiguityWeights::elbow`] to count at all (the
/// sine of the angle from horizontal); it counts fully straight down.
const ELBOW_HANG: f64 = 0.3;

/// How far an upper arm or thigh may cross inwards of straight down before [`AmbiguityWeights::
/// medial`] counts it (the sine of the angle).
const MEDIAL_FREE: f64 = 0.1;

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
const SPINE_BACK: f64 = 0.2;

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
const HEAD_FORWARD: f64 = 0.2;

/// How much more a head tilted sideways pays in [`AmbiguityWeights::trunk_up`] than one
/// tilted forwards (on top of the tilt both pay): the neck bends forwards far more than
/// sideways. The references tilt the head sideways by a sine of 0.18 at most (0.13 at the
/// median of the most tilted clip), forwards by up to 0.78 (dribbling looks down at the ball);
/// a head leaning well forward in an oblique view has a mirror root less forward but tilted
/// sideways, which the isotropic prior preferred on every frame of dribble_oblique. `bench
/// lift`'s suite from exact 2D with true lengths at 0 / 1 / 2 / 3 / 10: wrong roots 5.0 / 4.7 /
/// 4.7 / 4.9 / 5.1 % (dribble_oblique 9.4 / 4.6 / 4.2 / 4.2 / 4.2 %; from 3 walk_across_side's
/// head, seen from the side, follows the key triangle's small errors sideways).
const HEAD_SIDEWAYS: f64 = 2.0;

/// How far the thighs must split for a stride to count fully in [`AmbiguityWeights::
/// arm_swing`]: the product of their forward components, one forward and one back (0.2 each
/// way). At 0.02 and 0.08 `bench lift`'s suite from exact 2D was within 0.3 mm of 0.04.
const GAIT_SPLIT: f64 = 0.04;

/// The radius of the trunk around the spine that [`AmbiguityWeights::contact`] keeps a wrist
/// out of, as a share of the trunk's (frontal) breadth: a round capsule stands for a trunk
/// less deep than broad, so its radius is nearer half the depth than half the breadth (0.35 of
/// the default 1.75 m subject's 0.35 m is 0.12 m).
const TRUNK_DEPTH: f64 = 0.35;

/// The radius of a thigh around its bone that [`AmbiguityWeights::contact`] keeps a wrist out
/// of, as a share of the thigh's breadth (0.45 of the default subject's 0.16 m is 0.07 m).
const THIGH_DEPTH: f64 = 0.45;

/// [`AmbiguityWeights::image_depth`]'s default: chosen on the suite's dev split.
const IMAGE_DEPTH: f64 = 1.0;

/// [`AmbiguityWeights::image_facing`]'s default: chosen on the suite's dev split.
const IMAGE_FACING: f64 = 1.0;

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
fn image_depth_cost(group: &Group, p: &PerJoint<Point3<f64>>, body: &NetworkBody) -> f64 {
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

/// Forced root choices: `(frame index, bone) → root`, set by a user flipping a limb.
pub type DepthOverrides = BTreeMap<(FrameIndex, Bone), Root>;

/// Which prior scores a group.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Prior {
    Head,
    Spine,
    Hips,
    Arm,
    Leg,
}

/// Bones whose roots are chosen together.
struct Group {
    bones: &'static [Bone],
    prior: Prior,
}

use Joint::*;

/// How many groups of bones have their roots chosen together.
pub const GROUP_COUNT: usize = 7;

/// Centre outwards: every group's first parent is known when it is solved. The legs come
/// before the arms, whose prior reads the thighs ([`AmbiguityWeights::arm_swing`]).
const GROUPS: [Group; GROUP_COUNT] = [
    Group {
        bones: &[Bone::new(Chest, Neck), Bone::new(Neck, HeadTop)],
        prior: Prior::Head,
    },
    Group {
        bones: &[Bone::new(Pelvis, Chest)],
        prior: Prior::Spine,
    },
    Group {
        bones: &[Bone::new(Pelvis, LeftHip), Bone::new(Pelvis, RightHip)],
        prior: Prior::Hips,
    },
    Group {
        bones: &[Bone::new(LeftHip, LeftKnee), Bone::new(LeftKnee, LeftAnkle)],
        prior: Prior::Leg,
    },
    Group {
        bones: &[
            Bone::new(RightHip, RightKnee),
            Bone::new(RightKnee, RightAnkle),
        ],
        prior: Prior::Leg,
    },
    Group {
        bones: &[
            Bone::new(LeftShoulder, LeftElbow),
            Bone::new(LeftElbow, LeftWrist),
        ],
        prior: Prior::Arm,
    },
    Group {
        bones: &[
            Bone::new(RightShoulder, RightElbow),
            Bone::new(RightElbow, RightWrist),
        ],
        prior: Prior::Arm,
    },
];

/// A bone's ends in the order the lift visits them, `(known, solved)`: the lift runs from the
/// key triangle outwards, so the spine is solved from the chest down to the pelvis although the
/// model's tree is rooted at the pelvis. Every other bone runs parent to child.
pub fn lift_order(bone: Bone) -> (Joint, Joint) {
    if bone == Bone::new(Pelvis, Chest) {
        (Chest, Pelvis)
    } else {
        (bone.parent, bone.child)
    }
}

/// The skeleton of a sequence with every root chosen.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    /// Joint positions per frame.
    pub points: Vec<PerJoint<Point3<f64>>>,
    /// The root taken by each bone (indexed like [`Bone::ALL`]) per frame.
    pub choices: Vec<[Root; BONE_COUNT]>,
    /// Whether each bone was too long for its 2D image (flagged, placed off its ray).
    pub too_long: Vec<[bool; BONE_COUNT]>,
    /// How much the clip-wide cost of the bone's group would rise, at best, were the bone to
    /// take its other root on that frame (`margins`): small where the choice was close,
    /// infinite where the user forced it.
    pub margins: Vec<[f64; BONE_COUNT]>,
    /// The minimised total of each group of bones, priors (but the arms' swing and gait
    /// symmetry and the spine's look ahead, which only steer their roots) plus squared
    /// accelerations (squared metres), in the order they are solved: head and neck, spine, hips,
    /// left leg, right leg, left arm, right arm.
    pub group_costs: [f64; GROUP_COUNT],
}

/// The key triangle's directions in one frame: left, up, forward (unit vectors).
#[derive(Clone)]
struct TrunkFrame {
    left: Vector3<f64>,
    up: Vector3<f64>,
    forward: Vector3<f64>,
}

impl TrunkFrame {
    fn of(points: &PerJoint<Point3<f64>>) -> TrunkFrame {
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
    fn forward_sine(&self, from: &Point3<f64>, to: &Point3<f64>) -> f64 {
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
    fn pelvis(&self, points: &PerJoint<Point3<f64>>) -> TrunkFrame {
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
fn tilted(base: Vector3<f64>, toward: Vector3<f64>, sine: f64) -> Vector3<f64> {
    base * (1.0 - sine * sine).sqrt() + toward * sine
}

/// An arm's [`AmbiguityWeights::arm_swing`] term (squared metres, weighted; 0 for the other
/// groups).
fn swing_cost(
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
fn posture_cost(
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
fn hanging_share(upper: &Vector3<f64>, trunk: &TrunkFrame, from: f64) -> f64 {
    ((-upper.dot(&trunk.up) - from) / (1.0 - from)).clamp(0.0, 1.0)
}

/// How deep a wrist lies inside the trunk or a thigh, squared (metres squared), for
/// [`AmbiguityWeights::contact`]. The spine and both legs are solved before the arms.
fn inside_body(wrist: &Point3<f64>, p: &PerJoint<Point3<f64>>, subject: &SubjectModel) -> f64 {
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
fn arm_swing(
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

/// One candidate of a group on one frame.
#[derive(Clone)]
struct Candidate {
    /// Camera-space positions of the group's child joints.
    absolute: [Point3<f64>; 2],
    too_long: [bool; 2],
    unary: f64,
    /// The part of `unary` that only steers the choice and is left out of the group's reported
    /// cost: the arms' [`swing_cost`] and [`gait::Symmetry::cost`], the spine's [`hanging_cost`].
    steer: f64,
}

/// Resolves every bone's root over the sequence.
///
/// `key[t]` holds the key joints (shoulders and chest) of frame `t`; `rays[t]` the unit viewing
/// ray of every joint; `frame_index[t]` the video frame (for overrides).
pub fn resolve(
    key: &[[Point3<f64>; 3]],
    rays: &[PerJoint<Vector3<f64>>],
    frame_index: &[FrameIndex],
    bodies: &[Option<NetworkBody>],
    subject: &SubjectModel,
    weights: &AmbiguityWeights,
    overrides: &DepthOverrides,
) -> Resolved {
    let n = key.len();
    let points: Vec<PerJoint<Point3<f64>>> = key
        .iter()
        .map(|k| {
            let mut p = PerJoint::from_fn(|_| Point3::origin());
            p.0[LeftShoulder.index()] = k[0];
            p.0[RightShoulder.index()] = k[1];
            p.0[Chest.index()] = k[2];
            p
        })
        .collect();
    let trunks: Vec<TrunkFrame> = points.iter().map(TrunkFrame::of).collect();
    let inputs = Inputs {
        rays,
        frame_index,
        bodies,
        subject,
        weights,
        overrides,
        trunks: &trunks,
    };
    let mut resolved = Resolved {
        points,
        choices: vec![[Root::Near; BONE_COUNT]; n],
        too_long: vec![[false; BONE_COUNT]; n],
        margins: vec![[0.0; BONE_COUNT]; n],
        group_costs: [0.0; GROUP_COUNT],
    };
    for g in 0..GROUP_COUNT {
        solve_group(g, &inputs, &mut resolved, None);
    }
    // The arms again, each steered towards the other arm's pose half a stride away
    // ([`AmbiguityWeights::gait_symmetry`]), both from the same previous round.
    if weights.gait_symmetry > 0.0
        && let Some(lag) = gait::gait_lag(&resolved.points, &trunks)
    {
        for _ in 0..gait::SYMMETRY_ROUNDS {
            let previous = resolved.points.clone();
            let symmetry = gait::Symmetry {
                lag,
                previous: &previous,
                trunks: &trunks,
            };
            for g in ARM_GROUPS {
                if symmetry.holds(&GROUPS[g]) {
                    solve_group(g, &inputs, &mut resolved, Some(&symmetry));
                }
            }
        }
    }
    resolved
}

/// What every group's solve reads: the rays, the frames' video indices (for overrides), the
/// subject, the weights, the user's overrides and the key triangle's frames.
struct Inputs<'a> {
    rays: &'a [PerJoint<Vector3<f64>>],
    frame_index: &'a [FrameIndex],
    /// The network's 3D body per frame (empty, or `None` on a frame: no such evidence).
    bodies: &'a [Option<NetworkBody>],
    subject: &'a SubjectModel,
    weights: &'a AmbiguityWeights,
    overrides: &'a DepthOverrides,
    trunks: &'a [TrunkFrame],
}

/// Chooses the roots of group `g` over the whole sequence on the trajectories already chosen
/// for its parents, and writes its joints, choices and cost into `resolved`. `symmetry`, when
/// given, steers an arm towards the other arm's pose half a stride away.
fn solve_group(
    g: usize,
    inputs: &Inputs<'_>,
    resolved: &mut Resolved,
    symmetry: Option<&gait::Symmetry<'_>>,
) {
    let Inputs {
        rays,
        frame_index,
        bodies,
        subject,
        weights,
        overrides,
        trunks,
    } = *inputs;
    let group = &GROUPS[g];
    let combos = 1usize << group.bones.len();
    let candidates: Vec<Vec<Candidate>> = (0..resolved.points.len())
        .map(|t| {
            (0..combos)
                .map(|combo| {
                    let mut p = resolved.points[t];
                    let mut c = Candidate {
                        absolute: [Point3::origin(); 2],
                        too_long: [false; 2],
                        unary: 0.0,
                        steer: 0.0,
                    };
                    for (k, bone) in group.bones.iter().enumerate() {
                        let (known, solved) = lift_order(*bone);
                        let roots =
                            bone_roots(&p[known], &rays[t][solved], subject.bone_length(*bone));
                        let root = root_of(combo, k);
                        if overrides
                            .get(&(frame_index[t], *bone))
                            .is_some_and(|o| *o != root)
                        {
                            c.unary = f64::INFINITY;
                        }
                        if roots.too_long {
                            // The joint cannot lie on its ray: the miss counts against
                            // this candidate (a wrong parent often causes it).
                            let q = roots.get(root).coords;
                            let ray = &rays[t][solved];
                            c.unary += weights.miss * (q - ray * ray.dot(&q)).norm_squared();
                        }
                        p.0[solved.index()] = roots.get(root);
                        c.absolute[k] = roots.get(root);
                        c.too_long[k] = roots.too_long;
                    }
                    if c.unary.is_finite() {
                        c.steer = swing_cost(group, &p, &trunks[t], weights);
                        if group.prior == Prior::Spine && weights.lookahead > 0.0 {
                            c.steer += weights.lookahead
                                * hanging_cost(&p, &rays[t], &trunks[t], subject, weights);
                        }
                        if let Some(symmetry) = symmetry {
                            c.steer += weights.gait_symmetry * symmetry.cost(group, &p, t);
                        }
                        if let Some(Some(body)) = bodies.get(t)
                            && weights.image_depth > 0.0
                        {
                            c.steer += weights.image_depth * image_depth_cost(group, &p, body);
                        }
                        c.unary += posture_cost(group, &p, &trunks[t], subject, weights) + c.steer;
                    }
                    c
                })
                .collect()
        })
        .collect();
    let (path, cost) = viterbi(&candidates);
    // The steering terms choose the roots but stay out of the cost `fit_score` weighs
    // calibration poses by: from the tracker's output the swing term let a trunk turned the
    // wrong way win on treadmill_oblique (78.8 → 221.1 mm).
    let steer: f64 = path
        .iter()
        .enumerate()
        .map(|(t, &c)| candidates[t][c].steer)
        .sum();
    resolved.group_costs[g] = cost - steer;
    let marginals = margins::min_marginals(&candidates);
    for (t, &combo) in path.iter().enumerate() {
        let c = &candidates[t][combo];
        for (k, bone) in group.bones.iter().enumerate() {
            resolved.points[t].0[lift_order(*bone).1.index()] = c.absolute[k];
            let b = bone.index();
            resolved.choices[t][b] = root_of(combo, k);
            resolved.too_long[t][b] = c.too_long[k];
            // The best the clip can do with this bone's other root here.
            let other = (0..combos)
                .filter(|&o| root_of(o, k) != root_of(combo, k))
                .map(|o| marginals[t][o])
                .fold(f64::INFINITY, f64::min);
            resolved.margins[t][b] = (other - cost).max(0.0);
        }
    }
}

/// The root a group's `combo` gives its `k`-th bone (bit `k`: 0 near, 1 far).
fn root_of(combo: usize, k: usize) -> Root {
    if combo >> k & 1 == 0 {
        Root::Near
    } else {
        Root::Far
    }
}

/// Where [`GROUPS`] holds the hips and the two legs, for [`hanging_cost`], and the two arms,
/// for [`AmbiguityWeights::gait_symmetry`].
const HIPS_GROUP: usize = 2;
const LEG_GROUPS: [usize; 2] = [3, 4];
const ARM_GROUPS: [usize; 2] = [5, 6];

/// `p` with group `g`'s joints placed on their rays by the roots of `combo`, for
/// [`hanging_cost`] (a bone too long for its image is placed as [`resolve`] places it).
fn placed(
    g: usize,
    combo: usize,
    p: &PerJoint<Point3<f64>>,
    rays: &PerJoint<Vector3<f64>>,
    subject: &SubjectModel,
) -> PerJoint<Point3<f64>> {
    let mut q = *p;
    for (k, bone) in GROUPS[g].bones.iter().enumerate() {
        let (known, solved) = lift_order(*bone);
        let roots = bone_roots(&q[known], &rays[solved], subject.bone_length(*bone));
        q.0[solved.index()] = roots.get(root_of(combo, k));
    }
    q
}

/// [`AmbiguityWeights::lookahead`]'s cost for a pelvis placed in `p` on one frame: the least
/// prior of the hips plus each leg at its best roots below them (unweighted, squared metres).
/// A joint's miss off its ray is left out: badly tracked legs would otherwise decide for the
/// pelvis.
fn hanging_cost(
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

/// Squared second difference of the candidates' camera-space positions at three frames.
///
/// A hand or a knee carries its own momentum: it moves smoothly in space, not only relative to
/// the shoulder or hip it hangs from (which the key triangle's and the spine's choices move).
/// It was measured relative to the group's root joint before; `bench lift` (refined; before →
/// after) from exact 2D with true lengths 11.0 → 10.9 mm, wrong roots 868 → 828 bone-frames
/// (4.4 → 4.2 %; dance_oblique 151 → 132, jumping_jacks_frontal 42 → 26), on the reference's
/// key triangle 3.9 → 3.2 %; 2 px noise 46.7 → 46.0 (from the height 61.3 → 60.9); from the
/// tracker 83.0 → 82.0 (from the height 89.1 → 88.7); the real sample unchanged but from its
/// exact 2D and the height, 97.2 → 98.8. Half relative and half absolute gave 826 wrong roots;
/// absolute scaled by 0.5 / 0.7 / 1.4 / 2 against the priors, 887 / 900 / 899 / 966.
///
/// It is per frame, not per second: scaled to physical units by (fps/30)^k for k = 1 / 2 / 4
/// the suite's wrong roots went 722 → 786 / 852 / 1034 (walk_toward_frontal at 60 frames/s
/// 63 → 138–140), for k = −0.5 / −1 to 755 / 768. Weighed ×10 / ×100 / ×1000 where the
/// group's first bone has its two roots under 5 mm apart: 770 / 845 / 909.
fn acceleration(a: &Candidate, b: &Candidate, c: &Candidate) -> f64 {
    (0..2)
        .map(|k| {
            (c.absolute[k].coords - b.absolute[k].coords * 2.0 + a.absolute[k].coords)
                .norm_squared()
        })
        .sum()
}

/// Weight of the squared velocity between the first two frames (only matters for two-frame
/// clips, where there is no acceleration).
const VELOCITY_WEIGHT: f64 = 0.01;

/// The best totals of the first two frames, `[a·k + b]` with frame 0 at `a` and frame 1 at `b`
/// (their unaries and the velocity between them). Needs two frames or more.
fn first_pair(candidates: &[Vec<Candidate>]) -> Vec<f64> {
    let k = candidates[0].len();
    let mut cost = vec![f64::INFINITY; k * k];
    for a in 0..k {
        for b in 0..k {
            let (ca, cb) = (&candidates[0][a], &candidates[1][b]);
            let v: f64 = (0..2)
                .map(|i| (cb.absolute[i] - ca.absolute[i]).norm_squared())
                .sum();
            cost[a * k + b] = ca.unary + cb.unary + VELOCITY_WEIGHT * v;
        }
    }
    cost
}

/// One step of the second-order Viterbi: from the best totals `cost[a·k + b]` of frames
/// `t − 2`, `t − 1`, those of frames `t − 1`, `t` (`[b·k + c]`), with the `a` each came from.
fn forward_step(candidates: &[Vec<Candidate>], t: usize, cost: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let k = candidates[t].len();
    let mut next = vec![f64::INFINITY; k * k];
    let mut from = vec![0usize; k * k];
    for b in 0..k {
        for c in 0..k {
            let cc = &candidates[t][c];
            for a in 0..k {
                let prev = cost[a * k + b];
                if !prev.is_finite() {
                    continue;
                }
                let total = prev
                    + cc.unary
                    + acceleration(&candidates[t - 2][a], &candidates[t - 1][b], cc);
                if total < next[b * k + c] {
                    next[b * k + c] = total;
                    from[b * k + c] = a;
                }
            }
        }
    }
    (next, from)
}

/// The sequence of candidate indices minimising priors plus squared accelerations.
fn viterbi(candidates: &[Vec<Candidate>]) -> (Vec<usize>, f64) {
    let n = candidates.len();
    let best_single = |t: usize| {
        (0..candidates[t].len())
            .min_by(|&a, &b| candidates[t][a].unary.total_cmp(&candidates[t][b].unary))
            .unwrap_or(0)
    };
    if n < 2 {
        let path: Vec<usize> = (0..n).map(best_single).collect();
        let cost = path
            .iter()
            .enumerate()
            .map(|(t, &c)| candidates[t][c].unary)
            .sum();
        return (path, cost);
    }
    let k = candidates[0].len();
    // cost[a * k + b]: best total with frame t−1 at a and frame t at b.
    let mut cost = first_pair(candidates);
    let mut back: Vec<Vec<usize>> = Vec::with_capacity(n);
    for t in 2..n {
        let (next, from) = forward_step(candidates, t, &cost);
        cost = next;
        back.push(from);
    }
    let end = (0..k * k)
        .min_by(|&x, &y| cost[x].total_cmp(&cost[y]))
        .unwrap_or(0);
    let mut path = vec![0usize; n];
    path[n - 2] = end / k;
    path[n - 1] = end % k;
    for t in (2..n).rev() {
        path[t - 2] = back[t - 2][path[t - 1] * k + path[t]];
    }
    (path, cost[end])
}

/// A candidate whose first child sits at `x` on a line, for the Viterbi tests.
#[cfg(test)]
fn test_candidate(x: f64, unary: f64) -> Candidate {
    Candidate {
        absolute: [Point3::new(x, 0.0, 0.0), Point3::origin()],
        too_long: [false; 2],
        unary,
        steer: 0.0,
    }
}

#[cfg(test)]
mod tests;
