//! OpenCV's trackers as baselines in `bench track`, when Python's OpenCV is present:
//! `scripts/opencv_baselines.py` tracks each clip from the same clicked marks (Lucas–Kanade on
//! every clip; CSRT, at about a fifth of a second a frame, on the test split and the real clips
//! only) and writes positions, which are scored here like our own tracks. Outputs are kept in
//! the suite's folder and reused while the clip and its marks are unchanged.

use crate::args::GlobalArgs;
use crate::bench_suite::{BenchClip, Tally};
use crate::{ExitError, say};
use anyhow::anyhow;
use nalgebra::Point2;
use std::path::Path;
use std::process::Command;
use videomocap_core::formats::Marks;
use videomocap_core::skeleton::{Joint, PerJoint};
use videomocap_testkit::eval::suite::{Family, Split};
use videomocap_testkit::eval::{Accuracy, score_positions};
use videomocap_testkit::repo_root;
use videomocap_testkit::synth::GroundTruth;

/// Width of [`cell`].
pub const WIDTH: usize = 28;
/// The columns of [`cell`].
pub const COLUMNS: &str = "LK PCK.2  lost  CSRT   lost";

/// One split's column: Lucas–Kanade's PCK@0.2 and lost share, then CSRT's (blank without).
pub fn cell(s: &[Accuracy; 2]) -> String {
    let csrt = if s[1].count > 0 {
        format!("{:>6.3} {:>5.1}%", s[1].pck02(), 100.0 * s[1].lost())
    } else {
        format!("{:>13}", "-")
    };
    format!("{:>7.3} {:>5.1}% {csrt}", s[0].pck02(), 100.0 * s[0].lost())
}

/// Whether `python3` can import OpenCV.
fn opencv_present() -> bool {
    Command::new("python3")
        .args(["-c", "import cv2, numpy"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Runs the baselines on `clips` from `clicked` (one set of marks per clip) and scores them;
/// `None` when OpenCV is not there.
pub fn run(
    clips: &[BenchClip],
    clicked: &[Marks],
    suite_dir: &Path,
    global: &GlobalArgs,
) -> Result<Option<Tally<[Accuracy; 2]>>, ExitError> {
    if !opencv_present() {
        return Ok(None);
    }
    let out_dir = suite_dir.join("opencv");
    std::fs::create_dir_all(&out_dir).map_err(ExitError::failed)?;
    let mut jobs = Vec::new();
    let mut outputs = Vec::new();
    for (clip, marks) in clips.iter().zip(clicked) {
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
        let stamp = serde_json::json!({"video": video, "marks": joints, "methods": methods});
        let file = out_dir.join(format!("{}.json", clip.name.replace(' ', "_")));
        let stamp_file = file.with_extension("stamp");
        let stamp_text = stamp.to_string();
        let fresh =
            std::fs::read_to_string(&stamp_file).is_ok_and(|s| s == stamp_text) && file.is_file();
        if !fresh {
            jobs.push(serde_json::json!({
                "name": clip.name, "video": video, "marks": joints, "methods": methods,
                "joints": Joint::ALL.iter().map(|j| j.name()).collect::<Vec<_>>(),
                "out": file,
            }));
        }
        outputs.push((file, stamp_file, stamp));
    }
    if !jobs.is_empty() {
        say(
            global,
            &format!("running OpenCV's trackers on {} clips …", jobs.len()),
        );
        let jobs_file = out_dir.join("jobs.json");
        videomocap_core::formats::write_atomically(
            &jobs_file,
            serde_json::Value::Array(jobs).to_string().as_bytes(),
        )
        .map_err(ExitError::failed)?;
        let status = Command::new("python3")
            .arg(repo_root().join("scripts/opencv_baselines.py"))
            .arg(&jobs_file)
            .status()
            .map_err(ExitError::failed)?;
        if !status.success() {
            return Err(ExitError::failed(anyhow!(
                "scripts/opencv_baselines.py failed ({status})"
            )));
        }
        for (_, stamp_file, stamp) in &outputs {
            videomocap_core::formats::write_atomically(stamp_file, stamp.to_string().as_bytes())
                .map_err(ExitError::failed)?;
        }
    }
    let mut tally = Tally::default();
    for (clip, (file, _, _)) in clips.iter().zip(&outputs) {
        let gt = GroundTruth::load(&clip.dir.join("gt.json")).map_err(ExitError::failed)?;
        let text = std::fs::read_to_string(file).map_err(ExitError::failed)?;
        let value: serde_json::Value = serde_json::from_str(&text).map_err(ExitError::failed)?;
        let mut scores = [Accuracy::default(), Accuracy::default()];
        for (k, method) in ["lk", "csrt"].iter().enumerate() {
            let Some(frames) = value.get(*method).and_then(|v| v.as_array()) else {
                continue;
            };
            let positions = frames.iter().enumerate().filter_map(|(i, f)| {
                let rows = f.as_array()?;
                let points = PerJoint::from_fn(|j| {
                    let xy = rows.get(j.index()).and_then(|r| r.as_array());
                    let c = |n: usize| {
                        xy.and_then(|v| v.get(n))
                            .and_then(|v| v.as_f64())
                            .unwrap_or(f64::NAN)
                    };
                    Point2::new(c(0), c(1))
                });
                (i < gt.frames.len()).then_some((i, points))
            });
            scores[k] = score_positions(&gt, positions)
                .map_err(ExitError::failed)?
                .overall;
        }
        tally.add(clip, &scores);
    }
    Ok(Some(tally))
}
