//! The pose network in pure Rust: on a real frame, cropped around the body the reference
//! marks, it finds the limb joints; a model file that is missing, truncated or not a model is
//! refused by name.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use nalgebra::{Point2, Vector3};
use videomocap_core::network::{Crop, NetworkError, PoseNetwork};
use videomocap_core::skeleton::{Joint, PerJoint};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::eval::is_limb_joint;
use videomocap_testkit::synth::GroundTruth;

#[test]
fn on_the_real_sample_the_network_finds_the_limb_joints_within_a_fifth_of_the_torso() {
    let dir = videomocap_testkit::repo_root().join("sample_videos/pose2sim_balancing_cam01");
    let gt = GroundTruth::load(&dir.join("gt.json")).unwrap();
    let mut video = Video::open(&dir.join("video.mp4"), &OpenOptions::default()).unwrap();
    let network = PoseNetwork::bundled().unwrap();
    let (mut within, mut count) = (0, 0);
    for index in [0, 40, 80] {
        let frame = video.frame(index).unwrap();
        let p = &gt.frames[index].points2d;
        let truth = PerJoint::from_fn(|j| Point2::new(p[j.index()][0], p[j.index()][1]));
        let crop = Crop::around(&truth).unwrap();
        let pose = network.run(&frame.image, &crop).unwrap();
        assert!(
            pose.presence > 0.5,
            "frame {index}: presence {}",
            pose.presence
        );
        let torso = (truth[Joint::Neck] - truth[Joint::Pelvis]).norm();
        for j in Joint::ALL.into_iter().filter(|&j| is_limb_joint(j)) {
            count += 1;
            within += usize::from((pose.joints[j].pos - truth[j]).norm() <= 0.2 * torso);
        }
    }
    let pck = within as f64 / count as f64;
    eprintln!("network on reference crops, 13 limb joints, 3 frames: PCK@0.2 {pck:.3}");
    assert!(pck >= 0.7, "PCK@0.2 {pck:.2}");
}

#[test]
fn a_model_file_that_is_missing_truncated_or_not_a_model_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.onnx");
    let e = PoseNetwork::load(&missing).err().unwrap();
    assert!(matches!(e, NetworkError::Model { .. }));
    assert!(e.to_string().contains("missing.onnx"), "{e}");
    let bundled = std::fs::read(
        videomocap_testkit::repo_root().join("assets/blazepose/pose_landmark_full.onnx"),
    )
    .unwrap();
    let truncated = dir.path().join("truncated.onnx");
    std::fs::write(&truncated, &bundled[..bundled.len() / 3]).unwrap();
    let e = PoseNetwork::load(&truncated).err().unwrap();
    assert!(e.to_string().contains("truncated.onnx"), "{e}");
    let text = dir.path().join("text.onnx");
    std::fs::write(&text, "not a model").unwrap();
    let e = PoseNetwork::load(&text).err().unwrap();
    assert!(e.to_string().contains("text.onnx"), "{e}");
}

/// Our limb joints and BlazePose's landmarks for them.
const LIMB_LANDMARKS: [(Joint, usize); 12] = [
    (Joint::LeftShoulder, 11),
    (Joint::RightShoulder, 12),
    (Joint::LeftElbow, 13),
    (Joint::RightElbow, 14),
    (Joint::LeftWrist, 15),
    (Joint::RightWrist, 16),
    (Joint::LeftHip, 23),
    (Joint::RightHip, 24),
    (Joint::LeftKnee, 25),
    (Joint::RightKnee, 26),
    (Joint::LeftAnkle, 27),
    (Joint::RightAnkle, 28),
];

/// The model run plainly, as tract loads it with its defaults (every output, one thread): the
/// slow reference the product's pruned graph is checked against.
fn plain_landmarks(
    plan: &std::sync::Arc<tract_onnx::prelude::TypedRunnableModel>,
    input: Vec<f32>,
) -> (Vec<f32>, f32, Vec<f32>) {
    use tract_onnx::prelude::*;
    let input = tract_ndarray::Array4::from_shape_vec((1, 256, 256, 3), input).unwrap();
    let outputs = plan.run(tvec!(Tensor::from(input).into())).unwrap();
    let values = |n: usize| -> Vec<f32> {
        let o = outputs.iter().find(|o| o.len() == n).unwrap();
        o.to_plain_array_view::<f32>()
            .unwrap()
            .iter()
            .copied()
            .collect()
    };
    (values(195), values(1)[0], values(117))
}

#[test]
fn the_products_network_gives_the_plain_models_landmarks_within_half_a_pixel() {
    use tract_onnx::prelude::*;
    let root = videomocap_testkit::repo_root();
    let plain = tract_onnx::onnx()
        .model_for_path(root.join("assets/blazepose/pose_landmark_full.onnx"))
        .unwrap()
        .with_input_fact(0, f32::fact([1, 256, 256, 3]).into())
        .unwrap()
        .into_optimized()
        .unwrap()
        .into_runnable()
        .unwrap();
    let network = PoseNetwork::bundled().unwrap().with_threads(2);
    let (mut worst, mut crops) = (0.0f64, 0);
    for clip in [
        "pose2sim_balancing_cam01",
        "pose2sim_distractor_cam01",
        "synth_walk_oblique",
    ] {
        let dir = root.join("sample_videos").join(clip);
        let gt = GroundTruth::load(&dir.join("gt.json")).unwrap();
        let mut video = Video::open(&dir.join("video.mp4"), &OpenOptions::default()).unwrap();
        for index in [0, 25, 50] {
            let frame = video.frame(index).unwrap();
            let p = &gt.frames[index].points2d;
            let truth = PerJoint::from_fn(|j| Point2::new(p[j.index()][0], p[j.index()][1]));
            let around = Crop::around(&truth).unwrap();
            // The body's crop, and the same crop half off the frame's left edge (a joint
            // leaving the frame: the network sees black where the image ends).
            let off = Crop {
                centre: Point2::new(0.0, around.centre.y),
                ..around
            };
            for (what, crop) in [("body", around), ("half off", off)] {
                let pose = network.run(&frame.image, &crop).unwrap();
                let (landmarks, flag, world) = plain_landmarks(&plain, crop.sample(&frame.image));
                let presence = 1.0 / (1.0 + (-f64::from(flag)).exp());
                eprintln!(
                    "{clip} {index} {what}: presence {:.4} vs {presence:.4}",
                    pose.presence
                );
                assert!(
                    (pose.presence - presence).abs() < 1e-3,
                    "{clip} {index} {what}"
                );
                let sig = |x: f32| 1.0 / (1.0 + (-f64::from(x)).exp());
                for (j, i) in LIMB_LANDMARKS {
                    let reference =
                        crop.to_image(f64::from(landmarks[i * 5]), f64::from(landmarks[i * 5 + 1]));
                    worst = worst.max((pose.joints[j].pos - reference).norm());
                    // Everything else the product reads: the confidence and the 3D body.
                    let confidence = sig(landmarks[i * 5 + 3]) * sig(landmarks[i * 5 + 4]);
                    assert!(
                        (pose.joints[j].confidence - confidence).abs() < 1e-3,
                        "{clip} {index} {j:?} confidence {} vs {confidence}",
                        pose.joints[j].confidence
                    );
                    let w = Vector3::new(world[i * 3], world[i * 3 + 1], world[i * 3 + 2])
                        .cast::<f64>();
                    assert!(
                        (pose.world[j] - w).norm() < 1e-3,
                        "{clip} {index} {j:?} world {:?} vs {w:?}",
                        pose.world[j]
                    );
                }
                let centre = crop.to_image(
                    f64::from(landmarks[33 * 5]),
                    f64::from(landmarks[33 * 5 + 1]),
                );
                let next = pose.next_crop.expect("a next crop");
                assert!(
                    (next.centre - centre).norm() < 0.5,
                    "{clip} {index} next crop"
                );
                crops += 1;
            }
        }
    }
    eprintln!("{crops} crops: largest difference to the plain model {worst:.4} px");
    assert!(worst <= 0.5, "largest difference {worst} px");
}
