//! The second pipeline (Chu, Jenkins, Mataric, "Converting Sequences of Human Volumes into
//! Kinematic Motion"): point volumes → Isomap → nonlinear spherical shells → skeleton curve →
//! rigid bodies → joint positions, labelled consistently over the sequence and handed to the
//! shared export (local frames, joint angles, BVH).
//!
//! Data flows `cloud`/`carve` → `isomap` → `shells` → `curve` → `bodies` (one frame, [`process_frame`])
//! → `sequence` (all frames, [`assemble`]).

pub mod articulated;
pub mod bodies;
pub mod carve;
pub mod clean;
pub mod cloud;
pub mod curve;
mod follow;
mod handles;
pub mod isomap;
pub mod labels;
pub mod sequence;
pub mod shells;
pub mod voxel;

pub use articulated::{ArticulatedParams, FitPoints, Fitted, fit_points};
pub use bodies::{BodyFit, BodyParams, Part};
pub use clean::{CleanParams, Cleaned, clean_clip};
pub use cloud::{PointCloud, list_frames, read_cloud};
pub use curve::{CurveParams, SkeletonCurve};
pub use isomap::{IsomapParams, Neighbourhood};
pub use sequence::{Assembled, assemble};
pub use shells::ShellParams;
pub use voxel::VoxelGrid;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::Point3;
use rayon::prelude::*;
use std::num::NonZero;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;
use videomocap_core::formats::FormatError;

/// A volume input could not be read or is not valid; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum VolumeError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {problem}")]
    Invalid { path: PathBuf, problem: String },
    #[error(transparent)]
    Format(#[from] FormatError),
}

impl VolumeError {
    /// Turns an I/O error on `path` into [`VolumeError::Io`] (for `map_err`).
    pub fn io(path: &Path) -> impl FnOnce(std::io::Error) -> VolumeError + '_ {
        move |source| VolumeError::Io {
            path: path.to_owned(),
            source,
        }
    }
}

/// Why one frame gave no pose (the sequence goes on: the frame is interpolated or skipped).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameProblem {
    #[error("{0} points; at least {1} are needed")]
    TooFewPoints(usize, usize),
    #[error(transparent)]
    Isomap(#[from] isomap::IsomapProblem),
    #[error(transparent)]
    Curve(#[from] curve::CurveProblem),
    #[error("{0}")]
    Unreadable(String),
}

/// Every setting of the pipeline, with the paper's values as defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeParams {
    /// Neighbourhood radius as a multiple of the point spacing (the median nearest-neighbour
    /// distance): 1.8 takes the 26 neighbours of a voxel, the paper's ε of about one voxel
    /// diagonal.
    pub radius_spacings: f64,
    /// Landmarks for landmark Isomap.
    pub landmarks: usize,
    /// Shells and clustering.
    pub shells: ShellParams,
    /// Tree refinement.
    pub curve: CurveParams,
    /// Body fitting.
    pub bodies: BodyParams,
    /// Frames with fewer points are skipped.
    pub min_points: usize,
    /// The skeleton curve sees at most about this many points: a denser cloud is merged onto a
    /// coarser lattice first (the curve only starts the fit; the fit takes every point's share).
    /// 6,000: the suite's clouds are read as they are, about 11,000 points reach the curve as
    /// about 1,400 (docs/method.md, "Point volumes", Speed).
    pub curve_points: usize,
    /// The subject's articulated body fitted over the clip.
    pub articulated: ArticulatedParams,
    /// What carving adds taken off the clip's clouds first (the floor sheet, points no
    /// neighbouring frame has); `None`: the clouds as read.
    pub clean: Option<CleanParams>,
}

impl Default for VolumeParams {
    fn default() -> Self {
        VolumeParams {
            radius_spacings: 1.8,
            landmarks: 12,
            shells: ShellParams::default(),
            curve: CurveParams::default(),
            bodies: BodyParams::default(),
            min_points: 100,
            curve_points: 6_000,
            articulated: ArticulatedParams::default(),
            clean: Some(CleanParams::default()),
        }
    }
}

/// One frame's result: the points used, the skeleton curve, the bodies and the time taken.
#[derive(Debug, Clone)]
pub struct FrameResult {
    /// Input positions of the points kept (the largest connected component).
    pub points: Vec<Point3<f64>>,
    /// The skeleton curve in input space (indices into `points`).
    pub curve: SkeletonCurve,
    /// The fitted bodies and joint positions.
    pub fit: BodyFit,
    /// Seconds spent in Isomap (graph, geodesics, MDS) and in everything else.
    pub seconds: [f64; 2],
}

/// The median distance from a point to its nearest neighbour (the voxel size of voxel data).
pub fn point_spacing(points: &[Point3<f64>]) -> f64 {
    if points.len() < 2 {
        return 0.0;
    }
    let coords: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&coords);
    let step = (coords.len() / 500).max(1);
    let two = NonZero::new(2).unwrap_or(NonZero::<usize>::MIN);
    let mut d: Vec<f64> = coords
        .iter()
        .step_by(step)
        .filter_map(|q| {
            tree.nearest_n::<SquaredEuclidean>(q, two)
                .get(1)
                .map(|n| n.distance.sqrt())
        })
        .collect();
    d.sort_by(f64::total_cmp);
    d.get(d.len() / 2).copied().unwrap_or(0.0)
}

/// The volume-to-posture procedure on one frame. Beyond the paper, when a limb touches the body
/// (a hand on the hip) and so closes a loop, the loop is opened where it touches, as seen from
/// the head the first pass found, and the frame is done again; the second result is kept when
/// it gives a pose that shows as many arms as the first.
pub fn process_frame(
    points: &[Point3<f64>],
    params: &VolumeParams,
) -> Result<FrameResult, FrameProblem> {
    if points.len() < params.min_points {
        return Err(FrameProblem::TooFewPoints(points.len(), params.min_points));
    }
    let start = Instant::now();
    let spacing = point_spacing(points);
    let iso = IsomapParams {
        neighbourhood: Neighbourhood::Radius(spacing * params.radius_spacings),
        landmarks: params.landmarks,
    };
    let mut graph = isomap::Neighbours::new(points, &iso)?;
    let graph_s = start.elapsed().as_secs_f64();
    let first = embed_and_fit(&graph, &iso, params)?;
    // Isomap's share: the neighbourhood graph and every embedding (not the loop opening).
    let mut isomap_s = graph_s + first.isomap_s;
    let mut result = first.result;
    if let Some(head) = first.head
        && graph.open_handles(head) > 0
    {
        // A second pass that fails keeps the first one's answer.
        if let Ok(second) = embed_and_fit(&graph, &iso, params) {
            isomap_s += second.isomap_s;
            // Kept unless it shows fewer arms than the first.
            let unseen = |r: &Result<FrameResult, FrameProblem>| {
                r.as_ref().map_or(usize::MAX, |f| f.curve.arms_unseen())
            };
            if second.result.is_ok() && unseen(&second.result) <= unseen(&result) {
                result = second.result;
            }
        }
    }
    result.map(|mut r| {
        let total = start.elapsed().as_secs_f64();
        r.seconds = [isomap_s, total - isomap_s];
        r
    })
}

/// One pass of the procedure on a built graph.
struct Pass {
    /// The frame's result (`seconds` not yet filled in).
    result: Result<FrameResult, FrameProblem>,
    /// Where the head is: the curve's head tip, or a guess when the curve could not be named.
    head: Option<Point3<f64>>,
    /// Seconds spent embedding.
    isomap_s: f64,
}

fn embed_and_fit(
    graph: &isomap::Neighbours,
    iso: &IsomapParams,
    params: &VolumeParams,
) -> Result<Pass, FrameProblem> {
    let start = Instant::now();
    let embedding = isomap::embed_graph(graph, iso)?;
    let isomap_s = start.elapsed().as_secs_f64();
    let kept: Vec<Point3<f64>> = graph.points().to_vec();
    let full = {
        let mut d: Vec<u32> = embedding.degree.clone();
        d.sort_unstable();
        d.get(d.len() * 95 / 100).copied().unwrap_or(0)
    };
    let surface: Vec<bool> = embedding
        .degree
        .iter()
        .map(|&d| f64::from(d) < 0.8 * f64::from(full))
        .collect();
    let mut tree = shells::build(&embedding.coords, &params.shells);
    curve::adjust_tree_nodes(&mut tree, &params.curve);
    let curve = match curve::skeleton_curve(&tree, &embedding.coords, &kept) {
        Ok(c) => c,
        Err(e) => {
            return Ok(Pass {
                result: Err(e.into()),
                head: curve::head_tip_guess(&tree, &kept),
                isomap_s,
            });
        }
    };
    let fit = bodies::fit(&curve, &kept, &surface, &params.bodies);
    let head = curve.head.last().map(|&i| curve.points[i]);
    Ok(Pass {
        result: Ok(FrameResult {
            points: kept,
            curve,
            fit,
            seconds: [0.0; 2],
        }),
        head,
        isomap_s,
    })
}

/// A processed sequence: every frame's result (or why it has none) and the assembled motion.
#[derive(Debug, Clone)]
pub struct Processed {
    /// The frame files, in order.
    pub files: Vec<PathBuf>,
    /// Per frame: its result, or the problem that left it without a pose.
    pub results: Vec<Result<FrameResult, FrameProblem>>,
    /// Labels, sides and the 16-joint skeleton: the subject's body fitted over the clip when
    /// it could be (`fitted`), else the paper's skeleton curve alone; the warnings of both.
    pub assembled: Assembled,
    /// The paper's skeleton curve alone (labels and sides over the clip), before the fit.
    pub curve_skeleton: videomocap_core::formats::Skeleton3d,
    /// The articulated fit, when the curve posed a frame to start it.
    pub fitted: Option<Fitted>,
    /// What the cleaning took off the clouds before the pipeline.
    pub cleaned: Cleaned,
}

impl Processed {
    /// Frames whose skeleton curve showed all five limbs.
    pub fn five_limb_frames(&self) -> usize {
        five_limb_frames(&self.results)
    }
    /// Frames with a pose of their own (five limbs, or arms against the trunk placed from
    /// other frames); the rest are interpolated or left out.
    pub fn posed_frames(&self) -> usize {
        self.results.iter().filter(|r| r.is_ok()).count()
    }
}

/// One frame as the sequence needs it: the curve's result and the points the fit takes.
pub fn process_frame_for_fit(
    points: &[Point3<f64>],
    params: &VolumeParams,
) -> (Result<FrameResult, FrameProblem>, FitPoints) {
    let spacing = point_spacing(points);
    let fit = fit_points(points, spacing, params.articulated.max_points);
    let coarse = coarsen(points, spacing, params.curve_points);
    (process_frame(&coarse, params), fit)
}

/// `points` (lattice spacing `spacing_m`) merged onto a lattice coarse enough to leave about
/// `max_points`: one point, the mean of its members, per coarse cell.
fn coarsen(points: &[Point3<f64>], spacing_m: f64, max_points: usize) -> Vec<Point3<f64>> {
    if points.len() <= max_points || spacing_m <= 0.0 {
        return points.to_vec();
    }
    let cell = spacing_m * (points.len() as f64 / max_points as f64).cbrt().ceil();
    let mut cells: std::collections::HashMap<[i64; 3], (nalgebra::Vector3<f64>, usize)> =
        std::collections::HashMap::new();
    for p in points {
        let key = [p.x, p.y, p.z].map(|c| (c / cell).floor() as i64);
        let e = cells.entry(key).or_insert((nalgebra::Vector3::zeros(), 0));
        e.0 += p.coords;
        e.1 += 1;
    }
    let mut out: Vec<(_, Point3<f64>)> = cells
        .into_iter()
        .map(|(k, (s, n))| (k, Point3::from(s / n as f64)))
        .collect();
    // A fixed order, whatever the hash map's.
    out.sort_by_key(|(k, _)| *k);
    out.into_iter().map(|(_, p)| p).collect()
}

/// The second pass over the clip and the articulated fit: assembles the curve's `results`
/// (labels, sides, skeleton) and fits the subject's body to `points` started from it; the
/// returned [`Assembled`] holds the fitted skeleton and its warnings, then the curve's (named
/// as the curve's), when the fit could run, and the curve's skeleton is returned beside it.
pub fn assemble_and_fit(
    results: &[Result<FrameResult, FrameProblem>],
    points: &[FitPoints],
    names: &[String],
    fps: f64,
    params: &VolumeParams,
) -> (
    Assembled,
    videomocap_core::formats::Skeleton3d,
    Option<Fitted>,
) {
    let mut assembled = assemble(results, names, fps);
    let curve = assembled.skeleton.clone();
    let clean: Vec<bool> = results
        .iter()
        .map(|r| r.as_ref().is_ok_and(|f| f.curve.arms_unseen() == 0))
        .collect();
    let fitted = articulated::fit_clip(points, &assembled, &clean, names, &params.articulated);
    if let Some(f) = &fitted {
        assembled.skeleton = f.skeleton.clone();
        // The fitted body poses every frame with points, so the curve's own warnings (what it
        // interpolated or left out) are said to be the curve's, after the fit's.
        let curve_said = std::mem::take(&mut assembled.warnings);
        assembled.warnings = f.warnings.clone();
        assembled.warnings.extend(
            curve_said
                .into_iter()
                .map(|w| format!("skeleton curve (the fitted body's start), {w}")),
        );
    }
    (assembled, curve, fitted)
}

/// Frames of `results` whose skeleton curve showed all five limbs.
pub fn five_limb_frames(results: &[Result<FrameResult, FrameProblem>]) -> usize {
    results
        .iter()
        .flatten()
        .filter(|f| f.curve.arms_unseen() == 0)
        .count()
}

/// Why a whole sequence gave nothing.
#[derive(Debug, thiserror::Error)]
pub enum SequenceError {
    #[error(transparent)]
    Input(#[from] VolumeError),
    #[error("{dir}: none of the {frames} frames gave a pose (first problem: {first})")]
    NoPose {
        dir: PathBuf,
        frames: usize,
        first: String,
    },
    #[error("cancelled")]
    Cancelled,
}

/// Runs the pipeline on every point cloud of `dir` (frames in parallel with rayon), calling
/// `progress(done, total)` as frames finish; a frame that cannot be read or gives no pose is a
/// warning, not an error, unless no frame gives a pose.
pub fn process_directory(
    dir: &Path,
    params: &VolumeParams,
    fps: f64,
    progress: &(dyn Fn(usize, usize) + Sync),
    cancel: &AtomicBool,
) -> Result<Processed, SequenceError> {
    let files = list_frames(dir)?;
    let mut clouds: Vec<Result<PointCloud, String>> = files
        .par_iter()
        .map(|f| read_cloud(f).map_err(|e| e.to_string()))
        .collect();
    let cleaned = clean_read(&mut clouds, params);
    let done = AtomicUsize::new(0);
    let (results, points): (Vec<Result<FrameResult, FrameProblem>>, Vec<FitPoints>) = clouds
        .par_iter()
        .map(|c| {
            if cancel.load(Ordering::Relaxed) {
                return (
                    Err(FrameProblem::Unreadable("cancelled".into())),
                    FitPoints::default(),
                );
            }
            let r = match c {
                Ok(points) => process_frame_for_fit(points, params),
                Err(e) => (
                    Err(FrameProblem::Unreadable(e.clone())),
                    FitPoints::default(),
                ),
            };
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, files.len());
            r
        })
        .unzip();
    if cancel.load(Ordering::Relaxed) {
        return Err(SequenceError::Cancelled);
    }
    if !results.iter().any(Result::is_ok) {
        let first = results
            .iter()
            .find_map(|r| r.as_ref().err().map(ToString::to_string))
            .unwrap_or_default();
        return Err(SequenceError::NoPose {
            dir: dir.to_owned(),
            frames: files.len(),
            first,
        });
    }
    let names: Vec<String> = files
        .iter()
        .map(|f| {
            f.file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    let (mut assembled, curve_skeleton, fitted) =
        assemble_and_fit(&results, &points, &names, fps, params);
    assembled.warnings.extend(cleaned.warnings());
    Ok(Processed {
        files,
        results,
        assembled,
        curve_skeleton,
        fitted,
        cleaned,
    })
}

/// The readable clouds of `clouds` cleaned together as `params.clean` says (an unreadable
/// frame counts as an empty one); what was taken off.
fn clean_read(clouds: &mut [Result<PointCloud, String>], params: &VolumeParams) -> Cleaned {
    let Some(clean) = &params.clean else {
        return Cleaned::default();
    };
    let mut readable: Vec<Vec<Point3<f64>>> = clouds
        .iter_mut()
        .map(|c| c.as_mut().map(std::mem::take).unwrap_or_default())
        .collect();
    let cleaned = clean_clip(&mut readable, clean);
    for (c, r) in clouds.iter_mut().zip(readable) {
        if let Ok(c) = c {
            *c = r;
        }
    }
    cleaned
}
