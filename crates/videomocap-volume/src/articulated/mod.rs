//! The subject's articulated body fitted over the clip (issue 91): what the paper's skeleton
//! curve starts, this finishes. In order ([`fit_clip`]):
//!
//! 1. **The body** (`body`): the project's typical body at the clip's height, its lengths,
//!    widths and capsule radii fitted to the points of a few frames whose curve showed all five
//!    limbs, the median kept (robust over the clip) and held near the typical proportions.
//! 2. **The fit per frame** (`solve`): Levenberg–Marquardt over the root and the joints'
//!    rotations (within the joints' limits, a thigh's turn about itself among them) pulls every
//!    capsule onto the frame's points, started from the frame before (the previous frames'
//!    motion) and from the curve's own pose on this frame (its labels chosen over the whole
//!    clip, its sides taken facing the way the frame before faces); the better fit is kept.
//!    Which way the body faces is decided stretch by stretch (`facing`): the clip is tracked
//!    from its first frame's best fit and from that fit turned round (a track never turns the
//!    body round between two frames), and each stretch of frames takes the track whose fits
//!    explain its points better, a change of track paying a price; where the two fit about as
//!    well, the curve's facing decides and a warning names the stretch. What tells front from
//!    back: the feet (a capsule forward of each ankle) on a real body's volume, the knees' bend
//!    (the thighs cannot turn half round about themselves) on a bent leg.
//! 3. **Flags**: a frame whose fit leaves many points off the body or a capsule without points
//!    is flagged with the reason; a frame without points is interpolated and flagged. No frame is
//!    dropped.

mod body;
mod facing;
mod model;
mod points;
mod solve;

pub use model::{Pose, SubjectBody};
pub use points::{FitPoints, fit_points};

use crate::sequence::Assembled;
use facing::facing_chosen;
use nalgebra::{Point3, Rotation3, Vector3};
use solve::{FrameData, Quality};
use std::collections::BTreeMap;
use videomocap_core::formats::{Frame3d, FrameIndex, Skeleton3d};
use videomocap_core::skeleton::{Bone, PerJoint};

/// Settings of the articulated fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArticulatedParams {
    /// At most this many surface points per frame enter the fit (evenly thinned).
    pub max_points: usize,
    /// Levenberg–Marquardt steps per start.
    pub iterations: usize,
    /// Frames (with a five-limb curve, spread over the clip) whose points fit the body.
    pub body_frames: usize,
    /// A frame whose fit leaves more than this share of its points off the body is flagged.
    pub poor_unexplained: f64,
    /// A frame with a capsule farther than this many voxel sizes from every point is flagged.
    pub poor_gap_voxels: f64,
}

impl Default for ArticulatedParams {
    fn default() -> Self {
        ArticulatedParams {
            max_points: 1000,
            iterations: 12,
            body_frames: 8,
            poor_unexplained: 0.25,
            poor_gap_voxels: 2.5,
        }
    }
}

/// The clip fitted with the subject's body.
#[derive(Debug, Clone)]
pub struct Fitted {
    /// The 16 joints per frame (rigid: the body's lengths), flags saying what went wrong.
    pub skeleton: Skeleton3d,
    /// The subject's body.
    pub body: SubjectBody,
    /// One sentence per flagged frame.
    pub warnings: Vec<String>,
    /// Frames whose pose came from the curve's start rather than the previous frame's.
    pub from_curve: usize,
}

/// The robust loss's scale in voxel sizes (the capsules are not the body's exact shape).
const SIGMA_SPACINGS: f64 = 1.5;

fn frame_data(p: &FitPoints) -> FrameData {
    FrameData::new(p.points.clone(), (SIGMA_SPACINGS * p.spacing_m).max(0.01))
}

/// A fitted frame.
#[derive(Debug, Clone, Copy)]
struct Done {
    pose: Pose,
    quality: Quality,
    /// Whether its fit started from the curve's pose rather than the previous frame's.
    from_curve: bool,
}

/// Fits the subject's body to every frame of the clip. `points[i]` are frame i's points (`None`
/// or empty: none), `curve` the paper's pipeline's result (its skeleton's frames start every
/// fit), `names[i]` names frame i in warnings. `None` when the curve posed no frame.
pub fn fit_clip(
    points: &[FitPoints],
    curve: &Assembled,
    clean: &[bool],
    names: &[String],
    params: &ArticulatedParams,
) -> Option<Fitted> {
    let n = points.len();
    let mut curve_pose: Vec<Option<PerJoint<Point3<f64>>>> = vec![None; n];
    for f in &curve.skeleton.frames {
        if f.index.0 < n && f.flags.is_empty() {
            curve_pose[f.index.0] = Some(f.points);
        }
    }
    let body = body::read_body(points, &curve_pose, clean, params)?;
    let data: Vec<Option<FrameData>> = points
        .iter()
        .map(|p| (p.points.len() >= 20).then(|| frame_data(p)))
        .collect();
    let first = (0..n).find(|&i| curve_pose[i].is_some() && data[i].is_some())?;
    let clip = Clip {
        body: &body,
        data: &data,
        curve: &curve_pose,
        first,
        params,
    };
    let facing = track(&clip, None);
    // The body turned round on the first frame, tracked the same way: each stretch of the clip
    // takes the track whose fits explain its points better (`facing_chosen`).
    let mut facing_warnings = Vec::new();
    let done = match facing.done[first] {
        Some(f) => {
            let other = track(&clip, Some(turned_round(&f.pose)));
            let pick = facing_chosen(&facing, &other, &curve_pose);
            facing_warnings = facing::unsure(&facing, &other, &pick, names);
            pick.iter()
                .enumerate()
                .map(|(i, &b)| if b { other.done[i] } else { facing.done[i] })
                .collect()
        }
        _ => facing.done,
    };
    let from_curve = done.iter().flatten().filter(|d| d.from_curve).count();
    let (skeleton, mut warnings) = skeleton_of(&done, points, &body, names, params, curve)?;
    warnings.extend(facing_warnings);
    Some(Fitted {
        skeleton,
        body,
        warnings,
        from_curve,
    })
}

/// What every frame's fit starts from.
struct Clip<'a> {
    body: &'a SubjectBody,
    data: &'a [Option<FrameData>],
    curve: &'a [Option<PerJoint<Point3<f64>>>],
    /// The first frame with points and a curve pose: the tracking starts there.
    first: usize,
    params: &'a ArticulatedParams,
}

/// The clip's fits from one start on its first frame.
struct Tracked {
    done: Vec<Option<Done>>,
}

/// Every frame fitted from the frame before (the first frame from `start`, or its best start
/// when `None`), forwards from the first frame, then backwards before it.
fn track(clip: &Clip, start: Option<Pose>) -> Tracked {
    let n = clip.data.len();
    let first = clip.first;
    let mut out = Tracked {
        done: vec![None; n],
    };
    let order: Vec<(usize, Option<usize>)> = (first..n)
        .map(|i| (i, i.checked_sub(1).filter(|&p| p >= first)))
        .chain((0..first).rev().map(|i| (i, Some(i + 1))))
        .collect();
    for (i, before) in order {
        let Some(d) = &clip.data[i] else { continue };
        // The nearest fitted frame on the side the track comes from (a frame without points
        // does not make the next one start afresh, which would lose the track's facing).
        let prev = before.and_then(|b| {
            if b < i {
                (first..=b).rev().find_map(|k| out.done[k])
            } else {
                (b..n).find_map(|k| out.done[k])
            }
        });
        let f = match (i == first, start) {
            (true, Some(s)) => Started {
                fit: solve::fit(&s, clip.body, d, clip.params.iterations, false),
                from_curve: false,
            },
            _ => best_start(
                clip.body,
                d,
                clip.curve[i].as_ref(),
                prev.map(|p| p.pose),
                prev.is_none(),
                clip.params,
            ),
        };
        out.done[i] = Some(Done {
            pose: f.fit.pose,
            quality: f.fit.quality,
            from_curve: f.from_curve && prev.is_some(),
        });
    }
    out
}

/// `pose` turned half a turn about the vertical (+Y) through its root.
fn turned_round(pose: &Pose) -> Pose {
    let mut p = *pose;
    p.pelvis = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI) * p.pelvis;
    p
}

/// The best of a frame's fits and where it started.
pub(crate) struct Started {
    /// The fit.
    pub fit: solve::Fit,
    /// Whether it started from the curve's pose (and not the previous frame's).
    pub from_curve: bool,
}

/// Facings of the upright starts, radians about +Y.
const FACINGS: usize = 8;

/// The best fit of `body` to the frame `d` from its starts: the previous frame's pose `prev`,
/// the curve's `curve` (facing the way `prev` faces, and without `prev` both ways, since on a
/// real body's volume the curve's pose faces backwards; kept only when clearly better than the
/// previous frame's); and when neither fits well (or neither exists, or `search`), the body
/// standing upright (+Y, the project's world) at the points' centre in [`FACINGS`] facings
/// (with `prev`, only those less than a right angle from its facing).
pub(crate) fn best_start(
    body: &SubjectBody,
    d: &FrameData,
    curve: Option<&PerJoint<Point3<f64>>>,
    prev: Option<Pose>,
    search: bool,
    params: &ArticulatedParams,
) -> Started {
    let run = |start: &Pose| solve::fit(start, body, d, params.iterations, false);
    let mut best: Option<Started> = prev.map(|p| Started {
        fit: run(&p),
        from_curve: false,
    });
    if let Some(c) = curve {
        // The curve's sides are its weakest reading: its pose is taken facing the way the
        // previous frame's fit faces, and with no previous frame both ways (the cheaper kept).
        let (ahead, round) = (Pose::from_joints(c), Pose::from_joints(&swapped_sides(c)));
        let starts = match prev {
            Some(p) if (ahead.pelvis * Vector3::z()).dot(&(p.pelvis * Vector3::z())) < 0.0 => {
                vec![round]
            }
            Some(_) => vec![ahead],
            None => vec![ahead, round],
        };
        for start in starts {
            let f = run(&start);
            // The curve's start replaces the previous frame's only when clearly better.
            if best
                .as_ref()
                .is_none_or(|b| f.quality.cost < 0.98 * b.fit.quality.cost)
            {
                best = Some(Started {
                    fit: f,
                    from_curve: true,
                });
            }
        }
    }
    let poor = best
        .as_ref()
        .is_none_or(|b| is_poor(&b.fit.quality, d, params));
    if search || poor {
        let centre = d.points.iter().fold(Vector3::zeros(), |a, p| a + p.coords)
            / d.points.len().max(1) as f64;
        for k in 0..FACINGS {
            let mut start = Pose::default_standing();
            start.root = Point3::from(centre);
            let turn = k as f64 * std::f64::consts::TAU / FACINGS as f64;
            start.pelvis = Rotation3::from_axis_angle(&Vector3::y_axis(), turn);
            // Within a track the body does not turn round between two frames (the clip's two
            // tracks try both ways).
            if prev.is_some_and(|p| {
                (start.pelvis * Vector3::z()).dot(&(p.pelvis * Vector3::z())) < 0.0
            }) {
                continue;
            }
            let f = run(&start);
            if best
                .as_ref()
                .is_none_or(|b| f.quality.cost < b.fit.quality.cost)
            {
                best = Some(Started {
                    fit: f,
                    from_curve: false,
                });
            }
        }
    }
    // `poor` is true when `best` was None, and FACINGS > 0 filled it.
    best.unwrap_or_else(|| Started {
        fit: run(&Pose::default_standing()),
        from_curve: false,
    })
}

/// The joints `p` with left and right named the other way round (the body seen facing the
/// other way).
fn swapped_sides(p: &PerJoint<Point3<f64>>) -> PerJoint<Point3<f64>> {
    let mut out = *p;
    let (l, r) = (model::side_joints(0), model::side_joints(1));
    for k in 0..6 {
        out[l[k]] = p[r[k]];
        out[r[k]] = p[l[k]];
    }
    out
}

/// Whether a fit leaves too many points off the body or a capsule without points.
fn is_poor(q: &Quality, d: &FrameData, params: &ArticulatedParams) -> bool {
    q.unexplained > params.poor_unexplained
        || q.worst_gap.1 > params.poor_gap_voxels * d.sigma_m / SIGMA_SPACINGS
}

/// Segment names for warnings, in [`model::SEGMENTS`] order.
const SEGMENT_NAMES: [&str; 15] = [
    "lower trunk",
    "upper trunk",
    "shoulders",
    "hips",
    "head",
    "left upper arm",
    "left forearm",
    "right upper arm",
    "right forearm",
    "left thigh",
    "left shin",
    "right thigh",
    "right shin",
    "left foot",
    "right foot",
];

/// The fitted frames as a skeleton: flags for poor fits, frames without a fit interpolated.
fn skeleton_of(
    done: &[Option<Done>],
    points: &[FitPoints],
    body: &SubjectBody,
    names: &[String],
    params: &ArticulatedParams,
    curve: &Assembled,
) -> Option<(Skeleton3d, Vec<String>)> {
    let name = |i: usize| names.get(i).map_or("?", String::as_str);
    let mut warnings = Vec::new();
    let good: Vec<usize> = (0..done.len()).filter(|&i| done[i].is_some()).collect();
    good.first()?;
    let mut frames = Vec::new();
    for i in 0..done.len() {
        let Some(d) = done[i] else {
            let reason = format!("{} points to fit", points[i].points.len());
            let (Some(a), Some(b)) = (
                (0..i).rev().find_map(|k| done[k].map(|d| (k, d))),
                (i + 1..done.len()).find_map(|k| done[k].map(|d| (k, d))),
            ) else {
                warnings.push(format!(
                    "frame {i} ({}): {reason}; left out (no fitted frame on both sides)",
                    name(i)
                ));
                continue;
            };
            let (ja, jb) = (a.1.pose.posed(body).joints, b.1.pose.posed(body).joints);
            let t = (i - a.0) as f64 / (b.0 - a.0) as f64;
            warnings.push(format!("frame {i} ({}): {reason}; interpolated", name(i)));
            frames.push(Frame3d {
                index: FrameIndex(i),
                points: PerJoint::from_fn(|j| ja[j] + (jb[j] - ja[j]) * t),
                flags: vec!["interpolated".to_owned(), "no_points".to_owned()],
            });
            continue;
        };
        let mut flags = Vec::new();
        let q = d.quality;
        if q.unexplained > params.poor_unexplained {
            flags.push("poor_fit:points_off_body".to_owned());
            warnings.push(format!(
                "frame {i} ({}): poor fit, {:.0} % of the points lie off the body",
                name(i),
                100.0 * q.unexplained
            ));
        }
        let gap_limit = params.poor_gap_voxels * points[i].spacing_m.max(0.01);
        if q.worst_gap.1 > gap_limit {
            let seg = SEGMENT_NAMES.get(q.worst_gap.0).copied().unwrap_or("?");
            flags.push(format!("poor_fit:no_points:{}", seg.replace(' ', "_")));
            warnings.push(format!(
                "frame {i} ({}): poor fit, the {seg} has no points within {:.0} mm",
                name(i),
                1000.0 * q.worst_gap.1
            ));
        }
        frames.push(Frame3d {
            index: FrameIndex(i),
            points: d.pose.posed(body).joints,
            flags,
        });
    }
    let rest = Pose::default_standing().posed(body).joints;
    let bone_lengths_m: BTreeMap<String, f64> = Bone::ALL
        .iter()
        .map(|b| (b.key(), (rest[b.child] - rest[b.parent]).norm().max(1e-6)))
        .collect();
    Some((
        Skeleton3d {
            camera: curve.skeleton.camera,
            fps: curve.skeleton.fps,
            bone_lengths_m,
            frames,
        },
        warnings,
    ))
}
