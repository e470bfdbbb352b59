//! The benchmark suite (v4): synthetic clips of people (MakeHuman's skinned mesh; v3 drew
//! mannequins from the same parameters) rendered from every bundled motion-capture take and
//! the procedural motions, on varied bodies, annotators, views, clothes and scenes, split by take
//! into `dev` (tune here) and `test` (read when a change is done); plus the two real clips.
//!
//! The takes, their split and every clip's view, framing and scene are fixed in
//! `tests/data/suite/suite.json` (written once by `scripts/make_suite.py`); what is drawn per
//! clip (the body, the annotator's joint definitions, the colours) comes from the clip's seed.
//! Clips render once into a folder and are redone only when their parameters change.

use crate::synth::{
    Appearance, BodyShape, Clothes, Framing, JointDefinitions, MotionSource, ProceduralMotion,
    SensorEffects, Surface, SynthError, SynthParams, VideoOutput, View, background, framing,
    render_clip,
};
use nalgebra::Point2;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::{FormatError, Marks, write_atomically};
use videomocap_core::skeleton::PerJoint;

/// The suite's file, under the crate's root.
pub const SUITE_FILE: &str = "tests/data/suite/suite.json";

/// The two real clips, under the crate's root: (name, folder).
pub const REAL_CLIPS: [(&str, &str); 2] = [
    ("real balancing", "sample_videos/pose2sim_balancing_cam01"),
    (
        "real + distractor",
        "sample_videos/pose2sim_distractor_cam01",
    ),
];

/// The spread of the bodies' segment lengths around the proportions table (±12 %).
pub const BODY_SPREAD: f64 = 0.12;

/// Standard deviation of a user's click on a mark, pixels per coordinate.
pub const CLICK_NOISE_PX: f64 = 2.0;

/// Which half of the suite a clip belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// Tune here.
    Dev,
    /// Read when a change is done; never swept.
    Test,
}

impl Split {
    /// `dev` or `test`.
    pub fn name(self) -> &'static str {
        match self {
            Split::Dev => "dev",
            Split::Test => "test",
        }
    }
}

/// The kinds of motion the benchmarks report apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// Walks and runs.
    WalkRun,
    /// Dance with turns (ballet, salsa).
    Dance,
    /// Sport (basketball, swordplay).
    Sport,
    /// Bending and sitting.
    BendSit,
    /// The procedural motions.
    Procedural,
    /// The real clips.
    Real,
}

impl Family {
    /// Every family, in table order.
    pub const ALL: [Family; 6] = [
        Family::WalkRun,
        Family::Dance,
        Family::Sport,
        Family::BendSit,
        Family::Procedural,
        Family::Real,
    ];

    /// The family's name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Family::WalkRun => "walk/run",
            Family::Dance => "dance",
            Family::Sport => "sport",
            Family::BendSit => "bend/sit",
            Family::Procedural => "procedural",
            Family::Real => "real",
        }
    }
}

#[derive(Debug, Deserialize)]
struct SuiteFile {
    format: String,
    version: u32,
    /// `mesh` (v4) or `capsule` (the mannequin of v3).
    body: String,
    takes: Vec<TakeEntry>,
    clips: Vec<ClipEntry>,
}

#[derive(Debug, Deserialize)]
struct TakeEntry {
    take: String,
    family: Family,
    split: Split,
    #[serde(default)]
    procedural: Option<String>,
}

#[derive(Debug, Deserialize)]
struct ClipEntry {
    name: String,
    take: String,
    #[serde(default)]
    file: Option<String>,
    start_s: f64,
    frames: usize,
    fps: u32,
    view: String,
    size: [u32; 2],
    person_px: f64,
    distance_m: f64,
    background: Option<String>,
    clothes: String,
    loose: bool,
    distractor: bool,
    motion_blur: bool,
    noise: f64,
    flicker: f64,
    seed: u64,
}

/// One clip of the suite.
#[derive(Debug, Clone)]
pub struct SuiteClip {
    /// Its name (also its folder's).
    pub name: String,
    /// The motion take it renders (no take is in both splits).
    pub take: String,
    /// Its family.
    pub family: Family,
    /// Its split.
    pub split: Split,
    /// How to render it.
    pub params: SynthParams,
}

/// The suite could not be read or rendered.
#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    #[error("{path}: {problem}")]
    Invalid { path: PathBuf, problem: String },
    #[error(transparent)]
    Format(#[from] FormatError),
    #[error("suite clip {clip}: {source}")]
    Render { clip: String, source: SynthError },
}

/// The whole suite.
#[derive(Debug, Clone)]
pub struct Suite {
    /// Its clips, in the file's order.
    pub clips: Vec<SuiteClip>,
}

impl Suite {
    /// Reads the suite from `root` (the crate's folder): checks every clip's take, view,
    /// clothes and background, and builds its render parameters.
    pub fn load(root: &Path) -> Result<Suite, SuiteError> {
        let path = root.join(SUITE_FILE);
        let invalid = |problem: String| SuiteError::Invalid {
            path: path.clone(),
            problem,
        };
        let text = std::fs::read_to_string(&path).map_err(|source| FormatError::Io {
            path: path.clone(),
            source,
        })?;
        let file: SuiteFile = serde_json::from_str(&text).map_err(|source| FormatError::Json {
            path: path.clone(),
            source,
        })?;
        if file.format != "videomocap.suite" || file.version != 4 {
            return Err(invalid(format!(
                "expected format videomocap.suite version 4, found {} version {}",
                file.format, file.version
            )));
        }
        let surface = match file.body.as_str() {
            "mesh" => Surface::Mesh,
            "capsule" => Surface::Capsules,
            other => return Err(invalid(format!("body {other}: expected mesh or capsule"))),
        };
        let data = path.parent().unwrap_or(root).to_owned();
        let mut clips = Vec::with_capacity(file.clips.len());
        for c in &file.clips {
            let take = file
                .takes
                .iter()
                .find(|t| t.take == c.take)
                .ok_or_else(|| invalid(format!("clip {}: unknown take {}", c.name, c.take)))?;
            let motion = match (&take.procedural, &c.file) {
                (Some(kind), _) => MotionSource::Procedural(
                    ProceduralMotion::from_name(kind)
                        .ok_or_else(|| invalid(format!("take {}: no motion {kind}", take.take)))?,
                ),
                (None, Some(file)) => MotionSource::Bvh {
                    path: data.join(file),
                    start_s: c.start_s,
                },
                (None, None) => {
                    return Err(invalid(format!("clip {}: no motion file", c.name)));
                }
            };
            let params = clip_params(c, motion, surface, root).map_err(invalid)?;
            clips.push(SuiteClip {
                name: c.name.clone(),
                take: c.take.clone(),
                family: take.family,
                split: take.split,
                params,
            });
        }
        Ok(Suite { clips })
    }

    /// Renders the clips missing from `dir` (or rendered from other parameters), telling
    /// `progress` each clip's name before it renders; returns each clip's folder.
    pub fn ensure_rendered(
        &self,
        dir: &Path,
        progress: &mut dyn FnMut(&str),
    ) -> Result<Vec<PathBuf>, SuiteError> {
        let mut out = Vec::with_capacity(self.clips.len());
        for clip in &self.clips {
            let folder = dir.join(&clip.name);
            let stamp = format!("suite v4: {:?}\n", clip.params);
            let current = std::fs::read_to_string(folder.join(SPEC_FILE)).is_ok_and(|s| s == stamp)
                && folder.join("gt.json").is_file();
            if !current {
                progress(&clip.name);
                render_clip(
                    &clip.params,
                    &folder,
                    &mut |_, _| {},
                    &AtomicBool::new(false),
                )
                .map_err(|source| SuiteError::Render {
                    clip: clip.name.clone(),
                    source,
                })?;
                write_atomically(&folder.join(SPEC_FILE), stamp.as_bytes())?;
            }
            out.push(folder);
        }
        let names: String = self.clips.iter().map(|c| format!("{}\n", c.name)).collect();
        write_atomically(&dir.join(SUITE_INDEX), names.as_bytes())?;
        Ok(out)
    }
}

/// The file in each rendered clip's folder naming the parameters it was rendered from.
const SPEC_FILE: &str = "suite_spec.txt";

/// The file in the suite's folder listing its clips, one name per line (for
/// `scripts/opencv_baselines.py`).
pub const SUITE_INDEX: &str = "clips.txt";

/// The render parameters of one clip of the file.
fn clip_params(
    c: &ClipEntry,
    motion: MotionSource,
    surface: Surface,
    root: &Path,
) -> Result<SynthParams, String> {
    let view =
        View::from_name(&c.view).ok_or_else(|| format!("clip {}: view {}", c.name, c.view))?;
    let clothes = Clothes::from_name(&c.clothes)
        .ok_or_else(|| format!("clip {}: clothes {}", c.name, c.clothes))?;
    let [width, height] = c.size;
    let background_image = c
        .background
        .as_ref()
        .map(|b| root.join("assets/backgrounds").join(b));
    let bg = match &background_image {
        Some(path) => image::open(path)
            .map_err(|e| format!("clip {}: {}: {e}", c.name, path.display()))?
            .resize_to_fill(width, height, image::imageops::FilterType::Triangle)
            .to_rgb8(),
        None => background(width, height, c.seed),
    };
    let body = BodyShape::drawn(c.seed, BODY_SPREAD);
    let stature = body.stature_m();
    Ok(SynthParams {
        motion,
        frames: c.frames,
        fps: c.fps,
        width,
        height,
        view,
        // The focal length that shows the person `person_px` tall at `distance_m`.
        focal_px: c.person_px * c.distance_m / stature,
        person_px: c.person_px,
        allow_off_frame: false,
        effects: SensorEffects {
            noise_sigma: c.noise,
            flicker: c.flicker,
            seed: c.seed,
        },
        background_seed: c.seed,
        background_image,
        output: VideoOutput::Mp4,
        body: Some(body),
        shoulder_girdle: true,
        joint_definitions: JointDefinitions::drawn(c.seed),
        appearance: Appearance::drawn(clothes, c.loose, &bg, c.seed),
        distractor: c.distractor.then_some(c.seed.wrapping_add(1)),
        motion_blur: c.motion_blur,
        surface,
    })
}

/// How a suite clip frames its subject, without rendering it.
pub fn clip_framing(clip: &SuiteClip) -> Result<Framing, SuiteError> {
    framing(&clip.params).map_err(|source| SuiteError::Render {
        clip: clip.name.clone(),
        source,
    })
}

/// The number of frames a suite clip's motion really has (a take may end before `frames`).
pub fn clip_frames(clip: &SuiteClip) -> Result<usize, SuiteError> {
    crate::synth::load_motion(&clip.params)
        .map(|m| m.frames.len())
        .map_err(|source| SuiteError::Render {
            clip: clip.name.clone(),
            source,
        })
}

/// The marks as a user clicks them: each coordinate moved by Gaussian noise of `sigma_px`
/// (seeded by the clip's name, so every run and every benchmark sees the same clicks).
pub fn clicked_marks(marks: &Marks, sigma_px: f64, clip_name: &str) -> Marks {
    let seed = clip_name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let normal = Normal::new(0.0, sigma_px.max(0.0)).ok();
    let mut jitter = || normal.map_or(0.0, |n| n.sample(&mut rng));
    Marks {
        frame: marks.frame,
        points: PerJoint::from_fn(|j| {
            let p = marks.points[j];
            Point2::new(p.x + jitter(), p.y + jitter())
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::{BTreeMap, BTreeSet};
    use videomocap_core::formats::FrameIndex;

    fn suite() -> Suite {
        Suite::load(&crate::repo_root()).unwrap()
    }

    #[test]
    fn the_split_is_by_take_and_about_two_thirds_dev() {
        let s = suite();
        assert!(s.clips.len() >= 40, "{} clips", s.clips.len());
        let mut split_of: BTreeMap<&str, BTreeSet<Split>> = BTreeMap::new();
        for c in &s.clips {
            split_of.entry(&c.take).or_default().insert(c.split);
        }
        for (take, splits) in &split_of {
            assert_eq!(splits.len(), 1, "take {take} is in both splits");
        }
        let dev = s.clips.iter().filter(|c| c.split == Split::Dev).count();
        let share = dev as f64 / s.clips.len() as f64;
        assert!((0.55..=0.75).contains(&share), "dev share {share}");
        // Every family but the real one has clips in both splits.
        for family in &Family::ALL[..5] {
            for split in [Split::Dev, Split::Test] {
                assert!(
                    s.clips
                        .iter()
                        .any(|c| c.family == *family && c.split == split),
                    "{family:?} has no {split:?} clip"
                );
            }
        }
        // Every bundled motion-capture take is used.
        let takes: BTreeSet<&str> = s.clips.iter().map(|c| c.take.as_str()).collect();
        assert!(takes.len() >= 32, "{} takes", takes.len());
    }

    #[test]
    fn every_clip_stays_within_the_suites_bounds() {
        let s = suite();
        let mut total = 0;
        let mut views = BTreeSet::new();
        let mut portrait = 0;
        let mut broken = Vec::new();
        for c in &s.clips {
            let p = &c.params;
            views.insert(format!("{:?}", p.view));
            let frames = clip_frames(c).unwrap();
            if frames != p.frames || !(90..=200).contains(&frames) {
                broken.push(format!("{}: {frames} of {} frames", c.name, p.frames));
            }
            total += frames;
            let f = clip_framing(c).unwrap();
            let (lo, hi) = if (p.width, p.height) == (640, 480) {
                (140.0, 460.0)
            } else {
                portrait += 1;
                assert_eq!((p.width, p.height), (720, 1280), "{}", c.name);
                (250.0, 900.0)
            };
            if f.stature_px.0 < lo || f.stature_px.1 > hi {
                broken.push(format!(
                    "{}: person {:.0}–{:.0} px",
                    c.name, f.stature_px.0, f.stature_px.1
                ));
            }
            if f.depth_m.0 < 2.0 || f.depth_m.1 > 9.0 {
                broken.push(format!(
                    "{}: camera {:.1}–{:.1} m away",
                    c.name, f.depth_m.0, f.depth_m.1
                ));
            }
            let h = p.body.as_ref().map_or(0.0, BodyShape::stature_m);
            if !(1.40..=2.05).contains(&h) {
                broken.push(format!("{}: {h:.2} m tall", c.name));
            }
        }
        assert!(broken.is_empty(), "{}", broken.join("\n"));
        assert_eq!(views.len(), 6, "{views:?}");
        assert!(portrait >= 3);
        // The render-time cap: about 10 minutes on two cores.
        assert!(total <= 7000, "{total} frames");
    }

    #[test]
    fn clicked_marks_move_by_about_the_click_noise_and_repeat() {
        let marks = Marks {
            frame: FrameIndex(0),
            points: PerJoint::from_fn(|j| Point2::new(100.0 + j.index() as f64, 50.0)),
        };
        let a = clicked_marks(&marks, CLICK_NOISE_PX, "clip");
        let b = clicked_marks(&marks, CLICK_NOISE_PX, "clip");
        let c = clicked_marks(&marks, CLICK_NOISE_PX, "other");
        assert_eq!(a.points, b.points);
        assert_ne!(a.points, c.points);
        let rms = (a
            .points
            .iter()
            .map(|(j, p)| (p - marks.points[j]).norm_squared())
            .sum::<f64>()
            / 32.0)
            .sqrt();
        assert!((0.8..4.0).contains(&rms), "{rms}");
    }
}
