//! `videomocap run`: track, lift and export into one directory.

use super::args::{GlobalArgs, LiftOptions, RunArgs};
use super::export::{Outputs3d, report_3d, write_3d, write_tracks_csv};
use super::{ExitError, say};
use anyhow::anyhow;
use std::path::Path;
use videomocap_core::skeleton::Joint;
use videomocap_core::track::{SpanKind, TrackerParams};

/// File names `run` writes in its output directory.
pub(super) const TRACKS_JSON: &str = "tracks2d.json";
pub(super) const TRACKS_CSV: &str = "tracks2d.csv";
pub(super) const SKELETON_JSON: &str = "skeleton3d.json";
pub(super) const BVH: &str = "motion.bvh";
pub(super) const JOINTS_CSV: &str = "joints3d.csv";
pub(super) const TRC: &str = "motion.trc";

/// `run`.
pub(super) fn run(a: &RunArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let threads = super::cpus::thread_budget(a.threads)?.threads;
    super::cpus::limit_global_pool(threads);
    run_into(
        &RunInput {
            video: &a.video,
            marks: a.marks.as_deref(),
            keys: a.keys.as_deref(),
            tracker: videomocap_core::track::TrackerParams::default(),
            no_network: a.no_network,
            threads,
            options: &a.options,
        },
        &a.out_dir,
        global,
    )?;
    Ok(())
}

/// What one `run` works from.
pub(super) struct RunInput<'a> {
    /// The video (or image folder).
    pub video: &'a Path,
    /// A marks file, or
    pub marks: Option<&'a Path>,
    /// a keys file.
    pub keys: Option<&'a Path>,
    /// Tracker settings.
    pub tracker: videomocap_core::track::TrackerParams,
    /// Track with VBA alone.
    pub no_network: bool,
    /// Threads for every pool of the run (decoder, tracker, pose network); see `cli::cpus`.
    pub threads: usize,
    /// Camera, subject and lift settings.
    pub options: &'a LiftOptions,
}

/// What one `run` found, for reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct RunReport {
    /// Frames of the clip.
    pub frames: usize,
    /// Joint-frames left weak, lost or off the frame (not interpolated), percent.
    pub weak_pct: f64,
    /// Frames the lift flagged (a bone too long for its image, no key pose), percent.
    pub flagged_pct: f64,
}

/// Tracks, lifts and exports into `out_dir` (created if missing).
pub(super) fn run_into(
    input: &RunInput,
    out_dir: &Path,
    global: &GlobalArgs,
) -> Result<RunReport, ExitError> {
    let (params, known) = super::lift::check_options(input.options)?;
    let (mut video, keys) =
        super::track::open_checked(input.video, input.marks, input.keys, input.threads)?;
    std::fs::create_dir_all(out_dir)
        .map_err(|e| ExitError::failed(anyhow!("{}: cannot create: {e}", out_dir.display())))?;
    let out = super::track::track_with_progress(
        &mut video,
        &keys,
        input.threads,
        TrackerParams {
            // `--no-network` is the settings' switch turned off.
            network: input.tracker.network && !input.no_network,
            ..input.tracker
        },
        global,
    )?;
    let path = out_dir.join(TRACKS_JSON);
    out.tracks.save(&path).map_err(ExitError::failed)?;
    super::track::report(&out, global);
    say(global, &format!("wrote {}", path.display()));
    let csv = out_dir.join(TRACKS_CSV);
    write_tracks_csv(&out.tracks, &csv)?;
    say(global, &format!("wrote {}", csv.display()));
    let lifted = super::lift::lift_with_progress(
        &out.tracks,
        input.video,
        input.options,
        params,
        &known,
        global,
    )?;
    let path = out_dir.join(SKELETON_JSON);
    lifted.skeleton.save(&path).map_err(ExitError::failed)?;
    super::lift::report(&lifted, params.foot_lock, global);
    say(global, &format!("wrote {}", path.display()));
    let outputs = Outputs3d {
        bvh: Some(out_dir.join(BVH)),
        csv: Some(out_dir.join(JOINTS_CSV)),
        trc: Some(out_dir.join(TRC)),
        rig: input.options.rig,
    };
    let written = write_3d(&lifted.skeleton, &path, None, &outputs)?;
    report_3d(&written, global);
    let frames = out.tracks.frames.len();
    let weak: usize = out
        .spans
        .iter()
        .filter(|s| s.kind != SpanKind::Interpolated)
        .map(|s| s.frames())
        .sum();
    let flagged = lifted
        .reports
        .iter()
        .filter(|r| !r.flags.is_empty())
        .count();
    let pct = |k: usize, n: usize| 100.0 * k as f64 / n.max(1) as f64;
    Ok(RunReport {
        frames,
        weak_pct: pct(weak, frames * Joint::ALL.len()),
        flagged_pct: pct(flagged, frames),
    })
}
