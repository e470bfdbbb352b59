//! `videomocap bench track`: tracking accuracy and speed.
//!
//! Accuracy: suite v3 ([`videomocap_testkit::eval::suite`]: every bundled motion-capture take and the
//! procedural motions on varied bodies, views and scenes, split by take into dev and test) plus
//! the two real clips, each tracked from the marks of frame 0 as a user clicks them (2 px of
//! noise; the exact marks as a second condition) by the VBA tracker and by a fixed-template
//! matcher per joint (the baseline written here: the marked patch of each joint searched around
//! its last position, no prediction, no model update), and by OpenCV's Lucas–Kanade and CSRT
//! when Python's OpenCV is present, and MediaPipe Pose when it is (`bench_baselines`). Tables put dev and test side by side per
//! clip family. Metrics from [`videomocap_testkit::eval`].
//!
//! Speed: `bench_track_speed`.

use crate::args::{BenchArgs, GlobalArgs};
use crate::bench_suite::{BenchClip, Tally, bench_clips};
use crate::{ExitError, say};
use nalgebra::Point2;
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::Marks;
use videomocap_core::skeleton::{Joint, PerJoint};
use videomocap_core::track::FloatFrame;
use videomocap_core::track::{TrackJob, TrackerParams, track_video};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::eval::suite::{CLICK_NOISE_PX, Family, Split, clicked_marks};
use videomocap_testkit::eval::{Accuracy, ClipScore, is_limb_joint, score_positions, score_tracks};
use videomocap_testkit::synth::GroundTruth;

/// The fixed-template baseline: each joint's marked square patch (side 8% of the marked
/// stature) searched by the sum of absolute RGB differences within ±20% of the stature of its
/// last position (every 2 px, then ±1 px around the best). No prediction, no model update.
pub(crate) fn fixed_template_track(
    video: &mut Video,
    marks: &PerJoint<Point2<f64>>,
    stature_px: f64,
) -> Result<Vec<PerJoint<Point2<f64>>>, ExitError> {
    let half = ((0.04 * stature_px).round() as i64).max(4);
    let radius = ((0.2 * stature_px).round() as i64).max(8);
    let first = video.frame(0).map_err(ExitError::failed)?.image;
    let first_floats = FloatFrame::new(&first);
    let f0 = first_floats.view();
    let (w, h) = (first.width() as i64, first.height() as i64);
    let clampi = |v: i64, hi: i64| v.clamp(0, hi - 1) as usize;
    let templates: Vec<Vec<[f32; 3]>> = Joint::ALL
        .iter()
        .map(|&j| {
            let (cx, cy) = (marks[j].x.round() as i64, marks[j].y.round() as i64);
            let mut t = Vec::new();
            for dy in -half..=half {
                for dx in -half..=half {
                    t.push(f0.pixel(clampi(cx + dx, w), clampi(cy + dy, h)));
                }
            }
            t
        })
        .collect();
    let mut pos: Vec<(i64, i64)> = Joint::ALL
        .iter()
        .map(|&j| (marks[j].x.round() as i64, marks[j].y.round() as i64))
        .collect();
    let mut out = vec![*marks];
    // One buffer for every frame (a fresh one per frame costs its page faults).
    let mut floats = first_floats;
    for index in 1..video.info().frame_count {
        let image = video.frame(index).map_err(ExitError::failed)?.image;
        floats.fill(&image);
        let f = floats.view();
        let sad = |t: &[[f32; 3]], cx: i64, cy: i64, bound: f32| -> f32 {
            let mut s = 0.0;
            let mut k = 0;
            for dy in -half..=half {
                for dx in -half..=half {
                    let p = f.pixel(clampi(cx + dx, w), clampi(cy + dy, h));
                    let q = t[k];
                    s += (p[0] - q[0]).abs() + (p[1] - q[1]).abs() + (p[2] - q[2]).abs();
                    k += 1;
                }
                if s > bound {
                    return f32::INFINITY;
                }
            }
            s
        };
        for (i, t) in templates.iter().enumerate() {
            let (px, py) = pos[i];
            let mut best = (f32::INFINITY, px, py);
            for step_then in [(2i64, radius), (1, 2)] {
                let (step, r) = step_then;
                let (bx, by) = (best.1, best.2);
                let mut dy = -r;
                while dy <= r {
                    let mut dx = -r;
                    while dx <= r {
                        let c = sad(t, bx + dx, by + dy, best.0);
                        if c < best.0 {
                            best = (c, bx + dx, by + dy);
                        }
                        dx += step;
                    }
                    dy += step;
                }
            }
            pos[i] = (best.1, best.2);
        }
        out.push(PerJoint::from_fn(|j| {
            let (x, y) = pos[j.index()];
            Point2::new(x as f64, y as f64)
        }));
    }
    Ok(out)
}

/// Tracks an opened suite clip from its marks with the VBA tracker.
pub(crate) fn track_opened(
    video: &mut Video,
    marks: &Marks,
    threads: usize,
    params: TrackerParams,
) -> Result<videomocap_core::formats::Tracks2d, ExitError> {
    let job = TrackJob::from_marks(marks, params, threads);
    let out = track_video(video, &job, &mut |_| {}, &AtomicBool::new(false))
        .map_err(ExitError::failed)?;
    Ok(out.tracks)
}

/// The tracking benchmarks' threads (all the machine has) and tracker settings (`--tracker-
/// settings`, else the defaults).
pub(crate) fn threads_and_settings(a: &BenchArgs) -> Result<(usize, TrackerParams), ExitError> {
    let threads = crate::bench_suite::machine_threads();
    let params = match &a.tracker_settings {
        Some(p) => videomocap::cli::track::load_settings(p)?,
        None => TrackerParams::default(),
    };
    Ok((threads, params))
}

/// A clip's tracking scores: the VBA tracker from the clicked marks and from the exact ones, the
/// fixed template from the clicked marks.
type TrackScores = [Accuracy; 3];

/// The column of one split in the tracking table.
fn track_cell(s: &TrackScores) -> String {
    format!(
        "{:>6.3} {:>5.1}% {:>7.1} {:>6.3} {:>6.3}",
        s[0].pck02(),
        100.0 * s[0].lost(),
        s[0].mean_px(),
        s[1].pck02(),
        s[2].pck02()
    )
}

/// The columns of [`track_cell`].
const TRACK_COLUMNS: &str = " PCK.2   lost mean px  exact  templ";
const TRACK_WIDTH: usize = 35;

/// Tracks and scores one clip: (VBA from the clicked marks, VBA from the exact marks, the fixed
/// template from the clicked marks), the VBA's limb joints ([`is_limb_joint`]) from the clicked
/// marks, and the clicked marks.
fn score_clip(
    clip: &BenchClip,
    threads: usize,
    params: TrackerParams,
) -> Result<(TrackScores, ClipScore, Marks), ExitError> {
    let gt = GroundTruth::load(&clip.dir.join("gt.json")).map_err(ExitError::failed)?;
    let marks = Marks::load(&clip.dir.join("marks.json")).map_err(ExitError::failed)?;
    let clicked = clicked_marks(&marks, CLICK_NOISE_PX, &clip.name);
    let mut video = Video::open(&clip.dir.join("video.mp4"), &OpenOptions::default())
        .map_err(ExitError::failed)?;
    let mut vba = |m: &Marks| -> Result<ClipScore, ExitError> {
        let tracks = track_opened(&mut video, m, threads, params)?;
        score_tracks(&gt, &tracks).map_err(ExitError::failed)
    };
    let (clicks_score, from_exact) = (vba(&clicked)?, vba(&marks)?);
    let (from_clicks, from_exact) = (clicks_score.overall, from_exact.overall);
    let stature = videomocap_core::track::stature_px(
        &clicked.points,
        &videomocap_core::skeleton::Proportions::default(),
    );
    let base = fixed_template_track(&mut video, &clicked.points, stature)?;
    let template = score_positions(&gt, base.into_iter().enumerate())
        .map_err(ExitError::failed)?
        .overall;
    Ok(([from_clicks, from_exact, template], clicks_score, clicked))
}

/// The accuracy run over the suite's clips: the table's lines so far, the per-clip JSON rows,
/// the tally by family and split, and per clip the clicked marks, VBA's limb joints and VBA's
/// scores (for the baselines that follow); the real clips' limb joints apart.
struct AccuracyRun {
    lines: Vec<String>,
    rows_json: Vec<serde_json::Value>,
    tally: Tally<TrackScores>,
    clicked: Vec<Marks>,
    real_limbs: Vec<(String, Accuracy)>,
    vba_limbs: Vec<Accuracy>,
    vba_scores: Vec<ClipScore>,
}

/// Runs the accuracy and speed benchmark and prints its tables.
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let (threads, params) = threads_and_settings(a)?;
    let clips = bench_clips(&a.suite_dir, &a.split, a.clip.as_deref(), global)?;
    let mut acc = track_clips(&clips, threads, params, global)?;
    let mut lines = std::mem::take(&mut acc.lines);
    lines.extend(summary_lines(&acc));
    let opencv = crate::bench_baselines::opencv(&clips, &acc.clicked, &a.suite_dir, global)?;
    lines.push(String::new());
    lines.extend(crate::bench_baselines::opencv_lines(opencv.as_ref()));
    let mediapipe =
        crate::bench_baselines::mediapipe(&clips, &acc.vba_limbs, &a.suite_dir, global)?;
    let mut views = crate::bench_views::ViewTable::new(&["VBA", "MediaPipe"]);
    if let Some((_, mp)) = &mediapipe {
        for ((clip, ours), theirs) in clips.iter().zip(&acc.vba_scores).zip(mp) {
            views.add(clip, &[ours, theirs]);
        }
    }
    lines.extend(mediapipe_lines(mediapipe.as_ref().map(|(t, _)| t), &views));
    lines.extend(crate::bench_track_speed::speed_lines(
        &clips, threads, params,
    )?);
    if global.json {
        println!(
            "{}",
            serde_json::json!({
                "clips": acc.rows_json,
                "vba": acc.tally.json(|s| accuracy_json(&s[0])),
                "vba_exact_marks": acc.tally.json(|s| accuracy_json(&s[1])),
                "fixed_template": acc.tally.json(|s| accuracy_json(&s[2])),
                "real_limb_joints": acc.real_limbs
                    .iter()
                    .map(|(name, a)| serde_json::json!({"clip": name, "vba": accuracy_json(a)}))
                    .collect::<Vec<_>>(),
                "views": views.json(),
                "mediapipe": mediapipe.as_ref().map(|((t, _), _)| t.json(|s| serde_json::json!({
                    "vba_limbs": accuracy_json(&s[0]),
                    "mediapipe_limbs": accuracy_json(&s[1]),
                    "mediapipe_all": accuracy_json(&s[2]),
                }))),
                "opencv": opencv.map(|t| serde_json::json!({
                    "lucas_kanade": t.json(|s| accuracy_json(&s[0])),
                    "csrt": t.json(|s| accuracy_json(&s[1])),
                })),
                "table": lines,
            })
        );
    } else {
        for l in lines {
            println!("{l}");
        }
    }
    Ok(())
}

/// Tracks and scores every clip: the table's heading and a row per clip.
fn track_clips(
    clips: &[BenchClip],
    threads: usize,
    params: TrackerParams,
    global: &GlobalArgs,
) -> Result<AccuracyRun, ExitError> {
    let mut acc = AccuracyRun {
        lines: vec![
            format!(
                "suite v4: {} clips ({} dev, {} test) and 2 real clips (dev); marks clicked with {} px of noise unless 'exact'",
                clips.len() - 2,
                clips
                    .iter()
                    .filter(|c| c.split == Split::Dev && c.family != Family::Real)
                    .count(),
                clips.iter().filter(|c| c.split == Split::Test).count(),
                CLICK_NOISE_PX
            ),
            String::new(),
            format!(
                "{:<26} {:<5} {:<11} {TRACK_COLUMNS}",
                "clip", "split", "family"
            ),
        ],
        rows_json: Vec::new(),
        tally: Tally::default(),
        clicked: Vec::new(),
        real_limbs: Vec::new(),
        vba_limbs: Vec::new(),
        vba_scores: Vec::new(),
    };
    for clip in clips {
        say(global, &format!("tracking {} …", clip.name));
        let (s, score, marks) = score_clip(clip, threads, params)?;
        let limbs = score.limbs();
        acc.vba_scores.push(score);
        if clip.family == Family::Real {
            acc.real_limbs.push((clip.name.clone(), limbs));
        }
        acc.vba_limbs.push(limbs);
        acc.lines.push(format!(
            "{:<26} {:<5} {:<11} {}",
            clip.name,
            clip.split.name(),
            clip.family.name(),
            track_cell(&s)
        ));
        acc.rows_json.push(serde_json::json!({
            "clip": clip.name, "split": clip.split.name(), "family": clip.family.name(),
            "vba": accuracy_json(&s[0]), "vba_exact_marks": accuracy_json(&s[1]),
            "fixed_template": accuracy_json(&s[2]),
        }));
        acc.tally.add(clip, &s);
        acc.clicked.push(marks);
    }
    Ok(acc)
}

/// The tally's table and the real clips' limb joints.
fn summary_lines(acc: &AccuracyRun) -> Vec<String> {
    let mut lines = vec![
        String::new(),
        "VBA from clicked marks (PCK@0.2, lost, mean px), from exact marks (PCK@0.2), fixed template from clicked marks (PCK@0.2)"
            .to_owned(),
    ];
    lines.extend(Tally::<TrackScores>::heading(TRACK_WIDTH, TRACK_COLUMNS));
    lines.extend(acc.tally.lines(TRACK_WIDTH, track_cell));
    if !acc.real_limbs.is_empty() {
        lines.push(String::new());
        lines.push(format!(
            "real clips, the {} limb joints (the four chains and the pelvis), VBA from clicked marks: {}",
            Joint::ALL.into_iter().filter(|&j| is_limb_joint(j)).count(),
            acc.real_limbs
                .iter()
                .map(|(name, a)| format!("{name} PCK@0.2 {:.3}", a.pck02()))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    lines
}

/// MediaPipe's lines: the per-view table and VBA alone against the network alone, or a line
/// saying how to add it when Python's MediaPipe is missing.
fn mediapipe_lines(
    mediapipe: Option<&crate::bench_baselines::LearnedScores>,
    views: &crate::bench_views::ViewTable,
) -> Vec<String> {
    let mut lines = Vec::new();
    let Some((t, per_clip)) = mediapipe else {
        lines.push("(MediaPipe baseline: python3 with mediapipe not found; `python3 -m pip install mediapipe==0.10.21` adds it)".to_owned());
        return lines;
    };
    lines.push(String::new());
    lines.push(
        "per view: VBA from clicked marks against MediaPipe Pose (its own detector, no marks)"
            .to_owned(),
    );
    lines.extend(views.lines());
    lines.push(String::new());
    lines.push(
        "VBA alone (clicked marks) against the network alone (MediaPipe Pose 0.10.21, its own detector, no marks), PCK@0.2 of the 13 limb joints; MediaPipe's lost share and its 16 joints (neck, chest, pelvis and head top derived: scripts/mediapipe_baseline.py)".to_owned(),
    );
    lines.extend(Tally::<crate::bench_baselines::Learned>::heading(
        crate::bench_baselines::LEARNED_WIDTH,
        crate::bench_baselines::LEARNED_COLUMNS,
    ));
    lines.extend(t.lines(
        crate::bench_baselines::LEARNED_WIDTH,
        crate::bench_baselines::learned_cell,
    ));
    for (name, s) in per_clip.iter().filter(|(n, _)| n.starts_with("real")) {
        lines.push(format!(
            "{name:<18} |{}",
            crate::bench_baselines::learned_cell(s)
        ));
    }
    lines
}

/// An accuracy as JSON: PCK@0.1, PCK@0.2, lost share, mean error in pixels, samples.
pub(crate) fn accuracy_json(a: &Accuracy) -> serde_json::Value {
    serde_json::json!({"pck01": a.pck01(), "pck02": a.pck02(), "lost": a.lost(), "mean_px": a.mean_px(), "samples": a.count})
}
