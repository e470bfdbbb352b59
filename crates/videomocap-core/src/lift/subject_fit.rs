//! Beyond the paper: the subject's lengths read from the tracks when only the height (or some
//! lengths) are known.
//!
//! Eqs. 6–11 need the key triangle's shape (both shoulders and the chest) in metres, and every
//! limb's depth follows from its bone length; the lift is very sensitive to both (a key
//! triangle seen nearly face on turns by several degrees for a 1 % error in a side).
//!
//! - **A first reading** ([`fit_to_tracks`]), with no depths: the chest's drop below the
//!   shoulder line (its image distance along the trunk over the trunk's image length, the
//!   median over the frames: turning about the vertical foreshortens neither) and each limb's
//!   0.8 quantile of image length over the trunk's, held within [`LIMB_RANGE`] of the table,
//!   then scaled back to the height. It sets up the first lift, and stands when the clip is
//!   too short for the whole-clip reading.
//! - **The whole-clip reading** ([`fit_in_perspective`]): a first lift gives every frame's
//!   depths, and each part (trunk, head, limbs, both widths) is the
//!   [`ENVELOPE_QUANTILE`] over the clip of its image length times its parent's depth. A bone's
//!   image is never longer than the bone, and most motions bring each part square to the
//!   camera now and then, so this upper envelope measures every part in one unit; one scale
//!   makes the stature stack the height's, or comes from the lengths the user gave
//!   ([`KnownLengths`]). A part whose envelope stays under [`LIMB_RANGE`] of the table was never
//!   seen square and keeps the table's. Read lengths carry a doubt of [`LENGTH_MARGIN`]
//!   ([`SubjectModel::length_doubt`]).
//!
//! `docs/method.md` ("3D reconstruction") and `bench lift` have the figures.

mod at_depth;
mod reading;

pub use reading::SubjectFit;
pub(super) use reading::{ChestDrop, LengthOrigin, PartLength};

use at_depth::fit_at_depth;

use super::LiftError;
use super::job::LiftJob;
use super::params::LiftParams;
use super::smoothing::{adaptive_sigmas, smoothed_images};
use super::solve::lift_per_frame;
use crate::camera::PinholeCamera;
use crate::formats::{KnownLengths, PointSource, Tracks2d};
use crate::skeleton::{Bone, Joint, PerJoint, Proportions, SubjectModel};
use nalgebra::{Point2, Point3};

/// A trunk shorter than this in the image (pixels) is not measured.
const MIN_TRUNK_PX: f64 = 10.0;

/// The measured drop is kept within this factor of the proportions' (either way): marks that
/// put the chest level with the shoulders are a marking slip, not a build.
const MAX_DROP_FACTOR: f64 = 1.6;

/// Track points below this confidence are not used.
const MIN_CONFIDENCE: f32 = 0.5;

/// The quantile of a limb's image length (over the trunk's) taken as its length.
const LIMB_QUANTILE: f64 = 0.8;

/// The quantile of a group's image length times depth taken as its length (its upper envelope
/// over the clip, short of the few frames where noise or a slip makes it longer). On the
/// benchmark's dev split from exact 2D and the stated height (with [`LENGTH_MARGIN`] 0): 0.8 /
/// 0.9 / 0.95 / 1.0 gave 119.7 / 118.5 / 122.2 / 136.7 mm; with the margin 0.9 and 0.95 were
/// within 3 mm, 0.95 ahead with 2 px noise (118.0 against 120.5).
pub(super) const ENVELOPE_QUANTILE: f64 = 0.95;

/// The doubt ([`SubjectModel::length_doubt`]) of a length read from the clip: the lift solves
/// the limbs and the head (every bone hung from a joint by one of its two depth roots) this
/// share shorter than read, then gives them back their length along the direction found. The
/// costs are lopsided: a bone modelled longer than it is tilts out of the image plane by
/// √(L² − l²) to make up for it (5 % too long on a 0.45 m thigh square to the camera is 0.14 m of depth, and a wrong root doubles it), while one
/// modelled shorter misses its image by the difference and stays square to its ray. So when a
/// length is uncertain by a few per cent, the answer leans to the bone lying flat. On the dev
/// split from exact 2D and the stated height (quantile 0.95): margin 0 / 3 / 5 / 8 / 11 %:
/// 122.2 / 114.9 / 110.9 / 111.4 / 116.1 mm MPJPE; with 2 px noise 125.1 / 118.9 / 118.0 /
/// 119.7 / 123.6 mm (the cut-out: 138.5 and 142.6).
pub(super) const LENGTH_MARGIN: f64 = 0.05;

/// A limb's measured length is held within these factors of the table's.
pub(super) const LIMB_RANGE: (f64, f64) = (0.8, 1.2);

/// Fewest measured frames for a limb's length: a quantile of a handful of poses says little.
const MIN_LIMB_FRAMES: usize = 10;

/// The bones measured together (left and right pooled, parent first), each named for the
/// report.
const LIMBS: [(&str, &[(Joint, Joint)]); 5] = {
    use Joint::*;
    [
        ("head", &[(Neck, HeadTop)]),
        (
            "upper arms",
            &[(LeftShoulder, LeftElbow), (RightShoulder, RightElbow)],
        ),
        (
            "forearms",
            &[(LeftElbow, LeftWrist), (RightElbow, RightWrist)],
        ),
        ("thighs", &[(LeftHip, LeftKnee), (RightHip, RightKnee)]),
        ("shanks", &[(LeftKnee, LeftAnkle), (RightKnee, RightAnkle)]),
    ]
};

/// The bones stacked in the stature (ankle to head top, one leg), parent first.
const STATURE_STACK: [(Joint, Joint); 5] = {
    use Joint::*;
    [
        (LeftKnee, LeftAnkle),
        (LeftHip, LeftKnee),
        (Pelvis, Chest),
        (Chest, Neck),
        (Neck, HeadTop),
    ]
};

/// The chest's perpendicular distance from the shoulder line in the subject model, metres, and
/// its offset along the line from the shoulders' midpoint (towards the left shoulder).
fn model_triangle(subject: &SubjectModel) -> Option<(f64, f64)> {
    let w = subject.shoulder_width_m;
    let a = subject.bone_length(Bone::new(Joint::Chest, Joint::LeftShoulder));
    let b = subject.bone_length(Bone::new(Joint::Chest, Joint::RightShoulder));
    if !(w.is_finite() && w > 0.0) {
        return None;
    }
    // Chest at (x, h) with the left shoulder at (w/2, 0) and the right at (−w/2, 0).
    let x = (b * b - a * a) / (2.0 * w);
    let h2 = a * a - (x - w / 2.0).powi(2);
    (h2 > 0.0).then(|| (h2.sqrt(), x))
}

fn stature_stack(subject: &SubjectModel) -> f64 {
    STATURE_STACK
        .iter()
        .map(|&(a, b)| subject.bone_length(Bone::new(a, b)))
        .sum()
}

/// One frame's smoothed points, which of them are trusted, the trunk's image length when it
/// can be measured, and the joints' depths when a first lift gave them.
struct FrameView<'a> {
    points: &'a PerJoint<Point2<f64>>,
    trusted: PerJoint<bool>,
    trunk_px: Option<f64>,
    depth: Option<&'a PerJoint<Point3<f64>>>,
}

impl FrameView<'_> {
    fn all_trusted(&self, joints: &[Joint]) -> bool {
        joints.iter().all(|&j| self.trusted[j])
    }
}

/// The tracks smoothed as the lift smooths them, with their trust and, when given, each frame's
/// lifted joints.
fn views<'a>(
    tracks: &'a Tracks2d,
    images: &'a [PerJoint<Point2<f64>>],
    lifted: Option<&'a [PerJoint<Point3<f64>>]>,
) -> Vec<FrameView<'a>> {
    tracks
        .frames
        .iter()
        .zip(images)
        .enumerate()
        .map(|(t, (f, points))| {
            let trusted = PerJoint::from_fn(|j| {
                let p = &f.points[j];
                p.confidence >= MIN_CONFIDENCE
                    && p.source == PointSource::Tracked
                    && points[j].x.is_finite()
                    && points[j].y.is_finite()
            });
            let trunk = (points[Joint::Pelvis] - points[Joint::Neck]).norm();
            let trunk_px =
                (trusted[Joint::Pelvis] && trusted[Joint::Neck] && trunk >= MIN_TRUNK_PX)
                    .then_some(trunk);
            FrameView {
                points,
                trusted,
                trunk_px,
                depth: lifted.and_then(|l| l.get(t)),
            }
        })
        .collect()
}

/// The median drop over the frames whose shoulders, chest, neck and pelvis are trusted, and
/// how many frames that was.
fn measure_drop(views: &[FrameView<'_>]) -> Option<(f64, usize)> {
    use Joint::*;
    let mut drops: Vec<f64> = views
        .iter()
        .filter_map(|v| {
            let trunk = v.trunk_px?;
            if !v.all_trusted(&[LeftShoulder, RightShoulder, Chest]) {
                return None;
            }
            let p = v.points;
            let axis = p[Pelvis] - p[Neck];
            let mid = nalgebra::center(&p[LeftShoulder], &p[RightShoulder]);
            Some((p[Chest] - mid).dot(&axis) / (trunk * trunk))
        })
        .collect();
    if drops.is_empty() {
        return None;
    }
    drops.sort_by(f64::total_cmp);
    Some((drops[drops.len() / 2], drops.len()))
}

/// A limb group's [`LIMB_QUANTILE`] of image length over trunk length, when enough frames show
/// it.
fn measure_limb(views: &[FrameView<'_>], bones: &[(Joint, Joint)]) -> Option<f64> {
    let ratios: Vec<f64> = views
        .iter()
        .flat_map(|v| {
            bones.iter().filter_map(move |&(a, b)| {
                let trunk = v.trunk_px?;
                // Perspective: a limb nearer the camera than the trunk looks longer. The depth
                // of the bone's parent end, not its middle: the child's hangs on the bone's
                // own root choice in the first lift (suite 39.0 mm against 40.9, the real
                // sample 107.0 against 108.3).
                let nearer = v.depth.map_or(1.0, |z| {
                    2.0 * z[a].z / (z[Joint::Neck].z + z[Joint::Pelvis].z)
                });
                (v.all_trusted(&[a, b]) && nearer.is_finite() && nearer > 0.0)
                    .then(|| (v.points[b] - v.points[a]).norm() / trunk * nearer)
            })
        })
        .collect();
    if ratios.len() < MIN_LIMB_FRAMES * bones.len() {
        return None;
    }
    quantile(ratios, LIMB_QUANTILE)
}

/// The `q` quantile of `values` (the nearest rank); `None` when there are none.
fn quantile(mut values: Vec<f64>, q: f64) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    let k = ((values.len().checked_sub(1)?) as f64 * q).round() as usize;
    values.get(k).copied()
}

/// The subject with its key triangle's height and its limbs' lengths read from the tracks (see
/// the module's text), and what was read; unchanged where nothing could be measured. The lift
/// reads it through [`fit_in_perspective`]; the tests read this first step alone.
#[cfg(test)]
pub(super) fn fit_to_tracks(
    subject: &SubjectModel,
    tracks: &Tracks2d,
) -> (SubjectModel, SubjectFit) {
    let images = smoothed_images(tracks, &adaptive_sigmas(tracks));
    fit(subject, &views(tracks, &images, None))
}

/// The first reading (`fit_to_tracks`), then the limbs read again with each image length scaled by the depth of its
/// bone's parent over the trunk's in a first lift (per frame, with `params`) with that fit through
/// `camera`: in a side view the near limbs are nearer the camera than the trunk and look several
/// per cent longer. Falls back to the first fit when that lift fails.
pub(super) fn fit_in_perspective(
    subject: &SubjectModel,
    tracks: &Tracks2d,
    camera: PinholeCamera,
    params: &LiftParams,
    known: &KnownLengths,
) -> Result<(SubjectModel, SubjectFit), LiftError> {
    let images = smoothed_images(tracks, &adaptive_sigmas(tracks));
    let first = fit(subject, &views(tracks, &images, None));
    let job = LiftJob {
        tracks,
        camera,
        subject: first.0.clone(),
        params: *params,
        overrides: Default::default(),
    };
    let read = match lift_per_frame(&job) {
        Ok(per) => {
            let v = views(tracks, &images, Some(&per.resolved.points));
            fit_at_depth(subject, &v, known)?.unwrap_or_else(|| fit(subject, &v))
        }
        Err(_) => first,
    };
    Ok(read)
}

/// The fit on the tracks' views (see the module's text).
fn fit(subject: &SubjectModel, views: &[FrameView<'_>]) -> (SubjectModel, SubjectFit) {
    let trunk = subject.trunk_m();
    let mut out = subject.clone();
    let mut fit = SubjectFit {
        chest_drop: None,
        limbs: Vec::new(),
        stature_scale: 1.0,
        parts: Vec::new(),
        scale_from_given: false,
    };
    if !(trunk.is_finite() && trunk > 0.0) {
        return (out, fit);
    }
    fit.chest_drop = place_chest(&mut out, subject, views, 1.0);
    for (name, bones) in LIMBS {
        let Some(ratio) = measure_limb(views, bones) else {
            continue;
        };
        let measured = ratio * trunk;
        let mut factor = 1.0;
        for &(a, b) in bones {
            let k = Bone::new(a, b).index();
            let table = subject.bone_length_m[k];
            let length = measured.clamp(LIMB_RANGE.0 * table, LIMB_RANGE.1 * table);
            factor = length / table;
            out.bone_length_m[k] = length;
        }
        fit.limbs.push((name, factor));
    }
    let (before, after) = (stature_stack(subject), stature_stack(&out));
    if before > 0.0 && after > 0.0 {
        let scale = before / after;
        out.bone_length_m.iter_mut().for_each(|l| *l *= scale);
        out.shoulder_width_m *= scale;
        fit.stature_scale = scale;
    }
    // Read or from the table, the limbs and the head are uncertain (see `fit_at_depth`).
    for (k, b) in Bone::ALL.iter().enumerate() {
        if ![Joint::Pelvis, Joint::Chest].contains(&b.parent) {
            out.length_doubt[k] = LENGTH_MARGIN;
        }
    }
    (out, fit)
}

/// Places the chest in `out` (its two chest–shoulder bones) at the drop below the shoulder line
/// the tracks show (their median, held within [`MAX_DROP_FACTOR`] of `subject`'s), on `out`'s
/// trunk and shoulder width, its offset along the line scaled by `width_factor` (`out`'s width
/// over `subject`'s). Without a measurable drop the two bones are scaled by `width_factor`.
fn place_chest(
    out: &mut SubjectModel,
    subject: &SubjectModel,
    views: &[FrameView<'_>],
    width_factor: f64,
) -> Option<ChestDrop> {
    let chest = |j| Bone::new(Joint::Chest, j).index();
    let sides = [Joint::LeftShoulder, Joint::RightShoulder];
    let (Some((h, x)), Some((drop, frames))) = (model_triangle(subject), measure_drop(views))
    else {
        for j in sides {
            out.bone_length_m[chest(j)] *= width_factor;
        }
        return None;
    };
    let model = h / subject.trunk_m();
    let measured = drop.clamp(model / MAX_DROP_FACTOR, model * MAX_DROP_FACTOR);
    let h_new = measured * out.trunk_m();
    let (w, x) = (out.shoulder_width_m, x * width_factor);
    out.bone_length_m[chest(sides[0])] = (h_new * h_new + (x - w / 2.0).powi(2)).sqrt();
    out.bone_length_m[chest(sides[1])] = (h_new * h_new + (x + w / 2.0).powi(2)).sqrt();
    Some(ChestDrop {
        measured,
        model,
        frames,
    })
}

/// What a user who knows only the subject's height gets: the proportions table scaled to the
/// height and fitted to the tracks seen through `camera` (`fit_in_perspective`, its first lift
/// with `params`).
pub fn subject_from_height(
    height_m: f64,
    tracks: &Tracks2d,
    camera: PinholeCamera,
    params: &LiftParams,
    known: &KnownLengths,
) -> Result<(SubjectModel, SubjectFit), LiftError> {
    let subject = SubjectModel::from_height(height_m, Proportions::default())?;
    fit_in_perspective(&subject, tracks, camera, params, known)
}

#[cfg(test)]
mod tests;
