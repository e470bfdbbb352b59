//! `videomocap batch`: one process and three shards give the same summary, every row runs
//! exactly once, a rerun skips what is done, and a bad row fails alone.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use assert_cmd::Command;
use std::collections::BTreeSet;
use std::path::Path;
use videomocap_testkit::synth::{ProceduralMotion, View, render_small_clip};

/// Runs `videomocap batch` (without the pose network) with `leading` before and `args` after
/// the manifest and output folder.
fn run_batch(leading: &[&str], manifest: &Path, out: &Path, args: &[&str]) -> std::process::Output {
    Command::cargo_bin("videomocap")
        .unwrap()
        .args(leading)
        .arg("batch")
        .arg(manifest)
        .arg("--out-dir")
        .arg(out)
        .args(["--no-network"])
        .args(args)
        .output()
        .unwrap()
}

/// Runs `videomocap batch` with `args`, quiet, in JSON; (exit code, stdout).
fn batch(manifest: &Path, out: &Path, args: &[&str]) -> (i32, String) {
    let o = run_batch(&["--quiet", "--json"], manifest, out, args);
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
    )
}

/// Runs `videomocap batch` with `args` and without `--quiet`; (exit code, stderr).
fn batch_loud(manifest: &Path, out: &Path, args: &[&str]) -> (i32, String) {
    let o = run_batch(&[], manifest, out, args);
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The hidden entries of a folder (temporary row folders).
fn hidden_entries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

/// The summary without its seconds column (timings differ between runs).
fn summary_without_seconds(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("summary.csv"))
        .unwrap()
        .lines()
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            cells.remove(5);
            cells.join(",")
        })
        .collect()
}

/// The ids a `--json` run reported, with their status.
fn reported(stdout: &str) -> Vec<(String, String)> {
    let v: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["id"].as_str().unwrap().to_owned(),
                r["status"].as_str().unwrap().to_owned(),
            )
        })
        .collect()
}

#[test]
fn three_shards_run_every_row_once_and_gather_the_one_process_summary() {
    let dir = tempfile::tempdir().unwrap();
    render_small_clip(dir.path(), ProceduralMotion::Wave, 6, View::Oblique).unwrap();
    // Four good rows of the same clip, one without marks, one whose video is missing.
    let mut manifest = String::from("video,keys,height_m,id\n");
    for k in 0..4 {
        manifest += &format!("frames,marks.json,1.{k}5,take_{k}\n");
    }
    manifest += "frames,,,unmarked\nmissing.mp4,marks.json,,gone\n";
    let m = dir.path().join("manifest.csv");
    std::fs::write(&m, manifest).unwrap();

    let one = dir.path().join("one");
    let (code, _) = batch(&m, &one, &["--jobs", "2"]);
    assert_eq!(code, 1, "two rows cannot be done");
    let summary = summary_without_seconds(&one);
    assert_eq!(summary.len(), 7);
    for k in 0..4 {
        assert!(
            summary[k + 1].starts_with(&format!("take_{k},ok,6,")),
            "{summary:?}"
        );
        assert!(one.join(format!("take_{k}/motion.bvh")).exists());
    }
    assert!(
        summary[5].starts_with("unmarked,needs_marks,"),
        "{}",
        summary[5]
    );
    assert!(summary[6].starts_with("gone,failed,"), "{}", summary[6]);
    assert!(summary[6].contains("missing.mp4"), "{}", summary[6]);
    // No half-written row is left behind.
    assert_eq!(hidden_entries(&one), Vec::<String>::new());

    // A rerun skips the finished rows (their status files are not rewritten) and says which.
    let status = one.join("take_0/status.json");
    let before = std::fs::read_to_string(&status).unwrap();
    let other = one.join("take_1/status.json");
    let other_before = std::fs::read_to_string(&other).unwrap();
    let (code, err) = batch_loud(&m, &one, &[]);
    assert_eq!(code, 1);
    assert!(
        err.contains("skipped 4 rows already done")
            && err.contains("take_0, take_1, take_2, take_3"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&status).unwrap(), before);
    // A changed input (the stated height) redoes that row only.
    std::fs::write(
        &m,
        std::fs::read_to_string(&m)
            .unwrap()
            .replace("1.05,take_0", "1.8,take_0"),
    )
    .unwrap();
    batch(&m, &one, &[]);
    assert_ne!(std::fs::read_to_string(&status).unwrap(), before);
    assert_eq!(std::fs::read_to_string(&other).unwrap(), other_before);

    // A Slurm array of three tasks (`--shard slurm`, --array=1-3), three processes, then the
    // summary gathered.
    let sharded = dir.path().join("sharded");
    let mut seen = Vec::new();
    let children: Vec<_> = (1..=3)
        .map(|k| {
            std::process::Command::new(assert_cmd::cargo::cargo_bin("videomocap"))
                .args(["--quiet", "--json", "batch"])
                .arg(&m)
                .arg("--out-dir")
                .arg(&sharded)
                .args(["--no-network", "--shard", "slurm"])
                .env("SLURM_ARRAY_TASK_ID", k.to_string())
                .env("SLURM_ARRAY_TASK_MIN", "1")
                .env("SLURM_ARRAY_TASK_MAX", "3")
                .env("SLURM_ARRAY_TASK_COUNT", "3")
                .stdout(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let o = c.wait_with_output().unwrap();
        let rows = reported(&String::from_utf8_lossy(&o.stdout));
        // Six rows over three tasks: two each.
        assert_eq!(rows.len(), 2, "{rows:?}");
        seen.extend(rows);
    }
    let ids: Vec<&str> = seen.iter().map(|(id, _)| id.as_str()).collect();
    let unique: BTreeSet<&str> = ids.iter().copied().collect();
    assert_eq!(ids.len(), 6, "every row in exactly one shard: {ids:?}");
    assert_eq!(unique.len(), 6);
    let (code, _) = batch(&m, &sharded, &["--summary-only"]);
    assert_eq!(code, 1);
    assert_eq!(
        summary_without_seconds(&sharded),
        summary_without_seconds(&one)
    );
}

#[test]
fn a_malformed_manifest_exits_2_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.csv");
    std::fs::write(&m, "video,height_m\na.mp4,1.7\nb.mp4,tall\n").unwrap();
    let o = Command::cargo_bin("videomocap")
        .unwrap()
        .arg("batch")
        .arg(&m)
        .arg("--out-dir")
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("m.csv: line 3: column height_m"), "{err}");
}

#[test]
fn every_manifest_problem_is_reported_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.csv");
    // A duplicate id before a bad height and a bad field of view: all three are named.
    std::fs::write(
        &m,
        "video,height_m,fov_deg,id\na.mp4,1.7,,x\nb.mp4,1.7,,x\nc.mp4,tall,,c\nd.mp4,,-60,d\n",
    )
    .unwrap();
    let (code, err) = batch_loud(&m, &dir.path().join("out"), &[]);
    assert_eq!(code, 2);
    for want in [
        "3 problems",
        "m.csv: line 3: column id: \"x\" is used twice",
        "m.csv: line 4: column height_m: \"tall\"",
        "m.csv: line 5: column fov_deg: \"-60\"",
    ] {
        assert!(err.contains(want), "{want}: {err}");
    }
    assert!(!dir.path().join("out").exists(), "nothing runs");
}

#[test]
fn a_killed_batch_leaves_nothing_behind_after_the_rerun() {
    let dir = tempfile::tempdir().unwrap();
    render_small_clip(dir.path(), ProceduralMotion::Wave, 12, View::Oblique).unwrap();
    let m = dir.path().join("manifest.csv");
    std::fs::write(&m, "video,keys,id\nframes,marks.json,take\n").unwrap();
    let out = dir.path().join("out");
    // Killed (as by a time limit or scancel) while it writes its row.
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("videomocap"))
        .args(["--quiet", "batch"])
        .arg(&m)
        .arg("--out-dir")
        .arg(&out)
        .args(["--no-network", "--threads", "1"])
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while !out.is_dir() || hidden_entries(&out).is_empty() {
        assert!(
            started.elapsed().as_secs() < 60,
            "no temporary folder appeared"
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let left = hidden_entries(&out);
    assert_eq!(left.len(), 1, "{left:?}");
    assert!(left[0].starts_with(".partial-take-"), "{left:?}");
    assert!(
        !out.join("take").exists(),
        "a row's folder is complete or absent"
    );
    // The rerun does the row and removes the dead process's folder.
    let (code, err) = batch_loud(&m, &out, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("removed 1 unfinished row folder"), "{err}");
    assert_eq!(hidden_entries(&out), Vec::<String>::new());
    assert!(out.join("take/motion.bvh").exists());
}
