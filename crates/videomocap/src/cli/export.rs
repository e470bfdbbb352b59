//! `videomocap export`: BVH, CSV and TRC from a skeleton3d.json, or the tracks CSV from a
//! tracks2d.json; also the export step of `run` and `lift --bvh`.

use super::args::{ExportArgs, GlobalArgs};
use super::{ExitError, say};
use anyhow::anyhow;
use std::path::{Path, PathBuf};
use videomocap_core::export::{self, BvhExport, RigNames, WorldSkeleton};
use videomocap_core::formats::{self, Skeleton3d, Tracks2d};

/// Which 3D files to write (any may be absent).
#[derive(Debug, Default)]
pub struct Outputs3d {
    pub bvh: Option<PathBuf>,
    pub csv: Option<PathBuf>,
    pub trc: Option<PathBuf>,
    /// The BVH's bone names.
    pub rig: RigNames,
}

/// What a 3D export wrote and measured.
pub struct Written3d {
    pub world: WorldSkeleton,
    pub bvh: Option<BvhExport>,
    pub paths: Vec<PathBuf>,
}

/// Writes the requested 3D exports of `skeleton` (read from `source`, named in errors).
pub fn write_3d(
    skeleton: &Skeleton3d,
    source: &Path,
    fps: Option<f64>,
    outputs: &Outputs3d,
) -> Result<Written3d, ExitError> {
    let named = |e: export::ExportError| ExitError::bad_input(anyhow!("{}: {e}", source.display()));
    let world = WorldSkeleton::new(skeleton, fps).map_err(named)?;
    let mut paths = Vec::new();
    let mut bvh = None;
    let save = |path: &Path, text: &str| export::save_text(path, text).map_err(ExitError::failed);
    if let Some(path) = &outputs.bvh {
        let out = export::bvh(&world, outputs.rig).map_err(named)?;
        paths.push(save(path, &out.text)?);
        bvh = Some(out);
    }
    if let Some(path) = &outputs.csv {
        paths.push(save(path, &export::skeleton_csv(&world))?);
    }
    if let Some(path) = &outputs.trc {
        let name = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        paths.push(save(path, &export::trc(&world, &name))?);
    }
    Ok(Written3d { world, bvh, paths })
}

/// Prints what a 3D export did.
pub fn report_3d(w: &Written3d, global: &GlobalArgs) {
    say(
        global,
        &format!(
            "world: up from the {}; the floor {}; {} frames at {} fps",
            w.world.world.up_source,
            w.world.world.floor_source,
            w.world.frames.len(),
            w.world.fps
        ),
    );
    if let Some(b) = &w.bvh {
        say(
            global,
            &format!(
                "BVH read back: every joint within {:.3} mm of the skeleton; largest Euler step between frames {:.1}°",
                b.max_round_trip_m * 1000.0,
                b.max_angle_step_deg
            ),
        );
    }
    for p in &w.paths {
        say(global, &format!("wrote {}", p.display()));
    }
}

/// `export`.
pub fn run(a: &ExportArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    if a.bvh.is_none() && a.csv.is_none() && a.trc.is_none() {
        return Err(ExitError::bad_input(anyhow!(
            "nothing to write: give at least one of --bvh, --csv, --trc"
        )));
    }
    match formats::load_any(&a.input).map_err(ExitError::bad_input)? {
        formats::AnyFile::Skeleton3d(skeleton) => {
            let outputs = Outputs3d {
                bvh: a.bvh.clone(),
                csv: a.csv.clone(),
                trc: a.trc.clone(),
                rig: a.rig,
            };
            let written = write_3d(&skeleton, &a.input, a.fps, &outputs)?;
            report_3d(&written, global);
            if global.json {
                let summary = serde_json::json!({
                    "frames": written.world.frames.len(),
                    "fps": written.world.fps,
                    "up_source": written.world.world.up_source.to_string(),
                    "floor_source": written.world.world.floor_source.to_string(),
                    "bvh_round_trip_mm": written.bvh.as_ref().map(|b| b.max_round_trip_m * 1000.0),
                    "bvh_max_euler_step_deg": written.bvh.as_ref().map(|b| b.max_angle_step_deg),
                    "written": written.paths,
                });
                println!("{summary}");
            }
            Ok(())
        }
        formats::AnyFile::Tracks2d(tracks) => {
            if a.bvh.is_some() || a.trc.is_some() {
                return Err(ExitError::bad_input(anyhow!(
                    "{}: a tracks2d file is 2D; --bvh and --trc need a skeleton3d (run `lift` first)",
                    a.input.display()
                )));
            }
            let Some(path) = &a.csv else {
                return Ok(());
            };
            write_tracks_csv(&tracks, path)?;
            say(global, &format!("wrote {}", path.display()));
            if global.json {
                println!(
                    "{}",
                    serde_json::json!({"frames": tracks.frames.len(), "written": [path]})
                );
            }
            Ok(())
        }
    }
}

/// Writes the tracks CSV.
pub fn write_tracks_csv(tracks: &Tracks2d, path: &Path) -> Result<(), ExitError> {
    export::save_text(path, &export::tracks_csv(tracks)).map_err(ExitError::failed)?;
    Ok(())
}
