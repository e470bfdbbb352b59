//! `videomocap track` end to end: marks, keys with a correction, and a project re-tracked.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use assert_cmd::Command;
use videomocap_core::formats::FrameIndex;
use videomocap_core::formats::{Marks, Tracks2d};
use videomocap_core::skeleton::Joint;
use videomocap_testkit::synth::{ProceduralMotion, View, render_small_clip};

/// A 320×240 PNG sequence of `frames` frames of `motion` seen from `view`, with its marks.
fn render(dir: &std::path::Path, motion: ProceduralMotion, frames: usize, view: View) {
    render_small_clip(dir, motion, frames, view).unwrap();
}

#[test]
fn the_track_command_writes_tracks_that_load() {
    let dir = tempfile::tempdir().unwrap();
    render(dir.path(), ProceduralMotion::Wave, 8, View::Oblique);
    let out = dir.path().join("tracks2d.json");
    let status = Command::cargo_bin("videomocap")
        .unwrap()
        .args(["--quiet", "track"])
        .arg(dir.path().join("frames"))
        .arg("--marks")
        .arg(dir.path().join("marks.json"))
        .arg("-o")
        .arg(&out)
        .arg("--threads")
        .arg("1")
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let t = Tracks2d::load(&out).unwrap();
    assert_eq!(t.frames.len(), 8);
    assert_eq!((t.source.width, t.source.height), (320, 240));
    // The same joints as keys, with a correction on frame 5; then the project re-tracked.
    let marks = Marks::load(&dir.path().join("marks.json")).unwrap();
    let mut keys = videomocap_core::formats::KeyFrames::from_marks(&marks);
    let wrist = t.frames[5].points[Joint::LeftWrist].pos + nalgebra::Vector2::new(4.0, 0.0);
    keys.set(FrameIndex(5), Joint::LeftWrist, wrist);
    keys.save(&dir.path().join("keys.json")).unwrap();
    let cli = |args: &[&std::ffi::OsStr]| {
        let o = Command::cargo_bin("videomocap")
            .unwrap()
            .args(["--quiet", "track"])
            .args(args)
            .args(["--threads", "1"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let frames = dir.path().join("frames");
    let keyed = dir.path().join("keyed.json");
    let keys_path = dir.path().join("keys.json");
    cli(&[
        frames.as_os_str(),
        "--keys".as_ref(),
        keys_path.as_os_str(),
        "-o".as_ref(),
        keyed.as_os_str(),
    ]);
    let k = Tracks2d::load(&keyed).unwrap();
    assert_eq!(k.frames[5].points[Joint::LeftWrist].pos, wrist);
    let mut project = videomocap_core::project::Project::new(frames.clone());
    project.keys = keys;
    let project_path = dir.path().join("p.json");
    project.save(&project_path).unwrap();
    cli(&[project_path.as_os_str()]);
    let again = videomocap_core::project::Project::load(&project_path).unwrap();
    let tracks = again.tracks.expect("tracks saved into the project");
    assert_eq!(tracks.frames, k.frames);
}
