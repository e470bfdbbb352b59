//! `videomocap volume DIR --out-dir OUT`: the second pipeline on a directory of per-frame point
//! clouds, with a progress bar; writes skeleton3d.json, motion.bvh, joints3d.csv and motion.trc
//! and prints one warning per frame that gave no pose.

use super::args::{GlobalArgs, VolumeArgs};
use super::export::{Outputs3d, report_3d, write_3d};
use super::{ExitError, progress_bar, say};
use anyhow::anyhow;
use std::sync::atomic::AtomicBool;
use videomocap_volume::{SequenceError, VolumeParams, process_directory};

pub(super) fn run(a: &VolumeArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    check_args(a)?;
    let params = VolumeParams::default();
    let bar = progress_bar(global, 0, "volumes");
    let processed = process_directory(
        &a.input,
        &params,
        a.fps,
        &|done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
        &AtomicBool::new(false),
    )
    .map_err(|e| match e {
        SequenceError::Cancelled => ExitError::failed(e),
        _ => ExitError::bad_input(e),
    })?;
    bar.finish_and_clear();
    for w in &processed.assembled.warnings {
        say(global, &format!("warning: {w}"));
    }
    std::fs::create_dir_all(&a.out_dir)
        .map_err(|e| ExitError::failed(anyhow!("{}: cannot create: {e}", a.out_dir.display())))?;
    let skeleton_path = a.out_dir.join("skeleton3d.json");
    let skeleton = &processed.assembled.skeleton;
    skeleton.save(&skeleton_path).map_err(ExitError::failed)?;
    summary(&processed, global);
    say(global, &format!("wrote {}", skeleton_path.display()));
    let outputs = Outputs3d {
        bvh: Some(a.out_dir.join("motion.bvh")),
        csv: Some(a.out_dir.join("joints3d.csv")),
        trc: Some(a.out_dir.join("motion.trc")),
        rig: a.rig,
    };
    let written = write_3d(skeleton, &skeleton_path, None, &outputs)?;
    report_3d(&written, global);
    Ok(())
}

/// The input must be a directory and the frame rate positive.
fn check_args(a: &VolumeArgs) -> Result<(), ExitError> {
    let meta = std::fs::metadata(&a.input)
        .map_err(|e| ExitError::bad_input(anyhow!("{}: cannot open: {e}", a.input.display())))?;
    if !meta.is_dir() {
        return Err(ExitError::bad_input(anyhow!(
            "{}: expected a directory of per-frame point clouds (.ply, .xyz, .voxels.json)",
            a.input.display()
        )));
    }
    if !(a.fps.is_finite() && a.fps > 0.0) {
        return Err(ExitError::bad_input(anyhow!(
            "--fps must be positive, got {}",
            a.fps
        )));
    }
    Ok(())
}

/// How many frames gave a curve and a pose, the time per frame, and how the articulated fit
/// went.
fn summary(processed: &videomocap_volume::Processed, global: &GlobalArgs) {
    let (five, ok) = (processed.five_limb_frames(), processed.posed_frames());
    let (iso, rest) = processed
        .results
        .iter()
        .flatten()
        .fold((0.0, 0.0), |(i, r), f| (i + f.seconds[0], r + f.seconds[1]));
    say(
        global,
        &format!(
            "{} of {} frames gave a five-limb skeleton curve, {} a pose (arms against the trunk placed from other frames); left/right from the {:?}; {:.1} ms per frame on one core ({:.0}% Isomap)",
            five,
            processed.files.len(),
            ok,
            processed.assembled.sides_from,
            1000.0 * (iso + rest) / ok.max(1) as f64,
            100.0 * iso / (iso + rest).max(1e-12),
        ),
    );
    match &processed.fitted {
        Some(f) => {
            let flagged = f
                .skeleton
                .frames
                .iter()
                .filter(|k| !k.flags.is_empty())
                .count();
            say(
                global,
                &format!(
                    "the subject's body fitted over the clip: {flagged} of {} frames flagged (see the warnings), {} started from the curve's pose",
                    f.skeleton.frames.len(),
                    f.from_curve
                ),
            );
        }
        None => say(
            global,
            "warning: the articulated fit could not start (no frame with a five-limb curve and points); the skeleton is the curve's",
        ),
    }
}
