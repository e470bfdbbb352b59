//! `videomocap-bench speed track`: issue 95's table. Whole processes on the same clips, back to
//! back in one run: `videomocap track` with the pose network, `videomocap track --no-network`,
//! and MediaPipe Pose (`scripts/mediapipe_baseline.py`: its own detector and the same BlazePose
//! full model, TFLite) when `mediapipe` imports. Each process runs `--runs` times, the three
//! taking turns so that the machine's load falls on all alike; the table gives the medians of
//! wall and CPU time (user + system, the process and its children) and the ratios to
//! MediaPipe's, which are what carry over from a shared, noisy machine.

use crate::args::{BenchArgs, GlobalArgs};
use crate::{ExitError, say};
use anyhow::{Context, anyhow};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use videomocap_testkit::repo_root;
use videomocap_testkit::synth::{Surface, SynthParams, VideoOutput, render_clip};

/// One clip of the table: its label, video and marks.
struct Clip {
    label: String,
    video: PathBuf,
    marks: PathBuf,
}

/// Wall and CPU seconds of one process.
#[derive(Debug, Clone, Copy)]
struct Timing {
    wall_s: f64,
    cpu_s: f64,
}

/// CPU seconds (user + system) used so far by this process's waited-for children.
#[allow(unsafe_code)] // getrusage: std has no safe way to read children's CPU time
fn children_cpu_s() -> f64 {
    // SAFETY: getrusage writes one plain struct that we own.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: RUSAGE_CHILDREN is a valid `who`, `usage` is a valid pointer.
    let rc = unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) };
    if rc != 0 {
        return f64::NAN;
    }
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(usage.ru_utime) + secs(usage.ru_stime)
}

/// Runs `cmd` to the end and times it; a failure names the command and shows its stderr.
fn timed(mut cmd: Command) -> anyhow::Result<Timing> {
    let cpu0 = children_cpu_s();
    let t0 = Instant::now();
    let out = cmd.output().with_context(|| format!("running {cmd:?}"))?;
    let wall_s = t0.elapsed().as_secs_f64();
    if !out.status.success() {
        return Err(anyhow!(
            "{cmd:?} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(Timing {
        wall_s,
        cpu_s: children_cpu_s() - cpu0,
    })
}

/// The median of `v` (the mean of the middle two for an even count; NaN for none).
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The `videomocap` binary built beside this tool (same profile).
fn videomocap_exe() -> anyhow::Result<PathBuf> {
    let me = std::env::current_exe().context("finding this program")?;
    let exe = me.with_file_name("videomocap");
    if !exe.is_file() {
        return Err(anyhow!(
            "{} is missing: build it with the same profile (cargo build --release -p videomocap)",
            exe.display()
        ));
    }
    Ok(exe)
}

/// The clips: a synthetic 640×480 walk of 100 frames (rendered here) and the real 1080×1920
/// portrait sample (100 frames).
fn clips(dir: &Path, global: &GlobalArgs) -> anyhow::Result<Vec<Clip>> {
    say(
        global,
        "rendering two 640×480 synthetic walks of 100 frames …",
    );
    let params = SynthParams {
        frames: 100,
        output: VideoOutput::Mp4,
        ..SynthParams::default()
    };
    let out = dir.join("synth640");
    let r = render_clip(&params, &out, &mut |_, _| {}, &AtomicBool::new(false))?;
    // The same walk drawn as one of suite v4's people (MakeHuman's mesh): the network, trained
    // on people, is steadier on it than on the capsule mannequin, and leaves out more frames.
    let person = SynthParams {
        surface: Surface::Mesh,
        ..params
    };
    let p = render_clip(
        &person,
        &dir.join("person640"),
        &mut |_, _| {},
        &AtomicBool::new(false),
    )?;
    let real = repo_root().join("sample_videos/pose2sim_balancing_cam01");
    Ok(vec![
        Clip {
            label: "640×480, 100 frames (synthetic walk)".into(),
            video: r.video,
            marks: r.marks,
        },
        Clip {
            label: "640×480, 100 frames (person walk)".into(),
            video: p.video,
            marks: p.marks,
        },
        Clip {
            label: "1080×1920 portrait, 100 frames (real sample)".into(),
            video: real.join("video.mp4"),
            marks: real.join("marks.json"),
        },
    ])
}

/// The three processes of one clip, in the order they take turns.
fn commands(clip: &Clip, dir: &Path, mediapipe: bool) -> anyhow::Result<Vec<Command>> {
    let exe = videomocap_exe()?;
    let track = |no_network: bool| {
        let mut c = Command::new(&exe);
        c.arg("track")
            .arg(&clip.video)
            .arg("--marks")
            .arg(&clip.marks)
            .arg("-o")
            .arg(dir.join("tracks2d.json"))
            .arg("--quiet");
        if no_network {
            c.arg("--no-network");
        }
        c
    };
    let mut out = vec![track(false), track(true)];
    if mediapipe {
        let jobs = dir.join("mediapipe-jobs.json");
        let job = serde_json::json!([{
            "name": clip.label,
            "video": clip.video,
            "out": dir.join("mediapipe.json"),
        }]);
        std::fs::write(&jobs, job.to_string())?;
        let mut c = Command::new("python3");
        c.arg(repo_root().join("scripts/mediapipe_baseline.py"))
            .arg(&jobs);
        out.push(c);
    }
    Ok(out)
}

/// Runs the table (see the module's text).
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let runs = a.runs.max(1);
    let dir = tempfile::tempdir().map_err(ExitError::failed)?;
    let clips = clips(dir.path(), global).map_err(ExitError::failed)?;
    let mediapipe = Command::new("python3")
        .args(["-c", "import mediapipe, cv2"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !mediapipe {
        say(global, "MediaPipe not installed: its column is left out");
    }
    let mut rows = Vec::new();
    for clip in &clips {
        let mut times: Vec<Vec<Timing>> = Vec::new();
        for k in 0..runs {
            say(global, &format!("{}: run {}/{runs} …", clip.label, k + 1));
            let cmds = commands(clip, dir.path(), mediapipe).map_err(ExitError::failed)?;
            times.resize(cmds.len(), Vec::new());
            for (i, cmd) in cmds.into_iter().enumerate() {
                times[i].push(timed(cmd).map_err(ExitError::failed)?);
            }
        }
        let med: Vec<Timing> = times
            .iter()
            .map(|t| Timing {
                wall_s: median(t.iter().map(|x| x.wall_s).collect()),
                cpu_s: median(t.iter().map(|x| x.cpu_s).collect()),
            })
            .collect();
        rows.push((clip.label.clone(), med));
    }
    print_table(&rows, runs, global);
    Ok(())
}

fn print_table(rows: &[(String, Vec<Timing>)], runs: usize, global: &GlobalArgs) {
    if global.json {
        let v: Vec<_> = rows
            .iter()
            .map(|(label, t)| {
                let cell = |x: Option<&Timing>| {
                    x.map(|x| serde_json::json!({"wall_s": x.wall_s, "cpu_s": x.cpu_s}))
                };
                serde_json::json!({
                    "clip": label,
                    "runs": runs,
                    "network": cell(t.first()),
                    "no_network": cell(t.get(1)),
                    "mediapipe": cell(t.get(2)),
                })
            })
            .collect();
        println!("{}", serde_json::Value::Array(v));
        return;
    }
    println!(
        "whole processes, medians of {runs} runs taking turns; wall s / CPU s, and ours ÷ MediaPipe's"
    );
    println!(
        "{:<46} {:>20} {:>14} {:>14} {:>18}",
        "clip", "track (network)", "--no-network", "MediaPipe", "network ÷ MP wall/CPU"
    );
    for (label, t) in rows {
        let cell = |x: Option<&Timing>| {
            x.map_or_else(
                || "-".to_string(),
                |x| format!("{:.2} / {:.2}", x.wall_s, x.cpu_s),
            )
        };
        let ratio = match (t.first(), t.get(2)) {
            (Some(o), Some(m)) => format!("{:.2} / {:.2}", o.wall_s / m.wall_s, o.cpu_s / m.cpu_s),
            _ => "-".into(),
        };
        println!(
            "{:<46} {:>20} {:>14} {:>14} {:>18}",
            label,
            cell(t.first()),
            cell(t.get(1)),
            cell(t.get(2)),
            ratio
        );
    }
}

/// `speed network`: the network's operator counts (the ONNX file, the plan the product runs)
/// and the time of each kind of operator, on one thread and on two.
pub(crate) fn run_network(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    use videomocap_core::network::PoseNetwork;
    let runs = a.runs.max(1);
    for threads in [1, 2] {
        say(
            global,
            &format!("profiling the network on {threads} thread(s) …"),
        );
        let network = PoseNetwork::bundled()
            .map_err(ExitError::failed)?
            .with_threads(threads);
        let p = network.profile(runs).map_err(ExitError::failed)?;
        if threads == 1 {
            let total = |m: &std::collections::BTreeMap<String, usize>| m.values().sum::<usize>();
            println!("ONNX file, {} nodes: {:?}", total(&p.onnx_ops), p.onnx_ops);
            println!("plan, {} nodes: {:?}", total(&p.plan_ops), p.plan_ops);
        }
        println!(
            "{threads} thread(s): {:.1} ms a run (median of {runs}); per operator:",
            p.run_ms
        );
        let sum: f64 = p.times.iter().map(|t| t.ms).sum();
        for t in &p.times {
            println!(
                "  {:<28} {:>4} nodes {:>8.2} ms {:>6.1} %",
                t.op,
                t.nodes,
                t.ms,
                100.0 * t.ms / sum
            );
        }
    }
    Ok(())
}
