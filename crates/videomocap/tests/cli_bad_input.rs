//! Bad input through the command line: each case exits with code 2 and a message naming the
//! file and the problem, never a panic.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use assert_cmd::Command;
use std::path::{Path, PathBuf};

fn sample_dir() -> PathBuf {
    videomocap_testkit::repo_root().join("sample_videos/pose2sim_balancing_cam01")
}

/// Runs the binary and returns (exit code, stderr).
fn run(args: &[&str]) -> (i32, String) {
    let out = Command::cargo_bin("videomocap")
        .unwrap()
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

fn assert_bad(args: &[&str], must_contain: &[&str]) {
    let (code, stderr) = run(args);
    assert_eq!(code, 2, "{args:?}: {stderr}");
    for s in must_contain {
        assert!(stderr.contains(s), "{args:?}: expected {s:?} in {stderr:?}");
    }
}

#[test]
fn a_missing_path_is_named() {
    assert_bad(
        &["info", "no/such/video.mp4"],
        &["no/such/video.mp4", "No such file"],
    );
}

#[test]
fn a_file_that_is_not_a_video_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("notes.mp4");
    std::fs::write(&p, "this is not a video\n".repeat(100)).unwrap();
    let ps = p.to_str().unwrap();
    assert_bad(&["info", ps], &[ps, "not a video"]);
}

#[test]
fn a_truncated_video_is_named_or_opens_shorter() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(sample_dir().join("video.mp4")).unwrap();
    let p = dir.path().join("half.mp4");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    let ps = p.to_str().unwrap();
    // The sample keeps its index at the end: half a file has none.
    assert_bad(&["info", ps], &[ps]);
}

#[test]
fn a_zero_frame_video_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("empty.mp4");
    let ok = std::process::Command::new("ffmpeg")
        .args([
            "-loglevel",
            "error",
            "-y",
            "-f",
            "lavfi",
            "-i",
            "testsrc2=size=64x48:rate=10",
            "-frames:v",
            "0",
            "-c:v",
            "libx264",
        ])
        .arg(&p)
        .status()
        .expect("the ffmpeg command is needed for this test (scripts/setup.sh installs it)");
    assert!(ok.success());
    let ps = p.to_str().unwrap();
    assert_bad(&["info", ps], &[ps]);
}

#[test]
fn image_directories_with_no_images_or_mixed_sizes_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dir.path().to_str().unwrap().to_owned();
    assert_bad(&["info", &ds], &[&ds, "no PNG or JPEG"]);
    image::RgbImage::new(8, 6)
        .save(dir.path().join("a1.png"))
        .unwrap();
    image::RgbImage::new(8, 7)
        .save(dir.path().join("a2.png"))
        .unwrap();
    assert_bad(&["info", &ds], &["a1.png", "a2.png", "8×7"]);
}

/// The sample's marks.json as JSON.
fn sample_marks() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(sample_dir().join("marks.json")).unwrap())
        .unwrap()
}

/// Writes `v` to a file `name` in a new temporary folder; returns the folder and the path.
fn written(name: &str, v: &serde_json::Value) -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    std::fs::write(&p, v.to_string()).unwrap();
    let s = p.to_str().unwrap().to_owned();
    (dir, s)
}

/// The sample's marks edited by `edit`, written to `name`.
fn marks_case(
    name: &str,
    edit: impl FnOnce(&mut serde_json::Value),
) -> (tempfile::TempDir, String) {
    let mut v = sample_marks();
    edit(&mut v);
    written(name, &v)
}

#[test]
fn bad_marks_are_named_with_the_joint() {
    let video = sample_dir().join("video.mp4");
    let video = video.to_str().unwrap();
    let (_d, missing) = marks_case("missing.json", |v| {
        v["joints"].as_object_mut().unwrap().remove("left_knee");
    });
    assert_bad(
        &["track", video, "--marks", &missing, "-o", "t.json"],
        &[&missing, "left_knee", "missing"],
    );
    let (_d, outside) = marks_case("outside.json", |v| {
        v["joints"]["right_wrist"] = serde_json::json!([2000.0, 10.0])
    });
    assert_bad(
        &["track", video, "--marks", &outside, "-o", "t.json"],
        &[&outside, "right_wrist", "outside"],
    );
    let (_d, version) = marks_case("v9.json", |v| v["version"] = serde_json::json!(9));
    assert_bad(
        &["track", video, "--marks", &version, "-o", "t.json"],
        &[&version, "version 9"],
    );
    let (_d, unknown) = marks_case("unknown.json", |v| {
        v["joints"]["nose"] = serde_json::json!([1.0, 1.0])
    });
    assert_bad(
        &["track", video, "--marks", &unknown, "-o", "t.json"],
        &[&unknown, "nose"],
    );
}

/// A keys file made from the sample's marks plus `extra` keys.
fn keys_case(name: &str, extra: serde_json::Value) -> (tempfile::TempDir, String) {
    let mut keys = vec![serde_json::json!({"frame": 0, "joints": sample_marks()["joints"]})];
    keys.extend(extra.as_array().unwrap().iter().cloned());
    written(
        name,
        &serde_json::json!({"format": "videomocap.keys", "version": 1, "keys": keys}),
    )
}

#[test]
fn bad_keys_are_named_with_the_frame_and_joint() {
    let video = sample_dir().join("video.mp4");
    let video = video.to_str().unwrap();
    let key = |frame: usize, joint: &str, x: f64| serde_json::json!({"frame": frame, "joints": {joint: [x, 100.0]}});
    let (_d, late) = keys_case("late.json", serde_json::json!([key(500, "neck", 10.0)]));
    assert_bad(
        &["track", video, "--keys", &late, "-o", "t.json"],
        &[&late, "frame 500", "100 frames"],
    );
    let (_d, twice) = keys_case(
        "twice.json",
        serde_json::json!([key(40, "left_wrist", 10.0), key(40, "left_wrist", 90.0)]),
    );
    assert_bad(
        &["track", video, "--keys", &twice, "-o", "t.json"],
        &[&twice, "frame 40", "left_wrist", "placed twice"],
    );
    let (_d, outside) = keys_case("outside.json", serde_json::json!([key(3, "neck", 5000.0)]));
    assert_bad(
        &["track", video, "--keys", &outside, "-o", "t.json"],
        &[&outside, "neck", "outside", "frame 3"],
    );
    let (_d, unknown) = keys_case("unknown.json", serde_json::json!([key(3, "nose", 5.0)]));
    assert_bad(
        &["track", video, "--keys", &unknown, "-o", "t.json"],
        &[&unknown, "nose"],
    );
    let (_d, fine) = keys_case("fine.json", serde_json::json!([]));
    assert_bad(&["track", video, "--keys", &fine], &["--output"]);
    assert_bad(&["track", video, "-o", "t.json"], &["--marks", "--keys"]);
}

#[test]
fn a_tracker_setting_out_of_its_range_is_named_with_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let video = sample_dir().join("video.mp4");
    let marks = sample_dir().join("marks.json");
    let settings = dir.path().join("tracker.json");
    std::fs::write(&settings, r#"{"short_penalty": -3}"#).unwrap();
    let ss = settings.to_str().unwrap();
    let out = dir.path().join("t.json");
    let args = [
        "track",
        video.to_str().unwrap(),
        "--marks",
        marks.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--tracker-settings",
        ss,
    ];
    assert_bad(&args, &[ss, "short_penalty", "0 or more", "-3"]);
    std::fs::write(&settings, r#"{"weak_reliability": 1.5}"#).unwrap();
    assert_bad(&args, &[ss, "weak_reliability", "between 0 and 1"]);
    assert!(!out.exists());
}

#[test]
fn malformed_json_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("broken.json");
    std::fs::write(&p, "{\"format\": \"videomocap.tracks2d\", ").unwrap();
    let ps = p.to_str().unwrap();
    assert_bad(&["lift", ps, "-o", "s.json"], &[ps, "JSON"]);
    assert_bad(&["export", ps, "--bvh", "m.bvh"], &[ps]);
}

#[test]
fn info_prints_the_samples_portrait_size_and_json() {
    let video = sample_dir().join("video.mp4");
    let out = Command::cargo_bin("videomocap")
        .unwrap()
        .args(["info", video.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (
            v["width"].as_u64(),
            v["height"].as_u64(),
            v["frame_count"].as_u64()
        ),
        (Some(1080), Some(1920), Some(100))
    );
    assert_eq!(v["fps"].as_f64(), Some(60.0));
}

#[test]
fn lift_writes_a_skeleton_and_refuses_a_bad_focal_length() {
    let dir = tempfile::tempdir().unwrap();
    let gt_path = videomocap_testkit::repo_root().join("sample_videos/synth_walk_oblique/gt.json");
    let gt = videomocap_testkit::synth::GroundTruth::load(&gt_path).unwrap();
    let tracks = videomocap_testkit::eval::pose3d::tracks_from_truth(&gt, 0.0, 1);
    let tp = dir.path().join("tracks2d.json");
    tracks.save(&tp).unwrap();
    let out = dir.path().join("skeleton3d.json");
    let (tp, outs) = (tp.to_str().unwrap(), out.to_str().unwrap());
    assert_bad(
        &["lift", tp, "-o", outs, "--focal-px=-3"],
        &["--focal-px", "positive"],
    );
    assert!(!out.exists());
    // A settings file with a weight out of its range is named with the setting.
    let settings = dir.path().join("settings.json");
    std::fs::write(&settings, r#"{"arm_swing": -5}"#).unwrap();
    let ss = settings.to_str().unwrap();
    assert_bad(
        &["lift", tp, "-o", outs, "--lift-settings", ss],
        &[ss, "arm_swing", "0 or more"],
    );
    assert!(!out.exists());
    // An older file: its retired settings are named and ignored, a renamed one carries over.
    std::fs::write(
        &settings,
        r#"{"ambiguity": {"elbow": -5, "contact": 3}, "calibration_tolerance_px": 2}"#,
    )
    .unwrap();
    let (code, stderr) = run(&["lift", tp, "-o", outs, "--lift-settings", ss]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("retired") && stderr.contains("ambiguity.elbow, calibration_tolerance_px"),
        "{stderr}"
    );
    assert!(!stderr.contains("ambiguity.contact"), "{stderr}");
    std::fs::remove_file(&out).unwrap();
    // A name that never was a setting is refused.
    std::fs::write(&settings, r#"{"elbow_weight": 1}"#).unwrap();
    assert_bad(
        &["lift", tp, "-o", outs, "--lift-settings", ss],
        &[ss, "elbow_weight"],
    );
    assert!(!out.exists());
    let (code, stderr) = run(&[
        "lift",
        tp,
        "-o",
        outs,
        "--focal-px",
        "600",
        "--height-m",
        "1.75",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let s = videomocap_core::formats::Skeleton3d::load(&out).unwrap();
    assert_eq!(s.frames.len(), gt.frames.len());
    assert_eq!(s.camera.focal_px, 600.0);
    assert!(stderr.contains("lifted 60 frames"), "{stderr}");
    // The lengths read are said, each with where it came from.
    assert!(
        stderr.contains("body lengths:") && stderr.contains("thigh"),
        "{stderr}"
    );
    // Known lengths: an unknown bone names the file and the key; one the video contradicts
    // names the part; a good one is kept.
    let lengths = dir.path().join("lengths.json");
    let ls = lengths.to_str().unwrap();
    std::fs::write(&lengths, r#"{"left_thigh": 0.4}"#).unwrap();
    assert_bad(
        &["lift", tp, "-o", outs, "--lengths", ls],
        &[ls, "unknown bone \"left_thigh\""],
    );
    std::fs::write(
        &lengths,
        r#"{"left_hip-left_knee": 0.2, "left_knee-left_ankle": 0.4, "shoulder_width": 0.36}"#,
    )
    .unwrap();
    assert_bad(
        &["lift", tp, "-o", outs, "--lengths", ls],
        &["thigh", "shorter than the video shows"],
    );
    std::fs::write(&lengths, r#"{"left_hip-left_knee": 0.43}"#).unwrap();
    let (code, stderr) = run(&["lift", tp, "-o", outs, "--lengths", ls]);
    assert_eq!(code, 0, "{stderr}");
    let s = videomocap_core::formats::Skeleton3d::load(&out).unwrap();
    // Kept, but for the refinement's own slack on every length (1 %).
    let thigh = s.bone_lengths_m["left_hip-left_knee"];
    assert!((thigh / 0.43 - 1.0).abs() < 0.011, "{thigh}");

    // lift --bvh, then export of the same skeleton to every format.
    let bvh = dir.path().join("lifted.bvh");
    let (code, stderr) = run(&["lift", tp, "-o", outs, "--bvh", bvh.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    let read = videomocap_core::bvh::Bvh::load(&bvh).unwrap();
    assert_eq!(read.frame_count(), 60);
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let out = Command::cargo_bin("videomocap")
        .unwrap()
        .args([
            "--json",
            "export",
            outs,
            "--bvh",
            &p("m.bvh"),
            "--csv",
            &p("j.csv"),
            "--trc",
            &p("m.trc"),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["frames"].as_u64(), Some(60));
    assert!(v["bvh_round_trip_mm"].as_f64().unwrap() < 1.0);
    assert_eq!(
        std::fs::read_to_string(p("j.csv")).unwrap().lines().count(),
        1 + 60 * 16
    );
    assert!(
        std::fs::read_to_string(p("m.trc"))
            .unwrap()
            .starts_with("PathFileType\t4")
    );
    let (code, stderr) = run(&["export", tp, "--csv", &p("t.csv")]);
    assert_eq!(code, 0, "{stderr}");
    let csv = std::fs::read_to_string(p("t.csv")).unwrap();
    assert!(csv.starts_with(
        "frame,time_s,joint,x_px,y_px,confidence,interpolated,off_frame,lost\n0,0.000000,head_top,"
    ));
    // What export cannot do is refused with the file named.
    assert_bad(&["export", outs], &["nothing to write"]);
    assert_bad(&["export", tp, "--bvh", &p("x.bvh")], &[tp, "skeleton3d"]);
    let mut old = videomocap_core::formats::Skeleton3d::load(Path::new(outs)).unwrap();
    old.fps = None;
    let old_path = p("old.json");
    old.save(Path::new(&old_path)).unwrap();
    assert_bad(
        &["export", &old_path, "--bvh", &p("x.bvh")],
        &[&old_path, "--fps"],
    );
    assert!(!Path::new(&p("x.bvh")).exists());
    let (code, stderr) = run(&["export", &old_path, "--bvh", &p("x.bvh"), "--fps", "30"]);
    assert_eq!(code, 0, "{stderr}");
    // The Mixamo rig: the same motion under Mixamo's names; an unknown rig is refused with
    // the choices named.
    let (code, stderr) = run(&["export", outs, "--bvh", &p("mx.bvh"), "--rig", "mixamo"]);
    assert_eq!(code, 0, "{stderr}");
    let mixamo = std::fs::read_to_string(p("mx.bvh")).unwrap();
    assert!(mixamo.starts_with("HIERARCHY\nROOT mixamorig:Hips\n"));
    assert!(
        mixamo.contains("JOINT mixamorig:LeftFoot") && mixamo.contains("JOINT mixamorig:Spine2")
    );
    let cmu = std::fs::read_to_string(p("m.bvh")).unwrap();
    assert_eq!(
        cmu.split("MOTION").nth(1),
        mixamo.split("MOTION").nth(1),
        "the same motion"
    );
    let (code, stderr) = run(&["export", outs, "--bvh", &p("no.bvh"), "--rig", "maya"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("cmu, mixamo"), "{stderr}");
    assert!(!Path::new(&p("no.bvh")).exists());
}

#[test]
fn run_tracks_lifts_and_exports_the_synthetic_sample() {
    let dir = tempfile::tempdir().unwrap();
    let sample = videomocap_testkit::repo_root().join("sample_videos/synth_walk_oblique");
    let video = sample.join("video.mp4");
    let marks = sample.join("marks.json");
    let (code, stderr) = run(&[
        "run",
        video.to_str().unwrap(),
        "--marks",
        marks.to_str().unwrap(),
        "--out-dir",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    for f in [
        "tracks2d.json",
        "tracks2d.csv",
        "skeleton3d.json",
        "motion.bvh",
        "joints3d.csv",
        "motion.trc",
    ] {
        assert!(dir.path().join(f).exists(), "{f} missing; {stderr}");
    }
    let read = videomocap_core::bvh::Bvh::load(&dir.path().join("motion.bvh")).unwrap();
    assert_eq!(read.frame_count(), 60);
    assert!(
        stderr.contains("BVH read back: every joint within 0.0"),
        "{stderr}"
    );
}

#[test]
fn a_degenerate_key_triangle_is_named_with_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let gt_path = videomocap_testkit::repo_root().join("sample_videos/synth_walk_oblique/gt.json");
    let gt = videomocap_testkit::synth::GroundTruth::load(&gt_path).unwrap();
    let mut tracks = videomocap_testkit::eval::pose3d::tracks_from_truth(&gt, 0.0, 1);
    for f in &mut tracks.frames {
        let left = f.points[videomocap_core::skeleton::Joint::LeftShoulder];
        f.points.0[videomocap_core::skeleton::Joint::RightShoulder.index()] = left;
    }
    let tp = dir.path().join("flat.json");
    tracks.save(&tp).unwrap();
    let tp = tp.to_str().unwrap();
    let out = dir.path().join("s.json");
    assert_bad(
        &["lift", tp, "-o", out.to_str().unwrap(), "--fov-deg", "60"],
        &[tp, "shoulders"],
    );
}

/// The user binary lists the user's commands and nothing of the developer tool (benchmarks,
/// the synthetic renderer, the crash-safety writer live in `videomocap-bench`).
#[test]
fn help_lists_only_the_users_commands() {
    let o = Command::cargo_bin("videomocap")
        .unwrap()
        .arg("--help")
        .output()
        .unwrap();
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    for command in [
        "gui", "info", "track", "lift", "export", "run", "volume", "carve",
    ] {
        assert!(
            help.lines().any(|l| l.trim_start().starts_with(command)),
            "{command} missing from:\n{help}"
        );
    }
    for hidden in ["synth", "bench", "stress-write"] {
        assert!(
            !help.lines().any(|l| l.trim_start().starts_with(hidden)),
            "{hidden} listed in:\n{help}"
        );
        let o = Command::cargo_bin("videomocap")
            .unwrap()
            .arg(hidden)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{hidden} is still a command");
    }
}
