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
mod memo;
mod priors;
mod viterbi;
mod weights;

pub(super) use priors::image_facing_cost;
pub use weights::AmbiguityWeights;

pub(crate) use memo::PriorMemo;

use super::backproject::{Root, bone_roots};
use super::prior::{PosePrior, PriorGroup, Side, TrunkFrame};
use crate::formats::{FrameIndex, NetworkBody};
use crate::skeleton::{BONE_COUNT, Bone, Joint, PerJoint, SubjectModel};
use nalgebra::{Point3, Vector3};
use priors::{hanging_cost, image_depth_cost, inside_body, swing_cost};
use std::collections::BTreeMap;
use viterbi::viterbi;

/// Forced root choices: `(frame index, bone) → root`, set by a user flipping a limb.
pub type DepthOverrides = BTreeMap<(FrameIndex, Bone), Root>;

/// Bones whose roots are chosen together.
struct Group {
    bones: &'static [Bone],
    /// The pose prior's group that scores them.
    prior: PriorGroup,
}

use Joint::*;

/// How many groups of bones have their roots chosen together.
pub(super) const GROUP_COUNT: usize = 7;

/// Centre outwards: every group's first parent is known when it is solved. The legs come
/// before the arms, whose prior reads the thighs ([`AmbiguityWeights::arm_swing`]).
const GROUPS: [Group; GROUP_COUNT] = [
    Group {
        bones: &[Bone::new(Chest, Neck), Bone::new(Neck, HeadTop)],
        prior: PriorGroup::Head,
    },
    Group {
        bones: &[Bone::new(Pelvis, Chest)],
        prior: PriorGroup::Spine,
    },
    Group {
        bones: &[Bone::new(Pelvis, LeftHip), Bone::new(Pelvis, RightHip)],
        prior: PriorGroup::Hips,
    },
    Group {
        bones: &[Bone::new(LeftHip, LeftKnee), Bone::new(LeftKnee, LeftAnkle)],
        prior: PriorGroup::Leg(Side::Left),
    },
    Group {
        bones: &[
            Bone::new(RightHip, RightKnee),
            Bone::new(RightKnee, RightAnkle),
        ],
        prior: PriorGroup::Leg(Side::Right),
    },
    Group {
        bones: &[
            Bone::new(LeftShoulder, LeftElbow),
            Bone::new(LeftElbow, LeftWrist),
        ],
        prior: PriorGroup::Arm(Side::Left),
    },
    Group {
        bones: &[
            Bone::new(RightShoulder, RightElbow),
            Bone::new(RightElbow, RightWrist),
        ],
        prior: PriorGroup::Arm(Side::Right),
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
    /// How sure each bone's root is (nats): the pose prior's log-likelihood ratio of the
    /// chosen root against the other on that frame (without the prior, how much the clip-wide
    /// cost of the bone's group would rise, at best, were the bone to take its other root
    /// there, at the prior's exchange rate): small where the choice was close, infinite where
    /// the user forced it. See `write_path`.
    pub margins: Vec<[f64; BONE_COUNT]>,
    /// The minimised total of each group of bones, priors (but the arms' swing and gait
    /// symmetry and the spine's look ahead, which only steer their roots) plus squared
    /// accelerations (squared metres), in the order they are solved: head and neck, spine, hips,
    /// left leg, right leg, left arm, right arm.
    pub group_costs: [f64; GROUP_COUNT],
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
    /// The candidate's pose prior cost (nats; 0 without the prior), for its bones' margins.
    nats: f64,
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
    let memo = PriorMemo::new(key.len());
    resolve_with(
        key,
        rays,
        frame_index,
        bodies,
        subject,
        weights,
        overrides,
        &memo,
        Margins::Compute,
    )
}

/// Whether a solve works out each bone's margin ([`Resolved::margins`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Margins {
    /// Every bone's margin ([`Resolved::margins`]).
    Compute,
    /// None (the margins left at 0): a trial solve whose cost alone is read, for the choice of
    /// the calibration pose and the facing (without the prior the margins' min-marginals cost
    /// as much again as the chain).
    Skip,
}

/// [`resolve`] keeping the pose prior's costs in `memo` for the next solve of the same lift
/// (the same rays, subject and weights), working out the margins only if asked.
#[allow(clippy::too_many_arguments)]
pub(crate) fn resolve_with(
    key: &[[Point3<f64>; 3]],
    rays: &[PerJoint<Vector3<f64>>],
    frame_index: &[FrameIndex],
    bodies: &[Option<NetworkBody>],
    subject: &SubjectModel,
    weights: &AmbiguityWeights,
    overrides: &DepthOverrides,
    memo: &PriorMemo,
    margins: Margins,
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
        prior: PosePrior::bundled()
            .ok()
            .filter(|_| weights.pose_prior > 0.0),
        memo,
        margins,
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
    /// The learned pose prior (`None`: unreadable, checked before the lift runs).
    prior: Option<&'a PosePrior>,
    /// The prior's costs already computed in this lift.
    memo: &'a PriorMemo,
    /// Whether the bones' margins are wanted.
    margins: Margins,
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
    let candidates: Vec<Vec<Candidate>> = (0..resolved.points.len())
        .map(|t| frame_candidates(g, t, inputs, &resolved.points[t], symmetry))
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
    write_path(g, inputs, &candidates, &path, cost, resolved);
}

/// Group `g`'s candidates on frame `t`, its parents placed in `p`: every combination of its
/// bones' roots with its unary cost (the 2D miss, the pose prior, the steering terms, a hand
/// inside the body; infinite against a user's override).
fn frame_candidates(
    g: usize,
    t: usize,
    inputs: &Inputs<'_>,
    p: &PerJoint<Point3<f64>>,
    symmetry: Option<&gait::Symmetry<'_>>,
) -> Vec<Candidate> {
    let Inputs {
        rays,
        frame_index,
        bodies,
        subject,
        weights,
        overrides,
        trunks,
        ..
    } = *inputs;
    let group = &GROUPS[g];
    let nats = prior_costs(g, t, inputs, p);
    (0..1usize << group.bones.len())
        .map(|combo| {
            let mut p = *p;
            let mut c = Candidate {
                absolute: [Point3::origin(); 2],
                too_long: [false; 2],
                unary: 0.0,
                steer: 0.0,
                nats: nats[combo].0,
            };
            for (k, bone) in group.bones.iter().enumerate() {
                let (known, solved) = lift_order(*bone);
                let roots = bone_roots(&p[known], &rays[t][solved], subject.bone_length(*bone));
                let root = root_of(combo, k);
                if overrides
                    .get(&(frame_index[t], *bone))
                    .is_some_and(|o| *o != root)
                {
                    c.unary = f64::INFINITY;
                }
                if roots.too_long {
                    // The joint cannot lie on its ray: the miss counts against this
                    // candidate (a wrong parent often causes it).
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
                c.steer += weights.lookahead * weights.pose_prior * nats[combo].1;
                if let Some(symmetry) = symmetry {
                    c.steer += weights.gait_symmetry * symmetry.cost(group, &p, t);
                }
                if let Some(Some(body)) = bodies.get(t)
                    && weights.image_depth > 0.0
                {
                    c.steer += weights.image_depth * image_depth_cost(group, &p, body);
                }
                if matches!(group.prior, PriorGroup::Arm(_)) {
                    let end = group.bones[1].child;
                    c.unary += weights.contact * inside_body(&p[end], &p, subject);
                }
                c.unary += weights.pose_prior * nats[combo].0 + c.steer;
            }
            c
        })
        .collect()
}

/// Writes group `g`'s chosen `path` (of total `cost`) into `resolved`: its joints, roots,
/// too-long flags and, when asked, each bone's margin (nats).
///
/// With the pose prior, a bone's margin is the prior's own log-likelihood ratio of its two
/// roots on that frame: the prior's cost of the group's best candidate with the bone's other
/// root (its other bones free) minus the chosen candidate's, at least 0; infinite where the
/// user forced the root. On dev (together, exact 2D) the choices this margin calls unsure at
/// 2 nats were wrong 3.75 × as often as the sure ones (30 against 8 %; the real sample 23
/// against 6 %), where the clip-wide min-marginal managed 1.5 × (`docs/method.md`, issue 94):
/// a choice the prior cannot tell apart is the one smooth motion and the network decide
/// alone, and those go wrong. Without the prior the margin is the clip-wide one: what taking
/// the other root would cost the whole clip at best ([`margins::min_marginals`]), in nats at
/// the prior's default exchange rate.
fn write_path(
    g: usize,
    inputs: &Inputs<'_>,
    candidates: &[Vec<Candidate>],
    path: &[usize],
    cost: f64,
    resolved: &mut Resolved,
) {
    let group = &GROUPS[g];
    let combos = 1usize << group.bones.len();
    let marginals = match inputs.margins {
        Margins::Compute if inputs.prior.is_none() => margins::min_marginals(candidates),
        _ => Vec::new(),
    };
    let per_nat = AmbiguityWeights::default().pose_prior;
    for (t, &combo) in path.iter().enumerate() {
        let here = &candidates[t];
        let c = &here[combo];
        for (k, bone) in group.bones.iter().enumerate() {
            resolved.points[t].0[lift_order(*bone).1.index()] = c.absolute[k];
            let b = bone.index();
            resolved.choices[t][b] = root_of(combo, k);
            resolved.too_long[t][b] = c.too_long[k];
            if inputs.margins == Margins::Skip {
                continue;
            }
            let others = (0..combos).filter(|&o| root_of(o, k) != root_of(combo, k));
            let least =
                |of: &dyn Fn(usize) -> f64| others.clone().map(of).fold(f64::INFINITY, f64::min);
            resolved.margins[t][b] = if least(&|o| here[o].unary).is_infinite() {
                f64::INFINITY
            } else if let Some(marginals) = marginals.get(t) {
                (least(&|o| marginals[o]) - cost).max(0.0) / per_nat
            } else {
                (least(&|o| here[o].nats) - c.nats).max(0.0)
            };
        }
    }
}

/// Group `g`'s candidates' pose prior on frame `t` (their joints placed from `p`): per
/// combination of roots, its cost and, for the spine, the look ahead's (both nats; zeros
/// without the prior). Read from the lift's memo where the joints they hang from are unchanged.
fn prior_costs(
    g: usize,
    t: usize,
    inputs: &Inputs<'_>,
    p: &PerJoint<Point3<f64>>,
) -> [(f64, f64); 4] {
    let Some(prior) = inputs.prior else {
        return [(0.0, 0.0); 4];
    };
    let group = &GROUPS[g];
    let (rays, trunk, subject) = (&inputs.rays[t], &inputs.trunks[t], inputs.subject);
    let look = group.prior == PriorGroup::Spine && inputs.weights.lookahead > 0.0;
    inputs.memo.costs(t, g, group.prior, p, || {
        let mut costs = [(0.0, 0.0); 4];
        for (combo, c) in costs.iter_mut().enumerate().take(1 << group.bones.len()) {
            let q = placed(g, combo, p, rays, subject);
            c.0 = prior.cost(group.prior, &q, trunk);
            if look {
                c.1 = hanging_cost(&q, rays, trunk, subject, prior);
            }
        }
        costs
    })
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

#[cfg(test)]
mod tests;
