//! What the lift reports on sequences built from the skeleton model itself: its flags, and bad
//! input refused with a reason or carried through.

mod lift_support;

use lift_support::{job_for, truth};
use std::sync::atomic::AtomicBool;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::formats::{FrameIndex, NetworkBody, Tracks2d};
use videomocap_core::lift::{
    DepthOverrides, FrameFlag, LiftError, LiftJob, LiftParams, lift, lift_per_frame,
};
use videomocap_core::skeleton::{Bone, Joint, PerJoint};
use videomocap_testkit::eval::pose3d::{score_skeleton, tracks_from_truth};

/// The (frame, bone) pairs flagged too long in `reports`.
fn too_long_flags(reports: &[videomocap_core::lift::FrameReport]) -> Vec<(FrameIndex, Bone)> {
    reports
        .iter()
        .flat_map(|r| {
            r.flags.iter().filter_map(move |f| match f {
                FrameFlag::TooLong(b) => Some((r.index, *b)),
                _ => None,
            })
        })
        .collect()
}

#[test]
fn a_bone_is_flagged_too_long_only_where_its_image_is_beyond_noise_and_length_doubt() {
    // Limbs 3 % short of the truth: every frame where one lies square to the camera has its
    // image a little too long, which says nothing about the tracks.
    let (gt, truth) = truth();
    let mut short = truth.clone();
    for b in Bone::ALL {
        if ![Joint::Pelvis, Joint::Chest].contains(&b.parent) {
            short.bone_length_m[b.index()] *= 0.97;
        }
    }
    let mut tracks = tracks_from_truth(&gt, 0.0, 3);
    let too_long = |tracks: &Tracks2d| {
        let job = job_for(tracks, &short, LiftParams::default());
        too_long_flags(&lift_per_frame(&job).unwrap().reports)
    };
    let quiet = too_long(&tracks);
    assert!(quiet.is_empty(), "{quiet:?}");
    // A wrist the tracker threw 40 px off its forearm on one frame: named there.
    let forearm = Bone::new(Joint::LeftElbow, Joint::LeftWrist);
    let p = &mut tracks.frames[30].points[Joint::LeftWrist].pos;
    let away =
        (*p - nalgebra::Point2::from(gt.frames[30].points2d[Joint::LeftElbow.index()])).normalize();
    *p += away * 40.0;
    let flagged = too_long(&tracks);
    assert!(flagged.contains(&(FrameIndex(30), forearm)), "{flagged:?}");
    // Lengths read with a doubt are solved that much shorter (leaning square to their rays):
    // the miss that leaning makes is not flagged, the thrown wrist still is.
    let mut doubtful = truth.clone();
    for b in Bone::ALL {
        if ![Joint::Pelvis, Joint::Chest].contains(&b.parent) {
            doubtful.length_doubt[b.index()] = 0.05;
        }
    }
    let flags_of = |tracks: &Tracks2d| {
        let job = job_for(tracks, &doubtful, LiftParams::default());
        too_long_flags(
            &lift(&job, &mut |_| {}, &AtomicBool::new(false))
                .unwrap()
                .reports,
        )
    };
    let exact = tracks_from_truth(&gt, 0.0, 3);
    let quiet = flags_of(&exact);
    assert!(quiet.is_empty(), "{quiet:?}");
    // After the refinement a forearm can turn to follow a throw it can reach; one thrown
    // farther than it could ever reach from its elbow is still named.
    let elbow = nalgebra::Point2::from(gt.frames[30].points2d[Joint::LeftElbow.index()]);
    let reach = (tracks.frames[30].points[Joint::LeftWrist].pos - elbow).norm();
    tracks.frames[30].points[Joint::LeftWrist].pos += away * reach;
    let flagged = flags_of(&tracks);
    assert!(flagged.contains(&(FrameIndex(30), forearm)), "{flagged:?}");
}

#[test]
fn bad_tracks_are_refused_with_a_reason() {
    let (gt, subject) = truth();
    let tracks = tracks_from_truth(&gt, 0.0, 3);
    let job = |tracks, focal| LiftJob {
        tracks,
        camera: PinholeCamera::centred(focal, 640, 480),
        subject: subject.clone(),
        params: LiftParams::default(),
        overrides: DepthOverrides::new(),
    };
    assert!(matches!(
        lift_per_frame(&job(&tracks, 0.0)),
        Err(LiftError::BadFocal(_))
    ));
    assert!(matches!(
        lift_per_frame(&job(&tracks, f64::NAN)),
        Err(LiftError::BadFocal(_))
    ));
    // One frame lifts.
    let mut one = tracks.clone();
    one.frames.truncate(1);
    let out = lift(&job(&one, 700.0), &mut |_| {}, &AtomicBool::new(false)).unwrap();
    assert_eq!(out.skeleton.frames.len(), 1);
    // No frames.
    let mut none = tracks.clone();
    none.frames.clear();
    assert!(matches!(
        lift_per_frame(&job(&none, 700.0)),
        Err(LiftError::NoFrames)
    ));
    // Shoulders on top of each other in every frame.
    let mut flat = tracks.clone();
    for f in &mut flat.frames {
        f.points.0[Joint::RightShoulder.index()] = f.points[Joint::LeftShoulder];
    }
    let e = lift_per_frame(&job(&flat, 700.0)).unwrap_err();
    assert!(matches!(e, LiftError::DegenerateKeyTriangle), "{e}");
    assert!(e.to_string().contains("shoulders"));
    // A NaN is named with its frame and joint.
    let mut broken = tracks.clone();
    broken.frames[7].points.0[Joint::LeftKnee.index()].pos.x = f64::NAN;
    let e = lift_per_frame(&job(&broken, 700.0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("frame 7") && e.contains("left_knee"), "{e}");
    // Settings out of their range are named (a negative weight would reward what its prior
    // forbids, a zero deviation divides by zero); a zero weight or anchor turns a term off.
    let with = |params: LiftParams| LiftJob {
        params,
        ..job(&tracks, 700.0)
    };
    let params = LiftParams {
        arm_swing: -5.0,
        ..LiftParams::default()
    };
    let e = lift_per_frame(&with(params)).unwrap_err().to_string();
    assert!(e.contains("arm_swing") && e.contains("-5"), "{e}");
    let params = LiftParams {
        image_depth: f64::INFINITY,
        ..LiftParams::default()
    };
    let e = lift(&with(params), &mut |_| {}, &AtomicBool::new(false)).unwrap_err();
    assert!(
        matches!(
            e,
            LiftError::BadSetting {
                name: "image_depth",
                ..
            }
        ),
        "{e}"
    );
    let params = LiftParams {
        smoothing_s: f64::NAN,
        ..LiftParams::default()
    };
    assert!(lift_per_frame(&with(params)).is_err());
    let params = LiftParams {
        hands_outside_body: 0.0,
        image_depth: 0.0,
        ..LiftParams::default()
    };
    assert!(params.validate().is_ok());
}

#[test]
fn frames_the_network_saw_no_body_on_are_lifted_and_flagged() {
    // The network's body (the truth about the pelvis, fully sure) on every frame but 20–25.
    let (gt, subject) = truth();
    let mut tracks = tracks_from_truth(&gt, 0.0, 3);
    for (f, g) in tracks.frames.iter_mut().zip(&gt.frames) {
        let p = g.points3d();
        f.body3d = Some(Box::new(NetworkBody {
            points: PerJoint::from_fn(|j| p[j] - p[Joint::Pelvis]),
            confidence: PerJoint::from_fn(|_| 0.9),
        }));
    }
    let gap = 20..26;
    for f in &mut tracks.frames[gap.clone()] {
        f.body3d = None;
    }
    let no_body = |tracks: &Tracks2d, image_depth: f64| {
        let params = LiftParams {
            image_depth,
            ..LiftParams::default()
        };
        let out = lift(
            &job_for(tracks, &subject, params),
            &mut |_| {},
            &AtomicBool::new(false),
        )
        .unwrap();
        let flagged: Vec<usize> = out
            .reports
            .iter()
            .filter(|r| r.flags.contains(&FrameFlag::NoImageDepth))
            .map(|r| r.index.get())
            .collect();
        // The skeleton file carries the flag by name.
        let named = out
            .skeleton
            .frames
            .iter()
            .filter(|f| f.flags.iter().any(|s| s == "no_image_depth"))
            .count();
        assert_eq!(named, flagged.len());
        (
            flagged,
            score_skeleton(&gt, &out.skeleton).unwrap().mpjpe_mm(),
        )
    };
    let (flagged, mm) = no_body(&tracks, LiftParams::default().image_depth);
    assert_eq!(flagged, gap.clone().collect::<Vec<_>>());
    assert!(mm < 60.0, "{mm:.1} mm");
    // The evidence turned off, or no body anywhere (the network not run): nothing to flag.
    assert!(no_body(&tracks, 0.0).0.is_empty());
    let mut without = tracks.clone();
    without.frames.iter_mut().for_each(|f| f.body3d = None);
    assert!(
        no_body(&without, LiftParams::default().image_depth)
            .0
            .is_empty()
    );
}
