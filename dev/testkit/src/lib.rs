//! videomocap's test kit, for tests and benchmarks only (never installed): [`synth`] renders
//! clips (and point volumes, and carving set-ups) with known joints, [`eval`] scores tracks,
//! skeletons and point-volume results against that ground truth and holds the benchmark suite.

pub mod eval;
pub mod synth;

use std::path::PathBuf;

/// The repository's root, where the test data (`tests/data/`), the bundled samples
/// (`sample_videos/`) and the scripts live. Tests and benchmarks run from a source checkout.
pub fn repo_root() -> PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}
