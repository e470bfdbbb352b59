//! `videomocap bench`: speed figures printed as a table. Decoding is compared with the `ffmpeg`
//! command decoding the same file to RGB in the same run (ratios, not absolute times, are what
//! matter on a shared machine).

use crate::args::{BenchArgs, GlobalArgs};
use crate::{ExitError, say};
use anyhow::{Context, anyhow};
use std::path::Path;
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::synth::{SynthParams, VideoOutput, render_clip};

/// Says so when this is a debug build (its figures are not the product's).
pub(crate) fn note_debug_build(global: &GlobalArgs) {
    if cfg!(debug_assertions) {
        say(
            global,
            "note: this is a debug build; run `cargo run --release -p videomocap-bench -- …` for real figures",
        );
    }
}

/// Runs the benchmark `what` (track, correct, lift, volume, or all, decode, synth).
pub(crate) fn run(what: &str, a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    note_debug_build(global);
    if what == "track" {
        return crate::bench_track::run(a, global);
    }
    if what == "correct" {
        return crate::bench_correct::run(a, global);
    }
    if what == "lift" && a.network {
        let default = videomocap_core::lift::LiftParams::default().image_depth;
        return crate::bench_lift_network::run(
            a,
            global,
            a.depth_weights.as_deref().unwrap_or(&[default]),
        );
    }
    if what == "lift" {
        return crate::bench_lift::run(a, global);
    }
    if what == "volume" {
        return crate::bench_volume::run(a, global);
    }
    let dir = tempfile::tempdir().map_err(ExitError::failed)?;
    let mut rows: Vec<[String; 4]> = Vec::new();
    if matches!(what, "all" | "decode") {
        rows.extend(decode_rows(dir.path(), a.frames, global)?);
    }
    if matches!(what, "all" | "synth") {
        rows.extend(synth_rows(dir.path())?);
    }
    if rows.is_empty() {
        return Err(ExitError::bad_input(anyhow!(
            "speed {}: expected all, decode or synth",
            what
        )));
    }
    if global.json {
        let v: Vec<_> = rows
            .iter()
            .map(|r| serde_json::json!({"what": r[0], "ours": r[1], "ffmpeg": r[2], "ratio": r[3]}))
            .collect();
        println!("{}", serde_json::Value::Array(v));
    } else {
        println!(
            "{:<38} {:>16} {:>16} {:>8}",
            "measure", "videomocap", "ffmpeg", "ratio"
        );
        for r in &rows {
            println!("{:<38} {:>16} {:>16} {:>8}", r[0], r[1], r[2], r[3]);
        }
    }
    Ok(())
}

/// Decoding speed at 640×480 and 1920×1080 (clips of `frames` made in `dir`), ours against
/// `ffmpeg -benchmark`: a row each (measure, ours, FFmpeg's, ratio).
fn decode_rows(
    dir: &Path,
    frames: usize,
    global: &GlobalArgs,
) -> Result<Vec<[String; 4]>, ExitError> {
    let mut rows = Vec::new();
    for (w, h) in [(640, 480), (1920, 1080)] {
        let file = dir.join(format!("bench_{w}x{h}.mp4"));
        say(
            global,
            &format!("making a {w}×{h} H.264 clip of {frames} frames …"),
        );
        make_clip(&file, w, h, frames, ClipKind::Noisy, 250).map_err(ExitError::failed)?;
        let ours = our_decode_fps(&file).map_err(ExitError::failed)?;
        let theirs = ffmpeg_decode_fps(&file, frames).map_err(ExitError::failed)?;
        rows.push([
            format!("decode {w}×{h} to RGB"),
            format!("{ours:.0} frames/s"),
            format!("{theirs:.0} frames/s"),
            format!("{:.2}", ours / theirs),
        ]);
    }
    Ok(rows)
}

/// The test kit's render time: per frame, and 100 frames at 640×480 with the MP4 (in `dir`).
fn synth_rows(dir: &Path) -> Result<Vec<[String; 4]>, ExitError> {
    let params = SynthParams {
        frames: 100,
        output: VideoOutput::Mp4,
        ..SynthParams::default()
    };
    let out = dir.join("synth");
    let t0 = Instant::now();
    let r = render_clip(&params, &out, &mut |_, _| {}, &AtomicBool::new(false))
        .map_err(ExitError::failed)?;
    let total = t0.elapsed().as_secs_f64();
    Ok(vec![
        [
            "synth render 640×480 (per frame)".into(),
            format!("{:.1} ms", r.render_s_per_frame * 1e3),
            "-".into(),
            "-".into(),
        ],
        [
            "synth 100 frames 640×480 incl. MP4".into(),
            format!("{total:.2} s"),
            "-".into(),
            "-".into(),
        ],
    ])
}

/// How a benchmark clip is encoded.
#[derive(Clone, Copy)]
pub(super) enum ClipKind {
    /// Sensor-like noise, B-frames, `veryfast` (decode-speed figures).
    Noisy,
    /// The plain test pattern, `ultrafast` (long clips, where length is the point).
    Plain,
}

/// A testsrc2 clip at 30 fps, H.264 with a keyframe every `gop` frames, made by the `ffmpeg`
/// command.
pub(super) fn make_clip(
    path: &Path,
    w: u32,
    h: u32,
    frames: usize,
    kind: ClipKind,
    gop: u32,
) -> anyhow::Result<()> {
    let mut cmd = Command::new("ffmpeg");
    cmd.args([
        "-hide_banner",
        "-loglevel",
        "error",
        "-y",
        "-f",
        "lavfi",
        "-i",
    ])
    .arg(format!("testsrc2=size={w}x{h}:rate=30"));
    match kind {
        ClipKind::Noisy => cmd.args([
            "-vf",
            "noise=alls=12:allf=t",
            "-preset",
            "veryfast",
            "-bf",
            "2",
        ]),
        ClipKind::Plain => cmd.args(["-preset", "ultrafast"]),
    };
    let status = cmd
        .arg("-frames:v")
        .arg(frames.to_string())
        .args(["-c:v", "libx264", "-pix_fmt", "yuv420p", "-g"])
        .arg(gop.max(1).to_string())
        .arg(path)
        .status()
        .context("bench needs the ffmpeg command (apt-get install ffmpeg)")?;
    if !status.success() {
        return Err(anyhow!("ffmpeg could not make {}", path.display()));
    }
    Ok(())
}

fn our_decode_fps(path: &Path) -> anyhow::Result<f64> {
    let options = OpenOptions {
        cache_bytes: 0,
        ..OpenOptions::default()
    };
    let mut video = Video::open(path, &options)?;
    let n = video.info().frame_count;
    let t0 = Instant::now();
    for i in 0..n {
        video.frame(i)?;
    }
    Ok(n as f64 / t0.elapsed().as_secs_f64())
}

fn ffmpeg_decode_fps(path: &Path, frames: usize) -> anyhow::Result<f64> {
    let out = Command::new("ffmpeg")
        .args(["-hide_banner", "-nostats", "-benchmark", "-i"])
        .arg(path)
        .args(["-pix_fmt", "rgb24", "-f", "null", "-"])
        .output()
        .context("running ffmpeg -benchmark")?;
    let text = String::from_utf8_lossy(&out.stderr);
    let rtime = text
        .split_whitespace()
        .find_map(|w| {
            w.strip_prefix("rtime=")
                .and_then(|v| v.trim_end_matches('s').parse::<f64>().ok())
        })
        .ok_or_else(|| anyhow!("ffmpeg -benchmark printed no rtime: {text}"))?;
    Ok(frames as f64 / rtime)
}
