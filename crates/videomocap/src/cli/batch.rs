//! `videomocap batch MANIFEST.csv --out-dir DIR`: `run` for every row of a manifest, resumable,
//! one row's failure never the batch's, split over a cluster with `--shard K/N` or
//! `--shard slurm` (`docs/batch.md`).
//!
//! Each row is run into a temporary folder renamed to `DIR/<id>` at the end, so a row's folder
//! is complete or absent (`partial`); its `status.json` says how it went and from what inputs,
//! and a rerun skips rows whose status is ok and whose inputs are unchanged (`summary`).

mod manifest;
mod partial;
mod shard;
mod summary;

use super::args::{BatchArgs, GlobalArgs, LiftOptions};
use super::cpus::{ThreadBudget, ThreadSource, limit_global_pool, thread_budget};
use super::run::{RunInput, RunReport, run_into};
use super::{ExitError, say};
use anyhow::anyhow;
use indicatif::{ProgressBar, ProgressStyle};
use manifest::{Row, read_manifest};
use partial::Partial;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Instant, UNIX_EPOCH};
use summary::{Inputs, STATUS_JSON, SUMMARY_CSV, Status, read_status, report, summary_csv};
use videomocap_core::formats::write_atomically;
use videomocap_core::track::TrackerParams;

/// `batch`.
pub(super) fn run(a: &BatchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let rows = read_manifest(&a.manifest)?;
    let shard = a.shard.as_deref().map(shard::parse_shard).transpose()?;
    if a.jobs == 0 {
        return Err(ExitError::bad_input(anyhow!("--jobs must be at least 1")));
    }
    let budget = thread_budget(a.threads)?;
    std::fs::create_dir_all(&a.out_dir)
        .map_err(|e| ExitError::failed(anyhow!("{}: cannot create: {e}", a.out_dir.display())))?;
    let removed = partial::remove_dead(&a.out_dir);
    if removed > 0 {
        say(
            global,
            &format!("removed {removed} unfinished row folder(s) of processes that were stopped"),
        );
    }
    let mine: Vec<&Row> = rows
        .iter()
        .enumerate()
        .filter(|(i, _)| shard.is_none_or(|s| s.holds(*i)))
        .map(|(_, r)| r)
        .collect();
    if let Some(s) = shard {
        say(
            global,
            &format!(
                "shard {} of {} (0-based): {} of {} rows",
                s.index,
                s.count,
                mine.len(),
                rows.len()
            ),
        );
    }
    let skipped = if a.summary_only {
        Vec::new()
    } else {
        run_rows(a, &mine, budget, global)
    };
    // The summary: of every row when not sharded (or gathering), else of this shard's.
    let whole = a.summary_only || shard.is_none();
    let scope: Vec<&Row> = if whole { rows.iter().collect() } else { mine };
    let statuses: Vec<(&Row, Option<Status>)> = scope
        .iter()
        .map(|r| (*r, read_status(&a.out_dir.join(&r.id))))
        .collect();
    if whole {
        let path = a.out_dir.join(SUMMARY_CSV);
        write_atomically(&path, summary_csv(&statuses).as_bytes()).map_err(ExitError::failed)?;
        say(global, &format!("wrote {}", path.display()));
    }
    report(&statuses, &skipped, global);
    let failed = statuses
        .iter()
        .filter(|(_, s)| s.as_ref().is_none_or(|s| s.status != "ok"))
        .count();
    if failed > 0 {
        let see = if whole {
            a.out_dir.join(SUMMARY_CSV)
        } else {
            a.out_dir.join("<id>").join(STATUS_JSON)
        };
        return Err(ExitError::failed(anyhow!(
            "{failed} of {} row(s) not done (see {})",
            statuses.len(),
            see.display()
        )));
    }
    Ok(())
}

/// How many rows run at once and on how many threads each: `--jobs`, never more rows than
/// threads, the threads shared out evenly.
fn plan_jobs(
    jobs: usize,
    budget: ThreadBudget,
    rows: usize,
    global: &GlobalArgs,
) -> (usize, usize) {
    let at_once = jobs.min(budget.threads).min(rows).max(1);
    if jobs > budget.threads {
        let why = match budget.source {
            ThreadSource::Requested => "--threads",
            ThreadSource::Slurm => "SLURM_CPUS_PER_TASK",
            ThreadSource::Affinity => "the CPUs this process may use",
        };
        say(
            global,
            &format!(
                "--jobs {jobs}: running {} row(s) at once, the {} thread(s) of {why}",
                at_once, budget.threads
            ),
        );
    }
    (at_once, (budget.threads / at_once).max(1))
}

/// Runs the rows not already done, `--jobs` at once, with a bar over the rows; returns the ids
/// of the rows skipped as done.
fn run_rows(
    a: &BatchArgs,
    rows: &[&Row],
    budget: ThreadBudget,
    global: &GlobalArgs,
) -> Vec<String> {
    let (at_once, threads) = plan_jobs(a.jobs, budget, rows.len(), global);
    limit_global_pool(budget.threads);
    let bar = if global.quiet {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::new(rows.len() as u64);
        if let Ok(style) =
            ProgressStyle::with_template("{msg:>20} [{bar:40}] {pos}/{len} rows, eta {eta}")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar
    };
    let next = AtomicUsize::new(0);
    let current: Mutex<BTreeSet<String>> = Mutex::default();
    let skipped: Mutex<Vec<(usize, String)>> = Mutex::default();
    let quiet = GlobalArgs {
        quiet: true,
        json: false,
    };
    let show = |set: &BTreeSet<String>| {
        bar.set_message(set.iter().cloned().collect::<Vec<_>>().join(", "));
    };
    std::thread::scope(|s| {
        for _ in 0..at_once {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(row) = rows.get(k) else { break };
                    if let Ok(mut c) = current.lock() {
                        c.insert(row.id.clone());
                        show(&c);
                    }
                    if run_row(a, row, threads, &quiet) == RowRun::Skipped
                        && let Ok(mut list) = skipped.lock()
                    {
                        list.push((k, row.id.clone()));
                    }
                    if let Ok(mut c) = current.lock() {
                        c.remove(&row.id);
                        show(&c);
                    }
                    bar.inc(1);
                }
            });
        }
    });
    bar.finish_and_clear();
    let mut skipped = skipped.into_inner().unwrap_or_default();
    skipped.sort();
    skipped.into_iter().map(|(_, id)| id).collect()
}

/// Whether a row ran or was found done.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum RowRun {
    /// Done before, inputs unchanged: not run again.
    Skipped,
    /// Run (ok or not).
    Ran,
}

/// Runs one row unless it is done and unchanged (or `--force`); its folder is replaced only
/// at the end.
fn run_row(a: &BatchArgs, row: &Row, threads: usize, quiet: &GlobalArgs) -> RowRun {
    let dir = a.out_dir.join(&row.id);
    let inputs = inputs_of(row, a.no_network);
    if !a.force
        && let (Some(old), Ok(now)) = (read_status(&dir), &inputs)
        && old.status == "ok"
        && old.inputs.as_ref() == Some(now)
    {
        return RowRun::Skipped;
    }
    let started = Instant::now();
    let partial = match Partial::create(&a.out_dir, &row.id) {
        Ok(p) => p,
        Err(e) => {
            eprintln!(
                "{}: cannot create the row's folder: {e}",
                a.out_dir.display()
            );
            return RowRun::Ran;
        }
    };
    let outcome =
        partial.with_heartbeat(|| process_row(a, row, &inputs, threads, &partial.path, quiet));
    let status = match &outcome {
        Ok((report, tracker)) => Status {
            status: "ok".into(),
            frames: report.frames,
            weak_pct: report.weak_pct,
            flagged_pct: report.flagged_pct,
            tracker: Some(*tracker),
            ..Status::blank(row)
        },
        Err(e) => {
            // A failed row keeps only its status.
            partial.discard();
            Status {
                status: if row.keys.is_none() {
                    "needs_marks"
                } else {
                    "failed"
                }
                .into(),
                error: Some(e.clone()),
                ..Status::blank(row)
            }
        }
    };
    let status = Status {
        seconds: started.elapsed().as_secs_f64(),
        inputs: inputs.ok(),
        threads: Some(threads),
        ..status
    };
    if let Err(e) = finish(&partial, &status, &dir) {
        eprintln!("{}: cannot write the row's results: {e}", dir.display());
        partial.discard();
    }
    RowRun::Ran
}

/// Tracks, lifts and exports one row into `tmp`; the error is the row's message.
fn process_row(
    a: &BatchArgs,
    row: &Row,
    inputs: &Result<Inputs, String>,
    threads: usize,
    tmp: &Path,
    quiet: &GlobalArgs,
) -> Result<(RunReport, TrackerParams), String> {
    if let Err(e) = inputs {
        return Err(e.clone());
    }
    let tracker = row
        .tracker_settings
        .as_deref()
        .map(super::track::load_settings)
        .transpose()
        .map_err(|e| super::message_with_causes(&e.error))?
        .unwrap_or_default();
    if row.keys.is_none() {
        return Err("needs marks: give the row a keys or marks file".into());
    }
    let options = LiftOptions {
        focal_px: row.focal_px,
        fov_deg: row.fov_deg,
        estimate_focal: false,
        height_m: row.height_m,
        lift_settings: row.lift_settings.clone(),
        lengths: row.lengths.clone(),
        no_foot_lock: false,
        rig: a.rig,
    };
    let (marks, keys) = match row.keys.as_deref() {
        Some(k) if is_marks(k) => (Some(k), None),
        k => (None, k),
    };
    let input = RunInput {
        video: &row.video,
        marks,
        keys,
        tracker,
        no_network: a.no_network,
        threads,
        options: &options,
    };
    // A panic in one row fails that row, never the batch.
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run_into(&input, tmp, quiet)
    }))
    .map_err(|_| "internal error (panic) while processing this row".to_owned())
    .and_then(|r| r.map_err(|e| super::message_with_causes(&e.error)))
    .map(|report| (report, tracker))
}

/// Writes the row's status into its temporary folder and renames that to `dir`.
fn finish(partial: &Partial, status: &Status, dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(&partial.path)?;
    let text = serde_json::to_string_pretty(status).map_err(std::io::Error::other)?;
    std::fs::write(partial.path.join(STATUS_JSON), text)?;
    if let Err(e) = partial.seal()
        && e.kind() != std::io::ErrorKind::NotFound
    {
        return Err(e);
    }
    if dir.exists() {
        std::fs::remove_dir_all(dir)?;
    }
    std::fs::rename(&partial.path, dir)
}

/// A marks file (one frame) rather than a keys file, by its format field.
fn is_marks(path: &Path) -> bool {
    std::fs::read_to_string(path).is_ok_and(|t| t.contains("\"videomocap.marks\""))
}

/// The row's inputs as they are now (an error when the video cannot be read).
fn inputs_of(row: &Row, no_network: bool) -> Result<Inputs, String> {
    let meta = std::fs::metadata(&row.video)
        .map_err(|e| format!("{}: cannot read: {e}", row.video.display()))?;
    let modified = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    let mut files = BTreeMap::new();
    for (name, path) in [
        ("keys", &row.keys),
        ("lengths", &row.lengths),
        ("tracker_settings", &row.tracker_settings),
        ("lift_settings", &row.lift_settings),
    ] {
        if let Some(p) = path {
            let bytes =
                std::fs::read(p).map_err(|e| format!("{}: cannot read: {e}", p.display()))?;
            files.insert(name.to_owned(), format!("{:016x}", fnv1a(&bytes)));
        }
    }
    Ok(Inputs {
        video: row.video.display().to_string(),
        video_bytes: meta.len(),
        video_modified_ns: modified,
        files,
        height_m: row.height_m,
        focal_px: row.focal_px,
        fov_deg: row.fov_deg,
        network: !no_network,
    })
}

/// FNV-1a, 64 bits: a hash that is the same in every process and on every machine.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}
