//! `videomocap carve SETUP -o OUT`: voxel carving (paper §2) of every frame of a carving set-up
//! (cameras.json with the box, and `masks/<camera>/`), with a progress bar; writes one
//! `.voxels.json` grid per frame for `videomocap volume`.

use super::args::{CarveArgs, GlobalArgs};
use super::{ExitError, progress_bar, say};
use anyhow::anyhow;
use std::sync::atomic::AtomicBool;
use videomocap_volume::VolumeError;
use videomocap_volume::carve::{carve_sequence, open_setup};

pub(super) fn run(a: &CarveArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    check_args(a)?;
    let person = parse_person(a.person.as_deref())?;
    let setup = open_setup(&a.setup).map_err(ExitError::bad_input)?;
    let bar = progress_bar(global, setup.frames.len() as u64, "carving");
    let kept = carve_sequence(
        &setup,
        a.voxel_mm / 1000.0,
        a.min_votes,
        person,
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
    let counts: Vec<Counts> = kept
        .iter()
        .map(|k| Counts {
            voxels: k.voxels,
            dropped_voxels: k.dropped_voxels,
            dropped_components: k.dropped_components,
        })
        .collect();
    report(global, &counts, person.is_some());
    let n = kept.len().max(1) as f64;
    say(
        global,
        &format!(
            "carved {} frames from {} cameras ({:.0} voxels per frame) into {}",
            kept.len(),
            setup.cameras.len(),
            kept.iter().map(|k| k.voxels).sum::<usize>() as f64 / n,
            a.output.display()
        ),
    );
    Ok(())
}

/// Refuses a voxel under 5 mm and a set-up that is not a directory.
fn check_args(a: &CarveArgs) -> Result<(), ExitError> {
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
    Ok(())
}

/// `--person X,Y,Z`: the point in the set-up's world the person stays near.
fn parse_person(text: Option<&str>) -> Result<Option<nalgebra::Point3<f64>>, ExitError> {
    let Some(text) = text else {
        return Ok(None);
    };
    let v: Vec<f64> = text
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()
        .filter(|v: &Vec<f64>| v.len() == 3 && v.iter().all(|x| x.is_finite()))
        .ok_or_else(|| {
            ExitError::bad_input(anyhow!(
                "--person must be X,Y,Z in metres (a point in the set-up's world the person stays near), got {text:?}"
            ))
        })?;
    Ok(Some(nalgebra::Point3::new(v[0], v[1], v[2])))
}

/// What a frame's carve kept and dropped.
struct Counts {
    voxels: usize,
    dropped_voxels: usize,
    dropped_components: usize,
}

/// Says how many frames carved to nothing and what the carve dropped (the other blobs: a second
/// person, a shadow cut off, fragments).
fn report(global: &GlobalArgs, kept: &[Counts], by_person: bool) {
    let empty = kept.iter().filter(|k| k.voxels == 0).count();
    if empty > 0 {
        say(
            global,
            &format!(
                "warning: {empty} frames carved to nothing (the person outside bounds_m, or masks that do not agree)"
            ),
        );
    }
    let with_others: Vec<usize> = (0..kept.len())
        .filter(|&k| kept[k].dropped_voxels > 0)
        .collect();
    if let (Some(first), Some(most)) = (
        with_others.first(),
        with_others
            .iter()
            .max_by_key(|&&k| kept[k].dropped_voxels)
            .copied(),
    ) {
        say(
            global,
            &format!(
                "dropped other blobs on {} of {} frames (from frame {first}; most on frame {most}: {} voxels in {} blobs), keeping {}",
                with_others.len(),
                kept.len(),
                kept[most].dropped_voxels,
                kept[most].dropped_components,
                if by_person {
                    "the person nearest --person, followed over the clip"
                } else {
                    "the largest (--person X,Y,Z keeps the one nearest a point)"
                }
            ),
        );
    }
}
