//! `videomocap carve SETUP -o OUT`: voxel carving (paper §2) of every frame of a carving set-up
//! (cameras.json with the box, and masks/<camera>/), with a progress bar; writes one
//! `.voxels.json` grid per frame for `videomocap volume`.

use super::args::{CarveArgs, GlobalArgs};
use super::{ExitError, progress_bar, say};
use anyhow::anyhow;
use std::sync::atomic::AtomicBool;
use videomocap::volume::VolumeError;
use videomocap::volume::carve::{carve_sequence, open_setup};

pub fn run(a: &CarveArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    if !(a.voxel_mm.is_finite() && a.voxel_mm >= 5.0) {
        return Err(ExitError::bad_input(anyhow!(
            "--voxel-mm must be at least 5, got {}",
            a.voxel_mm
        )));
    }
    if !a.setup.is_dir() {
        return Err(ExitError::bad_input(anyhow!(
            "{}: expected a carving set-up directory (cameras.json and masks/<camera>/)",
            a.setup.display()
        )));
    }
    let setup = open_setup(&a.setup).map_err(ExitError::bad_input)?;
    let bar = progress_bar(global, setup.frames.len() as u64, "carving");
    let counts = carve_sequence(
        &setup,
        a.voxel_mm / 1000.0,
        a.min_votes,
        &a.output,
        &|done, _| bar.set_position(done as u64),
        &AtomicBool::new(false),
    )
    .map_err(|e| match &e {
        // Writing the grids failed: processing, not input.
        VolumeError::Format(_) => ExitError::failed(e),
        VolumeError::Io { path, .. } if path.starts_with(&a.output) => ExitError::failed(e),
        _ => ExitError::bad_input(e),
    })?;
    bar.finish_and_clear();
    let empty = counts.iter().filter(|&&c| c == 0).count();
    if empty > 0 {
        say(
            global,
            &format!(
                "warning: {empty} frames carved to nothing (the person outside bounds_m, or masks that do not agree)"
            ),
        );
    }
    say(
        global,
        &format!(
            "carved {} frames from {} cameras ({:.0} voxels per frame) into {}",
            counts.len(),
            setup.cameras.len(),
            counts.iter().sum::<usize>() as f64 / counts.len().max(1) as f64,
            a.output.display()
        ),
    );
    Ok(())
}
