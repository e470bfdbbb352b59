//! The 3D reconstruction on sequences built from the skeleton model itself (rigid key triangle,
//! constant bone lengths), where the answer is known exactly.

mod lift_support;

use lift_support::{FRAMES, camera, job_for, run, truth, truth_of};
use nalgebra::Point3;
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::KnownLengths;
use videomocap_core::formats::{FrameIndex, UNUSUAL_POSE_FLAG};
use videomocap_core::lift::AmbiguityWeights;
use videomocap_core::lift::bone_roots;
use videomocap_core::lift::lift_order;
use videomocap_core::lift::subject_from_height;
use videomocap_core::lift::{
    CameraChoice, DepthOverrides, FocalSource, LiftError, LiftJob, LiftParams, LiftStage, Root,
    SubjectChoice, lift, lift_per_frame, reconstruct,
};
use videomocap_core::skeleton::{Bone, Joint, SubjectModel};
use videomocap_testkit::eval::pose3d::{
    key_triangle_flex_m, lift_on_reference_key, score_skeleton, tracks_from_truth,
};

#[test]
fn exact_tracks_give_back_the_skeleton() {
    let (gt, subject) = truth();
    let out = run(&gt, &subject, 0.0, false);
    let cam = camera();
    let mut flagged = 0;
    for (f, g) in out.per_frame.frames.iter().zip(&gt.frames) {
        let truth = g.points3d();
        // The key triangle is exact (eqs. 6–11 with exact inputs).
        for j in [Joint::LeftShoulder, Joint::RightShoulder, Joint::Chest] {
            assert!(
                (f.points[j] - truth[j]).norm() < 1e-6,
                "frame {} {j}",
                f.index
            );
        }
        // Every joint is at its bone's length from its parent and, unless flagged, on its ray.
        for b in Bone::ALL {
            let l = (f.points[b.child] - f.points[b.parent]).norm();
            assert!((l - subject.bone_length(b)).abs() < 1e-9);
        }
        if !f.flags.is_empty() {
            flagged += 1;
            continue;
        }
        // Unflagged, a joint misses its ray by no more than the flag lets pass: 5 % of its
        // bone's image length and half a pixel (exact tracks have no noise).
        for (j, p) in f.points.iter() {
            let image = |j: Joint| nalgebra::Point2::from(g.points2d[j.index()]);
            let e = (cam.project(p).unwrap() - image(j)).norm();
            let allowed = Bone::to(j).map_or(0.0, |b| {
                let parent = f.points[b.parent];
                0.05 * cam.focal_px * subject.bone_length(b) / parent.z
            }) + 0.5;
            assert!(e < allowed + 1e-6, "frame {} {j}: {e} px", f.index);
        }
    }
    // The roots are chosen without knowing the truth: this clip turns and swings its legs
    // towards the camera, the hardest case for a single view. Measured: 6 of 60 frames with a
    // joint off its ray (after a wrong parent root), MPJPE 28.7 mm, 8.3 % of roots wrong.
    let s = score_skeleton(&gt, &out.per_frame).unwrap();
    assert!(flagged <= 15, "{flagged} flagged frames");
    assert!(s.mpjpe_mm() < 60.0, "MPJPE {:.1} mm", s.mpjpe_mm());
    assert!(s.wrong_share() < 0.2, "wrong roots {:.3}", s.wrong_share());
}

#[test]
fn with_the_true_roots_exact_tracks_give_back_every_joint() {
    let (gt, subject) = truth();
    let tracks = tracks_from_truth(&gt, 0.0, 3);
    let cam = camera();
    // The root each bone takes in the truth, given as the user's choices.
    let mut overrides = DepthOverrides::new();
    for (t, f) in gt.frames.iter().enumerate() {
        let p = f.points3d();
        for bone in Bone::ALL {
            let (known, solved) = lift_order(bone);
            if matches!(solved, Joint::LeftShoulder | Joint::RightShoulder) {
                continue;
            }
            let ray = cam.ray(&nalgebra::Point2::from(f.points2d[solved.index()]));
            let roots = bone_roots(&p[known], &ray, subject.bone_length(bone));
            let root = if (roots.near - p[solved]).norm() <= (roots.far - p[solved]).norm() {
                Root::Near
            } else {
                Root::Far
            };
            overrides.insert((FrameIndex(t), bone), root);
        }
    }
    let job = LiftJob {
        tracks: &tracks,
        camera: cam,
        subject,
        // The geometry alone: the foot lock holds a slow foot at one depth, which the truth's
        // feet are only nearly.
        params: LiftParams {
            refine: false,
            smooth_tracks: false,
            foot_lock: false,
            ..LiftParams::default()
        },
        overrides,
    };
    let out = lift(&job, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    for (f, g) in out.skeleton.frames.iter().zip(&gt.frames) {
        let truth = g.points3d();
        for (j, p) in f.points.iter() {
            assert!((p - truth[j]).norm() < 1e-6, "frame {} {j}", f.index);
        }
        // Nothing wrong with the lift; the pose prior may find this procedural walk's pose
        // unusual on a frame, which is a statement about the pose.
        assert!(
            f.flags.iter().all(|s| s == UNUSUAL_POSE_FLAG),
            "{:?}",
            f.flags
        );
    }
}

#[test]
fn a_flipped_limb_stays_flipped_and_the_rest_is_resolved_again() {
    let (gt, subject) = truth();
    let tracks = tracks_from_truth(&gt, 0.0, 3);
    let mut job = LiftJob {
        tracks: &tracks,
        camera: camera(),
        subject,
        params: LiftParams::default(),
        overrides: DepthOverrides::new(),
    };
    let before = lift_per_frame(&job).unwrap();
    let bone = Bone::new(Joint::LeftHip, Joint::LeftKnee);
    let t = 8;
    let chosen = before.resolved.choices[t][bone.index()];
    job.overrides
        .insert((FrameIndex(t), bone), chosen.flipped());
    let after = lift_per_frame(&job).unwrap();
    assert_eq!(after.resolved.choices[t][bone.index()], chosen.flipped());
    assert_ne!(
        after.resolved.points[t][Joint::LeftKnee],
        before.resolved.points[t][Joint::LeftKnee]
    );
    // Bones of other limbs keep their choices.
    let arm = Bone::new(Joint::RightShoulder, Joint::RightElbow);
    assert_eq!(
        after.resolved.choices[t][arm.index()],
        before.resolved.choices[t][arm.index()]
    );
}

#[test]
fn the_refinement_lowers_its_cost_and_keeps_every_bone_at_its_length() {
    // The refined lengths stay within the length prior of the subject's (1 %: 5 % allowed),
    // and every frame's bones are snapped to them exactly, so the BVH reads back exactly.
    let (gt, subject) = truth();
    let out = run(&gt, &subject, 2.0, true);
    let r = out.refinement.expect("refinement ran");
    assert!(r.cost_after < r.cost_before, "{r:?}");
    assert_eq!(out.skeleton.frames.len(), FRAMES);
    for b in Bone::ALL {
        let l = out.skeleton.bone_lengths_m[&b.key()];
        let l0 = subject.bone_length(b);
        assert!((l - l0).abs() < 0.05 * l0, "{}: {l} vs {l0}", b.key());
        for f in &out.skeleton.frames {
            let d = (f.points[b.child] - f.points[b.parent]).norm();
            assert!(
                (d - l).abs() < 1e-9,
                "frame {} {}: {d} vs {l}",
                f.index,
                b.key()
            );
        }
    }
}

#[test]
fn the_refinement_leaves_exact_tracks_nearly_alone() {
    // The tracks read almost no noise, so the acceleration term barely pulls. Measured here:
    // 41.3 → 40.4 mm; the fixed 100 m/s² of the non-adaptive setting gave 41.3 → 45.8 mm.
    let (gt, subject) = truth();
    let out = run(&gt, &subject, 0.0, true);
    let per_frame = score_skeleton(&gt, &out.per_frame).unwrap().mpjpe_mm();
    let refined = score_skeleton(&gt, &out.skeleton).unwrap().mpjpe_mm();
    assert!(refined < per_frame + 1.0, "{per_frame} → {refined} mm");
}

/// A wrist the tracker put too far out for its forearm: the per-frame solve keeps the forearm's
/// length and leaves the wrist off its ray. Fitting the refinement to that point tilted the
/// whole trunk (jumping jacks on the suite: shoulders 7 → 57 mm); the anchor to the per-frame
/// solve keeps the trunk near where the trunk's own points put it (measured here: shoulders,
/// chest and neck 1.1 mm per frame, 8.8 mm refined without the anchor, 1.6 mm with it; the
/// anchor is a fitted constant since the settings were cut to eight, so the test holds the
/// refined trunk to the per-frame one; the head top is left out: its root is a choice, and
/// `HEAD_FORWARD` tips this body's upright head forwards on some frames).
#[test]
fn a_wrist_out_of_reach_does_not_tilt_the_trunk_in_the_refinement() {
    use Joint::*;
    let (gt, subject) = truth();
    let mut tracks = tracks_from_truth(&gt, 0.0, 3);
    for f in &mut tracks.frames {
        let (elbow, wrist) = (f.points[LeftElbow].pos, f.points[LeftWrist].pos);
        f.points[LeftWrist].pos = wrist + (wrist - elbow) * 0.6;
    }
    let trunk_error = || {
        let job = LiftJob {
            tracks: &tracks,
            camera: camera(),
            subject: subject.clone(),
            params: LiftParams {
                refine: true,
                smooth_tracks: false,
                ..LiftParams::default()
            },
            overrides: DepthOverrides::new(),
        };
        let out = lift(&job, &mut |_| {}, &AtomicBool::new(false)).unwrap();
        let error = |s: &videomocap_core::formats::Skeleton3d| {
            let mut sum = 0.0;
            for f in &s.frames {
                let t = gt.frames[f.index.get()].points3d();
                for j in [LeftShoulder, RightShoulder, Chest, Neck] {
                    sum += ((f.points[j] - f.points[Pelvis]) - (t[j] - t[Pelvis])).norm();
                }
            }
            1000.0 * sum / (4 * s.frames.len()) as f64
        };
        (error(&out.per_frame), error(&out.skeleton))
    };
    let (per_frame, anchored) = trunk_error();
    assert!(
        anchored < per_frame + 2.0,
        "trunk {per_frame:.1} mm per frame; refined {anchored:.1} mm (8.8 without the anchor)"
    );
}

#[test]
fn a_subject_fitted_to_the_tracks_beats_the_table_for_a_different_build() {
    // The real sample's subject carries the chest 0.335 of the trunk below the shoulder line,
    // the table 0.255: build such a subject, keep the table's other lengths, and lift it from
    // its height alone, with the table and with the subject fitted to the tracks.
    let table = SubjectModel::default();
    let trunk = table.bone_length(Bone::new(Joint::Chest, Joint::Neck))
        + table.bone_length(Bone::new(Joint::Pelvis, Joint::Chest));
    let mut built = table.clone();
    let half = table.shoulder_width_m / 2.0;
    let side = ((0.335 * trunk).powi(2) + half * half).sqrt();
    built.bone_length_m[Bone::new(Joint::Chest, Joint::LeftShoulder).index()] = side;
    built.bone_length_m[Bone::new(Joint::Chest, Joint::RightShoulder).index()] = side;
    let (gt, built) = truth_of(built);
    let tracks = tracks_from_truth(&gt, 0.0, 3);
    let (fitted, fit) = subject_from_height(
        table.height_m,
        &tracks,
        gt.camera(),
        &LiftParams::default(),
        &Default::default(),
    )
    .unwrap();
    let drop = fit.chest_drop.unwrap();
    assert!((drop.measured - 0.335).abs() < 0.01, "{drop:?}");
    let error = |subject: &SubjectModel| {
        let params = LiftParams {
            smooth_tracks: false,
            ..LiftParams::default()
        };
        let job = job_for(&tracks, subject, params);
        let out = lift(&job, &mut |_| {}, &AtomicBool::new(false)).unwrap();
        score_skeleton(&gt, &out.skeleton).unwrap().mpjpe_mm()
    };
    let (with_table, with_fit, exact) = (error(&table), error(&fitted), error(&built));
    // Measured: table 221.6 mm, fitted to the tracks 81.4 mm (this clip's shanks swing towards
    // the camera and are never seen square, so they are read short), true lengths 41.3 mm (the
    // clip swings its legs towards the camera: see `exact_tracks_give_back_the_skeleton`).
    assert!(
        with_fit < 0.5 * with_table && exact < with_fit,
        "table {with_table:.1} mm, read from the tracks {with_fit:.1} mm, true lengths {exact:.1} mm"
    );
}

#[test]
fn lengths_the_user_gives_are_kept_and_scale_the_rest_and_a_wrong_one_is_named() {
    // The table's subject, stated 12 % short: the lengths read from the clip come out short
    // with it; given the true thighs, every other part is scaled by them instead.
    let (gt, truth) = truth();
    let tracks = tracks_from_truth(&gt, 0.0, 3);
    let thigh = Bone::new(Joint::LeftHip, Joint::LeftKnee);
    let shank = Bone::new(Joint::RightKnee, Joint::RightAnkle);
    let read = |known: &KnownLengths| {
        subject_from_height(
            0.88 * truth.height_m,
            &tracks,
            gt.camera(),
            &LiftParams::default(),
            known,
        )
    };
    let (from_height, fit) = read(&KnownLengths::default()).unwrap();
    assert!(!fit.scale_from_given);
    let mut known = KnownLengths::default();
    known.bones.insert(thigh, truth.bone_length(thigh));
    let (given, fit) = read(&known).unwrap();
    assert!(fit.scale_from_given, "{fit}");
    assert_eq!(given.bone_length(thigh), truth.bone_length(thigh));
    // The shank no longer carries the height's error: read against the given thigh it is
    // about 1 / 0.88 of the one read against the height (measured 1.087: the clip never
    // shows its thighs quite square, so the given one is a little longer than the read one).
    let ratio = given.bone_length(shank) / from_height.bone_length(shank);
    assert!(
        (1.06..1.2).contains(&ratio),
        "shank given ÷ height {ratio:.3}"
    );
    assert!(
        fit.to_string().contains("thigh") && fit.to_string().contains("given"),
        "{fit}"
    );
    // A thigh given at 0.6 of what the video shows (with a true shank setting the scale).
    let mut wrong = KnownLengths::default();
    wrong.bones.insert(thigh, 0.6 * truth.bone_length(thigh));
    wrong.bones.insert(shank, truth.bone_length(shank));
    wrong.bones.insert(
        Bone::new(Joint::LeftKnee, Joint::LeftAnkle),
        truth.bone_length(shank),
    );
    wrong.shoulder_width_m = Some(truth.shoulder_width_m);
    match read(&wrong) {
        Err(e @ LiftError::LengthContradicted { name: "thigh", .. }) => {
            assert!(e.to_string().contains("thigh"), "{e}");
        }
        other => panic!("expected the thigh named, got {other:?}"),
    }
}

#[test]
fn refitting_the_key_path_brings_the_key_triangle_closer_and_steadies_it_on_noisy_tracks() {
    // 2 px noise: eqs. 10–11 turn the noise the 2D smoothing leaves into centimetres of depth
    // and jitter of the shoulders and chest; refitting their path over the clip (reprojection,
    // rigid sides, acceleration) cuts both, and the key triangle keeps its sides.
    let (gt, subject) = truth();
    let tracks = tracks_from_truth(&gt, 2.0, 3);
    let truth: Vec<_> = gt.frames.iter().map(|g| g.points3d()).collect();
    let key = [Joint::LeftShoulder, Joint::RightShoulder, Joint::Chest];
    // The key joints' mean error and jitter (their second differences over the frames against
    // the truth's), mm.
    let key_errors = |on: bool| {
        let params = LiftParams {
            steady_trunk: on,
            ..LiftParams::default()
        };
        let job = job_for(&tracks, &subject, params);
        let per = lift_per_frame(&job).unwrap();
        let p = &per.resolved.points;
        // The key triangle keeps its sides in every frame.
        for q in p {
            let side = (q[Joint::LeftShoulder] - q[Joint::Chest]).norm();
            let want = subject.bone_length(Bone::new(Joint::Chest, Joint::LeftShoulder));
            assert!((side - want).abs() < 1e-6, "{side} {want}");
        }
        let mut error = 0.0;
        for (q, r) in p.iter().zip(&truth) {
            for j in key {
                error += (q[j] - r[j]).norm();
            }
        }
        let mut jitter = 0.0;
        for t in 1..FRAMES - 1 {
            for j in key {
                let d2 = |q: &dyn Fn(usize) -> Point3<f64>| {
                    q(t + 1).coords - q(t).coords * 2.0 + q(t - 1).coords
                };
                jitter += (d2(&|u| p[u][j]) - d2(&|u| truth[u][j])).norm();
            }
        }
        (
            1000.0 * error / (3 * FRAMES) as f64,
            1000.0 * jitter / (3 * (FRAMES - 2)) as f64,
        )
    };
    let (off, on) = (key_errors(false), key_errors(true));
    // Measured: error 162.9 → 151.9 mm (mostly the whole triangle's depth, which one camera
    // sees worst), jitter 9.5 → 1.0 mm per frame.
    assert!(
        on.0 < 0.97 * off.0,
        "key joints' error {:.1} → {:.1} mm",
        off.0,
        on.0
    );
    assert!(
        on.1 < 0.5 * off.1,
        "key joints' jitter {:.1} → {:.1} mm",
        off.1,
        on.1
    );
}

#[test]
fn on_a_rigid_key_triangle_the_reference_key_lift_is_the_lift_and_a_sliding_chest_flexes_it() {
    let (mut gt, subject) = truth();
    // The model's key triangle is rigid, and the lift finds it exactly from exact tracks, so
    // putting the reference's triangle in place changes nothing: the difference left is the
    // root choices' alone.
    assert!(key_triangle_flex_m(&gt) < 1e-9);
    let out = run(&gt, &subject, 0.0, false);
    let on_key = lift_on_reference_key(&gt, &subject, &AmbiguityWeights::default());
    assert_eq!(on_key.frames.len(), out.per_frame.frames.len());
    for (a, b) in on_key.frames.iter().zip(&out.per_frame.frames) {
        for (j, p) in a.points.iter() {
            assert!((p - b.points[j]).norm() < 1e-6, "frame {} {j}", a.index);
        }
    }
    // A chest sliding ±1 cm along the trunk, as a motion-capture chest on the line from neck
    // to pelvis does when the spine bends: each chest–shoulder side (about 0.2 m, the chest
    // about 0.1 m below the shoulder line) changes by about half the slide, so the mean
    // standard deviation of the three sides (the width stays) is about
    // 2/3 · 0.5 · 1 cm / √2 ≈ 2.4 mm.
    for (t, f) in gt.frames.iter_mut().enumerate() {
        let p = f.points3d();
        let up = (nalgebra::center(&p[Joint::LeftShoulder], &p[Joint::RightShoulder])
            - p[Joint::Chest])
            .normalize();
        let slide = 0.01 * (t as f64 / 7.0).sin();
        let c = p[Joint::Chest] + up * slide;
        f.points3d[Joint::Chest.index()] = [c.x, c.y, c.z];
    }
    let flex = key_triangle_flex_m(&gt);
    assert!((0.0015..0.0035).contains(&flex), "flex {flex} m");
}

/// Every front end lifts through `reconstruct`: its stages run in order (camera, body lengths,
/// per-frame solve, refinement) and its result is the stated-height subject read through the
/// chosen camera, then lifted: the same as the steps taken one by one.
#[test]
fn reconstruct_runs_its_stages_in_order_and_equals_the_steps_one_by_one() {
    let (gt, _) = truth();
    let tracks = tracks_from_truth(&gt, 1.0, 5);
    let params = LiftParams::default();
    let mut stages = Vec::new();
    let done = reconstruct(
        &tracks,
        CameraChoice::FocalPx(700.0),
        &SubjectChoice::Height {
            height_m: 1.7,
            known: Default::default(),
        },
        &params,
        DepthOverrides::new(),
        &mut |p| {
            if stages.last() != Some(&p.stage) {
                stages.push(p.stage);
            }
        },
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(
        stages,
        [
            LiftStage::Camera,
            LiftStage::Subject,
            LiftStage::PerFrame,
            LiftStage::Refine
        ]
    );
    assert_eq!(done.camera, camera());
    assert_eq!(done.focal_source, FocalSource::Given);
    let (subject, fit) =
        subject_from_height(1.7, &tracks, camera(), &params, &Default::default()).unwrap();
    assert_eq!(done.fit, Some(fit));
    let by_hand = lift(
        &job_for(&tracks, &subject, params),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(done.output, by_hand);
    // The default camera is named as such for the user.
    let default = reconstruct(
        &tracks,
        CameraChoice::Default,
        &SubjectChoice::Model(Box::new(subject)),
        &LiftParams {
            refine: false,
            ..params
        },
        DepthOverrides::new(),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(default.focal_source, FocalSource::Default);
    assert!(default.fit.is_none());
    assert!(
        default.camera_line().contains("default"),
        "{}",
        default.camera_line()
    );
}
