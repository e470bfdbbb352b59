//! The README's benchmark figures equal the benchmark outputs committed under `docs/bench/`
//! (`videomocap-bench report --check`): a figure edited by hand, or an output committed without
//! running `videomocap-bench report`, fails the suite.

use std::process::Command;

#[test]
fn the_readmes_figures_match_the_committed_benchmark_outputs() {
    let root = videomocap_testkit::repo_root();
    let output = Command::new(env!("CARGO_BIN_EXE_videomocap-bench"))
        .arg("report")
        .arg("--check")
        .arg("--readme")
        .arg(root.join("README.md"))
        .arg("--figures")
        .arg(root.join("docs/bench/figures.json"))
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
}
