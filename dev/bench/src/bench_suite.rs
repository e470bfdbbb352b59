//! What every accuracy benchmark shares: the clips (suite v3, rendered once, and the two real
//! clips) and tables that put `dev` and `test` side by side, per clip family and overall.

use crate::args::GlobalArgs;
use crate::{ExitError, say};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use videomocap_testkit::eval::suite::{
    CLICK_NOISE_PX, Family, REAL_CLIPS, Split, Suite, clicked_marks,
};
use videomocap_testkit::repo_root;

/// One clip a benchmark scores.
#[derive(Debug, Clone)]
pub(crate) struct BenchClip {
    /// Its name.
    pub name: String,
    /// Its family ([`Family::Real`] for the real clips).
    pub family: Family,
    /// Its split (the real clips are development material).
    pub split: Split,
    /// Its folder (video.mp4, gt.json, marks.json).
    pub dir: PathBuf,
    /// Where the camera stands ([`ViewFamily::Real`] for the real clips).
    pub view: ViewFamily,
}

/// The views the per-view tables report apart: the camera in front, at an angle (the
/// suite's oblique, raised and low views, 30–45° to a side), in profile, behind; and the real
/// clips.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum ViewFamily {
    /// In front.
    Frontal,
    /// 30–45° to a side (oblique, raised, low).
    Oblique,
    /// In profile.
    Side,
    /// From behind.
    Behind,
    /// The real clips.
    Real,
}

impl ViewFamily {
    /// Every view family, in table order.
    pub(crate) const ALL: [ViewFamily; 5] = [
        ViewFamily::Frontal,
        ViewFamily::Oblique,
        ViewFamily::Side,
        ViewFamily::Behind,
        ViewFamily::Real,
    ];

    /// The family of a suite view.
    pub(crate) fn of(view: videomocap_testkit::synth::View) -> ViewFamily {
        use videomocap_testkit::synth::View;
        match view {
            View::Frontal => ViewFamily::Frontal,
            View::Oblique | View::Raised | View::Low => ViewFamily::Oblique,
            View::Side => ViewFamily::Side,
            View::Behind => ViewFamily::Behind,
        }
    }

    /// Its name in tables.
    pub(crate) fn name(self) -> &'static str {
        match self {
            ViewFamily::Frontal => "frontal",
            ViewFamily::Oblique => "oblique",
            ViewFamily::Side => "side",
            ViewFamily::Behind => "behind",
            ViewFamily::Real => "real",
        }
    }
}

/// A clip opened for scoring: its reference, the marks as a user clicks them, and its video.
pub(crate) struct OpenedClip {
    /// The reference (gt.json).
    pub gt: videomocap_testkit::synth::GroundTruth,
    /// The marks with [`CLICK_NOISE_PX`] of clicking noise.
    pub marks: videomocap_core::formats::Marks,
    /// The clip's video.
    pub video: videomocap_core::video::Video,
}

impl BenchClip {
    /// Opens the clip's reference, clicked marks and video.
    pub(crate) fn open(&self) -> Result<OpenedClip, ExitError> {
        use videomocap_core::formats::Marks;
        use videomocap_core::video::{OpenOptions, Video};
        let dir = &self.dir;
        let gt = videomocap_testkit::synth::GroundTruth::load(&dir.join("gt.json"))
            .map_err(ExitError::failed)?;
        let marks = clicked_marks(
            &Marks::load(&dir.join("marks.json")).map_err(ExitError::failed)?,
            CLICK_NOISE_PX,
            &self.name,
        );
        let video = Video::open(&dir.join("video.mp4"), &OpenOptions::default())
            .map_err(ExitError::failed)?;
        Ok(OpenedClip { gt, marks, video })
    }
}

/// The threads the benchmarks use: all the machine has.
pub(crate) fn machine_threads() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

/// `--lift-settings`, else the lift's defaults.
pub(crate) fn lift_settings(
    a: &crate::args::BenchArgs,
) -> Result<videomocap_core::lift::LiftParams, ExitError> {
    match &a.lift_settings {
        Some(p) => videomocap::cli::lift::load_settings(p),
        None => Ok(videomocap_core::lift::LiftParams::default()),
    }
}

/// The bundled pose network on `threads` threads (the product's loader), shareable between
/// jobs.
pub(crate) fn bundled_network(
    threads: usize,
) -> Result<std::sync::Arc<videomocap_core::network::PoseNetwork>, ExitError> {
    videomocap_core::network::PoseNetwork::shared(threads).map_err(ExitError::failed)
}

/// `--split`: all (`None`), dev or test.
pub(crate) fn parse_split(split: &str) -> Result<Option<Split>, ExitError> {
    match split {
        "all" => Ok(None),
        "dev" => Ok(Some(Split::Dev)),
        "test" => Ok(Some(Split::Test)),
        other => Err(ExitError::bad_input(anyhow::anyhow!(
            "--split {other}: expected all, dev or test"
        ))),
    }
}

/// The suite's clips, rendered into `suite_dir` when missing, then the real clips.
pub(crate) fn bench_clips(
    suite_dir: &Path,
    split: &str,
    clip: Option<&str>,
    global: &GlobalArgs,
) -> Result<Vec<BenchClip>, ExitError> {
    let wanted = parse_split(split)?;
    let mut suite = Suite::load(&repo_root()).map_err(ExitError::failed)?;
    // Only the clips asked for are rendered (a short look at one clip renders one clip).
    suite
        .clips
        .retain(|c| wanted.is_none_or(|w| c.split == w) && clip.is_none_or(|n| c.name.contains(n)));
    let dirs = suite
        .ensure_rendered(suite_dir, &mut |name| {
            say(global, &format!("rendering suite clip {name} …"))
        })
        .map_err(ExitError::failed)?;
    let mut out: Vec<BenchClip> = suite
        .clips
        .iter()
        .zip(dirs)
        .map(|(c, dir)| BenchClip {
            name: c.name.clone(),
            family: c.family,
            split: c.split,
            dir,
            view: ViewFamily::of(c.params.view),
        })
        .collect();
    out.extend(REAL_CLIPS.iter().map(|(name, dir)| BenchClip {
        name: (*name).to_owned(),
        family: Family::Real,
        split: Split::Dev,
        dir: repo_root().join(dir),
        view: ViewFamily::Real,
    }));
    out.retain(|c| wanted.is_none_or(|w| c.split == w) && clip.is_none_or(|n| c.name.contains(n)));
    Ok(out)
}

/// Scores that add up over clips.
pub(crate) trait Merge: Default + Clone {
    /// Adds another's samples.
    fn merge_from(&mut self, other: &Self);
}

impl Merge for videomocap_testkit::eval::Accuracy {
    fn merge_from(&mut self, other: &Self) {
        self.merge(other);
    }
}

impl Merge for videomocap_testkit::eval::pose3d::Pose3dScore {
    fn merge_from(&mut self, other: &Self) {
        self.merge(other);
    }
}

impl Merge for videomocap_testkit::eval::doubt::DoubtTally {
    fn merge_from(&mut self, other: &Self) {
        self.merge(other);
    }
}

impl Merge for videomocap_testkit::eval::volume::VolumeScore {
    fn merge_from(&mut self, other: &Self) {
        self.merge(other);
    }
}

impl<A: Merge, B: Merge> Merge for (A, B) {
    fn merge_from(&mut self, other: &Self) {
        self.0.merge_from(&other.0);
        self.1.merge_from(&other.1);
    }
}

impl<T: Merge, const N: usize> Merge for [T; N]
where
    [T; N]: Default,
{
    fn merge_from(&mut self, other: &Self) {
        for (a, b) in self.iter_mut().zip(other) {
            a.merge_from(b);
        }
    }
}

impl<T: Merge + Clone> Merge for Vec<T> {
    fn merge_from(&mut self, other: &Self) {
        for (k, b) in other.iter().enumerate() {
            match self.get_mut(k) {
                Some(a) => a.merge_from(b),
                None => self.push(b.clone()),
            }
        }
    }
}

/// A score per (split, family) and per split over all synthetic clips.
#[derive(Debug, Clone, Default)]
pub(crate) struct Tally<T> {
    cells: BTreeMap<(Split, Option<Family>), T>,
}

impl<T: Merge> Tally<T> {
    /// Adds a clip's score to its family and, for synthetic clips, to its split's overall.
    pub(crate) fn add(&mut self, clip: &BenchClip, score: &T) {
        self.cells
            .entry((clip.split, Some(clip.family)))
            .or_default()
            .merge_from(score);
        if clip.family != Family::Real {
            self.cells
                .entry((clip.split, None))
                .or_default()
                .merge_from(score);
        }
    }

    /// The score of a split's family (`None`: all its synthetic clips).
    pub(crate) fn get(&self, split: Split, family: Option<Family>) -> Option<&T> {
        self.cells.get(&(split, family))
    }

    /// One line per family that has clips and one overall, `dev` and `test` side by side: `cell`
    /// formats a score into a fixed-width column (`width` characters, blank where a split has no
    /// clip of the family).
    pub(crate) fn lines(&self, width: usize, cell: impl Fn(&T) -> String) -> Vec<String> {
        let rows = Family::ALL
            .iter()
            .map(|f| (f.name(), Some(*f)))
            .chain(std::iter::once(("synthetic overall", None)));
        rows.filter(|(_, family)| {
            [Split::Dev, Split::Test]
                .iter()
                .any(|s| self.get(*s, *family).is_some())
        })
        .map(|(name, family)| {
            let col = |split| {
                self.get(split, family)
                    .map_or_else(|| format!("{:width$}", ""), &cell)
            };
            format!("{name:<18} | {} | {}", col(Split::Dev), col(Split::Test))
        })
        .collect()
    }

    /// The table's heading: the split names over columns of `width` characters, then the
    /// columns' own heading.
    pub(crate) fn heading(width: usize, columns: &str) -> Vec<String> {
        vec![
            format!("{:<18} | {:<width$} | {:<width$}", "", "dev", "test"),
            format!("{:<18} | {columns:<width$} | {columns:<width$}", "family"),
        ]
    }

    /// Every cell as JSON: `{"dev": {"walk/run": …, "overall": …}, "test": …}`.
    pub(crate) fn json(&self, value: impl Fn(&T) -> serde_json::Value) -> serde_json::Value {
        let mut out = serde_json::Map::new();
        for split in [Split::Dev, Split::Test] {
            let mut m = serde_json::Map::new();
            for ((s, family), v) in &self.cells {
                if *s == split {
                    m.insert(
                        family.map_or("synthetic overall", Family::name).to_owned(),
                        value(v),
                    );
                }
            }
            out.insert(split.name().to_owned(), serde_json::Value::Object(m));
        }
        serde_json::Value::Object(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use videomocap_testkit::eval::Accuracy;

    fn clip(family: Family, split: Split) -> BenchClip {
        BenchClip {
            name: format!("{family:?}"),
            family,
            split,
            dir: PathBuf::new(),
            view: ViewFamily::Frontal,
        }
    }

    fn accuracy(error_px: f64, samples: usize) -> Accuracy {
        let mut a = Accuracy::default();
        for _ in 0..samples {
            a.add(error_px, 100.0);
        }
        a
    }

    #[test]
    fn the_tally_keeps_splits_apart_and_the_real_clips_out_of_the_synthetic_overall() {
        let mut t: Tally<Accuracy> = Tally::default();
        t.add(&clip(Family::WalkRun, Split::Dev), &accuracy(10.0, 4));
        t.add(&clip(Family::Dance, Split::Test), &accuracy(50.0, 4));
        t.add(&clip(Family::Real, Split::Dev), &accuracy(90.0, 4));
        let dev = t.get(Split::Dev, None).unwrap();
        assert_eq!(dev.count, 4);
        assert!((dev.mean_px() - 10.0).abs() < 1e-9);
        assert!((t.get(Split::Test, None).unwrap().mean_px() - 50.0).abs() < 1e-9);
        assert!(t.get(Split::Test, Some(Family::WalkRun)).is_none());
        let lines = t.lines(8, |a| format!("{:>8.1}", a.mean_px()));
        // walk/run, dance, real and the overall; no line for the families without clips.
        assert_eq!(lines.len(), 4, "{lines:#?}");
        assert!(lines[0].starts_with("walk/run") && lines[0].contains("10.0"));
        assert!(lines[3].starts_with("synthetic overall"));
        let json = t.json(|a| serde_json::json!(a.mean_px()));
        assert_eq!(json["test"]["dance"], serde_json::json!(50.0));
        assert_eq!(json["dev"]["real"], serde_json::json!(90.0));
    }
}
