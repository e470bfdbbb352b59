//! `videomocap bench lift`: 3D reconstruction accuracy and speed.
//!
//! On suite v3 (dev and test) and the two real clips, the lift runs on (a) the true 2D points,
//! (b) the true 2D plus Gaussian noise of 2 px (two draws, merged) and (c) the VBA tracker's own
//! output from the marks as a user clicks them; each with the subject's true bone lengths (the
//! geometry alone) and with the height a person would state (the user's condition); each with the
//! true focal length and with the default camera (60° across the longer side). Every figure sits
//! next to the flat cut-out's on the same input ([`cutout`]: every joint on its true viewing ray
//! at the reference pelvis's depth, whatever camera the lift was given), with our figure ÷ the
//! cut-out's. Scores from
//! [`videomocap_testkit::eval::pose3d`], after the global refinement; then the per-frame solve's speed.

use crate::args::{BenchArgs, GlobalArgs};
use crate::bench_suite::{BenchClip, Merge, OpenedClip, Tally, bench_clips};
use crate::bench_track::track_opened;
use crate::{ExitError, say};
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use videomocap_core::camera::default_focal;
use videomocap_core::formats::Tracks2d;

use videomocap_core::lift::{
    CameraChoice, LiftJob, LiftParams, SubjectChoice, lift_per_frame, reconstruct,
};
use videomocap_core::skeleton::{Bone, DEFAULT_HEIGHT_M};
use videomocap_core::track::TrackerParams;
use videomocap_testkit::eval::doubt::{DoubtTally, UNSURE_SWEEP, tally_doubt};
use videomocap_testkit::eval::pose3d::{
    Pose3dScore, cutout, score_skeleton, subject_from_truth, tracks_from_truth,
};
use videomocap_testkit::eval::suite::Split;
use videomocap_testkit::synth::GroundTruth;

/// The seeds of the noise draws of (b).
const NOISE_SEEDS: [u64; 2] = [7, 1];

const INPUTS: [&str; 3] = ["(a) true 2D", "(b) 2D + 2 px noise", "(c) VBA tracks"];
const LENGTHS: [&str; 2] = ["true lengths", "stated height"];
const FOCALS: [&str; 2] = ["true focal", "default 60°"];

/// The lift's score and the cut-out's on the same input and camera.
type Pair = (Pose3dScore, Pose3dScore);
/// Every case of one clip: `[input][lengths][focal]`, and per input the bone lengths the lift
/// ended with from the stated height and the true focal length, and its doubts there.
type Cases = ([[[Pair; 2]; 2]; 3], [(LengthErrors, DoubtTally); 3]);

/// How far the bone lengths a lift ended with are from the reference's: |read ÷ true − 1| per
/// bone and clip.
#[derive(Debug, Clone, Default)]
struct LengthErrors(Vec<f64>);

impl Merge for LengthErrors {
    fn merge_from(&mut self, other: &Self) {
        self.0.extend_from_slice(&other.0);
    }
}

impl LengthErrors {
    /// The median error, as a share.
    fn median(&self) -> f64 {
        let mut v = self.0.clone();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    }
}

/// The doubt table's heading.
pub(crate) fn doubt_columns() -> String {
    format!(
        "{:>8} {:>13} {}",
        "flagged",
        "wrong f/unf",
        UNSURE_SWEEP
            .iter()
            .map(|m| format!("{:>17}", format!("<{m:.3}: u% wu/ws")))
            .collect::<Vec<_>>()
            .join(" ")
    )
}

/// The doubt table's columns: frames flagged, wrong rates flagged / not, and per margin the
/// unsure share with the wrong rates unsure / sure (percent).
pub(crate) fn doubt_cell(d: &DoubtTally) -> String {
    let (wf, wu) = d.flagged_rates();
    let mut s = format!(
        "{:>7.1}% {:>6.1}/{:<6.1}",
        100.0 * d.frames_flagged_share(),
        100.0 * wf,
        100.0 * wu
    );
    for k in 0..UNSURE_SWEEP.len() {
        let (u, wu, ws) = d.unsure_rates(k);
        s += &format!(
            " {:>17}",
            format!("{:.1} {:.0}/{:.0}", 100.0 * u, 100.0 * wu, 100.0 * ws)
        );
    }
    s
}

/// The side table's column: the lengths' median error and the share of frames mirrored.
fn side_cell(errors: &LengthErrors, score: &Pose3dScore) -> String {
    format!(
        "{:>8.1}% {:>9.1}%",
        100.0 * errors.median(),
        100.0 * score.facing_mirrored_share()
    )
}
const SIDE_COLUMNS: &str = " lengths  mirrored";
const SIDE_WIDTH: usize = 20;

/// One split's column: MPJPE, the cut-out's, their ratio, PA-MPJPE and the wrong depth roots.
fn cell(p: &Pair) -> String {
    format!(
        "{:>6.1} {:>6.1} {:>5.2} {:>6.1} {:>5.1}%",
        p.0.mpjpe_mm(),
        p.1.mpjpe_mm(),
        p.0.mpjpe_mm() / p.1.mpjpe_mm().max(1e-9),
        p.0.pa_mpjpe_mm(),
        100.0 * p.0.wrong_share()
    )
}
const COLUMNS: &str = " MPJPE    cut ratio     PA  roots";
const WIDTH: usize = 33;

/// |read ÷ true − 1| for each bone the reference measures (not the derived joints').
fn length_errors(gt: &GroundTruth, read: &std::collections::BTreeMap<String, f64>) -> Vec<f64> {
    let truth = subject_from_truth(gt);
    let derived = gt.derived();
    Bone::ALL
        .iter()
        .filter(|b| !derived.contains(&b.parent) && !derived.contains(&b.child))
        .filter_map(|b| {
            let r = read.get(&b.key())?;
            Some((r / truth.bone_length(*b).max(1e-9) - 1.0).abs())
        })
        .collect()
}

/// Seconds the per-frame solve takes on `tracks` with the true lengths.
fn time_per_frame_solve(
    tracks: &Tracks2d,
    camera: videomocap_core::camera::PinholeCamera,
    gt: &GroundTruth,
    params: &LiftParams,
) -> Result<f64, ExitError> {
    let job = LiftJob {
        tracks,
        camera,
        subject: subject_from_truth(gt),
        params: *params,
        overrides: Default::default(),
    };
    let t0 = Instant::now();
    lift_per_frame(&job).map_err(ExitError::failed)?;
    Ok(t0.elapsed().as_secs_f64())
}

/// Lifts one clip in every case; returns its cases, the per-frame solve's (frames, seconds) on
/// (a) with true lengths and focal, and the whole lift's seconds (reading the lengths, the
/// per-frame solve, the refinement) on (a) from the stated height with the true focal.
fn run_clip(
    clip: &BenchClip,
    threads: usize,
    params: &LiftParams,
    with_tracker: bool,
) -> Result<(Cases, usize, f64, f64), ExitError> {
    let OpenedClip {
        gt,
        marks,
        mut video,
    } = clip.open()?;
    let mut inputs: Vec<(usize, Tracks2d)> = vec![(0, tracks_from_truth(&gt, 0.0, 1))];
    inputs.extend(NOISE_SEEDS.map(|seed| (1, tracks_from_truth(&gt, 2.0, seed))));
    if with_tracker {
        let tracked = track_opened(&mut video, &marks, threads, TrackerParams::default())?;
        inputs.push((2, tracked));
    }
    let stated = gt.stated_height_m.unwrap_or(DEFAULT_HEIGHT_M);
    let true_camera = gt.camera();
    let mut default_camera = true_camera;
    default_camera.focal_px = default_focal(gt.width, gt.height);
    let mut cases = Cases::default();
    let (mut solve_frames, mut solve_s, mut whole_s) = (0, 0.0, 0.0);
    for (i, tracks) in &inputs {
        // The cut-out always stands on the true viewing rays: the baseline, not a second lift.
        let flat =
            score_skeleton(&gt, &cutout(&gt, tracks, true_camera)).map_err(ExitError::failed)?;
        for (f, camera) in [true_camera, default_camera].into_iter().enumerate() {
            // The user's case reads the lengths through the camera; the true lengths are a
            // subject given whole.
            let subjects = [
                SubjectChoice::Model(Box::new(subject_from_truth(&gt))),
                SubjectChoice::Height {
                    height_m: stated,
                    known: Default::default(),
                },
            ];
            for (l, subject) in subjects.iter().enumerate() {
                if (*i, l, f) == (0, 0, 0) {
                    solve_s += time_per_frame_solve(tracks, camera, &gt, params)?;
                    solve_frames += tracks.frames.len();
                }
                let t0 = Instant::now();
                let out = reconstruct(
                    tracks,
                    CameraChoice::Given(camera),
                    subject,
                    params,
                    Default::default(),
                    &mut |_| {},
                    &AtomicBool::new(false),
                )
                .map_err(ExitError::failed)?
                .output;
                if (*i, l, f) == (0, 1, 0) {
                    whole_s += t0.elapsed().as_secs_f64();
                }
                let score = score_skeleton(&gt, &out.skeleton).map_err(ExitError::failed)?;
                if (l, f) == (1, 0) {
                    cases.1[*i]
                        .0
                        .0
                        .extend(length_errors(&gt, &out.skeleton.bone_lengths_m));
                    let doubt =
                        tally_doubt(&gt, &out.skeleton, &out.bones).map_err(ExitError::failed)?;
                    cases.1[*i].1.merge(&doubt);
                }
                let case = &mut cases.0[*i][l][f];
                case.0.merge(&score);
                case.1.merge(&flat);
            }
        }
    }
    Ok((cases, solve_frames, solve_s, whole_s))
}

/// The tables over splits and families: every input, lengths and camera; per family; lengths
/// and mirrored frames; flags and margins.
fn lift_tables(tally: &Tally<Cases>) -> Vec<String> {
    let mut out = vec![
        "lift after refinement: MPJPE (pelvis aligned), the flat cut-out's on the same input (true rays at the true pelvis depth), MPJPE ÷ cut-out, PA-MPJPE, wrong depth roots; mm".to_owned(),
        String::new(),
        format!(
            "{:<48} | {:<WIDTH$} | {:<WIDTH$}",
            "synthetic overall", "dev", "test"
        ),
        format!("{:<48} | {COLUMNS:<WIDTH$} | {COLUMNS:<WIDTH$}", "input, lengths, camera"),
    ];
    let blank = format!("{:WIDTH$}", "");
    for (i, input) in INPUTS.iter().enumerate() {
        for (l, lengths) in LENGTHS.iter().enumerate() {
            for (f, focal) in FOCALS.iter().enumerate() {
                let col = |split| {
                    tally
                        .get(split, None)
                        .map_or_else(|| blank.clone(), |c| cell(&c.0[i][l][f]))
                };
                out.push(format!(
                    "{:<48} | {} | {}",
                    format!("{input}, {lengths}, {focal}"),
                    col(Split::Dev),
                    col(Split::Test)
                ));
            }
        }
    }
    for (i, l, f) in [(0, 1, 0), (2, 1, 0), (2, 1, 1)] {
        out.push(String::new());
        out.push(format!(
            "per family: {}, {}, {}",
            INPUTS[i], LENGTHS[l], FOCALS[f]
        ));
        out.extend(Tally::<Pair>::heading(WIDTH, COLUMNS));
        out.extend(tally.lines(WIDTH, |c: &Cases| cell(&c.0[i][l][f])));
    }
    out.push(String::new());
    out.push(
        "stated height, true focal: the bone lengths the lift ended with (median |read ÷ true − 1| over bones and clips) and the frames with the body mirrored (shoulders in the wrong depth order, where they differ by over 5 cm)"
            .to_owned(),
    );
    for (i, input) in INPUTS.iter().enumerate() {
        out.push((*input).to_owned());
        out.extend(Tally::<Cases>::heading(SIDE_WIDTH, SIDE_COLUMNS));
        out.extend(tally.lines(SIDE_WIDTH, |c: &Cases| {
            side_cell(&c.1[i].0, &c.0[i][1][0].0)
        }));
    }
    out.push(String::new());
    out.push(
        "stated height, true focal: the depth choices that matter (roots apart, no coin flip): frames with a bone flagged too long; how often a flagged bone's choice is wrong against an unflagged one's; per margin, the share shown unsure and how often an unsure / a sure choice is wrong"
            .to_owned(),
    );
    let doubt_columns = doubt_columns();
    let doubt_width = doubt_columns.chars().count();
    for (i, input) in INPUTS.iter().enumerate() {
        out.push((*input).to_owned());
        out.extend(Tally::<Cases>::heading(doubt_width, &doubt_columns));
        out.extend(tally.lines(doubt_width, |c: &Cases| doubt_cell(&c.1[i].1)));
    }
    out
}

/// Every case's figures per split and family, the clips' rows and the printed table, as JSON.
fn lift_json(
    tally: &Tally<Cases>,
    rows_json: Vec<serde_json::Value>,
    out: &[String],
) -> serde_json::Value {
    let mut cases_json = serde_json::Map::new();
    for (i, input) in INPUTS.iter().enumerate() {
        for (l, lengths) in LENGTHS.iter().enumerate() {
            for (f, focal) in FOCALS.iter().enumerate() {
                cases_json.insert(
                    format!("{input}, {lengths}, {focal}"),
                    tally.json(|c| {
                        let p = &c.0[i][l][f];
                        serde_json::json!({
                            "mpjpe_mm": p.0.mpjpe_mm(), "pa_mpjpe_mm": p.0.pa_mpjpe_mm(),
                            "cutout_mm": p.1.mpjpe_mm(), "wrong_roots": p.0.wrong_share(),
                            "facing_mirrored": p.0.facing_mirrored_share(),
                            "length_median_error": ((l, f) == (1, 0)).then(|| c.1[i].0.median()),
                        })
                    }),
                );
            }
        }
    }
    serde_json::json!({"cases": cases_json, "clips": rows_json, "table": out})
}

/// Runs the lift benchmark and prints its tables.
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let threads = crate::bench_suite::machine_threads();
    let params = crate::bench_suite::lift_settings(a)?;
    let clips = bench_clips(&a.suite_dir, &a.split, a.clip.as_deref(), global)?;
    let mut tally: Tally<Cases> = Tally::default();
    let mut per_clip = vec![format!(
        "{:<26} {:<5} {:<11} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "per clip (true focal)", "split", "family", "(a) true", "(a) mm", "cut", "(c) mm", "cut"
    )];
    let (mut solve_frames, mut solve_s, mut whole_s) = (0, 0.0, 0.0);
    let mut rows_json = Vec::new();
    for clip in &clips {
        say(global, &format!("lifting {} …", clip.name));
        let (cases, n, s, w) = run_clip(clip, threads, &params, !a.no_tracker)?;
        solve_frames += n;
        solve_s += s;
        whole_s += w;
        let (ex, tr) = (&cases.0[0][1][0], &cases.0[2][1][0]);
        per_clip.push(format!(
            "{:<26} {:<5} {:<11} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>8.1}",
            clip.name,
            clip.split.name(),
            clip.family.name(),
            cases.0[0][0][0].0.mpjpe_mm(),
            ex.0.mpjpe_mm(),
            ex.1.mpjpe_mm(),
            tr.0.mpjpe_mm(),
            tr.1.mpjpe_mm()
        ));
        rows_json.push(serde_json::json!({
            "clip": clip.name, "split": clip.split.name(), "family": clip.family.name(),
            "exact_2d_true_lengths_mm": cases.0[0][0][0].0.mpjpe_mm(),
            "exact_2d_stated_height_mm": ex.0.mpjpe_mm(), "exact_2d_cutout_mm": ex.1.mpjpe_mm(),
            "tracker_stated_height_mm": tr.0.mpjpe_mm(), "tracker_cutout_mm": tr.1.mpjpe_mm(),
        }));
        tally.add(clip, &cases);
    }
    let mut out = lift_tables(&tally);
    out.push(String::new());
    out.extend(per_clip);
    out.push(String::new());
    out.push(format!(
        "speed: per-frame solve on (a) with true lengths {:.0} frames/s",
        solve_frames as f64 / solve_s.max(1e-9)
    ));
    out.push(format!(
        "speed: the whole lift from the stated height (reading the lengths, the per-frame solve, the refinement) on (a), one thread: {:.2} s per 1000 frames",
        1000.0 * whole_s / solve_frames.max(1) as f64
    ));
    if global.json {
        println!("{}", lift_json(&tally, rows_json, &out));
    } else {
        for l in out {
            println!("{l}");
        }
    }
    Ok(())
}
