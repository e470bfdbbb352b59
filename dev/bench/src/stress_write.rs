//! `videomocap-bench stress-write`: the writer the crash-safety test kills. Each round
//! changes the project (corrections whose x coordinate is the round number: on one frame in odd
//! rounds, on every frame in even ones, so consecutive files differ in size), saves it the
//! way the app's autosave and File ▸ Save do, and writes the BVH, CSV and TRC exports the way
//! `export` does. A torn file would show as one that does not load. Each step is announced on
//! stdout (`save N`, `export N`) just before it starts.

use crate::ExitError;
use crate::args::StressWriteArgs;
use anyhow::anyhow;
use nalgebra::Point2;
use std::io::Write;
use videomocap::cli::export::{Outputs3d, write_3d};
use videomocap_core::formats::FrameIndex;
use videomocap_core::project::Project;
use videomocap_core::skeleton::{Joint, PerJoint};

/// The frame whose left wrist carries the round number.
pub(crate) const ROUND_FRAME: usize = 1;

pub(crate) fn run(a: &StressWriteArgs) -> Result<(), ExitError> {
    let mut project = Project::load(&a.project).map_err(ExitError::bad_input)?;
    let skeleton = project.skeleton.clone().ok_or_else(|| {
        ExitError::bad_input(anyhow!(
            "{}: the project has no skeleton",
            a.project.display()
        ))
    })?;
    std::fs::create_dir_all(&a.out_dir).map_err(ExitError::failed)?;
    let outputs = Outputs3d {
        bvh: Some(a.out_dir.join("motion.bvh")),
        csv: Some(a.out_dir.join("joints3d.csv")),
        trc: Some(a.out_dir.join("motion.trc")),
        rig: Default::default(),
    };
    let frames = skeleton.frames.len();
    let mut round = 0u64;
    while a.rounds.is_none_or(|r| round < r) {
        round += 1;
        let mut correction = PerJoint::from_fn(|_| None);
        correction[Joint::LeftWrist] = Some(Point2::new(round as f64, 0.5));
        project.keys.frames.retain(|&f, _| f == FrameIndex(0));
        let corrected = if round.is_multiple_of(2) {
            1..frames
        } else {
            ROUND_FRAME..ROUND_FRAME + 1
        };
        for f in corrected {
            project.keys.frames.insert(FrameIndex(f), correction);
        }
        // Each step is announced on stdout first, so the test can aim its kill at it.
        announce(&format!("save {round}"))?;
        project.save(&a.project).map_err(ExitError::failed)?;
        announce(&format!("export {round}"))?;
        write_3d(&skeleton, &a.project, None, &outputs)?;
    }
    announce("done")
}

fn announce(step: &str) -> Result<(), ExitError> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{step}")
        .and_then(|()| out.flush())
        .map_err(ExitError::failed)
}
