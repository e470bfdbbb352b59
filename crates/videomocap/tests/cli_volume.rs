//! The point-volume commands end to end (`volume`, `carve`): volumes and carving set-ups made
//! by the test kit, the user binary run on them.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use assert_cmd::Command;
use videomocap_core::formats::Skeleton3d;
use videomocap_core::skeleton::{Joint, SubjectModel};
use videomocap_testkit::eval::volume::score_volume;
use videomocap_testkit::synth::{
    ProceduralMotion, SilhouetteFaults, VoxelParams, procedural, write_carving_setup,
    write_volume_sequence,
};

fn videomocap() -> Command {
    Command::cargo_bin("videomocap").unwrap()
}

#[test]
fn synth_volume_then_volume_writes_a_skeleton_and_a_bvh() {
    let tmp = tempfile::tempdir().unwrap();
    let vols = tmp.path().join("vols");
    let out = tmp.path().join("out");
    let motion = procedural(
        ProceduralMotion::JumpingJacks,
        &SubjectModel::default(),
        12,
        10.0,
    );
    let voxels = VoxelParams {
        voxel_m: 0.04,
        noise_voxels: 10,
        ..VoxelParams::default()
    };
    write_volume_sequence(&motion, &vols, &voxels, |_, _| {}).unwrap();
    assert!(vols.join("frame_0011.ply").is_file());
    let o = videomocap()
        .args(["volume"])
        .arg(&vols)
        .args(["--fps", "10", "--out-dir"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("five-limb"), "{stderr}");
    let skel = Skeleton3d::load(&out.join("skeleton3d.json")).unwrap();
    let truth = Skeleton3d::load(&vols.join("truth.skeleton3d.json")).unwrap();
    let ok = skel.frames.iter().filter(|f| f.flags.is_empty()).count();
    let s = score_volume(&truth, &skel, ok);
    assert!(s.mean_mm() < 60.0, "{}", s.mean_mm());
    assert!(
        std::fs::read_to_string(out.join("motion.bvh"))
            .unwrap()
            .starts_with("HIERARCHY")
    );
}

#[test]
fn volume_refuses_a_file_and_an_empty_directory_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("cloud.ply");
    std::fs::write(&file, "x").unwrap();
    let o = videomocap()
        .arg("volume")
        .arg(&file)
        .args(["--out-dir", "x"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("cloud.ply") && e.contains("directory"), "{e}");
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let o = videomocap()
        .arg("volume")
        .arg(&empty)
        .args(["--out-dir", "x"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("empty") && e.contains("no point clouds"), "{e}");
}

/// What `videomocap-bench synth --motion march --volume --views V --width 320 --height 240`
/// writes: `frames` marching frames (10 fps) as point volumes with a carving set-up of `views`
/// 320×240 cameras in `vols/carve`, with the typical faults of segmentation when `faulty`.
fn synth_carving_setup(vols: &std::path::Path, frames: usize, views: usize, faulty: bool) {
    let motion = procedural(
        ProceduralMotion::March,
        &SubjectModel::default(),
        frames,
        30.0,
    );
    write_volume_sequence(&motion, vols, &VoxelParams::default(), |_, _| {}).unwrap();
    let faults = if faulty {
        SilhouetteFaults::typical()
    } else {
        SilhouetteFaults::default()
    };
    write_carving_setup(
        &motion,
        &vols.join("carve"),
        views,
        (320, 240),
        &faults,
        &|_, _| {},
    )
    .unwrap();
}

#[test]
fn synth_views_then_carve_writes_one_grid_per_frame_and_refuses_bad_set_ups_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let vols = tmp.path().join("vols");
    synth_carving_setup(&vols, 3, 3, false);
    let setup = vols.join("carve");
    let grids = tmp.path().join("grids");
    videomocap()
        .arg("carve")
        .arg(&setup)
        .arg("-o")
        .arg(&grids)
        .assert()
        .success();
    for k in 0..3 {
        let g =
            videomocap_volume::VoxelGrid::load(&grids.join(format!("frame_{k:04}.voxels.json")))
                .unwrap();
        assert!(g.count() > 500, "frame {k}: {} voxels", g.count());
    }
    let carve = |setup: &std::path::Path| {
        let o = videomocap()
            .arg("carve")
            .arg(setup)
            .arg("-o")
            .arg(&grids)
            .output()
            .unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    // A mask of the wrong size is named.
    let mask = setup.join("masks/cam1/frame_0002.png");
    image::GrayImage::new(10, 10).save(&mask).unwrap();
    let (code, e) = carve(&setup);
    assert_eq!(code, Some(2), "{e}");
    assert!(e.contains("frame_0002.png") && e.contains("10×10"), "{e}");
    // One mask fewer for one camera.
    std::fs::remove_file(&mask).unwrap();
    let (code, e) = carve(&setup);
    assert_eq!(code, Some(2), "{e}");
    assert!(e.contains("cam1") && e.contains("2 masks"), "{e}");
    // No box to carve.
    let cameras = setup.join("cameras.json");
    let text = std::fs::read_to_string(&cameras).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json.as_object_mut().unwrap().remove("bounds_m");
    std::fs::write(&cameras, json.to_string()).unwrap();
    let (code, e) = carve(&setup);
    assert_eq!(code, Some(2), "{e}");
    assert!(e.contains("cameras.json") && e.contains("bounds_m"), "{e}");
}

/// Silhouettes with a second person in them (the synthetic faults): `carve --person`
/// keeps the blob at the point given, even where the other is as large, says what it dropped,
/// and refuses a point that is not X,Y,Z.
#[test]
fn carve_keeps_the_person_pointed_at_and_reports_the_other_blob() {
    let tmp = tempfile::tempdir().unwrap();
    let vols = tmp.path().join("vols");
    synth_carving_setup(&vols, 2, 4, true);
    let truth = Skeleton3d::load(&vols.join("truth.skeleton3d.json")).unwrap();
    let grids = tmp.path().join("grids");
    for (side, x) in [("the marcher", 0.0), ("the other", 1.2)] {
        let pelvis = truth.frames[0].points[Joint::Pelvis];
        let o = videomocap()
            .args(["carve", "--person"])
            .arg(format!("{},{},{}", pelvis.x + x, pelvis.y, pelvis.z))
            .arg(vols.join("carve"))
            .arg("-o")
            .arg(&grids)
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{e}");
        assert!(
            e.contains("dropped other blobs on 2 of 2 frames") && e.contains("nearest --person"),
            "{e}"
        );
        let g = videomocap_volume::VoxelGrid::load(&grids.join("frame_0000.voxels.json")).unwrap();
        let c = g.centres();
        let mean_x = c.iter().map(|p| p.x).sum::<f64>() / c.len().max(1) as f64;
        assert!(
            (mean_x - pelvis.x - x).abs() < 0.3,
            "{side}: carved blob centred at x = {mean_x:.2}, pelvis at {:.2}",
            pelvis.x + x
        );
    }
    let o = videomocap()
        .args(["carve", "--person", "1,2"])
        .arg(vols.join("carve"))
        .arg("-o")
        .arg(&grids)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--person must be X,Y,Z"));
}
