//! Tests of the parent module.

use super::priors::*;
use super::viterbi::test_candidate as cand;
use super::weights::*;
use super::*;

#[test]
fn viterbi_prefers_a_smooth_crossing_to_a_bounce() {
    // Two roots that meet at t = 3 and part again: the true path goes straight through
    // (0.3, 0.2, 0.1, 0, −0.1 …); the other root mirrors it.
    let xs = [0.3, 0.2, 0.1, 0.0, -0.1, -0.2, -0.3];
    let frames: Vec<Vec<Candidate>> = xs
        .iter()
        .map(|&x: &f64| vec![cand(x.abs(), 0.0), cand(-x.abs(), 0.0)])
        .collect();
    // Start pinned to the positive root by a small prior.
    let mut frames = frames;
    frames[0][1].unary = 0.001;
    let (path, _) = viterbi(&frames);
    let chosen: Vec<f64> = path
        .iter()
        .enumerate()
        .map(|(t, &c)| frames[t][c].absolute[0].x)
        .collect();
    for (c, x) in chosen.iter().zip(xs) {
        assert!((c - x).abs() < 1e-12, "{chosen:?}");
    }
}

/// A standing body (Y up, facing +Z) with its limbs along the given directions.
fn standing(
    subject: &SubjectModel,
    limbs: impl Fn(f64) -> [Vector3<f64>; 4],
) -> PerJoint<Point3<f64>> {
    crate::skeleton::standing_pose(
        |b| subject.bone_length(b),
        subject.shoulder_width_m,
        Point3::new(0.0, 1.0, 0.0),
        limbs,
    )
}

/// The bundled pose prior's cost of group `g` on pose `p` (nats) with the arms' swing and
/// contact terms at their default weights over the prior's.
fn group_prior(g: usize, p: &PerJoint<Point3<f64>>, subject: &SubjectModel) -> f64 {
    let (trunk, w) = (TrunkFrame::of(p), AmbiguityWeights::default());
    let prior = PosePrior::bundled().unwrap();
    let mut cost = prior.cost(GROUPS[g].prior, p, &trunk)
        + swing_cost(&GROUPS[g], p, &trunk, &w) / w.pose_prior;
    if matches!(GROUPS[g].prior, PriorGroup::Arm(_)) {
        let end = GROUPS[g].bones[1].child;
        cost += w.contact * inside_body(&p[end], p, subject) / w.pose_prior;
    }
    cost
}

/// The prior of group `g` on a standing body with its limbs along the given directions.
fn prior_of(g: usize, limbs: impl Fn(f64) -> [Vector3<f64>; 4]) -> f64 {
    let subject = SubjectModel::default();
    group_prior(g, &standing(&subject, limbs), &subject)
}

#[test]
fn the_priors_prefer_the_anatomical_of_two_mirror_images() {
    let down = -Vector3::y();
    let dir = |x: f64, y: f64, z: f64| Vector3::new(x, y, z).normalize();
    // The left arm hanging 0.3 outwards, or crossing 0.3 inwards.
    let out = prior_of(left_arm(), |s| {
        [dir(0.3 * s, -1.0, 0.0), dir(0.3 * s, -1.0, 0.3), down, down]
    });
    let across = prior_of(left_arm(), |s| {
        [
            dir(-0.3 * s, -1.0, 0.0),
            dir(-0.3 * s, -1.0, 0.3),
            down,
            down,
        ]
    });
    assert!(out < across, "{out} {across}");
    // The left knee bending backwards in the leg's plane, or sideways.
    let hinge = prior_of(left_leg(), |_| [down, down, down, dir(0.0, -1.0, -0.6)]);
    let sideways = prior_of(left_leg(), |s| [down, down, down, dir(0.6 * s, -1.0, 0.0)]);
    assert!(hinge < sideways, "{hinge} {sideways}");
    // A hanging elbow bent forwards, or as far backwards.
    let forwards = prior_of(left_arm(), |_| [down, dir(0.0, -1.0, 0.6), down, down]);
    let backwards = prior_of(left_arm(), |_| [down, dir(0.0, -1.0, -0.6), down, down]);
    assert!(forwards < backwards, "{forwards} {backwards}");
}

#[test]
fn a_knee_bends_in_its_own_pelvis_plane() {
    // The pelvis turned 0.3 rad against the shoulders, as in a stride; the left thigh
    // swung back, its knee bent backwards in the pelvis's own plane or in the shoulders'.
    // In the shoulders' frame the second looked the hinge (walk_across_side took the
    // mirror thigh for 41 frames so).
    let subject = SubjectModel::default();
    let down = -Vector3::y();
    let turn = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), 0.3);
    let length = |b: Bone| subject.bone_length(b);
    let leg = |shin: Vector3<f64>| {
        let mut p = standing(&subject, |_| [down; 4]);
        for hip in [LeftHip, RightHip] {
            p.0[hip.index()] = p[Pelvis] + turn * (p[hip] - p[Pelvis]);
        }
        let thigh = turn * Vector3::new(0.0, -1.0, -0.4).normalize();
        p.0[LeftKnee.index()] = p[LeftHip] + thigh * length(Bone::new(LeftHip, LeftKnee));
        p.0[LeftAnkle.index()] =
            p[LeftKnee] + shin.normalize() * length(Bone::new(LeftKnee, LeftAnkle));
        group_prior(left_leg(), &p, &subject)
    };
    let bent = Vector3::new(0.0, -0.6, -0.8);
    let (own, shoulders) = (leg(turn * bent), leg(bent));
    assert!(own < shoulders, "{own} {shoulders}");
}

#[test]
fn a_hanging_hand_stays_out_of_the_thigh() {
    let subject = SubjectModel::default();
    let down = -Vector3::y();
    let dir = |x: f64, y: f64, z: f64| Vector3::new(x, y, z).normalize();
    // The left forearm bent a little forwards and 0.3 outwards, or as far inwards: that
    // hand hangs inside the left thigh (the mirror images a side view cannot tell apart).
    let pose = |inwards: f64| {
        standing(&subject, |s| {
            [down, dir(0.3 * s * inwards, -1.0, 0.2), down, down]
        })
    };
    let (outside, inside) = (pose(1.0), pose(-1.0));
    assert!(inside_body(&inside[LeftWrist], &inside, &subject) > 0.0);
    assert_eq!(inside_body(&outside[LeftWrist], &outside, &subject), 0.0);
    // With the contact term the hand outside costs less.
    let (o, i) = (
        group_prior(left_arm(), &outside, &subject),
        group_prior(left_arm(), &inside, &subject),
    );
    assert!(o < i, "{o} {i}");
}

#[test]
fn a_head_looking_down_leans_forwards_not_sideways() {
    // Dribbling (frame 48 of the suite's dribble_oblique): the head top well forward of
    // the neck, or its mirror root, less forward but tilted sideways. The isotropic
    // pull towards HEAD_FORWARD alone preferred the mirror (squared distances 0.35 against
    // 0.44).
    let subject = SubjectModel::default();
    let down = -Vector3::y();
    let body = standing(&subject, |_| [down; 4]);
    let trunk = TrunkFrame::of(&body);
    let head = |left: f64, up: f64, forward: f64| {
        let mut p = body;
        let dir = (trunk.left * left + trunk.up * up + trunk.forward * forward).normalize();
        p.0[HeadTop.index()] = p[Neck] + dir * subject.bone_length(Bone::new(Neck, HeadTop));
        group_prior(group_of(Bone::new(Neck, HeadTop)), &p, &subject)
    };
    let (forwards, sideways) = (head(-0.14, 0.64, 0.75), head(-0.42, 0.73, 0.53));
    assert!(forwards < sideways, "{forwards} {sideways}");
}

/// The group holding `bone`.
fn group_of(bone: Bone) -> usize {
    GROUPS
        .iter()
        .position(|g| g.bones.contains(&bone))
        .expect("every lifted bone is in a group")
}

/// The left arm's group.
fn left_arm() -> usize {
    group_of(Bone::new(LeftShoulder, LeftElbow))
}

/// The left leg's group.
fn left_leg() -> usize {
    group_of(Bone::new(LeftHip, LeftKnee))
}

#[test]
fn in_a_stride_each_arm_swings_against_its_own_thigh() {
    let dir = |x: f64, y: f64, z: f64| Vector3::new(x, y, z).normalize();
    // The left arm 0.3 forwards or backwards, the left thigh `thigh` forwards and the right
    // one as far backwards (a stride), or both thighs straight down (standing): the swing
    // term alone (the learned prior has its own view of the arm, weighed against it).
    let arm = |z: f64, thigh: f64| {
        let subject = SubjectModel::default();
        let p = standing(&subject, |s| {
            let t = dir(0.0, -1.0, s * thigh);
            [dir(0.2 * s, -1.0, z), dir(0.2 * s, -1.0, z), t, t]
        });
        let w = AmbiguityWeights::default();
        swing_cost(&GROUPS[left_arm()], &p, &TrunkFrame::of(&p), &w)
    };
    // Left leg back: the left arm forwards.
    let (against, with) = (arm(0.3, -0.4), arm(-0.3, -0.4));
    assert!(against < with, "{against} {with}");
    // Left leg forwards: the left arm backwards.
    let (against, with) = (arm(-0.3, 0.4), arm(0.3, 0.4));
    assert!(against < with, "{against} {with}");
    // Standing: the swing term costs forwards and backwards the same (nothing: the pose
    // prior still tells them apart).
    let swing = |z: f64| {
        let subject = SubjectModel::default();
        let p = standing(&subject, |s| {
            [
                dir(0.2 * s, -1.0, z),
                dir(0.2 * s, -1.0, z),
                -Vector3::y(),
                -Vector3::y(),
            ]
        });
        let w = AmbiguityWeights::default();
        swing_cost(&GROUPS[left_arm()], &p, &TrunkFrame::of(&p), &w)
    };
    let (forwards, backwards) = (swing(0.3), swing(-0.3));
    assert!(
        forwards.abs() < 1e-12 && backwards.abs() < 1e-12,
        "{forwards} {backwards}"
    );
}

/// Key joints, viewing rays and frame indices: [`resolve`]'s inputs.
type Seen = (
    Vec<[Point3<f64>; 3]>,
    Vec<PerJoint<Vector3<f64>>>,
    Vec<FrameIndex>,
);

/// What [`resolve`] is given for a sequence of known bodies: their key joints, every
/// joint's viewing ray and the frame indices.
fn seen(frames: &[PerJoint<Point3<f64>>]) -> Seen {
    let key = frames
        .iter()
        .map(|p| [p[LeftShoulder], p[RightShoulder], p[Chest]])
        .collect();
    let rays = frames
        .iter()
        .map(|p| p.map(|_, q| q.coords.normalize()))
        .collect();
    (key, rays, (0..frames.len()).map(FrameIndex).collect())
}

/// `n` frames of a standing body moved by `offset`, whose limbs on side `s` (1 left, −1
/// right) point along `limbs(phase, s)` with `phase = sin(step · t)`.
fn striding(
    subject: &SubjectModel,
    n: u32,
    step: f64,
    offset: Vector3<f64>,
    limbs: impl Fn(f64, f64) -> [Vector3<f64>; 4],
) -> Vec<PerJoint<Point3<f64>>> {
    (0..n)
        .map(|t| {
            let phase = (f64::from(t) * step).sin();
            standing(subject, |s| limbs(phase, s)).map(|_, q| q + offset)
        })
        .collect()
}

#[test]
fn the_arms_swing_stays_out_of_the_reported_cost() {
    // A body three metres in front of the camera, facing away from it, walking on the
    // spot: each thigh swings forwards and backwards in depth and each arm against it.
    let subject = SubjectModel::default();
    let frames = striding(
        &subject,
        12,
        0.5,
        Vector3::new(0.0, 0.0, 3.0),
        |phase, s| {
            let thigh = Vector3::new(0.0, -1.0, 0.4 * s * phase).normalize();
            let arm = Vector3::new(0.15 * s, -1.0, -0.3 * s * phase).normalize();
            [arm, arm, thigh, thigh]
        },
    );
    let (key, rays, index) = seen(&frames);
    let solve = |arm_swing: f64, overrides: &DepthOverrides| {
        let w = AmbiguityWeights {
            arm_swing,
            ..AmbiguityWeights::default()
        };
        resolve(&key, &rays, &index, &[], &subject, &w, overrides)
    };
    // The frames whose elbow (the upper arm's root) is not where the body put it.
    let wrong = |r: &Resolved| -> Vec<(usize, Joint)> {
        let elbows = frames.iter().enumerate().flat_map(|(t, p)| {
            [LeftElbow, RightElbow]
                .into_iter()
                .filter(move |&j| (r.points[t][j] - p[j]).norm() > 1e-6)
                .map(move |j| (t, j))
        });
        elbows.collect()
    };
    let with = solve(1.0, &DepthOverrides::new());
    assert!(wrong(&with).is_empty(), "{:?}", wrong(&with));
    // The same roots without the swing: every group reports the same cost.
    let arms = GROUPS
        .iter()
        .filter(|g| matches!(g.prior, PriorGroup::Arm(_)));
    let forced: DepthOverrides = arms
        .flat_map(|g| g.bones.iter())
        .flat_map(|&bone| (0..frames.len()).map(move |t| (t, bone)))
        .map(|(t, bone)| ((FrameIndex(t), bone), with.choices[t][bone.index()]))
        .collect();
    let without = solve(0.0, &forced);
    assert_eq!(with.choices, without.choices);
    for (a, b) in with.group_costs.iter().zip(&without.group_costs) {
        assert!((a - b).abs() < 1e-9, "{a} {b}");
    }
}

#[test]
fn the_groups_named_for_the_look_ahead_and_the_gait_are_the_hips_legs_and_arms() {
    assert!(GROUPS[HIPS_GROUP].prior == PriorGroup::Hips);
    let legs = LEG_GROUPS.map(|g| GROUPS[g].prior);
    assert_eq!(
        legs,
        [PriorGroup::Leg(Side::Left), PriorGroup::Leg(Side::Right)]
    );
    let arms = ARM_GROUPS.map(|g| GROUPS[g].prior);
    assert_eq!(
        arms,
        [PriorGroup::Arm(Side::Left), PriorGroup::Arm(Side::Right)]
    );
    // Left first: the gait's symmetry pairs each arm with the other.
    assert_eq!(GROUPS[ARM_GROUPS[0]].bones[0].parent, LeftShoulder);
    assert_eq!(GROUPS[ARM_GROUPS[1]].bones[0].parent, RightShoulder);
}

#[test]
fn the_spine_looks_ahead_at_the_legs_hanging_from_it() {
    // A body two metres in front of the camera and two metres off its axis, in mid-stride
    // with its knees bent: seen this steeply, the pelvis's two roots lie well apart in depth,
    // and the truth is the far one (a tie would take the near).
    let subject = SubjectModel::default();
    let frames = striding(
        &subject,
        10,
        0.3,
        Vector3::new(0.0, -3.0, 2.0),
        |phase, s| {
            let thigh = Vector3::new(0.0, -1.0, 0.5 * s * phase).normalize();
            let shank = Vector3::new(0.0, -1.0, -0.3).normalize();
            let arm = Vector3::new(0.15 * s, -1.0, 0.0).normalize();
            [arm, arm, thigh, shank]
        },
    );
    let (key, rays, index) = seen(&frames);
    let solve = |lookahead: f64| {
        let w = AmbiguityWeights {
            lookahead,
            ..AmbiguityWeights::default()
        };
        resolve(
            &key,
            &rays,
            &index,
            &[],
            &subject,
            &w,
            &DepthOverrides::new(),
        )
    };
    let pelvis_wrong = |r: &Resolved| {
        (0..frames.len())
            .filter(|&t| (r.points[t][Pelvis] - frames[t][Pelvis]).norm() > 1e-6)
            .count()
    };
    assert_eq!(
        pelvis_wrong(&solve(AmbiguityWeights::default().lookahead)),
        0
    );
    // On every frame the look ahead alone (the least prior of the hips and legs hung from
    // each pelvis root) prefers the true root: its legs need not bend or splay.
    let prior = PosePrior::bundled().unwrap();
    let spine = group_of(Bone::new(Pelvis, Chest));
    for (t, truth) in frames.iter().enumerate() {
        let costs = [0, 1].map(|combo| {
            let q = placed(spine, combo, truth, &rays[t], &subject);
            let cost = hanging_cost(&q, &rays[t], &TrunkFrame::of(truth), &subject, prior);
            ((q[Pelvis] - truth[Pelvis]).norm() < 1e-6, cost)
        });
        let (right, wrong) = if costs[0].0 {
            (costs[0], costs[1])
        } else {
            (costs[1], costs[0])
        };
        assert!(right.0 && right.1 < wrong.1, "frame {t}: {costs:?}");
    }
}

/// The prior of group `g` on a standing body facing +Z whose `bone` points along `dir`
/// (normalised) from its parent end.
fn prior_along(g: usize, bone: Bone, dir: Vector3<f64>) -> f64 {
    let subject = SubjectModel::default();
    let mut p = standing(&subject, |_| [-Vector3::y(); 4]);
    let (from, to) = lift_order(bone);
    p[to] = p[from] + dir.normalize() * subject.bone_length(bone);
    group_prior(g, &p, &subject)
}

#[test]
fn the_head_bent_back_costs_more_than_bent_forward() {
    let head = |z: f64| prior_along(0, Bone::new(Neck, HeadTop), Vector3::new(0.0, 0.8, z));
    let (forward, back) = (head(0.6), head(-0.6));
    assert!(forward < back, "{forward} {back}");
}

#[test]
fn the_pelvis_hangs_a_little_behind_the_chest() {
    let spine = |z: f64| prior_along(1, Bone::new(Pelvis, Chest), Vector3::new(0.0, -1.0, z));
    // The pelvis 0.15 behind the chest's down direction against 0.05 in front (an upright
    // spine would call the nearer to straight down the better).
    let (behind, in_front) = (spine(-0.15), spine(0.05));
    assert!(behind < in_front, "{behind} {in_front}");
}

#[test]
fn the_head_leans_a_little_forwards() {
    let head = |z: f64| prior_along(0, Bone::new(Neck, HeadTop), Vector3::new(0.0, 1.0, z));
    // The head 0.35 forwards against 0.05 (an upright head would call the nearer to
    // straight up the better).
    let (forward, upright) = (head(0.35), head(0.05));
    assert!(forward < upright, "{forward} {upright}");
}

#[test]
fn an_infinite_unary_is_never_taken() {
    let mut frames: Vec<Vec<Candidate>> = (0..5)
        .map(|_| vec![cand(0.0, 0.0), cand(0.0, 1.0)])
        .collect();
    frames[2][0].unary = f64::INFINITY;
    assert_eq!(viterbi(&frames).0[2], 1);
    assert_eq!(viterbi(&frames[..1]).0[0], 0);
}

/// The network's 3D body steers a bone to the root whose depth step it shares, in
/// proportion to its confidence: sure evidence for the other root on every frame turns the
/// forearm over; evidence at confidence 0 changes nothing.
#[test]
fn the_image_depth_evidence_turns_a_bone_it_is_sure_of() {
    let subject = SubjectModel::default();
    let frames = striding(
        &subject,
        10,
        0.4,
        Vector3::new(0.0, 0.0, 3.0),
        |phase, s| {
            let arm = Vector3::new(0.15 * s, -1.0, 0.1 * phase).normalize();
            let forearm = Vector3::new(0.1 * s, -0.6, 0.7).normalize();
            [arm, forearm, -Vector3::y(), -Vector3::y()]
        },
    );
    let (key, rays, index) = seen(&frames);
    let w = AmbiguityWeights::default();
    let none = DepthOverrides::new();
    let alone = resolve(&key, &rays, &index, &[], &subject, &w, &none);
    let forearm = Bone::new(LeftElbow, LeftWrist);
    // The network's body: the lift's own, but the forearm on its other root.
    let other_body = |sure: f32| -> Vec<Option<NetworkBody>> {
        (0..frames.len())
            .map(|t| {
                let mut p = alone.points[t];
                let roots = bone_roots(
                    &p[LeftElbow],
                    &rays[t][LeftWrist],
                    subject.bone_length(forearm),
                );
                let other = match alone.choices[t][forearm.index()] {
                    Root::Near => Root::Far,
                    Root::Far => Root::Near,
                };
                p.0[LeftWrist.index()] = roots.get(other);
                Some(NetworkBody {
                    points: p.map(|_, q| q.coords),
                    confidence: PerJoint([sure; crate::skeleton::JOINT_COUNT]),
                })
            })
            .collect()
    };
    let apart: Vec<usize> = (0..frames.len())
        .filter(|&t| {
            let r = bone_roots(
                &alone.points[t][LeftElbow],
                &rays[t][LeftWrist],
                subject.bone_length(forearm),
            );
            (r.get(Root::Near) - r.get(Root::Far)).norm() > 0.1
        })
        .collect();
    assert!(apart.len() >= 8, "the roots differ on most frames");
    let sure = resolve(&key, &rays, &index, &other_body(1.0), &subject, &w, &none);
    let turned = apart
        .iter()
        .filter(|&&t| sure.choices[t][forearm.index()] != alone.choices[t][forearm.index()])
        .count();
    assert_eq!(turned, apart.len(), "sure evidence turns the forearm");
    let unsure = resolve(&key, &rays, &index, &other_body(0.0), &subject, &w, &none);
    assert_eq!(
        unsure.choices, alone.choices,
        "confidence 0 changes nothing"
    );
    // It steers and stays out of the reported cost.
    assert_eq!(unsure.group_costs, alone.group_costs);
}

/// With the prior, a bone's margin is the prior's own log-likelihood ratio of its two roots on
/// the frame (the group's other bones free), infinite where the user forced the root; without
/// the prior it is the clip-wide min-marginal, at the prior's exchange rate. The product's
/// unsure margin is ln 19 (the other root keeps a 5 % chance).
#[test]
fn a_margin_is_the_priors_likelihood_ratio_of_the_two_roots() {
    assert!((crate::lift::UNSURE_MARGIN - 19f64.ln()).abs() < 1e-12);
    let subject = SubjectModel::default();
    let frames = striding(&subject, 8, 0.5, Vector3::new(0.0, 0.0, 3.0), |phase, s| {
        let arm = Vector3::new(0.15 * s, -1.0, 0.2 * phase).normalize();
        let forearm = Vector3::new(0.1 * s, -0.7, 0.5).normalize();
        [arm, forearm, -Vector3::y(), -Vector3::y()]
    });
    let (key, rays, index) = seen(&frames);
    let w = AmbiguityWeights::default();
    let forearm = Bone::new(LeftElbow, LeftWrist);
    let forced: DepthOverrides = [((index[3], forearm), Root::Far)].into_iter().collect();
    let r = resolve(&key, &rays, &index, &[], &subject, &w, &forced);
    let prior = PosePrior::bundled().unwrap();
    let arm = &GROUPS[ARM_GROUPS[0]];
    let k = arm.bones.iter().position(|&b| b == forearm).unwrap();
    for (t, p) in r.points.iter().enumerate() {
        let trunk = TrunkFrame::of(p);
        let chosen = usize::from(r.choices[t][arm.bones[0].index()] == Root::Far)
            | usize::from(r.choices[t][forearm.index()] == Root::Far) << 1;
        let nats = |combo: usize| {
            prior.cost(
                arm.prior,
                &placed(ARM_GROUPS[0], combo, p, &rays[t], &subject),
                &trunk,
            )
        };
        let other = (0..4)
            .filter(|&o| root_of(o, k) != root_of(chosen, k))
            .map(nats)
            .fold(f64::INFINITY, f64::min);
        let margin = r.margins[t][forearm.index()];
        if t == 3 {
            assert!(margin.is_infinite());
            assert_eq!(r.choices[t][forearm.index()], Root::Far);
        } else {
            assert!(
                (margin - (other - nats(chosen)).max(0.0)).abs() < 1e-9,
                "frame {t}"
            );
        }
    }
    // Without the prior: the clip-wide margins, finite and not negative but where forced.
    let geometry = AmbiguityWeights {
        pose_prior: 0.0,
        ..w
    };
    let g = resolve(&key, &rays, &index, &[], &subject, &geometry, &forced);
    assert!(g.margins[3][forearm.index()].is_infinite());
    assert!(g.margins.iter().flatten().all(|m| *m >= 0.0));
}
