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
