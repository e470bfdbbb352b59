//! The desktop app (eframe/egui). Placeholder until the GUI issue: `run` is replaced there.

use std::path::PathBuf;

pub fn run(_video: Option<PathBuf>) -> anyhow::Result<()> {
    Err(anyhow::anyhow!("GUI not yet"))
}
