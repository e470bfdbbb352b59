//! Commands whose pipeline step is not built yet. Each one checks its inputs fully (so a user
//! learns about a bad file now) and then exits with code 2 and a sentence naming what is missing.

use super::ExitError;
use super::args::{ExportArgs, LiftArgs, LiftOptions, RunArgs, VolumeArgs};
use anyhow::anyhow;
use videomocap::formats::{Skeleton3d, Tracks2d};

fn not_built(capability: &str) -> ExitError {
    ExitError::bad_input(anyhow!(
        "{capability} is not built yet in this version of videomocap; the inputs were checked and are valid"
    ))
}

fn check_lift_options(o: &LiftOptions) -> Result<(), ExitError> {
    if let Some(f) = o.focal_px
        && !(f.is_finite() && f > 0.0)
    {
        return Err(ExitError::bad_input(anyhow!(
            "--focal-px must be positive, got {f}"
        )));
    }
    if let Some(d) = o.fov_deg
        && !(d.is_finite() && d > 0.0 && d < 180.0)
    {
        return Err(ExitError::bad_input(anyhow!(
            "--fov-deg must be between 0 and 180, got {d}"
        )));
    }
    if let Some(h) = o.height_m
        && !(h.is_finite() && h > 0.3 && h < 3.0)
    {
        return Err(ExitError::bad_input(anyhow!(
            "--height-m must be a person's height in metres (0.3 to 3), got {h}"
        )));
    }
    Ok(())
}

pub fn lift(a: &LiftArgs) -> Result<(), ExitError> {
    check_lift_options(&a.options)?;
    Tracks2d::load(&a.tracks).map_err(ExitError::bad_input)?;
    Err(not_built("3D reconstruction (lift)"))
}

pub fn export(a: &ExportArgs) -> Result<(), ExitError> {
    Skeleton3d::load(&a.skeleton).map_err(ExitError::bad_input)?;
    Err(not_built("BVH and CSV export (export)"))
}

/// `run`: the track step runs (tracks2d.json in the output directory); the steps after it are
/// not built yet.
pub fn run_all(a: &RunArgs, global: &super::args::GlobalArgs) -> Result<(), ExitError> {
    check_lift_options(&a.options)?;
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
    Err(not_built(
        "3D reconstruction and export (the lift and export steps of run)",
    ))
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
