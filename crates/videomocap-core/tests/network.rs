//! The pose network in pure Rust: on a real frame, cropped around the body the reference
//! marks, it finds the limb joints; a model file that is missing, truncated or not a model is
//! refused by name.

use nalgebra::Point2;
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
