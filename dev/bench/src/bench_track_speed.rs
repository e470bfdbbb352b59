//! `videomocap bench track`'s speed table: frames per second of the tracker at 640×480 and
//! 1080×1920, with frames already in memory (decoding excluded) and with decoding, on one
//! thread and on all; and how much longer tracking with decoding takes than decoding alone,
//! timed back to back in paired rounds.

use crate::ExitError;
use crate::bench_suite::BenchClip;
use anyhow::anyhow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use videomocap_core::formats::{FrameIndex, Marks};
use videomocap_core::skeleton::Joint;
use videomocap_core::track::{TrackJob, TrackerParams, track_video};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::eval::suite::{Family, REAL_CLIPS};
use videomocap_testkit::repo_root;
use videomocap_testkit::synth::GroundTruth;

/// Runs per speed figure; the fastest counts.
const SPEED_RUNS: usize = 3;

/// The speed table's lines: the first 640×480 suite clip among `clips` (none when `--clip`
/// picked only the real ones) and the real sample, each on one thread and on `threads`.
pub(crate) fn speed_lines(
    clips: &[BenchClip],
    threads: usize,
    params: TrackerParams,
) -> Result<Vec<String>, ExitError> {
    let mut lines = Vec::new();
    lines.push(String::new());
    lines.push(format!(
        "{:<48} {:>12}",
        "speed (all 16 joints; fastest of 3 runs)", "frames/s"
    ));
    // The first 640×480 suite clip of those measured (none when `--clip` picked only the real
    // ones), and the real sample.
    let is_vga = |c: &&BenchClip| {
        Video::open(&c.dir.join("video.mp4"), &OpenOptions::default())
            .is_ok_and(|v| (v.info().width, v.info().height) == (640, 480))
    };
    let mut timed: Vec<(&str, PathBuf)> = clips
        .iter()
        .filter(|c| c.family != Family::Real)
        .find(is_vga)
        .map(|c| ("640×480", c.dir.clone()))
        .into_iter()
        .collect();
    if timed.is_empty() {
        lines.push("(no 640×480 suite clip among the clips measured: not timed)".to_owned());
    }
    timed.push(("1080×1920", repo_root().join(REAL_CLIPS[0].1)));
    for (label, dir) in &timed {
        lines.extend(clip_speed_lines(label, dir, threads, params)?);
    }
    Ok(lines)
}

/// One clip's speed lines (`label` its size): tracking with and without decoding on one
/// thread and on `threads`, both ways at 640×480, decoding alone, and the paired ratio.
fn clip_speed_lines(
    label: &str,
    dir: &Path,
    threads: usize,
    params: TrackerParams,
) -> Result<Vec<String>, ExitError> {
    let mut lines = Vec::new();
    for decoding in [false, true] {
        for t in [1, threads] {
            let n = speed(dir, t, decoding, params)?;
            let what = if decoding {
                "with decoding"
            } else {
                "decoding excluded"
            };
            let plural = if t == 1 { "thread" } else { "threads" };
            lines.push(format!(
                "{:<48} {:>12.1}",
                format!("track {label}, {t} {plural}, {what}"),
                n
            ));
        }
    }
    if label == "640×480" {
        // The speed goal counts the backward pass a later key frame brings.
        let n = speed_both_ways(dir, params)?;
        lines.push(format!(
            "{:<48} {:>12.1}",
            "track 640×480, 1 thread, both ways, dec. excluded", n
        ));
    }
    let d = decode_speed(dir)?;
    lines.push(format!(
        "{:<48} {:>12.1}",
        format!("decode only {label}"),
        d
    ));
    let (median, low, high) = paired_ratio(dir, threads, params)?;
    lines.push(format!(
        "{:<48} {:>12.2}",
        format!("time ratio track+decode / decode {label}"),
        median
    ));
    lines.push(format!(
        "{:<48} {:>12}",
        format!("  (median of {RATIO_ROUNDS} paired rounds; range)"),
        format!("{low:.2}–{high:.2}")
    ));
    Ok(lines)
}

/// A prepared speed measurement of tracking one clip: the job and, when decoding is excluded,
/// the video with every frame already in its cache.
struct TrackTimer {
    dir: PathBuf,
    job: TrackJob,
    decoding: bool,
    preloaded: Option<Video>,
}

impl TrackTimer {
    fn new(
        dir: &Path,
        threads: usize,
        decoding: bool,
        params: TrackerParams,
    ) -> Result<Self, ExitError> {
        let marks = Marks::load(&dir.join("marks.json")).map_err(ExitError::failed)?;
        // Frames in memory are full size: the tracker shrinks them itself (it leaves a video
        // whose frames are in its cache at full size, as FFmpeg's scaling would empty it).
        Ok(TrackTimer {
            dir: dir.to_owned(),
            job: TrackJob::from_marks(&marks, params, threads),
            decoding,
            preloaded: None,
        })
    }

    /// Tracks the clip once: (frames, seconds). With decoding every run opens the video
    /// afresh (its cache would hold the frames); without, the frames are loaded before the
    /// clock starts and kept for the next run.
    fn run_once(&mut self) -> Result<(usize, f64), ExitError> {
        let mut video = match self.preloaded.take() {
            Some(v) => v,
            None => {
                let options = OpenOptions {
                    cache_bytes: 2 << 30,
                    ..OpenOptions::default()
                };
                Video::open(&self.dir.join("video.mp4"), &options).map_err(ExitError::failed)?
            }
        };
        let n = video.info().frame_count;
        if !self.decoding {
            for i in 0..n {
                let _: Arc<_> = video.frame(i).map_err(ExitError::failed)?.image;
            }
        }
        let t0 = Instant::now();
        track_video(&mut video, &self.job, &mut |_| {}, &AtomicBool::new(false))
            .map_err(ExitError::failed)?;
        let s = t0.elapsed().as_secs_f64();
        if !self.decoding {
            self.preloaded = Some(video);
        }
        Ok((n, s))
    }
}

/// Frames per second of tracking `dir`'s clip: the fastest of [`SPEED_RUNS`] runs (the machine
/// is shared, and a slow run measures the neighbours, not the tracker).
fn speed(
    dir: &Path,
    threads: usize,
    decoding: bool,
    params: TrackerParams,
) -> Result<f64, ExitError> {
    let mut timer = TrackTimer::new(dir, threads, decoding, params)?;
    let mut best = f64::INFINITY;
    let mut n = 0;
    for _ in 0..SPEED_RUNS {
        let (frames, s) = timer.run_once()?;
        n = frames;
        best = best.min(s);
    }
    Ok(n as f64 / best)
}

/// Frames per second of tracking `dir`'s suite clip on one thread, decoding excluded, with a
/// key frame on its last frame (the reference pose there) as well as the marks, so that a
/// backward pass runs over the whole clip too; fastest of [`SPEED_RUNS`].
fn speed_both_ways(dir: &Path, params: TrackerParams) -> Result<f64, ExitError> {
    let mut timer = TrackTimer::new(dir, 1, false, params)?;
    let gt = GroundTruth::load(&dir.join("gt.json")).map_err(ExitError::failed)?;
    let n = gt.frames.len();
    let last = gt
        .frames
        .last()
        .ok_or_else(|| ExitError::failed(anyhow!("{}: no reference frames", dir.display())))?
        .points2d();
    for j in Joint::ALL {
        timer.job.keys.set(FrameIndex(n - 1), j, last[j]);
    }
    let mut best = f64::INFINITY;
    for _ in 0..SPEED_RUNS {
        let (_, s) = timer.run_once()?;
        best = best.min(s);
    }
    Ok(n as f64 / best)
}

/// Decodes `dir`'s clip once: (frames, seconds).
fn decode_once(dir: &Path) -> Result<(usize, f64), ExitError> {
    let mut video =
        Video::open(&dir.join("video.mp4"), &OpenOptions::default()).map_err(ExitError::failed)?;
    let n = video.info().frame_count;
    let t0 = Instant::now();
    for i in 0..n {
        video.frame(i).map_err(ExitError::failed)?;
    }
    let s = t0.elapsed().as_secs_f64();
    if s <= 0.0 {
        return Err(ExitError::failed(anyhow!("decoding took no time")));
    }
    Ok((n, s))
}

/// Frames per second of decoding `dir`'s clip, the fastest of [`SPEED_RUNS`] runs.
fn decode_speed(dir: &Path) -> Result<f64, ExitError> {
    let mut best = f64::INFINITY;
    let mut n = 0;
    for _ in 0..SPEED_RUNS {
        let (frames, s) = decode_once(dir)?;
        n = frames;
        best = best.min(s);
    }
    Ok(n as f64 / best)
}

/// Rounds of the paired ratio measurement.
const RATIO_ROUNDS: usize = 5;

/// The time of tracking with decoding over the time of decoding alone, measured in
/// [`RATIO_ROUNDS`] rounds that each time both back to back, so both halves of a ratio see the
/// same neighbours on the shared machine: (median, lowest, highest) of the rounds' ratios.
/// The paired median still moves between runs on a shared machine, so quote it with its range
/// (the runs behind this: docs/log.md).
fn paired_ratio(
    dir: &Path,
    threads: usize,
    params: TrackerParams,
) -> Result<(f64, f64, f64), ExitError> {
    let mut timer = TrackTimer::new(dir, threads, true, params)?;
    // A first round warms the file cache and the thread pool; it is not counted.
    decode_once(dir)?;
    timer.run_once()?;
    let mut ratios = Vec::with_capacity(RATIO_ROUNDS);
    for _ in 0..RATIO_ROUNDS {
        let (_, decode) = decode_once(dir)?;
        let (_, track) = timer.run_once()?;
        ratios.push(track / decode);
    }
    ratios.sort_by(f64::total_cmp);
    Ok((
        ratios[RATIO_ROUNDS / 2],
        ratios[0],
        ratios[RATIO_ROUNDS - 1],
    ))
}
