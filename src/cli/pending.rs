//! Commands whose pipeline step is not built yet. Each one checks its inputs fully (so a user
//! learns about a bad file now) and then exits with code 2 and a sentence naming what is missing.

use super::ExitError;
use super::args::VolumeArgs;
use anyhow::anyhow;

fn not_built(capability: &str) -> ExitError {
    ExitError::bad_input(anyhow!(
        "{capability} is not built yet in this version of videomocap; the inputs were checked and are valid"
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
