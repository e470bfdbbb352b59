//! The batch manifest: a CSV file, one row per video, checked whole before anything runs.
//! Every problem found is reported at once (up to [`MAX_ERRORS`]), each with its line and
//! column, so a user fixes the file in one pass.

use crate::cli::ExitError;
use anyhow::anyhow;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The manifest's columns (`video` is the only one required).
pub(super) const COLUMNS: [&str; 9] = [
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

/// Errors listed before the rest are only counted: a screenful, enough to fix a file whose
/// columns are all wrong without burying the first lines.
pub(super) const MAX_ERRORS: usize = 20;

/// One row of the manifest, paths resolved against the manifest's folder.
#[derive(Debug, Clone)]
pub(super) struct Row {
    /// Line in the manifest (1 = the header).
    pub line: u64,
    pub id: String,
    pub video: PathBuf,
    pub keys: Option<PathBuf>,
    pub height_m: Option<f64>,
    pub focal_px: Option<f64>,
    pub fov_deg: Option<f64>,
    pub lengths: Option<PathBuf>,
    pub tracker_settings: Option<PathBuf>,
    pub lift_settings: Option<PathBuf>,
}

/// The problems found so far, each `(line, what)`.
#[derive(Default)]
struct Problems(Vec<(u64, String)>);

impl Problems {
    fn add(&mut self, line: u64, what: String) {
        self.0.push((line, what));
    }

    /// Bad input naming every problem (the first [`MAX_ERRORS`]), or `Ok` when there are none.
    fn into_result(self, path: &Path) -> Result<(), ExitError> {
        let mut problems = self.0;
        if problems.is_empty() {
            return Ok(());
        }
        problems.sort_by_key(|(line, _)| *line);
        let shown: Vec<String> = problems
            .iter()
            .take(MAX_ERRORS)
            .map(|(line, what)| format!("{}: line {line}: {what}", path.display()))
            .collect();
        let mut text = if problems.len() == 1 {
            shown.join("")
        } else {
            format!(
                "{}: {} problems (nothing was run):\n  {}",
                path.display(),
                problems.len(),
                shown.join("\n  ")
            )
        };
        if problems.len() > MAX_ERRORS {
            text.push_str(&format!("\n  … and {} more", problems.len() - MAX_ERRORS));
        }
        Err(ExitError::bad_input(anyhow!(text)))
    }
}

/// Reads and checks the manifest; a malformed one is bad input naming every line and column
/// at fault.
pub(super) fn read_manifest(path: &Path) -> Result<Vec<Row>, ExitError> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| ExitError::bad_input(anyhow!("{}: cannot read: {e}", path.display())))?;
    let mut problems = Problems::default();
    let header = reader
        .headers()
        .map_err(|e| ExitError::bad_input(anyhow!("{}: line 1: {e}", path.display())))?
        .clone();
    for name in &header {
        if !COLUMNS.contains(&name) {
            problems.add(
                1,
                format!("unknown column \"{name}\" (known: {})", COLUMNS.join(", ")),
            );
        }
    }
    if !header.iter().any(|h| h == "video") {
        problems.add(1, "no \"video\" column".into());
        return problems.into_result(path).map(|()| Vec::new());
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let mut rows = Vec::new();
    let mut first_line_of: BTreeMap<String, u64> = BTreeMap::new();
    for record in reader.records() {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                let line = e.position().map_or(0, |p| p.line());
                let fatal = !matches!(e.kind(), csv::ErrorKind::UnequalLengths { .. });
                problems.add(line, e.to_string());
                if fatal {
                    break;
                }
                continue;
            }
        };
        let line = record.position().map_or(0, |p| p.line());
        if let Some(row) = read_row(&header, &record, line, base, &mut problems) {
            match first_line_of.get(&row.id) {
                Some(first) => problems.add(
                    line,
                    format!(
                        "column id: \"{}\" is used twice (also line {first}; give each row its own id)",
                        row.id
                    ),
                ),
                None => {
                    first_line_of.insert(row.id.clone(), line);
                    rows.push(row);
                }
            }
        }
    }
    problems.into_result(path).map(|()| rows)
}

/// One record as a row, its problems added to `problems` (`None` when it has any).
fn read_row(
    header: &csv::StringRecord,
    record: &csv::StringRecord,
    line: u64,
    base: &Path,
    problems: &mut Problems,
) -> Option<Row> {
    let before = problems.0.len();
    let field = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .and_then(|i| record.get(i))
            .filter(|v| !v.is_empty())
    };
    let file = |name: &str| field(name).map(|v| base.join(v));
    let mut number = |name: &str| match field(name).map(|v| (v, v.parse::<f64>())) {
        None => None,
        Some((_, Ok(x))) if x.is_finite() && x > 0.0 => Some(x),
        Some((v, _)) => {
            problems.add(
                line,
                format!("column {name}: \"{v}\" is not a positive number"),
            );
            None
        }
    };
    let (height_m, focal_px, fov_deg) = (number("height_m"), number("focal_px"), number("fov_deg"));
    if focal_px.is_some() && fov_deg.is_some() {
        problems.add(line, "give focal_px or fov_deg, not both".into());
    }
    let video = file("video");
    if video.is_none() {
        problems.add(line, "column video: empty".into());
    }
    let id = match (field("id"), &video) {
        (Some(id), _) => id.to_owned(),
        (None, Some(v)) => v
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        (None, None) => String::new(),
    };
    if video.is_some() && (id.is_empty() || id.starts_with('.') || id.contains(['/', '\\'])) {
        problems.add(line, format!("column id: \"{id}\" cannot name a folder"));
    }
    if problems.0.len() > before {
        return None;
    }
    Some(Row {
        line,
        id,
        video: video?,
        keys: file("keys"),
        height_m,
        focal_px,
        fov_deg,
        lengths: file("lengths"),
        tracker_settings: file("tracker_settings"),
        lift_settings: file("lift_settings"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error_of(path: &Path, text: &str) -> String {
        std::fs::write(path, text).expect("write");
        let e = read_manifest(path).expect_err(text);
        assert_eq!(e.code, crate::cli::EXIT_BAD_INPUT);
        e.error.to_string()
    }

    #[test]
    fn a_malformed_manifest_names_its_line_and_column() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("m.csv");
        let check = |text: &str, want: &str| {
            let msg = error_of(&path, text);
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
            "line 3: column id: \"x\" is used twice (also line 2",
        );
        check("keys\nk.json\n", "no \"video\" column");
        std::fs::write(&path, "video,keys,id\nclips/a.mp4,k.json,\n").expect("write");
        let rows = read_manifest(&path).expect("good manifest");
        assert_eq!(rows[0].id, "a");
        assert_eq!(rows[0].video, dir.path().join("clips/a.mp4"));
        assert_eq!(rows[0].keys, Some(dir.path().join("k.json")));
    }

    #[test]
    fn every_problem_is_reported_at_once_up_to_the_limit() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("m.csv");
        // A duplicate id before a bad height, a short row and both camera columns: all four.
        let msg = error_of(
            &path,
            "video,height_m,focal_px,fov_deg,id\n\
             a.mp4,1.7,,,x\nb.mp4,1.7,,,x\nc.mp4,tall,,,c\nd.mp4\ne.mp4,,900,60,e\n",
        );
        assert!(msg.contains("4 problems"), "{msg}");
        for want in [
            "line 3: column id: \"x\" is used twice",
            "line 4: column height_m: \"tall\"",
            "line 5: ",
            "line 6: give focal_px or fov_deg, not both",
        ] {
            assert!(msg.contains(want), "{want}: {msg}");
        }
        // Past the limit the rest are counted.
        let mut text = String::from("video,height_m\n");
        for k in 0..(MAX_ERRORS + 5) {
            text += &format!("v{k}.mp4,-1\n");
        }
        let msg = error_of(&path, &text);
        assert_eq!(msg.matches("is not a positive number").count(), MAX_ERRORS);
        assert!(msg.contains("… and 5 more"), "{msg}");
    }
}
