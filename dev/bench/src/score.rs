//! `videomocap-bench score`: a synthetic clip's tracks against its ground truth, per joint.

use crate::{ExitError, say};
use std::path::Path;
use videomocap::cli::args::GlobalArgs;
use videomocap_core::formats::Tracks2d;
use videomocap_testkit::eval::score_tracks;
use videomocap_testkit::synth::GroundTruth;

/// Prints the per-joint and overall accuracy of `tracks` against `reference` (and, with
/// `--json`, a summary on stdout).
pub(crate) fn run(tracks: &Path, reference: &Path, global: &GlobalArgs) -> Result<(), ExitError> {
    let tracks = Tracks2d::load(tracks).map_err(ExitError::bad_input)?;
    let gt = GroundTruth::load(reference).map_err(ExitError::bad_input)?;
    let s = score_tracks(&gt, &tracks).map_err(ExitError::bad_input)?;
    for (j, acc) in s.per_joint.iter() {
        if acc.count > 0 {
            say(
                global,
                &format!(
                    "  {:<15} mean {:6.1} px  PCK@0.2 {:.3}  lost {:5.1}%",
                    j.name(),
                    acc.mean_px(),
                    acc.pck02(),
                    100.0 * acc.lost()
                ),
            );
        }
    }
    say(
        global,
        &format!(
            "against the reference: mean {:.1} px, PCK@0.1 {:.3}, PCK@0.2 {:.3}, lost {:.1}%",
            s.overall.mean_px(),
            s.overall.pck01(),
            s.overall.pck02(),
            100.0 * s.overall.lost()
        ),
    );
    if global.json {
        let summary = serde_json::json!({
            "mean_px": s.overall.mean_px(),
            "pck01": s.overall.pck01(),
            "pck02": s.overall.pck02(),
            "lost": s.overall.lost(),
        });
        println!("{summary:#}");
    }
    Ok(())
}
