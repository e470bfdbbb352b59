//! The tools a user would pick instead, as baselines in `bench track`, each when its Python
//! package is present:
//! - OpenCV's trackers (`scripts/opencv_baselines.py`) from the same clicked marks:
//!   Lucas–Kanade on every clip; CSRT, at about a fifth of a second a frame, on the test split
//!   and the real clips only;
//! - MediaPipe Pose (`scripts/mediapipe_baseline.py`), the learned detector alone on every
//!   frame, with no marks (it follows whoever it finds).
//!
//! Each script writes positions, which are scored here like our own tracks. Outputs are kept in
//! the suite's folder and reused while the clip (and, for OpenCV, its marks) is unchanged.

use crate::args::GlobalArgs;
use crate::bench_suite::{BenchClip, Tally};
use crate::{ExitError, say};
use anyhow::anyhow;
use nalgebra::Point2;
use std::path::{Path, PathBuf};
use std::process::Command;
use videomocap_core::formats::Marks;
use videomocap_core::skeleton::{Joint, PerJoint};
use videomocap_testkit::eval::suite::{Family, Split};
use videomocap_testkit::eval::{Accuracy, ClipScore, score_positions};
use videomocap_testkit::repo_root;
use videomocap_testkit::synth::GroundTruth;

/// Width of [`opencv_cell`].
pub(crate) const OPENCV_WIDTH: usize = 28;
/// The columns of [`opencv_cell`].
pub(crate) const OPENCV_COLUMNS: &str = "LK PCK.2  lost  CSRT   lost";

/// One split's column: Lucas–Kanade's PCK@0.2 and lost share, then CSRT's (blank without).
pub(crate) fn opencv_cell(s: &[Accuracy; 2]) -> String {
    let csrt = if s[1].count > 0 {
        format!("{:>6.3} {:>5.1}%", s[1].pck02(), 100.0 * s[1].lost())
    } else {
        format!("{:>13}", "-")
    };
    format!("{:>7.3} {:>5.1}% {csrt}", s[0].pck02(), 100.0 * s[0].lost())
}

/// Width of [`learned_cell`].
pub(crate) const LEARNED_WIDTH: usize = 35;
/// The columns of [`learned_cell`].
pub(crate) const LEARNED_COLUMNS: &str = "VBA limbs  MP limbs   lost  MP all";

/// VBA against MediaPipe: [VBA's 13 limb joints, MediaPipe's 13 limb joints, MediaPipe's 16].
pub(crate) type Learned = [Accuracy; 3];

/// One split's column of the learned comparison: PCK@0.2 of VBA's limb joints, MediaPipe's limb
/// joints (and its lost share), MediaPipe's 16 joints.
pub(crate) fn learned_cell(s: &Learned) -> String {
    format!(
        "{:>9.3} {:>9.3} {:>5.1}% {:>7.3}",
        s[0].pck02(),
        s[1].pck02(),
        100.0 * s[1].lost(),
        s[2].pck02()
    )
}

/// Whether `python3` can import `modules` (comma-separated).
fn python_has(modules: &str) -> bool {
    Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// One clip's job for a script: what its output depends on (`stamp`) and the job's entry
/// (without `out`, which is added here).
struct Job {
    name: String,
    stamp: serde_json::Value,
    entry: serde_json::Value,
}

/// Runs `script` on the jobs whose output in `out_dir` is missing or stale; returns each job's
/// output file, in order.
fn run_script(
    script: &str,
    what: &str,
    out_dir: &Path,
    jobs: Vec<Job>,
    global: &GlobalArgs,
) -> Result<Vec<PathBuf>, ExitError> {
    std::fs::create_dir_all(out_dir).map_err(ExitError::failed)?;
    let mut todo = Vec::new();
    let mut outputs = Vec::new();
    let mut stamps = Vec::new();
    for job in jobs {
        let file = out_dir.join(format!("{}.json", job.name.replace(' ', "_")));
        let stamp_file = file.with_extension("stamp");
        let stamp_text = job.stamp.to_string();
        let fresh =
            std::fs::read_to_string(&stamp_file).is_ok_and(|s| s == stamp_text) && file.is_file();
        if !fresh {
            let mut entry = job.entry;
            entry["name"] = serde_json::json!(job.name);
            entry["out"] = serde_json::json!(file);
            todo.push(entry);
            stamps.push((stamp_file, stamp_text));
        }
        outputs.push(file);
    }
    if !todo.is_empty() {
        say(global, &format!("running {what} on {} clips …", todo.len()));
        let jobs_file = out_dir.join("jobs.json");
        videomocap_core::formats::write_atomically(
            &jobs_file,
            serde_json::Value::Array(todo).to_string().as_bytes(),
        )
        .map_err(ExitError::failed)?;
        let status = Command::new("python3")
            .arg(repo_root().join("scripts").join(script))
            .arg(&jobs_file)
            .status()
            .map_err(ExitError::failed)?;
        if !status.success() {
            return Err(ExitError::failed(anyhow!(
                "scripts/{script} failed ({status})"
            )));
        }
        for (stamp_file, stamp) in &stamps {
            videomocap_core::formats::write_atomically(stamp_file, stamp.as_bytes())
                .map_err(ExitError::failed)?;
        }
    }
    Ok(outputs)
}

/// Where a joint a baseline did not report is scored (far off any image: lost).
const NOT_FOUND_PX: f64 = -1.0e4;

/// Scores `method`'s positions in a script's output `file` against the clip's truth (`None`
/// when the output has no such method).
fn score_output(
    gt: &GroundTruth,
    file: &Path,
    method: &str,
) -> Result<Option<ClipScore>, ExitError> {
    let text = std::fs::read_to_string(file).map_err(ExitError::failed)?;
    let value: serde_json::Value = serde_json::from_str(&text).map_err(ExitError::failed)?;
    let Some(frames) = value.get(method).and_then(|v| v.as_array()) else {
        return Ok(None);
    };
    // A frame without a person (null) scores as every joint lost: its joints are put far off
    // the image (a missing coordinate would count as neither found nor lost).
    let positions = frames.iter().enumerate().filter_map(|(i, f)| {
        let rows = f.as_array();
        let points = PerJoint::from_fn(|j| {
            let xy = rows
                .and_then(|r| r.get(j.index()))
                .and_then(|r| r.as_array());
            let c = |n: usize| {
                xy.and_then(|v| v.get(n))
                    .and_then(|v| v.as_f64())
                    .filter(|v| v.is_finite())
                    .unwrap_or(NOT_FOUND_PX)
            };
            Point2::new(c(0), c(1))
        });
        (i < gt.frames.len()).then_some((i, points))
    });
    Ok(Some(
        score_positions(gt, positions).map_err(ExitError::failed)?,
    ))
}

/// Runs OpenCV's trackers on `clips` from `clicked` (one set of marks per clip) and scores them;
/// `None` when OpenCV is not there.
pub(crate) fn opencv(
    clips: &[BenchClip],
    clicked: &[Marks],
    suite_dir: &Path,
    global: &GlobalArgs,
) -> Result<Option<Tally<[Accuracy; 2]>>, ExitError> {
    if !python_has("cv2, numpy") {
        return Ok(None);
    }
    let jobs = clips
        .iter()
        .zip(clicked)
        .map(|(clip, marks)| {
            let methods: &[&str] = if clip.split == Split::Test || clip.family == Family::Real {
                &["lk", "csrt"]
            } else {
                &["lk"]
            };
            let joints: serde_json::Map<String, serde_json::Value> = Joint::ALL
                .iter()
                .map(|&j| {
                    let p = marks.points[j];
                    (j.name().to_owned(), serde_json::json!([p.x, p.y]))
                })
                .collect();
            let video = clip.dir.join("video.mp4");
            Job {
                name: clip.name.clone(),
                stamp: serde_json::json!({"video": video, "marks": joints, "methods": methods}),
                entry: serde_json::json!({
                    "video": video, "marks": joints, "methods": methods,
                    "joints": Joint::ALL.iter().map(|j| j.name()).collect::<Vec<_>>(),
                }),
            }
        })
        .collect();
    let outputs = run_script(
        "opencv_baselines.py",
        "OpenCV's trackers",
        &suite_dir.join("opencv"),
        jobs,
        global,
    )?;
    let mut tally = Tally::default();
    for (clip, file) in clips.iter().zip(&outputs) {
        let gt = GroundTruth::load(&clip.dir.join("gt.json")).map_err(ExitError::failed)?;
        let mut scores = [Accuracy::default(), Accuracy::default()];
        for (k, method) in ["lk", "csrt"].iter().enumerate() {
            if let Some(s) = score_output(&gt, file, method)? {
                scores[k] = s.overall;
            }
        }
        tally.add(clip, &scores);
    }
    Ok(Some(tally))
}

/// OpenCV's table: its heading line (naming what is scored) and the per-family rows, or the line
/// that says how to install it.
pub(crate) fn opencv_lines(tally: Option<&Tally<[Accuracy; 2]>>) -> Vec<String> {
    let Some(t) = tally else {
        return vec!["(OpenCV baselines: python3 with cv2 not found; `python3 -m pip install opencv-contrib-python-headless numpy` adds them)".to_owned()];
    };
    let mut lines = vec![
        "OpenCV from the same clicked marks, all 16 joints: Lucas–Kanade (PCK@0.2, lost), CSRT (PCK@0.2, lost; test split and real clips only)".to_owned(),
    ];
    lines.extend(Tally::<[Accuracy; 2]>::heading(
        OPENCV_WIDTH,
        OPENCV_COLUMNS,
    ));
    lines.extend(t.lines(OPENCV_WIDTH, opencv_cell));
    lines
}

/// The learned comparison per split and family, and per clip (name, scores).
pub(crate) type LearnedScores = (Tally<Learned>, Vec<(String, Learned)>);

/// Runs MediaPipe Pose on `clips` (outputs kept and reused) and scores it, one score per clip;
/// `None` when MediaPipe is not there.
pub(crate) fn mediapipe_scores(
    clips: &[BenchClip],
    suite_dir: &Path,
    global: &GlobalArgs,
) -> Result<Option<Vec<ClipScore>>, ExitError> {
    if !python_has("cv2, mediapipe") {
        return Ok(None);
    }
    let jobs = clips
        .iter()
        .map(|clip| {
            let video = clip.dir.join("video.mp4");
            let size = std::fs::metadata(&video).map_or(0, |m| m.len());
            Job {
                name: clip.name.clone(),
                stamp: serde_json::json!({"video": video, "bytes": size, "model": "mediapipe 0.10.21 pose full"}),
                entry: serde_json::json!({"video": video}),
            }
        })
        .collect();
    let outputs = run_script(
        "mediapipe_baseline.py",
        "MediaPipe Pose",
        &suite_dir.join("mediapipe"),
        jobs,
        global,
    )?;
    let mut out = Vec::with_capacity(clips.len());
    for (clip, file) in clips.iter().zip(&outputs) {
        let gt = GroundTruth::load(&clip.dir.join("gt.json")).map_err(ExitError::failed)?;
        out.push(score_output(&gt, file, "mediapipe")?.ok_or_else(|| {
            ExitError::failed(anyhow!("{}: no mediapipe output", file.display()))
        })?);
    }
    Ok(Some(out))
}

/// Runs MediaPipe Pose on `clips` and scores it beside VBA's limb joints (`vba_limbs`, one per
/// clip); `None` when MediaPipe is not there. Also each clip's MediaPipe score.
pub(crate) fn mediapipe(
    clips: &[BenchClip],
    vba_limbs: &[Accuracy],
    suite_dir: &Path,
    global: &GlobalArgs,
) -> Result<Option<(LearnedScores, Vec<ClipScore>)>, ExitError> {
    let Some(scores) = mediapipe_scores(clips, suite_dir, global)? else {
        return Ok(None);
    };
    let mut tally = Tally::default();
    let mut per_clip = Vec::new();
    for ((clip, s), vba) in clips.iter().zip(&scores).zip(vba_limbs) {
        let scores = [*vba, s.limbs(), s.overall];
        tally.add(clip, &scores);
        per_clip.push((clip.name.clone(), scores));
    }
    Ok(Some(((tally, per_clip), scores)))
}
