//! Commands whose pipeline step is not built yet. Each one checks its inputs fully (so a user
//! learns about a bad file now) and then exits with code 2 and a sentence naming what is missing.

use super::ExitError;
use super::args::{ExportArgs, RunArgs, VolumeArgs};
use anyhow::anyhow;
use videomocap::formats::Skeleton3d;

fn not_built(capability: &str) -> ExitError {
    ExitError::bad_input(anyhow!(
        "{capability} is not built yet in this version of videomocap; the inputs were checked and are valid"
    ))
}

pub fn export(a: &ExportArgs) -> Result<(), ExitError> {
    Skeleton3d::load(&a.skeleton).map_err(ExitError::bad_input)?;
    Err(not_built("BVH and CSV export (export)"))
}

/// `run`: the track and lift steps run (tracks2d.json and skeleton3d.json in the output
/// directory); the export after them is not built yet.
pub fn run_all(a: &RunArgs, global: &super::args::GlobalArgs) -> Result<(), ExitError> {
    super::lift::check_options(&a.options)?;
    let (mut video, marks) = super::track::open_checked(&a.video, &a.marks)?;
    std::fs::create_dir_all(&a.out_dir)
        .map_err(|e| ExitError::failed(anyhow!("{}: cannot create: {e}", a.out_dir.display())))?;
    let out = super::track::track_with_progress(
        &mut video,
        &marks,
        None,
        videomocap::track::TrackerParams::default(),
        global,
    )?;
    let path = a.out_dir.join("tracks2d.json");
    out.tracks.save(&path).map_err(ExitError::failed)?;
    super::track::report(&out, global);
    super::say(global, &format!("wrote {}", path.display()));
    let lifted = super::lift::lift_with_progress(&out.tracks, &a.video, &a.options, global)?;
    let path = a.out_dir.join("skeleton3d.json");
    lifted.skeleton.save(&path).map_err(ExitError::failed)?;
    super::lift::report(&lifted, global);
    super::say(global, &format!("wrote {}", path.display()));
    Err(not_built("BVH export (the export step of run)"))
}

pub fn volume(a: &VolumeArgs) -> Result<(), ExitError> {
    let meta = std::fs::metadata(&a.input)
        .map_err(|e| ExitError::bad_input(anyhow!("{}: cannot open: {e}", a.input.display())))?;
    if !meta.is_dir() {
        return Err(ExitError::bad_input(anyhow!(
            "{}: expected a directory of per-frame point clouds",
            a.input.display()
        )));
    }
    Err(not_built("the volume pipeline (volume)"))
}
