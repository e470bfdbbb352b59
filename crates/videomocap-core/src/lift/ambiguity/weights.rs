//! The weights of the depth-ambiguity priors: fitted constants chosen on the suite's dev split
//! (`docs/method.md`); three of them a user may change through the lift's settings
//! ([`super::super::LiftParams`]).

/// How strongly each prior counts against the acceleration term (both in squared metres).
#[derive(Debug, Clone, Copy, PartialEq)]
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
    /// Elbows of hanging arms bend forwards. Measured in `docs/method.md` ("Fitted constants of
    /// the lift").
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
    /// that nothing else tells apart). Measured in `docs/method.md` ("Fitted constants of the
    /// lift").
    pub frontal: f64,
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
    /// Measured in `docs/method.md` ("Fitted constants of the lift").
    pub image_depth: f64,
    /// The image's evidence for which way the body faces: how strongly the shoulders' depth
    /// order against the network's (each frame's squared difference of the two depth steps,
    /// times the network's confidence, summed over the clip) counts in the choice of the key
    /// triangle's pose and facing, as one more part of the fit's sum of logarithms. Measured in
    /// `docs/method.md` ("Fitted constants of the lift").
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

/// [`AmbiguityWeights::image_depth`]'s default: chosen on the suite's dev split.
const IMAGE_DEPTH: f64 = 1.0;

/// [`AmbiguityWeights::image_facing`]'s default: chosen on the suite's dev split.
const IMAGE_FACING: f64 = 1.0;
