//! `videomocap-bench speed retrack`: issue 95's last target, a re-track after one correction on
//! a 300-frame 1080p clip, on two threads, as the app re-tracks (the video opened anew, the
//! first run's background, the network's output and VBA's passes reused as caches).
//!
//! The clip: the real 1080×1920 portrait sample (100 frames) played forwards, backwards and
//! forwards again by `ffmpeg` (300 frames of continuous motion), tracked from the sample's
//! marks with the pose network. The correction: the left wrist on the middle frame dragged
//! 6 px, one joint of one frame as a user's drag. Timed: the first track, the re-track (medians
//! of `--runs`) without VBA's passes cache (`TrackJob::previous_passes`: the passes run over
//! the whole clip again, decoding it) and with it (the forward pass taken up at the correction,
//! the frames not decoded), their ratio, and the re-track with VBA alone (`network` off) with
//! the cache. The tracks with the cache and without are compared, byte for byte.

use crate::args::{BenchArgs, GlobalArgs};
use crate::{ExitError, say};
use anyhow::{Context, anyhow};
use std::path::Path;
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use videomocap_core::formats::{FrameIndex, KeyFrames, Marks};
use videomocap_core::network::PoseNetwork;
use videomocap_core::skeleton::Joint;
use videomocap_core::track::{TrackJob, TrackOutput, TrackerParams, track_video};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::repo_root;

/// Threads of every run: the two cores of the target.
const THREADS: usize = 2;

/// Writes the 300-frame clip (forwards, backwards, forwards) to `out` with the `ffmpeg` command.
fn ping_pong(source: &Path, out: &Path) -> anyhow::Result<()> {
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(source)
        .args([
            "-filter_complex",
            "[0:v]split=3[a][b][c];[b]reverse[r];[a][r][c]concat=n=3:v=1:a=0[v]",
            "-map",
            "[v]",
            "-c:v",
            "libx264",
            "-crf",
            "18",
            "-pix_fmt",
            "yuv420p",
        ])
        .arg(out)
        .status()
        .context("running ffmpeg (needed to make the 300-frame clip)")?;
    if !status.success() {
        return Err(anyhow!(
            "ffmpeg could not make {} from {}",
            out.display(),
            source.display()
        ));
    }
    Ok(())
}

/// One timed track of `path` (the video opened inside the timing, as the app does).
fn timed_track(path: &Path, job: &TrackJob) -> anyhow::Result<(f64, TrackOutput)> {
    let started = Instant::now();
    let mut video = Video::open(path, &OpenOptions::default())?;
    let out = track_video(&mut video, job, &mut |_| {}, &AtomicBool::new(false))?;
    Ok((started.elapsed().as_secs_f64(), out))
}

/// Runs the measurement (see the module's text).
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let runs = a.runs.max(1);
    let dir = tempfile::tempdir().map_err(ExitError::failed)?;
    let real = repo_root().join("sample_videos/pose2sim_balancing_cam01");
    let clip = dir.path().join("ping_pong_300.mp4");
    say(global, "making the 300-frame 1080×1920 clip with ffmpeg …");
    ping_pong(&real.join("video.mp4"), &clip).map_err(ExitError::failed)?;
    let marks = Marks::load(&real.join("marks.json")).map_err(ExitError::failed)?;
    let network = PoseNetwork::shared(THREADS).map_err(ExitError::failed)?;
    let params = TrackerParams::default();
    let job = TrackJob::from_marks(&marks, params, THREADS).with_network(Some(network));
    say(global, "the first track …");
    let (first_s, first) = timed_track(&clip, &job).map_err(ExitError::failed)?;
    let n = first.tracks.frames.len();
    let middle = n / 2;
    let mut keys = KeyFrames::from_marks(&marks);
    let dragged =
        first.tracks.frames[middle].points[Joint::LeftWrist].pos + nalgebra::Vector2::new(6.0, 0.0);
    keys.set(FrameIndex(middle), Joint::LeftWrist, dragged);
    let uncached = TrackJob {
        keys,
        background: first.background.clone(),
        previous_network: first.network.clone(),
        ..job
    };
    let retrack = TrackJob {
        previous_passes: first.passes.clone(),
        ..uncached.clone()
    };
    let vba_alone = TrackJob {
        params: TrackerParams {
            network: false,
            ..params
        },
        ..retrack.clone()
    };
    let (mut without, mut with, mut alone) = (Vec::new(), Vec::new(), Vec::new());
    let (mut rerun, mut identical) = (0, true);
    for k in 0..runs {
        say(global, &format!("re-track {}/{runs} …", k + 1));
        let (s, plain) = timed_track(&clip, &uncached).map_err(ExitError::failed)?;
        without.push(s);
        let (s, out) = timed_track(&clip, &retrack).map_err(ExitError::failed)?;
        with.push(s);
        identical &= plain.tracks.to_json_value() == out.tracks.to_json_value();
        let (before, after) = (first.network.as_deref(), out.network.as_deref());
        if let (Some(before), Some(after)) = (before, after) {
            rerun = before
                .iter()
                .zip(after)
                .filter(|(b, a)| b.crop != a.crop)
                .count();
        }
        alone.push(timed_track(&clip, &vba_alone).map_err(ExitError::failed)?.0);
    }
    report(
        global,
        Measured {
            n,
            middle,
            runs,
            first_s,
            times: [without, with, alone],
            rerun,
            identical,
        },
    )
}

/// What [`run`] measured: the first track's time, and per re-track (without the passes cache,
/// with it, VBA alone with it) each run's time.
struct Measured {
    n: usize,
    middle: usize,
    runs: usize,
    first_s: f64,
    times: [Vec<f64>; 3],
    rerun: usize,
    identical: bool,
}

/// Prints the medians and their ratio (a line, or JSON); an error when the tracks with the
/// cache differed from those without it.
fn report(global: &GlobalArgs, m: Measured) -> Result<(), ExitError> {
    let Measured {
        n,
        middle,
        runs,
        first_s,
        times: [without, with, alone],
        rerun,
        identical,
    } = m;
    let median = crate::bench_speed::median;
    let (without, with, alone) = (median(without), median(with), median(alone));
    let ratio = with / without.max(1e-9);
    if global.json {
        let v = serde_json::json!({
            "frames": n, "threads": THREADS, "runs": runs, "first_track_s": first_s,
            "retrack_uncached_s": without, "retrack_s": with, "ratio": ratio,
            "retrack_vba_alone_s": alone, "network_frames_rerun": rerun,
            "identical": identical,
        });
        println!("{v}");
    } else {
        println!(
            "{n}-frame 1080×1920 clip, {THREADS} threads: first track {first_s:.2} s; after one \
             correction (frame {middle}'s left wrist dragged 6 px) the re-track without the \
             passes cache {without:.2} s, with it {with:.2} s ({ratio:.2} ×; medians of {runs}; \
             {rerun} network frames run again; tracks identical: {}), VBA alone with the cache \
             {alone:.2} s; target ≤ 1 s",
            if identical { "yes" } else { "NO" }
        );
    }
    if identical {
        Ok(())
    } else {
        Err(ExitError::failed(anyhow!(
            "the re-track with VBA's passes cache differs from the one without it"
        )))
    }
}
