//! `videomocap-bench report`: the README's benchmark figures, written from the benchmark outputs
//! committed under `docs/bench/`, so the README cannot drift from what was measured.
//!
//! Each committed output is a benchmark's standard output as it printed it (`videomocap-bench
//! lift --network --split test > docs/bench/lift-test.txt`; its first line names the command).
//! `docs/bench/figures.json` names each figure the README quotes: the output file, a line that
//! heads the table (a unique piece of it), the row's label and the cell's place in the row (the
//! values after the label, counted from 1, split at spaces, `|`, `/`, brackets and commas; with
//! an empty row label, the values on the heading line after the named text). A ratio of two figures
//! is a figure too. The README holds each as `<!--fig:NAME-->value<!--/fig-->`; `report` writes
//! the values, `report --check` (run by the test suite) fails when the README differs or a
//! marker names a figure that does not resolve.

use crate::ExitError;
use anyhow::{Context, anyhow, bail};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The marker that opens a figure in the README.
const OPEN: &str = "<!--fig:";
/// The marker that closes it.
const CLOSE: &str = "<!--/fig-->";

/// One figure `figures.json` names.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Figure {
    /// A cell of a table in a committed output.
    Cell {
        /// The output file, relative to the figures file's folder.
        file: String,
        /// A unique piece of the line that heads the table.
        table: String,
        /// The row's label (the line's text before its values).
        row: String,
        /// Which value of the row, from 1.
        cell: usize,
    },
    /// One figure over another, rounded.
    Ratio {
        /// The numerator's and the denominator's names.
        ratio: [String; 2],
        /// Digits after the decimal point.
        digits: usize,
    },
}

/// Where `report` reads and writes.
pub(crate) struct ReportPaths {
    /// The README to write or check.
    pub readme: PathBuf,
    /// `figures.json` beside the committed outputs.
    pub figures: PathBuf,
}

/// Writes the README's figures from the committed outputs, or with `check` only compares.
pub(crate) fn run(paths: &ReportPaths, check: bool) -> Result<(), ExitError> {
    let figures = load_figures(&paths.figures).map_err(ExitError::bad_input)?;
    let dir = paths.figures.parent().unwrap_or(Path::new("."));
    let readme = std::fs::read_to_string(&paths.readme)
        .with_context(|| format!("cannot read {}", paths.readme.display()))
        .map_err(ExitError::bad_input)?;
    let (written, changed) = rewrite(&readme, &figures, dir)
        .map_err(|e| ExitError::bad_input(e.context(format!("{}", paths.readme.display()))))?;
    if check {
        if changed.is_empty() {
            println!(
                "{}: every figure matches docs/bench",
                paths.readme.display()
            );
            return Ok(());
        }
        let list: Vec<String> = changed
            .iter()
            .map(|(name, old, new)| format!("{name}: README {old}, committed output {new}"))
            .collect();
        return Err(ExitError::bad_input(anyhow!(
            "{} differs from the committed benchmark outputs (run `videomocap-bench report`): {}",
            paths.readme.display(),
            list.join("; ")
        )));
    }
    videomocap_core::formats::write_atomically(&paths.readme, written.as_bytes())
        .with_context(|| format!("cannot write {}", paths.readme.display()))
        .map_err(|e| ExitError { code: 1, error: e })?;
    println!(
        "{}: {} figures rewritten",
        paths.readme.display(),
        changed.len()
    );
    Ok(())
}

fn load_figures(path: &Path) -> anyhow::Result<BTreeMap<String, Figure>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{} is not a figures file", path.display()))
}

/// The README with every marker's value written, and the figures that changed (name, old, new).
type Rewritten = (String, Vec<(String, String, String)>);

fn rewrite(
    readme: &str,
    figures: &BTreeMap<String, Figure>,
    dir: &Path,
) -> anyhow::Result<Rewritten> {
    let mut out = String::with_capacity(readme.len());
    let mut changed = Vec::new();
    let mut rest = readme;
    while let Some(start) = rest.find(OPEN) {
        let after_open = &rest[start + OPEN.len()..];
        let Some(name_end) = after_open.find("-->") else {
            bail!("a figure marker is not closed with `-->`");
        };
        let name = after_open[..name_end].trim();
        let body = &after_open[name_end + 3..];
        let Some(value_end) = body.find(CLOSE) else {
            bail!("figure {name}: no {CLOSE} after it");
        };
        let old = &body[..value_end];
        let new = value(name, figures, dir, 0)?;
        if old != new {
            changed.push((name.to_string(), old.to_string(), new.clone()));
        }
        out.push_str(&rest[..start]);
        out.push_str(OPEN);
        out.push_str(name);
        out.push_str("-->");
        out.push_str(&new);
        out.push_str(CLOSE);
        rest = &body[value_end + CLOSE.len()..];
    }
    out.push_str(rest);
    Ok((out, changed))
}

/// A figure's text as the committed outputs give it.
fn value(
    name: &str,
    figures: &BTreeMap<String, Figure>,
    dir: &Path,
    depth: usize,
) -> anyhow::Result<String> {
    if depth > 4 {
        bail!("figure {name}: ratios nested too deep");
    }
    match figures.get(name) {
        None => bail!("figure {name} is not in figures.json"),
        Some(Figure::Cell {
            file,
            table,
            row,
            cell,
        }) => {
            let path = dir.join(file);
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("figure {name}: cannot read {}", path.display()))?;
            cell_of(&text, table, row, *cell)
                .with_context(|| format!("figure {name} in {}", path.display()))
        }
        Some(Figure::Ratio { ratio, digits }) => {
            let number = |n: &str| -> anyhow::Result<f64> {
                let text = value(n, figures, dir, depth + 1)?;
                text.trim_end_matches('%')
                    .parse::<f64>()
                    .with_context(|| format!("figure {name}: {n} = {text} is not a number"))
            };
            let (a, b) = (number(&ratio[0])?, number(&ratio[1])?);
            if b == 0.0 {
                bail!("figure {name}: {} is zero", ratio[1]);
            }
            Ok(format!("{:.*}", *digits, a / b))
        }
    }
}

/// The `cell`-th value (from 1) of the row labelled `row` in the table headed by the one line
/// holding `table` (or, where several hold it, the one that is exactly it; the table ends at the first empty line), or with an empty `row` of that line
/// itself after `table`. Values are split at spaces, `|`, `/`, brackets and commas.
fn cell_of(text: &str, table: &str, row: &str, cell: usize) -> anyhow::Result<String> {
    let mut heads: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.contains(table))
        .map(|(i, _)| i)
        .collect();
    if heads.len() > 1 {
        // A heading that is a prefix of others names the line that is exactly it.
        heads.retain(|&i| text.lines().nth(i).is_some_and(|l| l.trim() == table));
    }
    let head = match heads.as_slice() {
        [one] => *one,
        [] => bail!("no line holds \"{table}\""),
        _ => bail!(
            "{} lines hold \"{table}\"; the table must be named by one",
            heads.len()
        ),
    };
    let after = if row.is_empty() {
        // A figure in the head line itself: the values after the named text.
        let line = text.lines().nth(head).unwrap_or_default();
        line.split_once(table)
            .map(|(_, after)| after)
            .unwrap_or_default()
    } else {
        let line = text
            .lines()
            .skip(head + 1)
            .take_while(|l| !l.trim().is_empty())
            .find(|l| {
                l.trim_start()
                    .strip_prefix(row)
                    .is_some_and(|after| after.is_empty() || after.starts_with([' ', '|']))
            })
            .ok_or_else(|| anyhow!("table \"{table}\" has no row \"{row}\""))?;
        &line.trim_start()[row.len()..]
    };
    after
        .split([' ', '|', '/', '(', ')', ','])
        .filter(|t| !t.is_empty())
        .nth(cell.wrapping_sub(1))
        .map(str::to_string)
        .ok_or_else(|| anyhow!("row \"{row}\" of \"{table}\" has no value {cell}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    const OUTPUT: &str = "# videomocap-bench lift\n\nlift: together\nfamily   | mm PA\nwalk/run |  49.4  32.7    0%\nsynthetic overall | 83.6 57.4 4%\n\nlift: cut-out\nsynthetic overall | 136.8 106.2\n";

    #[test]
    fn a_cell_is_read_by_table_row_and_place() {
        assert_eq!(
            cell_of(OUTPUT, "lift: together", "synthetic overall", 1).unwrap(),
            "83.6"
        );
        assert_eq!(
            cell_of(OUTPUT, "lift: together", "walk/run", 3).unwrap(),
            "0%"
        );
        assert_eq!(
            cell_of(OUTPUT, "cut-out", "synthetic overall", 2).unwrap(),
            "106.2"
        );
        assert!(cell_of(OUTPUT, "lift: together", "dance", 1).is_err());
        assert!(
            cell_of(OUTPUT, "lift:", "walk/run", 1).is_err(),
            "two tables match"
        );
        let nested = "lift\nsynthetic overall | 1.0\n\nlift: cut-out\nsynthetic overall | 2.0\n";
        assert_eq!(
            cell_of(nested, "lift", "synthetic overall", 1).unwrap(),
            "1.0"
        );
        assert!(cell_of(OUTPUT, "lift: together", "walk/run", 4).is_err());
        let line = "moved out of it: 284 (of 34480 joint-frames)\n";
        assert_eq!(cell_of(line, "moved out of it:", "", 1).unwrap(), "284");
        assert_eq!(cell_of(line, "moved out of it:", "", 3).unwrap(), "34480");
    }

    #[test]
    fn the_readme_is_rewritten_and_a_drift_is_reported() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("lift.txt"), OUTPUT).unwrap();
        let figures: BTreeMap<String, Figure> = serde_json::from_str(
            r#"{"t": {"file": "lift.txt", "table": "lift: together", "row": "synthetic overall", "cell": 1},
                "c": {"file": "lift.txt", "table": "cut-out", "row": "synthetic overall", "cell": 1},
                "r": {"ratio": ["t", "c"], "digits": 2}}"#,
        )
        .unwrap();
        let readme = "together <!--fig:t-->82.0<!--/fig--> mm, <!--fig:r-->0.61<!--/fig--> of it";
        let (out, changed) = rewrite(readme, &figures, dir.path()).unwrap();
        assert_eq!(
            out,
            "together <!--fig:t-->83.6<!--/fig--> mm, <!--fig:r-->0.61<!--/fig--> of it"
        );
        assert_eq!(changed, vec![("t".into(), "82.0".into(), "83.6".into())]);
        let (again, none) = rewrite(&out, &figures, dir.path()).unwrap();
        assert_eq!(again, out);
        assert!(none.is_empty());
        assert!(rewrite("<!--fig:missing-->1<!--/fig-->", &figures, dir.path()).is_err());
        assert!(rewrite("<!--fig:t-->1", &figures, dir.path()).is_err());
    }
}
