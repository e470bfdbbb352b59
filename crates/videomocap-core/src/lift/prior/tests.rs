use super::*;
use crate::skeleton::{Bone, standing_pose};

/// A body standing at the origin whose limbs swing by `phase` (radians): thighs forward and
/// back, each knee bent backwards by `knee` (radians, negative: forwards), arms against the legs.
fn walking(phase: f64, knee: f64) -> PerJoint<Point3<f64>> {
    let length = |b: Bone| match (b.parent, b.child) {
        (Pelvis, LeftHip | RightHip) => 0.09,
        (Chest, LeftShoulder | RightShoulder) => 0.2,
        _ => 0.3,
    };
    standing_pose(length, 0.36, Point3::origin(), |sign| {
        let swing = 0.4
            * (phase
                + if sign > 0.0 {
                    0.0
                } else {
                    std::f64::consts::PI
                })
            .sin();
        let thigh = Vector3::new(0.0, -swing.cos(), swing.sin());
        let bend = swing.min(0.0) - knee.abs() * knee.signum();
        let shank = Vector3::new(0.0, -(bend).cos(), (bend).sin());
        let arm = Vector3::new(0.1, -swing.cos(), -swing.sin()).normalize();
        [arm, arm, thigh, shank]
    })
}

fn learned() -> PosePrior {
    let poses: Vec<_> = (0..400)
        .map(|i| walking(i as f64 * 0.1, 0.2 + 0.1 * (i as f64 * 0.37).sin()))
        .collect();
    let file = learn(&poses, 4, vec!["synthetic".to_owned()], String::new()).unwrap();
    PosePrior::from_file(file).unwrap()
}

/// Learned from walking with knees that bend backwards, the prior prefers such a knee to its
/// mirror, bent forwards, and flags a pose it never saw without refusing it (finite cost).
#[test]
fn a_prior_learned_from_walking_prefers_knees_bent_backwards() {
    let prior = learned();
    let up = Vector3::y();
    let ordinary = walking(0.3, 0.3);
    let odd = walking(0.3, -0.6);
    let key = TrunkFrame::of(&ordinary);
    let leg = PriorGroup::Leg(Side::Left);
    // The odd knee pays beyond where unusual poses begin, the ordinary one below it. (Not a
    // fixed number of nats more: these 400 near-identical learned poses put the leg's ceiling
    // at its least, 2 nats, and every cost stays under it.)
    let model = &prior.models[leg.model()];
    let (a, b) = (
        prior.cost(leg, &ordinary, &key),
        prior.cost(leg, &odd, &key),
    );
    assert!(
        a < model.unusual && model.unusual < b && a + 1.0 < b,
        "{a} {b}"
    );
    assert!(!prior.is_unusual(&ordinary, &up));
    // An arm raised straight up and a leg bent forwards: never seen, but still a finite cost.
    let mut contorted = walking(0.3, -1.2);
    contorted[LeftWrist] = contorted[LeftShoulder] + Vector3::new(0.0, 0.6, 0.0);
    contorted[LeftElbow] = contorted[LeftShoulder] + Vector3::new(0.0, 0.3, 0.0);
    let cost = prior.pose_cost(&contorted);
    assert!(
        cost.is_finite() && cost > prior.pose_cost(&ordinary),
        "{cost}"
    );
    assert!(prior.is_unusual(&contorted, &up));
}

/// Upside down, an ordinary pose costs what it costs upright (the groups live in the body's
/// own frames), and only its stance against gravity makes it unusual.
#[test]
fn a_body_upside_down_is_unusual_only_for_its_stance() {
    let prior = learned();
    let up = Vector3::y();
    let upright = walking(0.7, 0.25);
    let turn = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI);
    let turned = upright.map(|_, p| turn * p);
    let (a, b) = (prior.pose_cost(&upright), prior.pose_cost(&turned));
    assert!((a - b).abs() < 1e-6 * (1.0 + a), "{a} {b}");
    assert!(!prior.is_unusual(&upright, &up));
    assert!(prior.is_unusual(&turned, &up));
}

/// The learned pose and its mirror image cost the same: the prior has no favourite side.
#[test]
fn a_mirrored_pose_costs_what_the_pose_costs() {
    let prior = learned();
    let p = walking(1.1, 0.25);
    let a = prior.pose_cost(&p);
    let b = prior.pose_cost(&mirror_pose(&p));
    assert!((a - b).abs() < 1e-6 * (1.0 + a.abs()), "{a} {b}");
}

/// A file that is not a prior, or is missing, is refused by its name; the bundled one reads.
#[test]
fn a_corrupt_or_missing_prior_is_refused_by_name() {
    let path = Path::new("somewhere/prior.json");
    let e = PosePrior::parse("{\"format\": 3}", path).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("somewhere/prior.json: not a usable pose prior")
    );
    let mut file = learn(&[walking(0.0, 0.2)], 1, Vec::new(), String::new()).unwrap();
    file.groups.retain(|g| g.name != "arm");
    let text = serde_json::to_string(&file).unwrap();
    let e = PosePrior::parse(&text, path).unwrap_err();
    assert!(e.to_string().contains("no group \"arm\""), "{e}");
    let missing = Path::new("/nonexistent/pose_prior.json");
    let e = PosePrior::load(missing).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/nonexistent/pose_prior.json: cannot read")
    );
    assert!(PosePrior::bundled().is_ok());
}

/// The bundled prior's mixtures give the same log density, to the bit, with the components far
/// below the best left out as with every component summed, at their means, between them and
/// far from all of them (directions drawn by a fixed sequence).
#[test]
fn leaving_out_negligible_components_changes_no_bit() {
    let prior = PosePrior::bundled().unwrap();
    let mut state: u64 = 7;
    let mut draw = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut pruned = 0;
    for model in &prior.models {
        let gmm = &model.gmm;
        let means: Vec<Vec<f64>> = gmm.components.iter().map(|c| c.mean.clone()).collect();
        for i in 0..200 {
            let x: Vec<f64> = match i % 3 {
                0 => means[i % means.len()].clone(),
                1 => (0..gmm.dims)
                    .map(|d| 0.5 * (means[0][d] + means[i % means.len()][d]) + 0.05 * draw())
                    .collect(),
                _ => (0..gmm.dims).map(|_| draw()).collect(),
            };
            let (fast, full) = (gmm.log_density(&x), gmm.log_density_full(&x));
            assert_eq!(
                fast.to_bits(),
                full.to_bits(),
                "{x:?}: {fast} against {full}"
            );
            // Whether this point exercises the leaving out at all.
            let best = gmm.terms(&x).fold(f64::NEG_INFINITY, f64::max);
            pruned += usize::from(gmm.terms(&x).any(|t| t < best - 40.0));
        }
    }
    assert!(pruned > 100, "{pruned} points with a negligible component");
}
