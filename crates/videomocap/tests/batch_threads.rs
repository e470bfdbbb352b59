//! A Slurm task given one CPU (`SLURM_CPUS_PER_TASK=1`) on a node whose cores it could all
//! use (no pinning) runs on one core: every pool of the run (the video decoder, the tracker,
//! the pose network, rayon's global pool) keeps to one thread at a time. Watched from outside
//! through `/proc/<pid>/task/*/stat`: how many of the process's threads are running or ready
//! to run (state `R`) at each look. A thread that is ready but waiting for a core counts as
//! well, so the measure does not depend on how busy the machine is.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Duration;
use videomocap_testkit::synth::{
    MotionSource, ProceduralMotion, SynthParams, VideoOutput, View, render_clip,
};

/// The threads of process `pid` in state `R` now (`None` once it has gone).
fn running_threads(pid: u32) -> Option<usize> {
    let tasks = std::fs::read_dir(format!("/proc/{pid}/task")).ok()?;
    let running = tasks
        .filter_map(Result::ok)
        .filter_map(|t| std::fs::read_to_string(t.path().join("stat")).ok())
        .filter(|stat| {
            // "tid (name) S …": the state follows the name's closing parenthesis.
            stat.rfind(')')
                .and_then(|i| stat[i + 1..].trim_start().chars().next())
                == Some('R')
        })
        .count();
    Some(running)
}

/// Runs a batch of one row on `clip` with `args` and `env`, looking at its threads every
/// millisecond; returns the share of looks that found two or more running, and the threads
/// the row's status reports.
fn share_of_parallel_looks(clip: &Path, args: &[&str], env: &[(&str, &str)]) -> (f64, u64) {
    let out = tempfile::tempdir().unwrap();
    let m = clip.join("manifest.csv");
    std::fs::write(&m, "video,keys,id\nvideo.mp4,marks.json,take\n").unwrap();
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("videomocap"))
        .args(["--quiet", "batch"])
        .arg(&m)
        .arg("--out-dir")
        .arg(out.path())
        .args(args)
        .env_remove("SLURM_CPUS_PER_TASK")
        .envs(env.iter().copied())
        .spawn()
        .unwrap();
    let (mut looks, mut parallel) = (0usize, 0usize);
    while child.try_wait().unwrap().is_none() {
        if let Some(n) = running_threads(child.id()) {
            looks += 1;
            parallel += usize::from(n >= 2);
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(child.wait().unwrap().success());
    let status: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.path().join("take/status.json")).unwrap(),
    )
    .unwrap();
    assert!(looks > 50, "too few looks ({looks}) to judge");
    (
        parallel as f64 / looks as f64,
        status["threads"].as_u64().unwrap_or(0),
    )
}

#[test]
fn a_task_given_one_cpu_runs_on_one_core() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if cores < 2 || !Path::new("/proc/self/task").exists() {
        eprintln!("skipped: needs Linux and at least 2 CPUs ({cores})");
        return;
    }
    // An H.264 clip, so FFmpeg's decoder threads are in the run, and the pose network on.
    let clip = tempfile::tempdir().unwrap();
    let params = SynthParams {
        motion: MotionSource::Procedural(ProceduralMotion::Wave),
        frames: 24,
        view: View::Oblique,
        width: 320,
        height: 240,
        focal_px: 300.0,
        person_px: 200.0,
        output: VideoOutput::Mp4,
        ..SynthParams::default()
    };
    render_clip(
        &params,
        clip.path(),
        &mut |_, _| {},
        &AtomicBool::new(false),
    )
    .unwrap();

    let (one, threads) = share_of_parallel_looks(clip.path(), &[], &[("SLURM_CPUS_PER_TASK", "1")]);
    assert_eq!(threads, 1);
    // The same run on two threads shows the measure sees parallel work when there is some.
    let (two, threads) = share_of_parallel_looks(clip.path(), &["--threads", "2"], &[]);
    assert_eq!(threads, 2);
    eprintln!("looks with ≥ 2 threads running: one CPU {one:.3}, two {two:.3}");
    assert!(
        two > 0.2,
        "two threads were seldom busy together ({two:.3})"
    );
    assert!(
        one < 0.03,
        "with one CPU, two threads ran together in {:.1} % of looks",
        100.0 * one
    );
}
