use super::super::least_squares::assert_rows_match_finite_differences;
use super::*;

#[test]
fn the_adaptive_acceleration_term_is_firmer_for_noisier_tracks() {
    let params = RefineParams::default();
    let dt = 1.0 / 30.0;
    let exact = acceleration_sigma_m(0.0, &params, dt);
    let half = acceleration_sigma_m(0.5, &params, dt);
    let noisy = acceleration_sigma_m(2.0, &params, dt);
    let very = acceleration_sigma_m(8.0, &params, dt);
    assert!(exact > half && half > noisy, "{exact} {half} {noisy}");
    assert!((exact - 600.0 * dt * dt).abs() < 1e-9, "{exact}");
    assert!(
        (very - MIN_ACCELERATION_MPS2 * dt * dt).abs() < 1e-12,
        "{very}"
    );
    let fixed = RefineParams {
        adaptive: false,
        ..params
    };
    assert_eq!(acceleration_sigma_m(2.0, &fixed, dt), 100.0 * dt * dt);
}

#[test]
fn snapping_puts_every_bone_at_its_length_along_its_direction() {
    let free: PerJoint<Point3<f64>> = PerJoint::from_fn(|j| {
        let i = j.index() as f64;
        Point3::new(0.07 * i - 0.5, 0.11 * i - 0.9, 3.0 + 0.03 * (i * i).sin())
    });
    let mut fallback = free;
    fallback[Joint::LeftWrist] = free[Joint::LeftElbow] + Vector3::new(0.0, 0.0, 0.3);
    let mut free = free;
    // A forearm shrunk to nothing takes the per-frame solve's direction.
    free[Joint::LeftWrist] = free[Joint::LeftElbow];
    let lengths: [f64; BONE_COUNT] = std::array::from_fn(|k| 0.2 + 0.01 * k as f64);
    let snapped = snap_to_lengths(&free, &fallback, &lengths);
    assert_eq!(snapped[Joint::Pelvis], free[Joint::Pelvis]);
    for (b, &len) in Bone::ALL.iter().zip(&lengths) {
        let d = snapped[b.child] - snapped[b.parent];
        assert!((d.norm() - len).abs() < 1e-12, "{}", b.key());
        let want = if b.child == Joint::LeftWrist {
            Vector3::z()
        } else {
            (free[b.child] - free[b.parent]).normalize()
        };
        assert!((d.normalize() - want).norm() < 1e-12, "{}", b.key());
    }
}

/// Central finite differences of every residual against the analytic rows.
#[test]
fn analytic_rows_match_finite_differences() {
    let cam = PinholeCamera::centred(800.0, 640, 480);
    let subject = SubjectModel::default();
    let n = 4;
    let start: Vec<PerJoint<Point3<f64>>> = (0..n)
        .map(|t| {
            PerJoint::from_fn(|j| {
                let i = j.index() as f64;
                Point3::new(
                    0.05 * i - 0.3 + 0.01 * t as f64,
                    0.1 * i - 0.8,
                    3.0 + 0.02 * i,
                )
            })
        })
        .collect();
    let images: Vec<PerJoint<Point2<f64>>> = start
        .iter()
        .map(|f| f.map(|_, p| cam.project(p).unwrap() + nalgebra::Vector2::new(1.5, -0.5)))
        .collect();
    let weights = vec![PerJoint::from_fn(|j| 0.3 + 0.04 * j.index() as f64); n];
    // The network's body, turned a little from the start, on every frame but the second.
    let bodies: Vec<Option<NetworkBody>> = (0..n)
        .map(|t| {
            (t != 1).then(|| NetworkBody {
                points: start[t]
                    .map(|j, p| p.coords + Vector3::new(0.0, 0.0, 0.03 * (j.index() % 3) as f64)),
                confidence: PerJoint::from_fn(|j| 0.4 + 0.05 * j.index() as f32),
            })
        })
        .collect();
    let start_lengths = subject_lengths(&subject);
    let problem = Problem {
        cam: &cam,
        images: &images,
        weights: &weights,
        start: &start,
        start_lengths,
        params: RefineParams::default(),
        accel_sigma_m: 20.0 / 900.0,
        directions: network_directions(&start, &bodies),
    };
    let x = Problem::pack(&start, &start_lengths.map(|l| l * 1.05));
    assert_rows_match_finite_differences(&problem, &x);
}
