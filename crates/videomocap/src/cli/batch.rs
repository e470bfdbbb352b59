//! `videomocap batch MANIFEST.csv --out-dir DIR`: `run` for every row of a manifest, resumable,
//! one row's failure never the batch's, split over a cluster with `--shard K/N` (`docs/batch.md`).
//!
//! Each row is run into a temporary folder renamed to `DIR/<id>` at the end, so a row's folder
//! is complete or absent; its `status.json` says how it went and from what inputs, and a rerun
//! skips rows whose status is ok and whose inputs are unchanged.

use super::args::{BatchArgs, GlobalArgs, LiftOptions};
use super::run::{RunInput, RunReport, run_into};
use super::{ExitError, say};
use anyhow::anyhow;
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Instant, UNIX_EPOCH};
use videomocap_core::formats::write_atomically;
use videomocap_core::track::TrackerParams;

/// The manifest's columns (`video` is the only one required).
const COLUMNS: [&str; 9] = [
    "video",
    "keys",
    "height_m",
    "focal_px",
    "fov_deg",
    "lengths",
    "tracker_settings",
    "lift_settings",
    "id",
];

/// Each row's status file, in its folder.
pub const STATUS_JSON: &str = "status.json";
/// The batch's summary, in the output folder.
pub const SUMMARY_CSV: &str = "summary.csv";

/// One row of the manifest, paths resolved against the manifest's folder.
#[derive(Debug, Clone)]
struct Row {
    /// Line in the manifest (1 = the header).
    line: u64,
    id: String,
    video: PathBuf,
    keys: Option<PathBuf>,
    height_m: Option<f64>,
    focal_px: Option<f64>,
    fov_deg: Option<f64>,
    lengths: Option<PathBuf>,
    tracker_settings: Option<PathBuf>,
    lift_settings: Option<PathBuf>,
}

/// What a row's outputs were made from: a rerun redoes the row when any of it changed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Inputs {
    video: String,
    video_bytes: u64,
    video_modified_ns: u128,
    /// Each given file (keys, lengths, settings) by column: a hash of its contents.
    files: BTreeMap<String, String>,
    height_m: Option<f64>,
    focal_px: Option<f64>,
    fov_deg: Option<f64>,
    network: bool,
}

/// A row's `status.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Status {
    format: String,
    version: u32,
    id: String,
    /// `ok`, `failed` or `needs_marks`.
    status: String,
    error: Option<String>,
    frames: usize,
    weak_pct: f64,
    flagged_pct: f64,
    seconds: f64,
    tool_version: String,
    /// The tracker settings used (defaults filled in).
    tracker: Option<TrackerParams>,
    inputs: Option<Inputs>,
}

/// `batch`.
pub fn run(a: &BatchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let rows = read_manifest(&a.manifest)?;
    let shard = a.shard.as_deref().map(parse_shard).transpose()?;
    if a.jobs == 0 {
        return Err(ExitError::bad_input(anyhow!("--jobs must be at least 1")));
    }
    std::fs::create_dir_all(&a.out_dir)
        .map_err(|e| ExitError::failed(anyhow!("{}: cannot create: {e}", a.out_dir.display())))?;
    let mine: Vec<&Row> = rows
        .iter()
        .filter(|r| shard.is_none_or(|(k, n)| shard_of(&r.id, n) == k))
        .collect();
    if !a.summary_only {
        run_rows(a, &mine, global);
    }
    // The summary: of every row when not sharded (or gathering), else of this shard's.
    let scope: Vec<&Row> = if a.summary_only || shard.is_none() {
        rows.iter().collect()
    } else {
        mine
    };
    let statuses: Vec<(&Row, Option<Status>)> = scope
        .iter()
        .map(|r| (*r, read_status(&a.out_dir.join(&r.id))))
        .collect();
    if a.summary_only || shard.is_none() {
        let path = a.out_dir.join(SUMMARY_CSV);
        write_atomically(&path, summary_csv(&statuses).as_bytes()).map_err(ExitError::failed)?;
        say(global, &format!("wrote {}", path.display()));
    }
    report(&statuses, global);
    let failed = statuses
        .iter()
        .filter(|(_, s)| s.as_ref().is_none_or(|s| s.status != "ok"))
        .count();
    if failed > 0 {
        let see = if a.summary_only || shard.is_none() {
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

/// Runs the rows not already done, `--jobs` at once, with a bar over the rows.
fn run_rows(a: &BatchArgs, rows: &[&Row], global: &GlobalArgs) {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = (cores / a.jobs).max(1);
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
    let quiet = GlobalArgs {
        quiet: true,
        json: false,
    };
    let show = |set: &BTreeSet<String>| {
        bar.set_message(set.iter().cloned().collect::<Vec<_>>().join(", "));
    };
    std::thread::scope(|s| {
        for _ in 0..a.jobs.min(rows.len()) {
            s.spawn(|| {
                while let Some(row) = rows.get(next.fetch_add(1, Ordering::Relaxed)) {
                    if let Ok(mut c) = current.lock() {
                        c.insert(row.id.clone());
                        show(&c);
                    }
                    run_row(a, row, threads, &quiet);
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
}

/// Runs one row unless it is done and unchanged (or `--force`); its folder is replaced only
/// at the end.
fn run_row(a: &BatchArgs, row: &Row, threads: usize, quiet: &GlobalArgs) {
    let dir = a.out_dir.join(&row.id);
    let inputs = inputs_of(row, a.no_network);
    if !a.force
        && let (Some(old), Ok(now)) = (read_status(&dir), &inputs)
        && old.status == "ok"
        && old.inputs.as_ref() == Some(now)
    {
        return;
    }
    let started = Instant::now();
    let tmp = a
        .out_dir
        .join(format!(".partial-{}-{}", row.id, std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let tracker = row
        .tracker_settings
        .as_deref()
        .map(super::track::load_settings)
        .transpose();
    let outcome: Result<(RunReport, TrackerParams), String> = match (&inputs, tracker) {
        (Err(e), _) => Err(e.clone()),
        (_, Err(e)) => Err(super::message_with_causes(&e.error)),
        _ if row.keys.is_none() => Err("needs marks: give the row a keys or marks file".into()),
        (Ok(_), Ok(tracker)) => {
            let tracker = tracker.unwrap_or_default();
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
                threads: Some(threads),
                options: &options,
            };
            // A panic in one row fails that row, never the batch.
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                run_into(&input, &tmp, quiet)
            }))
            .map_err(|_| "internal error (panic) while processing this row".to_owned())
            .and_then(|r| r.map_err(|e| super::message_with_causes(&e.error)))
            .map(|report| (report, tracker))
        }
    };
    let status = match &outcome {
        Ok((report, tracker)) => Status {
            status: "ok".into(),
            error: None,
            frames: report.frames,
            weak_pct: report.weak_pct,
            flagged_pct: report.flagged_pct,
            tracker: Some(*tracker),
            ..blank_status(row)
        },
        Err(e) => {
            // A failed row keeps only its status.
            let _ = std::fs::remove_dir_all(&tmp);
            Status {
                status: if row.keys.is_none() {
                    "needs_marks"
                } else {
                    "failed"
                }
                .into(),
                error: Some(e.clone()),
                ..blank_status(row)
            }
        }
    };
    let status = Status {
        seconds: started.elapsed().as_secs_f64(),
        inputs: inputs.ok(),
        ..status
    };
    let finish = || -> std::io::Result<()> {
        std::fs::create_dir_all(&tmp)?;
        let text = serde_json::to_string_pretty(&status).map_err(std::io::Error::other)?;
        std::fs::write(tmp.join(STATUS_JSON), text)?;
        if dir.exists() {
            std::fs::remove_dir_all(&dir)?;
        }
        std::fs::rename(&tmp, &dir)
    };
    if let Err(e) = finish() {
        eprintln!("{}: cannot write the row's results: {e}", dir.display());
        let _ = std::fs::remove_dir_all(&tmp);
    }
}

fn blank_status(row: &Row) -> Status {
    Status {
        format: "videomocap.batch-status".into(),
        version: 1,
        id: row.id.clone(),
        status: String::new(),
        error: None,
        frames: 0,
        weak_pct: 0.0,
        flagged_pct: 0.0,
        seconds: 0.0,
        tool_version: env!("CARGO_PKG_VERSION").into(),
        tracker: None,
        inputs: None,
    }
}

/// A marks file (one frame) rather than a keys file, by its format field.
fn is_marks(path: &Path) -> bool {
    std::fs::read_to_string(path).is_ok_and(|t| t.contains("\"videomocap.marks\""))
}

fn read_status(dir: &Path) -> Option<Status> {
    let text = std::fs::read_to_string(dir.join(STATUS_JSON)).ok()?;
    serde_json::from_str(&text).ok()
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

/// The shard (0 to n − 1) a row belongs to, from its id.
fn shard_of(id: &str, n: usize) -> usize {
    (fnv1a(id.as_bytes()) % n as u64) as usize
}

/// Reads `--shard K/N`.
fn parse_shard(text: &str) -> Result<(usize, usize), ExitError> {
    let bad = || ExitError::bad_input(anyhow!("--shard {text}: expected K/N with 0 ≤ K < N"));
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let (k, n): (usize, usize) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if k >= n {
        return Err(bad());
    }
    Ok((k, n))
}

/// Reads and checks the manifest; a malformed one is bad input naming the line and column.
fn read_manifest(path: &Path) -> Result<Vec<Row>, ExitError> {
    let bad = |line: u64, what: String| {
        ExitError::bad_input(anyhow!("{}: line {line}: {what}", path.display()))
    };
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| ExitError::bad_input(anyhow!("{}: cannot read: {e}", path.display())))?;
    let header = reader.headers().map_err(|e| bad(1, e.to_string()))?.clone();
    for name in &header {
        if !COLUMNS.contains(&name) {
            return Err(bad(
                1,
                format!("unknown column \"{name}\" (known: {})", COLUMNS.join(", ")),
            ));
        }
    }
    if !header.iter().any(|h| h == "video") {
        return Err(bad(1, "no \"video\" column".into()));
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let mut rows = Vec::new();
    let mut ids = BTreeSet::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            bad(line, e.to_string())
        })?;
        let line = record.position().map_or(0, |p| p.line());
        let field = |name: &str| {
            header
                .iter()
                .position(|h| h == name)
                .and_then(|i| record.get(i))
                .filter(|v| !v.is_empty())
        };
        let file = |name: &str| field(name).map(|v| base.join(v));
        let number = |name: &str| -> Result<Option<f64>, ExitError> {
            field(name)
                .map(|v| match v.parse::<f64>() {
                    Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
                    _ => Err(bad(
                        line,
                        format!("column {name}: \"{v}\" is not a positive number"),
                    )),
                })
                .transpose()
        };
        let video = file("video").ok_or_else(|| bad(line, "column video: empty".into()))?;
        let id = match field("id") {
            Some(id) => id.to_owned(),
            None => video
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
        };
        if id.is_empty() || id.starts_with('.') || id.contains(['/', '\\']) {
            return Err(bad(
                line,
                format!("column id: \"{id}\" cannot name a folder"),
            ));
        }
        if !ids.insert(id.clone()) {
            return Err(bad(
                line,
                format!("column id: \"{id}\" is used twice (give each row its own id)"),
            ));
        }
        let (focal_px, fov_deg) = (number("focal_px")?, number("fov_deg")?);
        if focal_px.is_some() && fov_deg.is_some() {
            return Err(bad(line, "give focal_px or fov_deg, not both".into()));
        }
        rows.push(Row {
            line,
            id,
            video,
            keys: file("keys"),
            height_m: number("height_m")?,
            focal_px,
            fov_deg,
            lengths: file("lengths"),
            tracker_settings: file("tracker_settings"),
            lift_settings: file("lift_settings"),
        });
    }
    Ok(rows)
}

/// `summary.csv`: one line per row (a row not run yet is `missing`).
fn summary_csv(statuses: &[(&Row, Option<Status>)]) -> String {
    let mut out = String::from("id,status,frames,weak_pct,flagged_pct,seconds,error\n");
    for (row, s) in statuses {
        let line = match s {
            Some(s) => format!(
                "{},{},{},{:.1},{:.1},{:.1},{}\n",
                row.id,
                s.status,
                s.frames,
                s.weak_pct,
                s.flagged_pct,
                s.seconds,
                quote(s.error.as_deref().unwrap_or(""))
            ),
            None => format!("{},missing,,,,,\n", row.id),
        };
        out.push_str(&line);
    }
    out
}

/// A CSV field, quoted when it needs to be.
fn quote(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}

/// The one-screen summary on stderr, and with `--json` on stdout.
fn report(statuses: &[(&Row, Option<Status>)], global: &GlobalArgs) {
    let count = |want: &str| {
        statuses
            .iter()
            .filter(|(_, s)| s.as_ref().map_or("missing", |s| s.status.as_str()) == want)
            .count()
    };
    say(
        global,
        &format!(
            "{} row(s): {} ok, {} failed, {} need marks, {} not run",
            statuses.len(),
            count("ok"),
            count("failed"),
            count("needs_marks"),
            count("missing")
        ),
    );
    for (row, s) in statuses {
        if let Some(s) = s.as_ref().filter(|s| s.status != "ok") {
            say(
                global,
                &format!(
                    "  {} (line {}): {}",
                    row.id,
                    row.line,
                    s.error.as_deref().unwrap_or(&s.status)
                ),
            );
        }
    }
    if global.json {
        let rows: Vec<serde_json::Value> = statuses
            .iter()
            .map(|(row, s)| match s {
                Some(s) => serde_json::json!({
                    "id": row.id, "status": s.status, "frames": s.frames,
                    "weak_pct": s.weak_pct, "flagged_pct": s.flagged_pct,
                    "seconds": s.seconds, "error": s.error,
                }),
                None => serde_json::json!({ "id": row.id, "status": "missing" }),
            })
            .collect();
        println!("{}", serde_json::json!({ "rows": rows }));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_split_rows_by_a_stable_hash_and_bad_shards_are_refused() {
        // The same id always lands in the same shard (FNV-1a of "walk_01").
        assert_eq!(fnv1a(b"walk_01"), fnv1a(b"walk_01"));
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        let ids: Vec<String> = (0..300).map(|k| format!("trial_{k}")).collect();
        let per: Vec<usize> = (0..3)
            .map(|k| ids.iter().filter(|id| shard_of(id, 3) == k).count())
            .collect();
        assert_eq!(per.iter().sum::<usize>(), 300);
        assert!(per.iter().all(|&c| c > 60), "{per:?}");
        assert_eq!(parse_shard("2/3").ok().map(|s| s.0), Some(2));
        assert!(parse_shard("3/3").is_err());
        assert!(parse_shard("x").is_err());
    }

    #[test]
    fn a_malformed_manifest_names_its_line_and_column() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("m.csv");
        let check = |text: &str, want: &str| {
            std::fs::write(&path, text).expect("write");
            let e = read_manifest(&path).expect_err(text);
            let msg = e.error.to_string();
            assert_eq!(e.code, super::super::EXIT_BAD_INPUT);
            assert!(msg.contains(want), "{msg}");
        };
        check(
            "video,height\na.mp4,1.7\n",
            "line 1: unknown column \"height\"",
        );
        check(
            "video,height_m\na.mp4,1.7\nb.mp4,tall\n",
            "line 3: column height_m",
        );
        check(
            "video,id\na.mp4,x\nb.mp4,x\n",
            "line 3: column id: \"x\" is used twice",
        );
        check("keys\nk.json\n", "no \"video\" column");
        std::fs::write(&path, "video,keys,id\nclips/a.mp4,k.json,\n").expect("write");
        let rows = read_manifest(&path).expect("good manifest");
        assert_eq!(rows[0].id, "a");
        assert_eq!(rows[0].video, dir.path().join("clips/a.mp4"));
        assert_eq!(rows[0].keys, Some(dir.path().join("k.json")));
    }
}
