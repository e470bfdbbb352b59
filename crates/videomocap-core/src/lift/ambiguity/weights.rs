//! The weights of the depth-ambiguity priors: fitted constants chosen on the suite's dev split
//! (`docs/method.md`); three of them a user may change through the lift's settings
//! ([`super::super::LiftParams`]).

/// How strongly each prior counts against the acceleration term (both in squared metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmbiguityWeights {
    /// The learned pose prior's cost (nats, [`super::super::prior::PosePrior`]) against the
    /// acceleration's squared metres: it replaces the hand-fitted ranges of motion (the head,
    /// spine, hips, knees, elbows, hanging limbs, medial and frontal limits, the straighter
    /// arm). Chosen on the suite's dev split (`docs/method.md`, issue 94).
    pub pose_prior: f64,
    /// In a walking or running stride (the thighs split forwards and backwards), each arm
    /// swings against its own thigh (the left arm forward with the right leg): the arm whose
    /// forward tilt has the same sign as its thigh's pays, in proportion to how far the thighs
    /// split (fully from 0.2 forwards and backwards), tilt times tilt. Measured in
    /// `docs/method.md` ("Fitted constants of the lift").
    pub arm_swing: f64,
    /// A wrist inside the body: nearer the spine (chest to pelvis) than 0.35 of the trunk's
    /// breadth, or a thigh than 0.45 of the thigh's, pays the squared depth it went in.
    /// Measured in `docs/method.md` ("Fitted constants of the lift").
    pub contact: f64,
    /// A joint off its viewing ray (its bone too short for its 2D image).
    pub miss: f64,
    /// The spine's look ahead: each of the pelvis's two roots also pays the least prior the
    /// hips and the legs can take hanging from it on that frame (each leg at its best roots).
    /// Measured in `docs/method.md` ("Fitted constants of the lift").
    pub lookahead: f64,
    /// In a gait (the thighs swinging alternately, repeating each other half a stride apart),
    /// each arm's upper arm and forearm pay their squared distance (times the bone's length
    /// squared) from the other arm's, mirrored left to right in the key triangle's frame, half
    /// a stride before and after. Measured in `docs/method.md` ("Fitted constants of the
    /// lift").
    pub gait_symmetry: f64,
    /// The image's depth evidence: where the pose network saw the body (the tracks' `body3d`),
    /// each bone pays the squared difference between its depth step (child minus parent, along
    /// the camera's axis) and the network's, times the network's confidence in both ends.
    /// The same weight counts the network's word on the body's facing in the choice of the key
    /// triangle's pose (the facing cost of `image_facing_cost`, one more part of the fit's sum of
    /// logarithms): the same evidence, one weight (issue 94; both were 1, set apart).
    /// Measured in `docs/method.md` ("Fitted constants of the lift").
    pub image_depth: f64,
}

impl Default for AmbiguityWeights {
    fn default() -> Self {
        AmbiguityWeights {
            pose_prior: POSE_PRIOR,
            arm_swing: 1.0,
            contact: 10.0,
            miss: 10.0,
            lookahead: 1.0,
            gait_symmetry: 0.3,
            image_depth: IMAGE_DEPTH,
        }
    }
}

/// [`AmbiguityWeights::pose_prior`]'s default (squared metres per nat): chosen on the suite's
/// dev split for `bench lift --network`'s together MPJPE from exact 2D, which it moves: at
/// 0.002 / 0.006, 97.0 / 93.8 mm (PA 63.9 / 65.5; the prior without the network 113.9 / 112.8).
/// `docs/method.md` ("The pose prior learned from motion capture").
const POSE_PRIOR: f64 = 0.006;

/// [`AmbiguityWeights::image_depth`]'s default: chosen on the suite's dev split.
const IMAGE_DEPTH: f64 = 1.0;
