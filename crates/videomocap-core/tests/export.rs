//! Exports: BVH round trips through our reader (random plausible motions, the real sample),
//! the golden file, the world frame against motion capture, and the tables.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use nalgebra::{Matrix3, Point3, Rotation3, Vector3};
use proptest::prelude::*;
use std::path::Path;
use videomocap_core::bvh::{Bvh, map_to_model};
use videomocap_core::camera::PinholeCamera;
use videomocap_core::export::rig::{RIG, rig_index_of};
use videomocap_core::export::{BvhExport, RigNames, WorldSkeleton, bvh, skeleton_csv, trc};
use videomocap_core::formats::FrameIndex;
use videomocap_core::formats::{CONTACT_FLAG, Frame3d, Skeleton3d};
use videomocap_core::skeleton::{Bone, Joint, PerJoint, SubjectModel};

/// Camera-from-world for a camera at `centre` turned by `yaw` about world up and tilted down by
/// `pitch` (radians); the world is Y up, the camera X right, Y down, Z forward.
fn camera_from_world(yaw: f64, pitch: f64) -> Matrix3<f64> {
    let flip = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    Rotation3::from_axis_angle(&Vector3::x_axis(), pitch).into_inner()
        * flip
        * Rotation3::from_axis_angle(&Vector3::y_axis(), yaw).into_inner()
}

fn to_camera(frames: &[PerJoint<Point3<f64>>], yaw: f64, pitch: f64) -> Skeleton3d {
    let r = camera_from_world(yaw, pitch);
    let centre = Point3::new(0.3, 1.6, 4.5);
    let r_yaw = Rotation3::from_axis_angle(&Vector3::y_axis(), -yaw);
    let centre = r_yaw * centre;
    Skeleton3d {
        camera: PinholeCamera::centred(800.0, 640, 480),
        fps: Some(30.0),
        bone_lengths_m: Default::default(),
        frames: frames
            .iter()
            .enumerate()
            .map(|(i, p)| Frame3d {
                index: FrameIndex(i),
                points: p.map(|_, q| Point3::from(r * (q - centre))),
                flags: vec![],
            })
            .collect(),
    }
}

/// Parameters of a random smooth motion: per bone a base turn and a swing (rotation vectors,
/// radians) and a phase; a body turn rate.
#[derive(Debug, Clone)]
struct Motion {
    base: Vec<[f64; 3]>,
    swing: Vec<[f64; 3]>,
    phase: Vec<f64>,
    turn: f64,
    height: f64,
}

fn motion_strategy() -> impl Strategy<Value = Motion> {
    let v = || prop::array::uniform3(-0.6f64..0.6);
    (
        prop::collection::vec(v(), 15),
        prop::collection::vec(v(), 15),
        prop::collection::vec(0.0f64..6.3, 15),
        -0.05f64..0.05,
        1.5f64..1.95,
    )
        .prop_map(|(base, swing, phase, turn, height)| Motion {
            base,
            swing,
            phase,
            turn,
            height,
        })
}

/// Rest direction of each bone (Y up, facing +Z, subject's left at +X; arms hanging).
fn rest_direction(b: Bone) -> Vector3<f64> {
    use Joint::*;
    match b.child {
        Chest | Neck | HeadTop => Vector3::y(),
        LeftShoulder => Vector3::new(1.0, 0.3, 0.0),
        RightShoulder => Vector3::new(-1.0, 0.3, 0.0),
        LeftHip => Vector3::x(),
        RightHip => -Vector3::x(),
        _ => -Vector3::y(),
    }
}

/// Frames of a plausible motion: every bone at its length; trunk, neck, head, clavicles and
/// hips swing a little, upper limbs swing freely, elbows and knees are hinges that flex their
/// anatomical way (0–140°) in a plane that twists with the upper bone.
fn frames_of(m: &Motion, n: usize) -> Vec<PerJoint<Point3<f64>>> {
    use Joint::*;
    let s = SubjectModel::from_height(m.height, Default::default()).unwrap();
    (0..n)
        .map(|t| {
            let body = Rotation3::from_axis_angle(&Vector3::y_axis(), m.turn * t as f64);
            let mut p = PerJoint::from_fn(|_| Point3::origin());
            let mut upper_turn = PerJoint::from_fn(|_| Rotation3::identity());
            p[Pelvis] = Point3::new(0.01 * t as f64, 0.95, 0.0);
            for (k, b) in Bone::ALL.iter().enumerate() {
                let w = (t as f64 * 0.2 + m.phase[k]).sin();
                let base = Vector3::from(m.base[k]);
                let swing = Vector3::from(m.swing[k]);
                let rest = rest_direction(*b).normalize();
                let dir = match b.child {
                    LeftWrist | RightWrist | LeftAnkle | RightAnkle => {
                        let hinge = if matches!(b.child, LeftWrist | RightWrist) {
                            -Vector3::x()
                        } else {
                            Vector3::x()
                        };
                        let upper = upper_turn[b.parent];
                        let twist = Rotation3::from_axis_angle(
                            &nalgebra::Unit::new_normalize(rest),
                            base.y + w * swing.y,
                        );
                        let axis = nalgebra::Unit::new_normalize(upper * twist * hinge);
                        let flex = (1.2 + 2.0 * base.x + 1.5 * w * swing.x).clamp(0.0, 2.4);
                        Rotation3::from_axis_angle(&axis, flex) * (upper * rest)
                    }
                    LeftElbow | RightElbow | LeftKnee | RightKnee => {
                        let turn = body * Rotation3::new(base + w * swing);
                        upper_turn[b.child] = turn;
                        turn * rest
                    }
                    _ => body * Rotation3::new(0.4 * (base + w * swing)) * rest,
                };
                p[b.child] = p[b.parent] + s.bone_length(*b) * dir;
            }
            p
        })
        .collect()
}

/// Largest step between neighbouring frames of any joint's rotation (geodesic angle, degrees),
/// and of any Euler channel on frames away from gimbal lock (|x| < 30° on both frames). Near
/// the lock the outer channels move up to (1 + |sin x|) / cos x times the joint's turn: at
/// 60° that is 3.7 times, and proptest's case 2c9fdb64 (in `export.proptest-regressions`)
/// stepped a channel 25.8° there while no joint turned more than 15.2° a frame; under 30° it
/// is at most 1.73 times.
fn steps(motion: &videomocap_core::export::kinematics::RigMotion) -> (f64, f64) {
    let (_, angles) = videomocap_core::export::bvh_text(motion, RigNames::Cmu);
    let rotating: Vec<usize> = (0..RIG.len()).filter(|&i| !RIG[i].is_end()).collect();
    let mut geodesic: f64 = 0.0;
    let mut euler: f64 = 0.0;
    for f in 1..motion.frames.len() {
        for (k, &i) in rotating.iter().enumerate() {
            let step = motion.frames[f - 1].local[i].rotation_to(&motion.frames[f].local[i]);
            geodesic = geodesic.max(step.angle().to_degrees());
            let (a, b) = (angles[f - 1][k], angles[f][k]);
            if a[1].abs() < 30.0 && b[1].abs() < 30.0 {
                for c in 0..3 {
                    euler = euler.max((a[c] - b[c]).abs());
                }
            }
        }
    }
    (geodesic, euler)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn bvh_round_trip_within_a_millimetre(m in motion_strategy(), yaw in -3.1f64..3.1, pitch in -0.4f64..0.4) {
        let world = frames_of(&m, 40);
        let skeleton = to_camera(&world, yaw, pitch);
        let ws = WorldSkeleton::new(&skeleton, None).unwrap();
        // Camera → world → camera is the identity.
        for (f, w) in skeleton.frames.iter().zip(&ws.frames) {
            for j in Joint::ALL {
                prop_assert!((ws.world.to_camera(&w[j]) - f.points[j]).norm() < 1e-9);
            }
        }
        let motion = videomocap_core::export::kinematics::solve(&ws.frames, 1.0 / 30.0).unwrap();
        let out = bvh(&ws, RigNames::Cmu).unwrap();
        prop_assert!(out.max_round_trip_m < 1e-3, "round trip {} m", out.max_round_trip_m);
        // Independently of the exporter's own check: read the text back here.
        let read = Bvh::parse(&out.text, Path::new("t.bvh")).unwrap();
        prop_assert_eq!(read.frame_count(), 40);
        let p = read.positions(39);
        for j in Joint::ALL {
            let got = p[rig_index_of(j)] / 100.0;
            prop_assert!((got - ws.frames[39][j]).norm() < 1e-3);
        }
        // No flips. An upper limb's swing turns at most 12° a frame here (0.2 rad/frame of
        // phase times a swing of up to 0.6 rad per axis); a hand's or foot's bone adds its twist
        // (up to 7°) and its flex (up to 10°), so a joint turns up to about 29° a frame, and an
        // Euler channel under 30° of gimbal lock steps at most 1.73 times that, about 51°
        // (3000 random cases turned a joint 26.9° once, over the 25° this bound used to be).
        // A flip (a twist taken the other way, an Euler solution switched or wrapped) jumps by
        // about 180° or 360°, far beyond both bounds.
        let (geodesic, euler) = steps(&motion);
        prop_assert!(geodesic < 45.0, "a joint turned {geodesic}° in one frame");
        prop_assert!(euler < 90.0, "an Euler angle stepped {euler}° in one frame");
    }
}

#[test]
fn the_written_hierarchy_is_the_rig_in_order() {
    let (_, out, read) = written([0.1, 0.0, 0.0], [0.0, 0.2, 0.0], 0.0, 0.0);
    assert_eq!(read.joints.len(), RIG.len());
    for (r, j) in RIG.iter().zip(&read.joints) {
        assert_eq!(r.is_end(), j.end_site);
        if !r.is_end() {
            assert_eq!(r.name, j.name);
        }
    }
    assert!((read.frame_time_s - 1.0 / 30.0).abs() < 1e-8);
    assert!(out.text.starts_with("HIERARCHY\nROOT Hips\n"));
    assert!(
        out.text
            .contains("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation")
    );
    assert!(!out.text.contains("-0.0000"));
}

/// The Mixamo names: the same hierarchy and numbers with other bone names, every one of them
/// Mixamo's (`mixamorig:` and a name from its rig), and the file maps back onto the 16 joints
/// through the reader's name table like any other rig.
#[test]
fn the_mixamo_rig_is_the_same_motion_under_mixamo_names() {
    let (ws, _, a) = written([0.1, 0.0, 0.0], [0.0, 0.2, 0.0], 0.0, 0.0);
    let mixamo = bvh(&ws, RigNames::Mixamo).unwrap();
    assert!(mixamo.max_round_trip_m < 1e-3);
    let b = Bvh::parse(&mixamo.text, Path::new("mixamo.bvh")).unwrap();
    assert_eq!(a.joints.len(), b.joints.len());
    for k in 0..3 {
        assert_eq!(a.frame(k), b.frame(k), "same motion");
    }
    const MIXAMO: [&str; 15] = [
        "Hips",
        "Spine",
        "Spine2",
        "Neck",
        "Head",
        "LeftShoulder",
        "LeftArm",
        "LeftForeArm",
        "LeftHand",
        "LeftUpLeg",
        "LeftLeg",
        "LeftFoot",
        "RightHand",
        "RightUpLeg",
        "RightFoot",
    ];
    let names: Vec<&str> = b
        .joints
        .iter()
        .filter(|j| !j.end_site)
        .map(|j| j.name.as_str())
        .collect();
    for n in &names {
        assert!(n.starts_with("mixamorig:"), "{n}");
    }
    for n in MIXAMO {
        assert!(
            names.contains(&format!("mixamorig:{n}").as_str()),
            "{n} missing"
        );
    }
    let mapped = map_to_model(&b, Path::new("mixamo.bvh")).unwrap();
    assert_eq!(mapped.frames.len(), 3);
    for j in [Joint::LeftWrist, Joint::RightAnkle, Joint::LeftKnee] {
        let got = mapped.frames[1][j];
        let want = ws.frames[1][j];
        assert!((got - want).norm() < 1e-3, "{j:?}: {got} against {want}");
    }
}

/// The End Site under the joint called `name`.
fn end_site_of(read: &Bvh, name: &str) -> usize {
    let i = read.find(name).unwrap();
    (0..read.joints.len())
        .find(|&k| read.joints[k].end_site && read.joints[k].parent == Some(i))
        .unwrap()
}

/// A three-frame motion: every bone turned by `base`, swinging by `swing`, seen from
/// `yaw`/`pitch`; its world skeleton and the CMU BVH written of it, read back.
fn written(
    base: [f64; 3],
    swing: [f64; 3],
    yaw: f64,
    pitch: f64,
) -> (WorldSkeleton, BvhExport, Bvh) {
    let m = Motion {
        base: vec![base; 15],
        swing: vec![swing; 15],
        phase: vec![0.0; 15],
        turn: 0.0,
        height: 1.7,
    };
    let ws = WorldSkeleton::new(&to_camera(&frames_of(&m, 3), yaw, pitch), None).unwrap();
    let out = bvh(&ws, RigNames::Cmu).unwrap();
    let read = Bvh::parse(&out.text, Path::new("t.bvh")).unwrap();
    (ws, out, read)
}

/// The hands continue the forearms by a hand's length; the feet point to the body's front with
/// the toes at the floor at rest, and turn with the shanks.
#[test]
fn hands_continue_the_forearms_and_feet_point_forward_to_the_floor() {
    let (ws, _, read) = written([0.0; 3], [0.0; 3], 0.7, 0.1);
    let f = &ws.frames[0];
    // Hand: along elbow → wrist, 0.74 of the forearm beyond the wrist.
    let hand = read.positions(0)[end_site_of(&read, "LeftHand")] / 100.0;
    let forearm = f[Joint::LeftWrist] - f[Joint::LeftElbow];
    let beyond = hand - f[Joint::LeftWrist];
    assert!(beyond.normalize().dot(&forearm.normalize()) > 0.999);
    assert!((beyond.norm() / forearm.norm() - 0.108 / 0.146).abs() < 1e-3);
    // Foot, at rest: in front of the ankle (the rest pose faces +Z) and down by the ankle's
    // height over the floor (0.039 of the stature), square-ish to the shank.
    let rest = read.rest_positions();
    let at = |name: &str| rest[read.find(name).unwrap()];
    let toe_rest = rest[end_site_of(&read, "RightFoot")];
    let foot_rest = (toe_rest - at("RightFoot")) / 100.0;
    let shank_rest = (at("RightFoot") - at("RightLeg")) / 100.0;
    assert!(foot_rest.z > 0.0 && foot_rest.x.abs() < 1e-9, "{foot_rest}");
    assert!(
        (foot_rest.y / shank_rest.norm() + 0.039 / 0.246).abs() < 1e-3,
        "toes {} m under the ankle",
        -foot_rest.y
    );
    // In motion the foot turns with the shank: the same angle to it on every frame.
    let rest_angle = shank_rest.angle(&foot_rest);
    for k in 0..3 {
        let p = read.positions(k);
        let (i, e) = (
            read.find("RightFoot").unwrap(),
            end_site_of(&read, "RightFoot"),
        );
        let angle = (p[i] - p[read.find("RightLeg").unwrap()]).angle(&(p[e] - p[i]));
        assert!(
            (angle - rest_angle).abs() < 1e-3,
            "{angle} against {rest_angle}"
        );
    }
}

/// The golden file: a fixed three-frame motion must give these exact bytes. After a deliberate
/// change of the format, regenerate with `UPDATE_GOLDEN=1 cargo test --test export`.
#[test]
fn golden_bvh() {
    let m = Motion {
        base: (0..15)
            .map(|k| [0.05 * k as f64, -0.1, 0.02 * k as f64])
            .collect(),
        swing: (0..15).map(|k| [0.1, 0.01 * k as f64, 0.0]).collect(),
        phase: (0..15).map(|k| k as f64).collect(),
        turn: 0.02,
        height: 1.75,
    };
    let ws = WorldSkeleton::new(&to_camera(&frames_of(&m, 3), 0.3, 0.2), None).unwrap();
    let text = bvh(&ws, RigNames::Cmu).unwrap().text;
    let path = videomocap_testkit::repo_root().join("tests/golden/three_frames.bvh");
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::write(&path, &text).unwrap();
    }
    let golden = std::fs::read_to_string(&path).unwrap();
    assert_eq!(text, golden, "BVH output changed; see the test's comment");
}

fn cmu_walk() -> Vec<PerJoint<Point3<f64>>> {
    let path = videomocap_testkit::repo_root().join("tests/data/cmu_02_01_walk.bvh");
    let bvh = Bvh::load(&path).unwrap();
    map_to_model(&bvh, &path).unwrap().frames
}

#[test]
fn up_and_floor_of_a_captured_walk_are_found() {
    let world = cmu_walk();
    let floor_truth = world
        .iter()
        .map(|p| p[Joint::LeftAnkle].y.min(p[Joint::RightAnkle].y))
        .fold(f64::INFINITY, f64::min);
    for (yaw, pitch) in [(0.0, 0.0), (0.8, 0.25), (-2.0, -0.1)] {
        let skeleton = to_camera(&world, yaw, pitch);
        let ws = WorldSkeleton::new(&skeleton, None).unwrap();
        let truth_up = camera_from_world(yaw, pitch) * Vector3::y();
        let angle = ws.world.up_in_camera().angle(&truth_up).to_degrees();
        let lowest = ws
            .frames
            .iter()
            .map(|p| p[Joint::LeftAnkle].y.min(p[Joint::RightAnkle].y))
            .fold(f64::INFINITY, f64::min);
        eprintln!(
            "yaw {yaw} pitch {pitch}: up off by {angle:.2}°, by {}; lowest ankle {lowest:.3} m (truth {floor_truth:.3} m above its floor)",
            ws.world.up_source
        );
        assert!(angle < 2.0, "up {angle}°");
        assert!((lowest - floor_truth).abs() < 0.05);
        let pelvis = ws.frames[0][Joint::Pelvis];
        assert!(
            pelvis.x.abs() < 1e-9 && pelvis.z.abs() < 1e-9,
            "origin under the pelvis"
        );
    }
}

/// A clip with a jump (a third of it in the air) keeps its floor under the ankles the lift
/// found planted, and the root leaves it and lands again; without any planted foot the floor
/// is said to be a guess.
#[test]
fn the_floor_rests_on_the_planted_feet_and_a_jump_leaves_it() {
    use videomocap_core::export::{FloorSource, world::ANKLE_HEIGHT_FRACTION, world::stature_m};
    let mut world = cmu_walk();
    let n = world.len();
    let jump = n / 3..2 * n / 3;
    for p in &mut world[jump.clone()] {
        for q in p.0.iter_mut() {
            q.y += 0.3;
        }
    }
    let lowest = world
        .iter()
        .map(|p| p[Joint::LeftAnkle].y.min(p[Joint::RightAnkle].y))
        .fold(f64::INFINITY, f64::min);
    let mut skeleton = to_camera(&world, 0.8, 0.2);
    for (t, f) in skeleton.frames.iter_mut().enumerate() {
        for (ankle, name) in [
            (Joint::LeftAnkle, "left_ankle"),
            (Joint::RightAnkle, "right_ankle"),
        ] {
            if !jump.contains(&t) && world[t][ankle].y < lowest + 0.03 {
                f.flags.push(format!("{CONTACT_FLAG}{name}"));
            }
        }
    }
    let ws = WorldSkeleton::new(&skeleton, None).unwrap();
    assert!(matches!(ws.world.floor_source, FloorSource::FeetPlanted { frames } if frames > 20));
    let ankle_height = ANKLE_HEIGHT_FRACTION * stature_m(&ws.frames);
    let mut planted = Vec::new();
    for t in 0..n {
        for a in [Joint::LeftAnkle, Joint::RightAnkle] {
            if ws.contact[t][a] {
                planted.push(ws.frames[t][a].y);
            }
        }
    }
    planted.sort_by(f64::total_cmp);
    let median = planted[planted.len() / 2];
    assert!(
        (median - ankle_height).abs() < 0.01,
        "{median} against {ankle_height}"
    );
    // The root leaves the floor by the jump's height and lands again.
    let (before, top, after) = (jump.start - 1, jump.start + 1, jump.end);
    let rise = |a: usize, b: usize, w: &[PerJoint<Point3<f64>>]| {
        w[b][Joint::Pelvis].y - w[a][Joint::Pelvis].y
    };
    assert!((rise(before, top, &ws.frames) - rise(before, top, &world)).abs() < 0.01);
    assert!((rise(before, after, &ws.frames) - rise(before, after, &world)).abs() < 0.01);
    // No planted foot: the lowest ankles, said to be a guess.
    for f in &mut skeleton.frames {
        f.flags.clear();
    }
    let guessed = WorldSkeleton::new(&skeleton, None).unwrap();
    assert_eq!(guessed.world.floor_source, FloorSource::NoFootPlanted);
    assert!(
        guessed
            .world
            .floor_source
            .to_string()
            .contains("check the floor")
    );
}

#[test]
fn csv_and_trc_hold_every_joint_of_every_frame() {
    let m = Motion {
        base: vec![[0.0; 3]; 15],
        swing: vec![[0.1, 0.0, 0.0]; 15],
        phase: vec![0.0; 15],
        turn: 0.0,
        height: 1.7,
    };
    let mut skeleton = to_camera(&frames_of(&m, 5), 0.0, 0.0);
    // A planted left foot on frame 1: a contact, not a problem.
    skeleton.frames[1]
        .flags
        .push(format!("{CONTACT_FLAG}left_ankle"));
    assert!(!skeleton.frames[1].flagged());
    let ws = WorldSkeleton::new(&skeleton, None).unwrap();
    let csv = skeleton_csv(&ws);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "frame,time_s,joint,x_m,y_m,z_m,off_frame,lost,contact"
    );
    let contact_rows: Vec<&str> = lines[1..]
        .iter()
        .filter(|l| l.ends_with(",1"))
        .copied()
        .collect();
    assert_eq!(contact_rows.len(), 1, "{contact_rows:?}");
    assert!(contact_rows[0].starts_with("1,") && contact_rows[0].contains(",left_ankle,"));
    assert_eq!(lines.len(), 1 + 5 * 16);
    let row: Vec<&str> = lines[1 + 16 * 2 + 3].split(',').collect();
    assert_eq!(row[0], "2");
    assert_eq!(row[2], "pelvis");
    let y: f64 = row[4].parse().unwrap();
    assert!((y - ws.frames[2][Joint::Pelvis].y).abs() < 1e-5);
    let trc = trc(&ws, "m.trc");
    let lines: Vec<&str> = trc.lines().collect();
    assert!(lines[0].starts_with("PathFileType\t4\t(X/Y/Z)\tm.trc"));
    assert_eq!(lines[2].split('\t').nth(2), Some("5"));
    assert_eq!(lines[2].split('\t').nth(3), Some("16"));
    assert_eq!(
        lines[3].split('\t').filter(|s| !s.is_empty()).count(),
        2 + 16
    );
    assert_eq!(lines[4].split('\t').filter(|s| !s.is_empty()).count(), 48);
    assert_eq!(lines.len(), 6 + 5);
    assert_eq!(lines[6 + 4].split('\t').count(), 2 + 48);
}

#[test]
fn gaps_and_missing_frame_rates_are_refused() {
    let m = Motion {
        base: vec![[0.0; 3]; 15],
        swing: vec![[0.0; 3]; 15],
        phase: vec![0.0; 15],
        turn: 0.0,
        height: 1.7,
    };
    let mut skeleton = to_camera(&frames_of(&m, 4), 0.0, 0.0);
    skeleton.frames[3].index = FrameIndex(7);
    let ws = WorldSkeleton::new(&skeleton, None).unwrap();
    let err = bvh(&ws, RigNames::Cmu).unwrap_err().to_string();
    assert!(err.contains("frame 7 follows frame 2"), "{err}");
    skeleton.fps = None;
    let err = WorldSkeleton::new(&skeleton, None).unwrap_err().to_string();
    assert!(err.contains("--fps"), "{err}");
    assert!(WorldSkeleton::new(&skeleton, Some(25.0)).is_ok());
}

/// The real sample: its reference 2D joints lifted with the default settings, exported, read
/// back: every joint of every frame within a millimetre.
#[test]
fn the_real_sample_round_trips_within_a_millimetre() {
    use videomocap_core::lift::{LiftJob, LiftParams, lift};
    use videomocap_testkit::eval::pose3d::{subject_from_truth, tracks_from_truth};
    let gt_path =
        videomocap_testkit::repo_root().join("sample_videos/pose2sim_balancing_cam01/gt.json");
    let gt = videomocap_testkit::synth::GroundTruth::load(&gt_path).unwrap();
    let tracks = tracks_from_truth(&gt, 0.0, 1);
    let job = LiftJob {
        tracks: &tracks,
        camera: gt.camera(),
        subject: subject_from_truth(&gt),
        params: LiftParams::default(),
        overrides: Default::default(),
    };
    let out = lift(
        &job,
        &mut |_| {},
        &std::sync::atomic::AtomicBool::new(false),
    )
    .unwrap();
    let ws = WorldSkeleton::new(&out.skeleton, None).unwrap();
    assert_eq!(ws.fps, 60.0);
    let b = bvh(&ws, RigNames::Cmu).unwrap();
    eprintln!(
        "real sample: {} frames, round trip {:.4} mm, largest Euler step {:.1}°, up from {}",
        b.frames,
        b.max_round_trip_m * 1000.0,
        b.max_angle_step_deg,
        ws.world.up_source
    );
    assert_eq!(b.frames, 100);
    assert!(b.max_round_trip_m < 1e-3);
    // Up from the lifted skeleton against up from the reference's own 3D joints.
    let reference: Vec<PerJoint<Point3<f64>>> = gt.frames.iter().map(|f| f.points3d()).collect();
    let reference_up = videomocap_core::export::WorldFrame::estimate(&reference, &[]).unwrap();
    let angle = ws
        .world
        .up_in_camera()
        .angle(&reference_up.up_in_camera())
        .to_degrees();
    eprintln!(
        "up: {angle:.1}° from the reference's ({})",
        reference_up.up_source
    );
    assert!(angle < 12.0, "up {angle}° from the reference's");
}
