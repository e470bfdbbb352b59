//! Commands whose pipeline step is not built yet. Each one checks its inputs fully (so a user
//! learns about a bad file now) and then exits with code 2 and a sentence naming what is missing.

use super::ExitError;
use super::args::{ExportArgs, LiftArgs, LiftOptions, RunArgs, VolumeArgs};
use anyhow::anyhow;
use std::path::Path;
use videomocap::formats::{Marks, Skeleton3d, Tracks2d};
use videomocap::video::{OpenOptions, Video};

fn not_built(capability: &str) -> ExitError {
    ExitError::bad_input(anyhow!(
        "{capability} is not built yet in this version of videomocap; the inputs were checked and are valid"
    ))
}

fn check_video_and_marks(video: &Path, marks: &Path) -> Result<(), ExitError> {
    let v = Video::open(video, &OpenOptions::default()).map_err(ExitError::bad_input)?;
    let m = Marks::load(marks).map_err(ExitError::bad_input)?;
    let info = v.info();
    if m.frame >= info.frame_count {
        return Err(ExitError::bad_input(anyhow!(
            "{}: marks are on frame {} but {} has {} frames",
            marks.display(),
            m.frame,
            video.display(),
            info.frame_count
        )));
    }
    m.check_in_frame(marks, info.width, info.height)
        .map_err(ExitError::bad_input)
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

pub fn run_all(a: &RunArgs) -> Result<(), ExitError> {
    check_lift_options(&a.options)?;
    check_video_and_marks(&a.video, &a.marks)?;
    Err(not_built(
        "the full pipeline (run: tracking, 3D reconstruction, export)",
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
