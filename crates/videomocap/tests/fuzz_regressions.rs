//! Replays the fuzz seeds and every input the fuzzers ever crashed on
//! (`tests/fuzz/seeds/TARGET/`, `tests/fuzz/regressions/TARGET/`) through the same checks the
//! fuzz targets run (`tests/fuzz/checks.rs`): no panic, round trips exact. Seeds must parse.

#[path = "../../../tests/fuzz/checks.rs"]
mod checks;

use std::path::Path;

fn files(dir: &Path) -> Vec<std::path::PathBuf> {
    match std::fs::read_dir(dir) {
        Ok(entries) => entries.filter_map(|e| e.ok().map(|e| e.path())).collect(),
        Err(_) => Vec::new(),
    }
}

#[test]
fn seeds_parse_and_round_trip() {
    let root = videomocap_testkit::repo_root().join("tests/fuzz/seeds");
    for target in checks::TARGETS {
        let seeds = files(&root.join(target));
        assert!(!seeds.is_empty(), "no seeds for {target}");
        for seed in seeds {
            let data = std::fs::read(&seed).unwrap();
            assert!(
                checks::check(target, &data),
                "seed {} does not parse",
                seed.display()
            );
        }
    }
}

#[test]
fn every_crash_found_by_fuzzing_is_fixed() {
    let root = videomocap_testkit::repo_root().join("tests/fuzz/regressions");
    for target in checks::TARGETS {
        let inputs = files(&root.join(target));
        // A missing or empty folder would let this test pass having checked nothing: each
        // target keeps hostile inputs (truncated, empty, not UTF-8, huge numbers and NaN)
        // beside any crash the fuzzers find.
        assert!(
            !inputs.is_empty(),
            "no regression inputs for {target} in {}",
            root.display()
        );
        for input in inputs {
            let data = std::fs::read(&input).unwrap();
            let outcome = std::panic::catch_unwind(|| checks::check(target, &data));
            assert!(outcome.is_ok(), "{} panics again", input.display());
        }
    }
}
