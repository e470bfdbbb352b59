//! `videomocap bench correct`: what correcting the tracks costs a user.
//!
//! Each clip of the tracking suite, and the real sample, is tracked from its marks; then a
//! simulated user ([`videomocap::eval::correction`]) goes to the first frame with a lost joint
//! (the guide's advice), drags every joint there more than 0.2 torso off onto the reference and
//! re-tracks from there, as the app's correction does (that frame becomes a key frame, the
//! forward pass restarts there, a backward pass fills the weak frames before it). The table
//! gives the accuracy after each round, the joints dragged so far, and how many rounds each
//! clip needs to reach PCK@0.2 ≥ 0.95.

use super::args::{BenchArgs, GlobalArgs};
use super::bench_track::{ensure_suite, threads_and_settings, track_opened};
use super::{ExitError, say};
use std::collections::BTreeSet;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use videomocap::eval::correction::next_correction;
use videomocap::eval::{Accuracy, score_tracks};
use videomocap::formats::{Marks, Tracks2d};
use videomocap::synth::GroundTruth;
use videomocap::track::{KeyFrames, TrackJob, TrackerParams, track_video};
use videomocap::video::{OpenOptions, Video};

/// The PCK@0.2 a clip must reach to count as corrected (the tracking issue's target).
const GOAL_PCK02: f64 = 0.95;

/// One clip's accuracy after each round (round 0: no correction) and the joints dragged in
/// each round.
struct Rounds {
    scores: Vec<Accuracy>,
    drags: Vec<usize>,
}

/// Tracks a clip and corrects it for `rounds` rounds at most (fewer when nothing is left
/// visibly wrong).
fn correct_clip(
    dir: &Path,
    rounds: usize,
    threads: usize,
    params: TrackerParams,
) -> Result<Rounds, ExitError> {
    let gt = GroundTruth::load(&dir.join("gt.json")).map_err(ExitError::failed)?;
    let marks = Marks::load(&dir.join("marks.json")).map_err(ExitError::failed)?;
    let mut video =
        Video::open(&dir.join("video.mp4"), &OpenOptions::default()).map_err(ExitError::failed)?;
    let mut tracks = track_opened(&mut video, &marks, threads, params)?;
    let mut keys = KeyFrames::from_marks(&marks);
    let mut done = BTreeSet::from([marks.frame]);
    let score = |tracks: &Tracks2d| -> Result<Accuracy, ExitError> {
        score_tracks(&gt, tracks)
            .map(|s| s.overall)
            .map_err(ExitError::failed)
    };
    let mut out = Rounds {
        scores: vec![score(&tracks)?],
        drags: vec![0],
    };
    for _ in 0..rounds {
        let Some(c) = next_correction(&gt, &tracks, &done) else {
            break;
        };
        for (joint, pos) in &c.drags {
            keys.set(c.frame, *joint, *pos);
        }
        done.insert(c.frame);
        let job = TrackJob {
            keys: keys.clone(),
            params,
            threads,
            from: Some(c.frame),
            previous: Some(tracks),
        };
        tracks = track_video(&mut video, &job, &mut |_| {}, &AtomicBool::new(false))
            .map_err(ExitError::failed)?
            .tracks;
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

/// Runs the correction benchmark and prints its table.
pub fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let (threads, params) = threads_and_settings(a)?;
    let rounds = a.corrections;
    let mut clips = ensure_suite(&a.suite_dir, global)?;
    let suite_len = clips.len();
    clips.push((
        "real sample".to_owned(),
        Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_videos/pose2sim_balancing_cam01"),
    ));
    let mut results = Vec::with_capacity(clips.len());
    for (name, dir) in &clips {
        say(global, &format!("correcting {name}"));
        results.push(correct_clip(dir, rounds, threads, params)?);
    }
    let mut lines = vec![
        format!(
            "simulated correction: each round goes to the first frame with a joint lost (over 0.5 \
             torso off), drags every joint there over 0.2 torso off onto the reference and \
             re-tracks from there ({rounds} rounds at most)"
        ),
        String::new(),
        format!(
            "{:<24} {:>6} {:>8} {:>8} {:>8} {:>14}",
            "suite overall", "round", "PCK@0.2", "lost", "mean px", "joints dragged"
        ),
    ];
    for k in 0..=rounds {
        let mut acc = Accuracy::default();
        let mut dragged = 0;
        for r in &results[..suite_len] {
            acc.merge(at_round(r, k));
            dragged += r.drags.iter().take(k + 1).sum::<usize>();
        }
        lines.push(format!(
            "{:<24} {:>6} {:>8.3} {:>7.1}% {:>8.1} {:>14}",
            "",
            k,
            acc.pck02(),
            100.0 * acc.lost(),
            acc.mean_px(),
            dragged
        ));
    }
    lines.push(String::new());
    lines.push(format!(
        "{:<24} {:>8} {:>8} {:>8} {:>14} {:>16}",
        "clip", "PCK@0.2", "→ last", "lost", "joints dragged", "rounds to 0.95"
    ));
    for ((name, _), r) in clips.iter().zip(&results) {
        let last = at_round(r, rounds);
        lines.push(format!(
            "{:<24} {:>8.3} {:>8.3} {:>7.1}% {:>14} {:>16}",
            name,
            r.scores[0].pck02(),
            last.pck02(),
            100.0 * last.lost(),
            r.drags.iter().sum::<usize>(),
            rounds_to_goal(r)
        ));
    }
    if global.json {
        let rows: Vec<_> = clips
            .iter()
            .zip(&results)
            .map(|((name, _), r)| {
                serde_json::json!({
                    "clip": name,
                    "pck02": r.scores.iter().map(Accuracy::pck02).collect::<Vec<_>>(),
                    "lost": r.scores.iter().map(Accuracy::lost).collect::<Vec<_>>(),
                    "drags": r.drags,
                })
            })
            .collect();
        println!("{}", serde_json::json!({"clips": rows, "table": lines}));
    } else {
        for l in lines {
            println!("{l}");
        }
    }
    Ok(())
}
