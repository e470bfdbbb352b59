//! `videomocap run`: track, lift and export into one directory.

use super::args::{GlobalArgs, RunArgs};
use super::export::{Outputs3d, report_3d, write_3d, write_tracks_csv};
use super::{ExitError, say};
use anyhow::anyhow;

/// File names `run` writes in its output directory.
pub const TRACKS_JSON: &str = "tracks2d.json";
pub const TRACKS_CSV: &str = "tracks2d.csv";
pub const SKELETON_JSON: &str = "skeleton3d.json";
pub const BVH: &str = "motion.bvh";
pub const JOINTS_CSV: &str = "joints3d.csv";
pub const TRC: &str = "motion.trc";

/// `run`.
pub fn run(a: &RunArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let (params, known) = super::lift::check_options(&a.options)?;
    let (mut video, keys) =
        super::track::open_checked(&a.video, a.marks.as_deref(), a.keys.as_deref())?;
    std::fs::create_dir_all(&a.out_dir)
        .map_err(|e| ExitError::failed(anyhow!("{}: cannot create: {e}", a.out_dir.display())))?;
    let out = super::track::track_with_progress(
        &mut video,
        &keys,
        None,
        videomocap_core::track::TrackerParams::default(),
        global,
    )?;
    let path = a.out_dir.join(TRACKS_JSON);
    out.tracks.save(&path).map_err(ExitError::failed)?;
    super::track::report(&out, global);
    say(global, &format!("wrote {}", path.display()));
    let csv = a.out_dir.join(TRACKS_CSV);
    write_tracks_csv(&out.tracks, &csv)?;
    say(global, &format!("wrote {}", csv.display()));
    let lifted =
        super::lift::lift_with_progress(&out.tracks, &a.video, &a.options, params, &known, global)?;
    let path = a.out_dir.join(SKELETON_JSON);
    lifted.skeleton.save(&path).map_err(ExitError::failed)?;
    super::lift::report(&lifted, global);
    say(global, &format!("wrote {}", path.display()));
    let outputs = Outputs3d {
        bvh: Some(a.out_dir.join(BVH)),
        csv: Some(a.out_dir.join(JOINTS_CSV)),
        trc: Some(a.out_dir.join(TRC)),
    };
    let written = write_3d(&lifted.skeleton, &path, None, &outputs)?;
    report_3d(&written, global);
    Ok(())
}
