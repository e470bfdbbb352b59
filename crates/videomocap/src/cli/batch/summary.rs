//! A row's `status.json` and the batch's summary: `summary.csv`, the one-screen report on
//! stderr and, with `--json`, the rows on stdout.

use super::manifest::Row;
use crate::cli::args::GlobalArgs;
use crate::cli::say;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use videomocap_core::track::TrackerParams;

/// Each row's status file, in its folder.
pub(super) const STATUS_JSON: &str = "status.json";
/// The batch's summary, in the output folder.
pub(super) const SUMMARY_CSV: &str = "summary.csv";
/// Skipped rows named in the report before the rest are only counted.
const SKIPPED_NAMED: usize = 10;

/// What a row's outputs were made from: a rerun redoes the row when any of it changed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct Inputs {
    pub video: String,
    pub video_bytes: u64,
    pub video_modified_ns: u128,
    /// Each given file (keys, lengths, settings) by column: a hash of its contents.
    pub files: BTreeMap<String, String>,
    pub height_m: Option<f64>,
    pub focal_px: Option<f64>,
    pub fov_deg: Option<f64>,
    pub network: bool,
}

/// A row's `status.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct Status {
    pub format: String,
    pub version: u32,
    pub id: String,
    /// `ok`, `failed` or `needs_marks`.
    pub status: String,
    pub error: Option<String>,
    pub frames: usize,
    pub weak_pct: f64,
    pub flagged_pct: f64,
    pub seconds: f64,
    pub tool_version: String,
    /// The tracker settings used (defaults filled in).
    pub tracker: Option<TrackerParams>,
    pub inputs: Option<Inputs>,
    /// Threads the row ran on (absent in status files of earlier versions).
    #[serde(default)]
    pub threads: Option<usize>,
}

impl Status {
    /// A status of `row` with nothing filled in yet.
    pub(super) fn blank(row: &Row) -> Status {
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
            threads: None,
        }
    }
}

/// A row's status, if its folder has a readable one.
pub(super) fn read_status(dir: &Path) -> Option<Status> {
    let text = std::fs::read_to_string(dir.join(STATUS_JSON)).ok()?;
    serde_json::from_str(&text).ok()
}

/// `summary.csv`: one line per row (a row not run yet is `missing`).
pub(super) fn summary_csv(statuses: &[(&Row, Option<Status>)]) -> String {
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

/// The report's line on rows skipped as done: how many, and the first few by id.
fn skipped_line(skipped: &[String]) -> String {
    let mut names: Vec<&str> = skipped
        .iter()
        .take(SKIPPED_NAMED)
        .map(String::as_str)
        .collect();
    if skipped.len() > SKIPPED_NAMED {
        names.push("…");
    }
    let rows = if skipped.len() == 1 { "row" } else { "rows" };
    format!(
        "skipped {} {rows} already done (ok, inputs unchanged; --force redoes them): {}",
        skipped.len(),
        names.join(", ")
    )
}

/// The one-screen summary on stderr, and with `--json` on stdout. `skipped`: the rows this run
/// found done and did not run again.
pub(super) fn report(statuses: &[(&Row, Option<Status>)], skipped: &[String], global: &GlobalArgs) {
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
    if !skipped.is_empty() {
        say(global, &skipped_line(skipped));
    }
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
        let skipped_ids: BTreeSet<&str> = skipped.iter().map(String::as_str).collect();
        let rows: Vec<serde_json::Value> = statuses
            .iter()
            .map(|(row, s)| match s {
                Some(s) => serde_json::json!({
                    "id": row.id, "status": s.status, "frames": s.frames,
                    "weak_pct": s.weak_pct, "flagged_pct": s.flagged_pct,
                    "seconds": s.seconds, "error": s.error,
                    "skipped": skipped_ids.contains(row.id.as_str()),
                }),
                None => serde_json::json!({ "id": row.id, "status": "missing" }),
            })
            .collect();
        println!(
            "{}",
            serde_json::json!({ "rows": rows, "skipped": skipped.len() })
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_skipped_line_counts_every_row_and_names_the_first_ten() {
        let ids: Vec<String> = (0..12).map(|k| format!("t{k}")).collect();
        let line = skipped_line(&ids);
        assert!(line.starts_with("skipped 12 rows already done"), "{line}");
        assert!(line.contains("t9, …") && !line.contains("t10"), "{line}");
        assert!(skipped_line(&ids[..2]).ends_with(": t0, t1"));
        assert!(skipped_line(&ids[..1]).starts_with("skipped 1 row already done"));
    }
}
