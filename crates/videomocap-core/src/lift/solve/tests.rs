//! Tests of the parent module.

use super::super::ambiguity::DepthOverrides;
use super::super::calibrate::KeyTriangle;
use super::super::calibrate::{Residuals, calibrate_from};
use super::super::facing::*;
use super::super::key_candidates::*;
use super::super::key_path::{centroid, tilt_m};
use super::super::params::LiftParams;
use super::per_frame::fit_score;
use super::*;
use crate::camera::PinholeCamera;
use crate::formats::Tracks2d;
use crate::skeleton::SubjectModel;
use nalgebra::Vector3;

#[test]
fn the_documented_defaults_are_the_defaults() {
    let json = crate::formats::documented_json("## lift settings");
    // Every setting is written out, each at its default.
    let documented: serde_json::Value = serde_json::from_str(json).unwrap();
    let defaults = serde_json::to_value(LiftParams::default()).unwrap();
    assert_eq!(documented, defaults);
    assert!(LiftParams::default().validate().is_ok());
}

/// The costs measured on the suite's treadmill_raised from the tracker's output (true
/// lengths): the right pose's trunk groups fit far better, but its badly tracked right leg
/// costs more than the whole wrong pose does.
#[test]
fn a_part_lost_under_every_pose_does_not_outvote_the_parts_that_agree() {
    use super::super::ambiguity::GROUP_COUNT;
    let right: (f64, [f64; GROUP_COUNT]) = (0.464, [0.02, 0.02, 0.0, 0.05, 0.16, 2.20, 6.95]);
    let wrong: (f64, [f64; GROUP_COUNT]) = (0.049, [0.08, 0.72, 0.06, 0.09, 0.17, 4.27, 1.55]);
    let sum = |(m, g): (f64, [f64; GROUP_COUNT])| m + g.iter().sum::<f64>();
    assert!(
        sum(right) > sum(wrong),
        "the plain sum picks the wrong pose"
    );
    assert!(fit_score(right.0, &right.1) < fit_score(wrong.0, &wrong.1));
    // Scale-free per part: a part ten times as costly under both poses changes nothing.
    let mut r = right.1;
    let mut w = wrong.1;
    r[6] *= 10.0;
    w[6] *= 10.0;
    let d = fit_score(right.0, &right.1) - fit_score(wrong.0, &wrong.1);
    assert!((fit_score(right.0, &r) - fit_score(wrong.0, &w) - d).abs() < 1e-9);
    // A part that fits exactly counts at the floor, not as minus infinity.
    assert!(fit_score(0.0, &[0.0; GROUP_COUNT]).is_finite());
}

#[test]
fn each_stretch_takes_the_facing_that_explains_the_clip_better() {
    // Twelve frames; on each the pose turned one way (+) and the other (−) both fit, except
    // frames 4 and 8, side-on, where only one does. The chain took + everywhere; the
    // truth is − on frames 5–7 only.
    let pose = |facing: f64| {
        [
            Point3::new(0.18, 0.0, 3.0 + facing),
            Point3::new(-0.18, 0.0, 3.0 - facing),
            Point3::new(0.0, 0.15, 3.0),
        ]
    };
    let candidates: Vec<(Vec<[Point3<f64>; 3]>, bool)> = (0..12)
        .map(|t| {
            if t == 4 || t == 8 {
                (vec![pose(0.0)], true)
            } else {
                (vec![pose(0.1), pose(-0.1)], true)
            }
        })
        .collect();
    let chain: Vec<_> = (0..12)
        .map(|t| {
            if t == 4 || t == 8 {
                pose(0.0)
            } else {
                pose(0.1)
            }
        })
        .collect();
    let truth = |t: usize| {
        if (5..8).contains(&t) {
            -0.1
        } else if t == 4 || t == 8 {
            0.0
        } else {
            0.1
        }
    };
    // The score: how far each frame's facing is from the truth's.
    let score = |key: &[[Point3<f64>; 3]]| {
        key.iter()
            .enumerate()
            .map(|(t, k)| (facing_m(k) / 2.0 - truth(t)).abs())
            .sum::<f64>()
    };
    let out = facing_by_segments(chain.clone(), &candidates, &[], score);
    for (t, k) in out.iter().enumerate() {
        assert!((facing_m(k) / 2.0 - truth(t)).abs() < 1e-12, "frame {t}");
    }
    // A score that prefers the chain leaves it alone.
    let keep = facing_by_segments(chain.clone(), &candidates, &[], |k| {
        k.iter().map(|k| -facing_m(k)).sum::<f64>()
    });
    assert_eq!(keep, chain);
}

#[test]
fn the_pitch_term_keeps_the_chain_on_the_reference_pitch() {
    // Every frame has the true pose (pitch 20 mm) and one tipped the other way (−20 mm),
    // both still: acceleration alone cannot tell them apart, the pitch term can.
    let pose = |tilt: f64| {
        [
            Point3::new(0.18, 0.0, 3.0),
            Point3::new(-0.18, 0.0, 3.0),
            Point3::new(0.0, 0.15, 3.0 + tilt),
        ]
    };
    let candidates = vec![vec![pose(-0.02), pose(0.02)]; 6];
    let chain = smoothest_key_path(&candidates, Some((0.14, 0.02)));
    assert!(chain.iter().all(|k| (tilt_m(k) - 0.02).abs() < 1e-12));
    let chain = smoothest_key_path(&candidates, Some((0.14, -0.02)));
    assert!(chain.iter().all(|k| (tilt_m(k) + 0.02).abs() < 1e-12));
}

#[test]
fn key_poses_behind_the_camera_are_dropped() {
    // A bending trunk seen from the side: the shoulders nearly on top of each other, as on
    // the suite's bend_side, where calibration once landed behind the camera.
    let subject = SubjectModel::default();
    let triangle = KeyTriangle::from_subject(&subject).unwrap();
    let cam = PinholeCamera::centred(600.0, 640, 480);
    let pose =
        nalgebra::Isometry3::new(Vector3::new(-0.4, -0.1, 3.0), Vector3::new(0.3, 1.45, 0.0));
    let front = triangle.points.map(|p| pose * p);
    let image = front.map(|p| cam.project(&p).unwrap());
    // Started near the negated triangle (a half turn in its own plane, then −D), the
    // calibration fits it exactly, behind the camera.
    let start = super::super::calibrate::Pose {
        rotation: pose.rotation.to_rotation_matrix()
            * nalgebra::Rotation3::new(Vector3::new(0.0, 0.0, 3.0)),
        translation: -pose.translation.vector,
    };
    let behind = calibrate_from(&cam, &triangle, &image, start, Residuals::Points);
    let back = triangle.points.map(|p| behind.pose.apply(&p));
    assert!(behind.rms_px < 1e-6, "{}", behind.rms_px);
    assert!(back.iter().all(|p| p.z < 0.0), "{back:?}");
    assert!(!plausible_key(&back, f64::INFINITY));
    assert!(plausible_key(&front, f64::INFINITY));
    assert!(!plausible_key(&front, 2.0));
}

#[test]
fn key_poses_deeper_than_the_trunk_allows_are_dropped() {
    let subject = SubjectModel::default();
    let triangle = KeyTriangle::from_subject(&subject).unwrap();
    let sides = crate::lift::calibrate::KEY_LINES.map(|(i, j)| triangle.side(i, j));
    let cam = PinholeCamera::centred(800.0, 640, 480);
    let pose = nalgebra::Isometry3::new(Vector3::new(0.1, 0.0, 3.0), Vector3::new(0.0, 0.4, 0.0));
    let image = triangle.points.map(|p| cam.project(&(pose * p)).unwrap());
    let tracks = Tracks2d {
        source: crate::formats::SourceInfo {
            path: "test".into(),
            width: 640,
            height: 480,
            fps: 30.0,
            frame_count: 1,
        },
        frames: Vec::new(),
    };
    let job = LiftJob {
        tracks: &tracks,
        camera: cam,
        subject,
        params: LiftParams::default(),
        overrides: DepthOverrides::new(),
    };
    let depth = |k: &[Point3<f64>; 3]| centroid(k).z;
    // Unbounded: the true pose (3 m away) is among the candidates.
    let (all, converged) = key_candidates(&job, &triangle, &sides, &image, f64::INFINITY);
    assert!(converged && all.iter().any(|k| (depth(k) - 3.0).abs() < 0.05));
    // Bounded at 2.9 m: nothing fits, so the closest fit comes back no deeper, flagged.
    let (bounded, converged) = key_candidates(&job, &triangle, &sides, &image, 2.9);
    assert!(!converged);
    assert_eq!(bounded.len(), 1);
    assert!(depth(&bounded[0]) <= 2.9 + 1e-9, "{}", depth(&bounded[0]));
}
