//! `videomocap bench correct`: what correcting the tracks costs a user.
//!
//! Each clip of the benchmark suite (dev and test), and the two real clips, is tracked from its
//! marks as a user clicks them; then a
//! simulated user ([`videomocap_testkit::eval::correction`]) goes to the first frame with a joint more
//! than 0.1 torso off, drags every joint there more than 0.1 torso off onto the reference and
//! re-tracks, as the app's correction does (that frame becomes a key frame, tracked forwards
//! and backwards), one round per 25 frames of clip. The tables give the accuracy before and
//! after, dev and test side by side per family, and per clip the joints dragged and how many
//! rounds it needs to reach PCK@0.2 ≥ 0.97.

use crate::args::{BenchArgs, GlobalArgs};
use crate::bench_suite::{BenchClip, Tally, bench_clips};
use crate::bench_track::{fixed_template_track, threads_and_settings};
use crate::{ExitError, say};
use std::collections::BTreeSet;
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use videomocap_core::formats::FrameIndex;
use videomocap_core::formats::Tracks2d;
use videomocap_core::track::{KeyFrames, TrackJob, TrackProgress, TrackerParams, track_video};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::eval::correction::next_correction;
use videomocap_testkit::eval::{Accuracy, moved_out, score_positions, score_tracks};
use videomocap_testkit::synth::GroundTruth;

/// The PCK@0.2 a clip must reach to count as corrected (the tracking issue's target).
const GOAL_PCK02: f64 = 0.97;

/// One clip's accuracy after each round (round 0: no correction) and the joints dragged in
/// each round.
struct Rounds {
    scores: Vec<Accuracy>,
    drags: Vec<usize>,
    /// The fixed-template baseline from the same clicked marks, uncorrected.
    template: Accuracy,
    /// Joint-frames within [`KEPT_TORSO`] before a re-track and beyond it after, summed over
    /// the rounds (what corrections spoiled).
    moved_out: usize,
    /// Per re-track, seconds from its start until every frame within [`REDRAW_SPAN`] of the
    /// corrected frame had arrived (what the app draws as they come).
    redraw_s: Vec<f64>,
}

/// A correction should move no joint-frame within this (torso lengths) out of it.
const KEPT_TORSO: f64 = 0.1;

/// Frames on each side of a correction whose re-tracked result the app should draw at once.
const REDRAW_SPAN: usize = 10;

/// The frames next to `frame` (within [`REDRAW_SPAN`], inside the clip's `n` frames).
fn next_to(frame: usize, n: usize) -> std::ops::Range<usize> {
    frame.saturating_sub(REDRAW_SPAN)..(frame + REDRAW_SPAN + 1).min(n)
}

/// The fixed-template baseline's accuracy from the same clicked marks, uncorrected.
fn template_score(
    video: &mut Video,
    gt: &GroundTruth,
    marks: &videomocap_core::formats::Marks,
) -> Result<Accuracy, ExitError> {
    let stature = videomocap_core::track::stature_px(
        &marks.points,
        &videomocap_core::skeleton::Proportions::default(),
    );
    let base = fixed_template_track(video, &marks.points, stature)?;
    Ok(score_positions(gt, base.into_iter().enumerate())
        .map_err(ExitError::failed)?
        .overall)
}

/// Tracks a clip and corrects it for `rounds` rounds at most (fewer when nothing is left
/// visibly wrong).
fn correct_clip(
    clip: &BenchClip,
    rounds: usize,
    threads: usize,
    params: TrackerParams,
    network: Option<std::sync::Arc<videomocap_core::network::PoseNetwork>>,
) -> Result<Rounds, ExitError> {
    let crate::bench_suite::OpenedClip {
        gt,
        marks,
        mut video,
    } = clip.open()?;
    let first = track_video(
        &mut video,
        &TrackJob::from_marks(&marks, params, threads).with_network(network.clone()),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .map_err(ExitError::failed)?;
    let (mut tracks, background) = (first.tracks, first.background);
    let (mut seen, mut passes) = (first.network, first.passes);
    let mut keys = KeyFrames::from_marks(&marks);
    let mut done = BTreeSet::from([marks.frame.get()]);
    let score = |tracks: &Tracks2d| -> Result<Accuracy, ExitError> {
        score_tracks(&gt, tracks)
            .map(|s| s.overall)
            .map_err(ExitError::failed)
    };
    let mut out = Rounds {
        scores: vec![score(&tracks)?],
        drags: vec![0],
        template: template_score(&mut video, &gt, &marks)?,
        redraw_s: Vec::new(),
        moved_out: 0,
    };
    for _ in 0..rounds {
        let Some(c) = next_correction(&gt, &tracks, &done) else {
            break;
        };
        for (joint, pos) in &c.drags {
            keys.set(FrameIndex(c.frame), *joint, *pos);
        }
        done.insert(c.frame);
        let (n, before) = (tracks.frames.len(), tracks.clone());
        let job = TrackJob {
            keys: keys.clone(),
            params,
            threads,
            background: background.clone(),
            network: network.clone(),
            previous_network: seen.take(),
            previous_passes: passes.take(),
        };
        let mut waiting: BTreeSet<usize> = next_to(c.frame, n).collect();
        // Timed as the app re-tracks: the job opens the video, reuses the background of the
        // first run, and draws frames as they arrive.
        let started = Instant::now();
        let mut video = Video::open(&clip.dir.join("video.mp4"), &OpenOptions::default())
            .map_err(ExitError::failed)?;
        let mut arrived_s = None;
        let mut on_progress = |p: &TrackProgress| {
            if let Some(f) = &p.frame {
                waiting.remove(&f.index.get());
                if waiting.is_empty() && arrived_s.is_none() {
                    arrived_s = Some(started.elapsed().as_secs_f64());
                }
            }
        };
        let result = track_video(&mut video, &job, &mut on_progress, &AtomicBool::new(false))
            .map_err(ExitError::failed)?;
        out.moved_out += moved_out(&gt, &before, &result.tracks, KEPT_TORSO);
        tracks = result.tracks;
        (seen, passes) = (result.network, result.passes);
        out.redraw_s
            .push(arrived_s.unwrap_or_else(|| started.elapsed().as_secs_f64()));
        out.scores.push(score(&tracks)?);
        out.drags.push(c.drags.len());
    }
    Ok(out)
}

/// The first round whose PCK@0.2 reaches [`GOAL_PCK02`], as text ("never" within the rounds).
fn rounds_to_goal(r: &Rounds) -> String {
    r.scores
        .iter()
        .position(|s| s.pck02() >= GOAL_PCK02)
        .map_or_else(|| "never".to_owned(), |k| k.to_string())
}

/// The accuracy of round `k`, or of the clip's last round when it stopped earlier (nothing
/// left to correct).
fn at_round(r: &Rounds, k: usize) -> &Accuracy {
    &r.scores[k.min(r.scores.len() - 1)]
}

/// Corrections a clip may use: one per [`FRAMES_PER_CORRECTION`] frames (at least one).
const FRAMES_PER_CORRECTION: usize = 25;

/// A split's column: PCK@0.2 and lost before any correction, then after the clip's budget,
/// then the fixed template's PCK@0.2 (uncorrected).
fn cell(s: &[Accuracy; 3]) -> String {
    format!(
        "{:>6.3} {:>5.1}% {:>6.3} {:>5.1}% {:>6.3}",
        s[0].pck02(),
        100.0 * s[0].lost(),
        s[1].pck02(),
        100.0 * s[1].lost(),
        s[2].pck02()
    )
}

/// Each clip's row (before, after, rounds, drags, rounds to 0.97, joint-frames moved out) and
/// how soon the real clips' frames near a correction were drawn.
fn clip_lines(clips: &[BenchClip], results: &[(usize, Rounds)]) -> Vec<String> {
    let mut lines = Vec::new();
    lines.push(String::new());
    lines.push(format!(
        "{:<26} {:<5} {:>8} {:>8} {:>8} {:>7} {:>14} {:>16} {:>9}",
        "clip",
        "split",
        "PCK@0.2",
        "→ after",
        "lost",
        "rounds",
        "joints dragged",
        "rounds to 0.97",
        "moved out"
    ));
    for (clip, (budget, r)) in clips.iter().zip(results) {
        let last = at_round(r, *budget);
        lines.push(format!(
            "{:<26} {:<5} {:>8.3} {:>8.3} {:>7.1}% {:>7} {:>14} {:>16} {:>9}",
            clip.name,
            clip.split.name(),
            r.scores[0].pck02(),
            last.pck02(),
            100.0 * last.lost(),
            r.scores.len() - 1,
            r.drags.iter().sum::<usize>(),
            rounds_to_goal(r),
            r.moved_out
        ));
    }
    let redraw: Vec<String> = clips
        .iter()
        .zip(results)
        .filter(|(_, (_, r))| !r.redraw_s.is_empty())
        .filter(|(clip, _)| clip.family == videomocap_testkit::eval::suite::Family::Real)
        .map(|(clip, (_, r))| {
            let mut t = r.redraw_s.clone();
            t.sort_by(f64::total_cmp);
            format!(
                "{} median {:.2} s, worst {:.2} s ({} re-tracks)",
                clip.name,
                t[t.len() / 2],
                t[t.len() - 1],
                t.len()
            )
        })
        .collect();
    if !redraw.is_empty() {
        lines.push(String::new());
        lines.push(format!(
            "after a correction, every frame within {REDRAW_SPAN} of it re-tracked (1080×1920): {}",
            redraw.join("; ")
        ));
    }
    lines
}

/// The clips' rows and the splits' tallies as JSON, with the printed table.
fn correct_json(
    clips: &[BenchClip],
    results: &[(usize, Rounds)],
    tally: &Tally<[Accuracy; 3]>,
    lines: &[String],
) -> serde_json::Value {
    let rows: Vec<_> = clips
        .iter()
        .zip(results)
        .map(|(clip, (budget, r))| {
            serde_json::json!({
                "clip": clip.name, "split": clip.split.name(), "family": clip.family.name(),
                "budget": budget,
                "pck02": r.scores.iter().map(Accuracy::pck02).collect::<Vec<_>>(),
                "lost": r.scores.iter().map(Accuracy::lost).collect::<Vec<_>>(),
                "drags": r.drags,
                "moved_out": r.moved_out,
                "redraw_s": r.redraw_s,
            })
        })
        .collect();
    let split = tally.json(|s| {
        serde_json::json!({
            "before": crate::bench_track::accuracy_json(&s[0]),
            "after": crate::bench_track::accuracy_json(&s[1]),
        "fixed_template": crate::bench_track::accuracy_json(&s[2]),
        })
    });
    serde_json::json!({"clips": rows, "splits": split, "table": lines})
}

/// Runs the correction benchmark and prints its table.
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let (threads, params) = threads_and_settings(a)?;
    let clips = bench_clips(&a.suite_dir, &a.split, a.clip.as_deref(), global)?;
    let network = a
        .network
        .then(|| crate::bench_suite::bundled_network(threads))
        .transpose()?;
    let mut results = Vec::with_capacity(clips.len());
    let mut tally: Tally<[Accuracy; 3]> = Tally::default();
    let mut spoiled: std::collections::BTreeMap<&str, (usize, usize)> = Default::default();
    for clip in &clips {
        say(global, &format!("correcting {}", clip.name));
        let gt = GroundTruth::load(&clip.dir.join("gt.json")).map_err(ExitError::failed)?;
        let budget = gt.frames.len().div_ceil(FRAMES_PER_CORRECTION).max(1);
        let r = correct_clip(clip, budget, threads, params, network.clone())?;
        tally.add(clip, &[r.scores[0], *at_round(&r, budget), r.template]);
        let e = spoiled.entry(clip.split.name()).or_default();
        e.0 += r.moved_out;
        e.1 += r.scores[0].count;
        results.push((budget, r));
    }
    let mut lines = vec![
        format!(
            "simulated correction from clicked marks: each round goes to the first frame with a \
             joint over 0.1 torso off, drags every joint there over 0.1 torso off onto the \
             reference and re-tracks; one round per {FRAMES_PER_CORRECTION} \
             frames of clip. Columns: PCK@0.2 and lost before any correction, then after them, then \
             the fixed template's PCK@0.2 from the same marks (uncorrected). Tracker: {}",
            if a.network {
                "VBA with the pose network's evidence (--network, the product's default)"
            } else {
                "VBA alone"
            }
        ),
        String::new(),
    ];
    const WIDTH: usize = 34;
    lines.extend(Tally::<[Accuracy; 3]>::heading(
        WIDTH,
        " PCK.2   lost  after   lost  templ",
    ));
    lines.extend(tally.lines(WIDTH, cell));
    lines.push(String::new());
    for (split, (moved, samples)) in &spoiled {
        lines.push(format!(
            "{split}: joint-frames within {KEPT_TORSO} torso that a correction moved out of it: {moved} (of {samples} joint-frames, summed over the re-tracks)"
        ));
    }
    lines.extend(clip_lines(&clips, &results));
    if global.json {
        println!("{}", correct_json(&clips, &results, &tally, &lines));
    } else {
        for l in lines {
            println!("{l}");
        }
    }
    Ok(())
}
