//! `docs/batch.md`'s Slurm script and submission lines, run as written with the Slurm variables
//! set by hand: a stand-in `sbatch` runs every task of the script's `--array` (with
//! `SLURM_ARRAY_TASK_*` and `SLURM_CPUS_PER_TASK` from its `#SBATCH` lines, in an environment
//! as bare as `--export=NONE` gives: `HOME` and a system `PATH`), then the `--wrap` gather.
//! No Slurm needed.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::Command;
use videomocap_testkit::synth::{ProceduralMotion, View, render_small_clip};

/// The stand-in `sbatch`: `--parsable SCRIPT ARGS…` runs the array's tasks (all at once, as a
/// cluster would) and prints the job id; `--dependency=afterany:ID --wrap CMD` checks the id
/// and runs the command. Anything else fails, so the docs cannot use an option it ignores.
const FAKE_SBATCH: &str = r#"#!/bin/bash
set -u
JOB=4242
log="$FAKE_SLURM_LOG"
if [ "${1:-}" = "--parsable" ]; then
    script=$2; shift 2
    echo "submit $script $*" >> "$log"
    array=$(sed -n 's/^#SBATCH --array=\([0-9-]*\).*/\1/p' "$script")
    cpus=$(sed -n 's/^#SBATCH --cpus-per-task=\([0-9]*\).*/\1/p' "$script")
    [ -n "$array" ] && [ -n "$cpus" ] || { echo "no --array or --cpus-per-task" >&2; exit 1; }
    min=${array%-*}; max=${array#*-}
    pids=()
    for id in $(seq "$min" "$max"); do
        env -i HOME="$HOME" PATH=/usr/bin:/bin \
            SLURM_JOB_ID=$((JOB + id)) SLURM_ARRAY_JOB_ID=$JOB SLURM_ARRAY_TASK_ID=$id \
            SLURM_ARRAY_TASK_MIN=$min SLURM_ARRAY_TASK_MAX=$max \
            SLURM_ARRAY_TASK_COUNT=$((max - min + 1)) SLURM_ARRAY_TASK_STEP=1 \
            SLURM_CPUS_PER_TASK=$cpus SLURM_SUBMIT_DIR="$PWD" \
            bash "$script" "$@" > "slurm-${JOB}_$id.out" 2>&1 &
        pids+=($!)
    done
    for p in "${pids[@]}"; do
        wait "$p"; echo "task exit $?" >> "$log"
    done
    echo "$JOB;cluster"
elif [ "${1:-}" = "--dependency=afterany:$JOB" ] && [ "${2:-}" = "--wrap" ]; then
    echo "gather $3" >> "$log"
    sh -c "$3" > "slurm-$((JOB + 1000)).out" 2>&1
    echo "gather exit $?" >> "$log"
    echo "$((JOB + 1000))"
else
    echo "fake sbatch: unsupported arguments: $*" >&2
    exit 1
fi
"#;

/// The `sh` code blocks of a Markdown file.
fn sh_blocks(markdown: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in markdown.lines().map(str::trim_end) {
        if current.is_none() {
            if line == "```sh" {
                current = Some(String::new());
            }
        } else if line == "```" {
            blocks.extend(current.take());
        } else if let Some(block) = current.as_mut() {
            block.push_str(line);
            block.push('\n');
        }
    }
    blocks
}

fn write_executable(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap();
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

#[test]
fn the_documented_slurm_script_runs_every_row_once_and_the_gather_is_right() {
    let docs =
        std::fs::read_to_string(videomocap_testkit::repo_root().join("docs/batch.md")).unwrap();
    let blocks = sh_blocks(&docs);
    let script = blocks
        .iter()
        .find(|b| b.starts_with("#!/bin/bash") && b.contains("#SBATCH --array="))
        .expect("docs/batch.md has the job-array script");
    let submit = blocks
        .iter()
        .find(|b| b.contains("sbatch --parsable"))
        .expect("docs/batch.md has the submission lines");
    // Sized for nodes of 2 cores.
    let cpus: usize = script
        .lines()
        .find_map(|l| l.strip_prefix("#SBATCH --cpus-per-task="))
        .expect("--cpus-per-task")
        .trim()
        .parse()
        .unwrap();
    assert!(
        (1..=2).contains(&cpus),
        "--cpus-per-task={cpus} on 2-core nodes"
    );

    // The user's home: the binary where `cargo install` puts it, the clips and manifest in a
    // folder of their own; the stand-in sbatch on the submitting shell's PATH.
    let home = tempfile::tempdir().unwrap();
    let cargo_bin = home.path().join(".cargo/bin");
    std::fs::create_dir_all(&cargo_bin).unwrap();
    std::os::unix::fs::symlink(
        assert_cmd::cargo::cargo_bin("videomocap"),
        cargo_bin.join("videomocap"),
    )
    .unwrap();
    let fake_bin = home.path().join("fake-bin");
    std::fs::create_dir_all(&fake_bin).unwrap();
    write_executable(&fake_bin.join("sbatch"), FAKE_SBATCH);
    let walks = home.path().join("walks");
    render_small_clip(&walks, ProceduralMotion::Wave, 5, View::Oblique).unwrap();
    let ids = ["s01_t01", "s01_t02", "s02_t01", "s02_t02", "s03_t01"];
    let mut manifest = String::from("video,keys,height_m,id\n");
    for (k, id) in ids.iter().enumerate() {
        manifest += &format!("frames,marks.json,1.{}0,{id}\n", 5 + k);
    }
    std::fs::write(walks.join("manifest.csv"), manifest).unwrap();
    write_executable(&walks.join("videomocap.sbatch"), script);

    let log = home.path().join("slurm.log");
    let out = Command::new("bash")
        .arg("-c")
        .arg(submit)
        .current_dir(&walks)
        .env_clear()
        .env("HOME", home.path())
        .env(
            "PATH",
            format!(
                "{}:{}:/usr/bin:/bin",
                fake_bin.display(),
                cargo_bin.display()
            ),
        )
        .env("FAKE_SLURM_LOG", &log)
        .output()
        .unwrap();
    let log_text = std::fs::read_to_string(&log).unwrap_or_default();
    let task_logs: String = std::fs::read_dir(&walks)
        .unwrap()
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with("slurm-"))
        .map(|e| std::fs::read_to_string(e.path()).unwrap())
        .collect();
    let context = format!(
        "{}\n{log_text}\n{task_logs}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{context}");
    // Every task and the gather exited 0.
    assert_eq!(log_text.matches("task exit 0").count(), 10, "{context}");
    assert!(log_text.contains("gather exit 0"), "{context}");

    // Every row once, ok, on no more threads than the task's CPUs; nothing half-written.
    let results = walks.join("results");
    let summary = std::fs::read_to_string(results.join("summary.csv")).unwrap();
    let lines: Vec<&str> = summary.lines().skip(1).collect();
    assert_eq!(lines.len(), ids.len(), "{summary}");
    for (line, id) in lines.iter().zip(ids) {
        assert!(line.starts_with(&format!("{id},ok,5,")), "{summary}");
        let status: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(results.join(id).join("status.json")).unwrap(),
        )
        .unwrap();
        let threads = status["threads"].as_u64().unwrap_or(0);
        assert!((1..=cpus as u64).contains(&threads), "{status}");
        assert!(results.join(id).join("motion.bvh").exists());
    }
    let hidden = std::fs::read_dir(&results)
        .unwrap()
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .count();
    assert_eq!(hidden, 0);
}
