//! Crash safety: `videomocap-bench stress-write` saves a project (as the app's autosave and
//! File ▸ Save do) and writes BVH, CSV and TRC exports over and over; this test kills it with
//! SIGKILL at random moments, hundreds of times, and after every kill checks that the project
//! on disk loads and is one of the versions the writer made, and that every export reads back
//! whole. `VIDEOMOCAP_KILLS` sets the number of kills (default 200).

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use rand::{Rng, SeedableRng};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};
use videomocap_core::bvh::Bvh;
use videomocap_core::formats::FrameIndex;
use videomocap_core::formats::{Skeleton3d, Tracks2d};
use videomocap_core::project::Project;
use videomocap_core::skeleton::Joint;

fn seed(name: &str) -> String {
    std::fs::read_to_string(
        videomocap_testkit::repo_root()
            .join("tests/fuzz/seeds")
            .join(name),
    )
    .unwrap()
}

/// A project with `n` frames of tracks and skeleton (the seeds' three frames repeated), large
/// enough (300 frames: 0.4 MB) that a save takes long enough to be killed in the middle.
fn big_project(n: usize) -> Project {
    let path = Path::new("seed");
    let mut project = Project::parse(&seed("project/small.json"), path).unwrap();
    let mut tracks = Tracks2d::parse(&seed("tracks2d/three_frames.json"), path).unwrap();
    let mut skeleton = Skeleton3d::parse(&seed("skeleton3d/three_frames.json"), path).unwrap();
    tracks.frames = (0..n)
        .map(|i| {
            let mut f = tracks.frames[i % 3].clone();
            f.index = FrameIndex(i);
            f
        })
        .collect();
    tracks.source.frame_count = n;
    skeleton.frames = (0..n)
        .map(|i| {
            let mut f = skeleton.frames[i % 3].clone();
            f.index = FrameIndex(i);
            f
        })
        .collect();
    project.tracks = Some(Arc::new(tracks));
    project.skeleton = Some(Arc::new(skeleton));
    project
}

#[test]
fn killing_the_writer_never_leaves_a_torn_project_or_export() {
    let kills: usize = std::env::var("VIDEOMOCAP_KILLS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200);
    let dir = tempfile::tempdir().unwrap();
    // The app's recovery file name: what the next start would offer to recover.
    let file = dir.path().join("autosave.videomocap.json");
    let out = dir.path().join("exports");
    let original = big_project(300);
    let frames = 300;
    original.save(&file).unwrap();
    let exe = env!("CARGO_BIN_EXE_videomocap-bench");
    let writer = || {
        Command::new(exe)
            .args(["stress-write", file.to_str().unwrap(), "--out-dir"])
            .arg(&out)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap()
    };

    // One uninterrupted run: how long a save and an export take.
    let mut child = writer();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let mut last = Instant::now();
    let (mut save_time, mut export_time) = (Duration::ZERO, Duration::ZERO);
    for _ in 0..4 {
        let step = lines.next().unwrap().unwrap();
        let now = Instant::now();
        if step.starts_with("export") {
            save_time = save_time.max(now - last);
        } else if step.starts_with("save 2") {
            export_time = export_time.max(now - last);
        }
        last = now;
    }
    child.kill().unwrap();
    child.wait().unwrap();

    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let (mut one_key, mut all_keys) = (0, 0);
    let mut aimed = [0usize; 2];
    let temp_files = |dir: &Path| {
        std::fs::read_dir(dir)
            .map(|d| {
                d.filter(|e| {
                    e.as_ref()
                        .is_ok_and(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
                })
                .count()
            })
            .unwrap_or(0)
    };
    for kill in 0..kills {
        // Aim at a save or an export of round 1–3, somewhere inside it.
        let export = rng.random_bool(0.5);
        let round = rng.random_range(1..=3);
        let step = format!("{} {round}", if export { "export" } else { "save" });
        let span = if export { export_time } else { save_time };
        let wait = rng.random_range(Duration::ZERO..=span);
        let mut child = writer();
        let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
        // The writer must reach the step (a writer that stopped early would test nothing).
        assert!(
            lines.any(|line| line.is_ok_and(|l| l == step)),
            "kill {kill}: the writer ended before {step}"
        );
        std::thread::sleep(wait);
        child.kill().unwrap(); // SIGKILL on Unix
        child.wait().unwrap();
        aimed[usize::from(export)] += 1;

        let project = Project::load(&file).unwrap_or_else(|e| {
            panic!("kill {kill} after {wait:?}: the project does not load: {e}")
        });
        assert_eq!(
            project.tracks, original.tracks,
            "kill {kill}: tracks changed"
        );
        assert_eq!(
            project.skeleton, original.skeleton,
            "kill {kill}: skeleton changed"
        );
        // One version of the writer's: all corrections carry the same round number, on one
        // frame (odd rounds) or on every frame but the marks' (even rounds).
        let rounds: Vec<f64> = project
            .keys
            .frames
            .iter()
            .filter(|(f, _)| **f != FrameIndex(0))
            .map(|(_, k)| k[Joint::LeftWrist].expect("the writer's correction").x)
            .collect();
        let round = rounds[0];
        assert!(
            rounds.iter().all(|&r| r == round),
            "kill {kill}: mixed rounds"
        );
        match (round as u64 % 2, rounds.len()) {
            (1, 1) => one_key += 1,
            (0, n) if n == frames - 1 => all_keys += 1,
            other => panic!(
                "kill {kill}: round {round} with {} corrections ({other:?})",
                rounds.len()
            ),
        }
        if out.join("motion.bvh").exists() {
            let bvh = Bvh::load(&out.join("motion.bvh"))
                .unwrap_or_else(|e| panic!("kill {kill}: the BVH does not load: {e}"));
            assert_eq!(bvh.frame_count(), frames, "kill {kill}");
        }
        // The CSV has a row per joint and frame, the TRC a row per frame under 6 header lines.
        for (name, lines) in [
            ("joints3d.csv", 16 * frames + 1),
            ("motion.trc", frames + 6),
        ] {
            if let Ok(text) = std::fs::read_to_string(out.join(name)) {
                assert!(text.ends_with('\n'), "kill {kill}: {name} ends mid-line");
                assert_eq!(text.lines().count(), lines, "kill {kill}: {name}");
            }
        }
    }
    // A kill in the middle of a write leaves its temporary file behind, never a torn target.
    let left = temp_files(dir.path()) + temp_files(&out);
    println!(
        "{kills} kills ({} aimed at project saves taking up to {save_time:?}, {} at exports \
         taking up to {export_time:?}): the project always loaded, whole ({one_key} from odd \
         rounds, {all_keys} from even ones); every export read back whole; {left} kills \
         landed mid-write (temporary files left behind)",
        aimed[0], aimed[1]
    );
    assert_eq!(one_key + all_keys, kills);
}
