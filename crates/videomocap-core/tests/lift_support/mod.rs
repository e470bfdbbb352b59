//! The walking-like test sequence the lift's integration tests share, built from the skeleton
//! model itself (rigid key triangle, constant bone lengths), where the answer is known exactly.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic
#![allow(dead_code)] // each test crate uses its own share of these

use nalgebra::{Point3, Rotation3, Vector3};
use std::sync::atomic::AtomicBool;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::formats::Tracks2d;
use videomocap_core::lift::{DepthOverrides, KeyTriangle, LiftJob, LiftOutput, LiftParams, lift};
use videomocap_core::skeleton::{Bone, Joint, PerJoint, SubjectModel};
use videomocap_testkit::eval::pose3d::tracks_from_truth;
use videomocap_testkit::synth::{GroundTruth, GroundTruthFrame};

pub(crate) const FRAMES: usize = 60;

pub(crate) fn camera() -> PinholeCamera {
    PinholeCamera::centred(700.0, 640, 480)
}

/// A lift of `tracks` through [`camera`], with no forced roots.
pub(crate) fn job_for<'a>(
    tracks: &'a Tracks2d,
    subject: &SubjectModel,
    params: LiftParams,
) -> LiftJob<'a> {
    LiftJob {
        tracks,
        camera: camera(),
        subject: subject.clone(),
        params,
        overrides: DepthOverrides::new(),
    }
}

/// A walking-like sequence of the default subject, turning slowly in front of the camera.
pub(crate) fn truth() -> (GroundTruth, SubjectModel) {
    truth_of(SubjectModel::default())
}

/// The walking-like sequence of subject `s`.
pub(crate) fn truth_of(s: SubjectModel) -> (GroundTruth, SubjectModel) {
    use Joint::*;
    let tri = KeyTriangle::from_subject(&s).unwrap();
    // The bone joining two joints, whichever way the model's tree runs.
    let len = |a: Joint, b: Joint| {
        let bone = if Bone::ALL.contains(&Bone::new(a, b)) {
            Bone::new(a, b)
        } else {
            Bone::new(b, a)
        };
        s.bone_length(bone)
    };
    let cam = camera();
    let mut frames = Vec::new();
    for t in 0..FRAMES {
        let phase = t as f64 / 30.0 * std::f64::consts::TAU;
        let r = Rotation3::from_axis_angle(&Vector3::y_axis(), 0.5 * (phase / 2.0).sin() + 0.4)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), 0.1);
        let d = Vector3::new(0.4 * t as f64 / FRAMES as f64 - 0.2, -0.35, 4.0);
        let mut p = PerJoint::from_fn(|_| Point3::origin());
        p.0[LeftShoulder.index()] = r * tri.points[0] + d;
        p.0[RightShoulder.index()] = r * tri.points[1] + d;
        p.0[Chest.index()] = r * tri.points[2] + d;
        let left = r * Vector3::x();
        let up = r * -Vector3::y();
        let fwd = left.cross(&up);
        let mut put = |a: Joint, b: Joint, dir: Vector3<f64>| {
            p.0[b.index()] = p[a] + dir.normalize() * len(a, b);
        };
        put(Chest, Neck, up + fwd * 0.1);
        put(Neck, HeadTop, up);
        put(Chest, Pelvis, -up + fwd * 0.05);
        put(Pelvis, LeftHip, left);
        put(Pelvis, RightHip, -left);
        for (side, sign, shoulder, elbow, wrist, hip, knee, ankle) in [
            (
                0.0,
                1.0,
                LeftShoulder,
                LeftElbow,
                LeftWrist,
                LeftHip,
                LeftKnee,
                LeftAnkle,
            ),
            (
                std::f64::consts::PI,
                -1.0,
                RightShoulder,
                RightElbow,
                RightWrist,
                RightHip,
                RightKnee,
                RightAnkle,
            ),
        ] {
            let swing = (phase + side).sin();
            put(
                shoulder,
                elbow,
                -up - fwd * (0.5 * swing) + left * (0.15 * sign),
            );
            // The forearm leads the upper arm forwards by 0.2–0.6 (an elbow does not bend
            // backwards; before 2026-11-23 it trailed by up to 0.4 here, 21° of overextension).
            put(elbow, wrist, -up + fwd * (0.4 - 0.3 * swing));
            put(hip, knee, -up + fwd * (0.45 * swing));
            put(
                knee,
                ankle,
                -up - fwd * (0.25 * (1.0 + (phase + side + 1.0).sin())),
            );
        }
        frames.push(GroundTruthFrame {
            index: t,
            points2d: p
                .0
                .iter()
                .map(|q| {
                    let u = cam.project(q).unwrap();
                    [u.x, u.y]
                })
                .collect(),
            points3d: p.0.iter().map(|q| [q.x, q.y, q.z]).collect(),
            visible: vec![true; 16],
        });
    }
    let gt = GroundTruth {
        source: "tests/lift.rs".into(),
        fps: 30.0,
        width: cam.width,
        height: cam.height,
        focal_px: cam.focal_px,
        cx: cam.cx,
        cy: cam.cy,
        joints: Joint::ALL.iter().map(|j| j.name().to_owned()).collect(),
        stated_height_m: None,
        derived_joints: vec![],
        bone_lengths_m: Default::default(),
        frames,
    };
    (gt, s)
}

pub(crate) fn run(
    gt: &GroundTruth,
    subject: &SubjectModel,
    noise: f64,
    refine: bool,
) -> LiftOutput {
    let tracks = tracks_from_truth(gt, noise, 3);
    let params = LiftParams {
        refine,
        // Exact tracks: no temporal smoothing, so the geometry must be exact; noisy ones get
        // the adaptive smoothing of the default settings.
        smooth_tracks: noise > 0.0,
        ..LiftParams::default()
    };
    let job = job_for(&tracks, subject, params);
    lift(&job, &mut |_| {}, &AtomicBool::new(false)).unwrap()
}
