//! The second pass across frames (paper §4), in the order [`assemble`] runs it: the clip's up
//! (upside-down frames left out), consistent limb labels with left and right (chosen over the
//! whole clip by `labels`, from continuity and the knees' or elbows' cues; beyond the paper,
//! which assigns no sides), static segment lengths from articulated frames (used to place the
//! elbow or knee of a straight limb), arms against the trunk placed from the frames that saw
//! them, and the 16-joint skeleton3d.
//!
//! Frames that gave no pose are interpolated between their good neighbours (flagged
//! `interpolated`) or, before the first and after the last good frame, left out.

use super::{FrameProblem, FrameResult};
use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::formats::{Frame3d, FrameIndex, Skeleton3d};
use videomocap_core::skeleton::{Bone, Joint, PerJoint, SubjectModel};

/// How left and right were decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SidesFrom {
    /// From the direction knees bend (they point forwards).
    Knees,
    /// From the direction elbows bend (they point backwards).
    Elbows,
    /// Nothing bends anywhere: arm1/leg1 are written as the left ones, arbitrarily.
    Arbitrary,
}

/// The assembled sequence.
#[derive(Debug, Clone)]
pub struct Assembled {
    /// The 16 joints per frame, in the volume's own coordinates (see `docs/formats.md`).
    pub skeleton: Skeleton3d,
    /// Per input frame, which fitted limb went to each slot (left arm, right arm, left leg,
    /// right leg); `None` for frames without a pose, and a slot's `None` for an arm the
    /// skeleton curve did not show (placed from other frames; see the warnings).
    pub slots: Vec<Option<[Option<usize>; 4]>>,
    /// One sentence per frame that had a problem.
    pub warnings: Vec<String>,
    /// How left and right were decided.
    pub sides_from: SidesFrom,
}

type Limb = super::bodies::LimbFit;

/// What a frame whose left and right cue disagrees with a labelling adds to that labelling's
/// price, in squared typical motions per frame (see `labels`): a run of frames agreeing on the
/// sides outweighs one step of doubtful continuity.
const SIDE_CUE: f64 = 1.0;

/// Offset of the bend point from the root–end line (zero when straight).
fn bend(l: &Limb) -> Option<Vector3<f64>> {
    let s = l.split?;
    let axis = (l.end - l.root).try_normalize(1e-12)?;
    let d = s - l.root;
    (d - axis * d.dot(&axis)).try_normalize(1e-12)
}

/// Labels, lengths, sides and the skeleton of a processed sequence. `results[i]` belongs to
/// input frame i; `names[i]` names it in warnings.
pub fn assemble(
    results: &[Result<FrameResult, FrameProblem>],
    names: &[String],
    fps: f64,
) -> Assembled {
    let mut warnings = Vec::new();
    for (i, r) in results.iter().enumerate() {
        if let Err(e) = r {
            warnings.push(format!(
                "frame {i} ({}): {e}; interpolated or left out",
                frame_name(names, i)
            ));
        }
    }
    let upright = upright(results, names, &mut warnings);
    let (labelled, order, sides_from) = labels_and_sides(&upright, names, &mut warnings);
    let fraction = limb_fractions(&labelled);
    let placed = place_arms(&upright, &labelled, names, &mut warnings);
    let poses: Vec<Option<PerJoint<Point3<f64>>>> = (0..placed.len())
        .map(|i| joints(upright[i], placed[i].as_ref(), &fraction))
        .collect();
    let mut frames = interpolate(&poses);
    let bone_lengths_m = make_rigid(&mut frames);
    Assembled {
        skeleton: Skeleton3d {
            // The volume has no camera; a nominal one keeps the file format whole.
            camera: PinholeCamera::centred(1000.0, 1000, 1000),
            fps: Some(fps),
            bone_lengths_m,
            frames,
        },
        slots: order,
        warnings,
        sides_from,
    }
}

/// Frame `i`'s name in warnings.
fn frame_name(names: &[String], i: usize) -> &str {
    names.get(i).map_or("?", String::as_str)
}

/// A frame's labelled limbs (left arm, right arm, left leg, right leg; an arm `None` where the
/// curve did not show it), `None` for a frame without a labelled pose.
type Slots = Option<[Option<Limb>; 4]>;

/// Which fitted limb of a frame went to each slot (see [`Assembled::slots`]).
type SlotOrder = Option<[Option<usize>; 4]>;

/// Step 0: The clip's up: the mean trunk direction (pelvis → neck) of the frames whose curve showed
/// all five limbs (of every frame with a pose when none did). A frame whose trunk points more
/// than a right angle away from it was named upside down (a leg taken for the head when an arm
/// lies against the trunk): it is left out like a frame without a pose.
fn upright<'a>(
    results: &'a [Result<FrameResult, FrameProblem>],
    names: &[String],
    warnings: &mut Vec<String>,
) -> Vec<Option<&'a FrameResult>> {
    let trunk = |f: &FrameResult| (f.fit.torso.b - f.fit.pelvis).try_normalize(1e-9);
    let mean_up = |five: bool| -> Option<Vector3<f64>> {
        results
            .iter()
            .flatten()
            .filter(|f| !five || f.curve.arms_unseen() == 0)
            .filter_map(trunk)
            .sum::<Vector3<f64>>()
            .try_normalize(1e-9)
    };
    let clip_up = mean_up(true).or_else(|| mean_up(false));
    results
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let f = r.as_ref().ok()?;
            if let (Some(up), Some(t)) = (clip_up, trunk(f))
                && up.dot(&t) < 0.0
            {
                warnings.push(format!(
                    "frame {i} ({}): the trunk named points against the clip's up (upside down); interpolated or left out",
                    frame_name(names, i)
                ));
                return None;
            }
            Some(f)
        })
        .collect()
}

/// Step 1: Labels and sides: left = up × front, where front is the way knees bend (or, if no knee
/// ever bends, the opposite of the way elbows bend), and the arms take the side of the leg
/// below them. Each frame's cues price its labellings; the labels are then chosen over the
/// whole clip (see `labels`), the cues with the continuity of the limbs, and frames whose
/// limbs do not follow from the frames around them are left out. Returns each frame's labelled
/// limbs, which fitted limb went to each slot, and how the sides were decided.
fn labels_and_sides(
    results: &[Option<&FrameResult>],
    names: &[String],
    warnings: &mut Vec<String>,
) -> (Vec<Slots>, Vec<SlotOrder>, SidesFrom) {
    let bends = |pair: [usize; 2], sign: f64| {
        move |f: &FrameResult| -> Vec<Vector3<f64>> {
            pair.iter()
                .filter_map(|&k| f.fit.limbs[k].as_ref().and_then(bend).map(|b| b * sign))
                .collect()
        }
    };
    let knees = bends([2, 3], 1.0);
    let elbows = bends([0, 1], -1.0);
    let sides_from = if results.iter().flatten().any(|f| !knees(f).is_empty()) {
        SidesFrom::Knees
    } else if results.iter().flatten().any(|f| !elbows(f).is_empty()) {
        SidesFrom::Elbows
    } else {
        SidesFrom::Arbitrary
    };
    let cue = |i: usize, labelling: &[usize; 4]| -> f64 {
        let Some(f) = results[i] else { return 0.0 };
        let l = labelling.map(|k| f.fit.limbs[k]);
        let mut cost = 0.0;
        let fronts = match sides_from {
            SidesFrom::Knees => knees(f),
            SidesFrom::Elbows => elbows(f),
            SidesFrom::Arbitrary => Vec::new(),
        };
        let front = fronts.iter().sum::<Vector3<f64>>().try_normalize(1e-12);
        let up = f.fit.torso.b - f.fit.torso.a;
        if let (Some(front), Some(l2), Some(l3)) = (front, l[2], l[3])
            && (l2.root - l3.root).dot(&up.cross(&front)) < 0.0
        {
            cost += SIDE_CUE;
        }
        if let [Some(a0), Some(a1), Some(l2), Some(l3)] = l
            && (a0.root - a1.root).dot(&(l2.root - l3.root)) < 0.0
        {
            cost += SIDE_CUE;
        }
        cost
    };
    let labels = super::labels::label(results, &cue);
    for &i in &labels.left_out {
        warnings.push(format!(
            "frame {i} ({}): its parts do not follow from the frames around it under any labelling (misnamed); interpolated or left out",
            frame_name(names, i)
        ));
    }
    let order = labels.order;
    let labelled = (0..results.len())
        .map(|i| {
            let (Some(f), Some(o)) = (results[i], order[i]) else {
                return None;
            };
            Some(o.map(|k| k.and_then(|k| f.fit.limbs[k])))
        })
        .collect();
    (labelled, order, sides_from)
}

/// Step 2: Static lengths from articulated frames: per slot, the upper segment's share of the limb
/// (the subject model's where no frame bent the limb), to place the elbow or knee of a
/// straight limb.
fn limb_fractions(labelled: &[Slots]) -> [f64; 4] {
    let mut sums = [[0.0f64; 2]; 4];
    let mut counts = [0usize; 4];
    for limbs in labelled.iter().flatten() {
        for (k, l) in limbs.iter().enumerate() {
            if let Some(l) = l
                && let Some(s) = l.split
            {
                sums[k][0] += (s - l.root).norm();
                sums[k][1] += (l.end - s).norm();
                counts[k] += 1;
            }
        }
    }
    let model = SubjectModel::default();
    let default_fraction = |k: usize| {
        let (u, l) = if k < 2 {
            (
                model.length_to(Joint::LeftElbow),
                model.length_to(Joint::LeftWrist),
            )
        } else {
            (
                model.length_to(Joint::LeftKnee),
                model.length_to(Joint::LeftAnkle),
            )
        };
        u / (u + l)
    };
    std::array::from_fn(|k| {
        if counts[k] > 0 {
            sums[k][0] / (sums[k][0] + sums[k][1]).max(1e-12)
        } else {
            default_fraction(k)
        }
    })
}

/// Step 3: Arms the curve did not show (in `seen`, the labelled limbs of `results`), placed from
/// the frames that saw them (see `place_unseen`), each with a warning.
fn place_arms(
    results: &[Option<&FrameResult>],
    seen: &[Slots],
    names: &[String],
    warnings: &mut Vec<String>,
) -> Vec<Slots> {
    let trunk_frames: Vec<Option<TrunkFrame>> = results
        .iter()
        .zip(seen)
        .map(|(f, l)| TrunkFrame::new((*f)?, l.as_ref()?))
        .collect();
    let mut placed = seen.to_vec();
    for slot in 0..2 {
        for i in 0..seen.len() {
            let (Some(Some(limbs)), Some(trunk)) = (placed.get(i), &trunk_frames[i]) else {
                continue;
            };
            if limbs[slot].is_some() {
                continue;
            }
            let (limb, how) = place_unseen(slot, i, seen, &trunk_frames, trunk, limbs);
            let side = if slot == 0 { "left" } else { "right" };
            warnings.push(format!(
                "frame {i} ({}): the {side} arm lies against the trunk (the skeleton curve has no branch for it); {how}",
                frame_name(names, i)
            ));
            if let Some(Some(l)) = placed.get_mut(i) {
                l[slot] = Some(limb);
            }
        }
    }
    placed
}

/// Step 4: A frame's 16 joints from its fit and its four placed limbs (`fraction`: each limb's
/// upper share, for a straight one). The chest joint (sternum) sits on the trunk axis at the
/// subject's proportion of the way from the neck to the pelvis; the chest branch node itself
/// lies at the shoulders.
fn joints(
    f: Option<&FrameResult>,
    limbs: Option<&[Option<Limb>; 4]>,
    fraction: &[f64; 4],
) -> Option<PerJoint<Point3<f64>>> {
    let (f, limbs) = (f?, limbs?);
    let limbs: [Limb; 4] = [limbs[0]?, limbs[1]?, limbs[2]?, limbs[3]?];
    let model = SubjectModel::default();
    let chest_fraction = {
        let neck_chest = model.length_to(Joint::Neck);
        let chest_pelvis = model.length_to(Joint::Chest);
        neck_chest / (neck_chest + chest_pelvis)
    };
    let mid = |k: usize| {
        let l = &limbs[k];
        l.split
            .unwrap_or_else(|| l.root + (l.end - l.root) * fraction[k])
    };
    use Joint::*;
    Some(PerJoint::from_fn(|j| match j {
        HeadTop => f.fit.head_top,
        Neck => f.fit.torso.b,
        Chest => f.fit.torso.b + (f.fit.pelvis - f.fit.torso.b) * chest_fraction,
        Pelvis => f.fit.pelvis,
        LeftShoulder => limbs[0].root,
        LeftElbow => mid(0),
        LeftWrist => limbs[0].end,
        RightShoulder => limbs[1].root,
        RightElbow => mid(1),
        RightWrist => limbs[1].end,
        LeftHip => limbs[2].root,
        LeftKnee => mid(2),
        LeftAnkle => limbs[2].end,
        RightHip => limbs[3].root,
        RightKnee => mid(3),
        RightAnkle => limbs[3].end,
    }))
}

/// The frames from the first posed to the last: a frame without a pose interpolated between
/// its posed neighbours (flagged `interpolated`).
fn interpolate(poses: &[Option<PerJoint<Point3<f64>>>]) -> Vec<Frame3d> {
    let good: Vec<usize> = (0..poses.len()).filter(|&i| poses[i].is_some()).collect();
    let mut frames = Vec::new();
    let (Some(&first), Some(&last)) = (good.first(), good.last()) else {
        return frames;
    };
    let mut before = first;
    for i in first..=last {
        if let Some(p) = &poses[i] {
            before = i;
            frames.push(Frame3d {
                index: FrameIndex(i),
                points: *p,
                flags: Vec::new(),
            });
            continue;
        }
        // Invariant: a good frame follows (i < last and `last` is good).
        let after = (i + 1..=last).find(|&k| poses[k].is_some()).unwrap_or(last);
        let (Some(a), Some(b)) = (&poses[before], &poses[after]) else {
            continue;
        };
        let t = (i - before) as f64 / (after - before) as f64;
        frames.push(Frame3d {
            index: FrameIndex(i),
            points: PerJoint::from_fn(|j| a[j] + (b[j] - a[j]) * t),
            flags: vec!["interpolated".to_owned()],
        });
    }
    frames
}

/// Static lengths (§4's second pass): each bone's median length over the frames; every frame
/// is rebuilt outwards from the pelvis keeping its bone directions, so that the skeleton is
/// rigid (and its BVH reproduces it exactly). Returns the lengths by bone key.
fn make_rigid(frames: &mut [Frame3d]) -> BTreeMap<String, f64> {
    let lengths: Vec<f64> = Bone::ALL
        .iter()
        .map(|b| {
            let mut v: Vec<f64> = frames
                .iter()
                .map(|f| (f.points[b.child] - f.points[b.parent]).norm())
                .filter(|d| *d > 1e-9)
                .collect();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(0.01)
        })
        .collect();
    for f in frames.iter_mut() {
        let old = f.points;
        for (b, len) in Bone::ALL.iter().zip(&lengths) {
            let dir = (old[b.child] - old[b.parent])
                .try_normalize(1e-12)
                .unwrap_or(Vector3::y());
            f.points[b.child] = f.points[b.parent] + dir * *len;
        }
    }
    Bone::ALL
        .iter()
        .zip(&lengths)
        .map(|(b, l)| (b.key(), l.max(1e-6)))
        .collect()
}

/// A frame's trunk axes: origin at the pelvis, `up` towards the neck, `across` along the hips
/// (leg slot 2 to 3, made square to `up`), `out` completing them.
#[derive(Debug, Clone, Copy)]
struct TrunkFrame {
    origin: Point3<f64>,
    axes: [Vector3<f64>; 3],
    /// Neck height above the pelvis, metres.
    height: f64,
}

impl TrunkFrame {
    fn new(f: &FrameResult, limbs: &[Option<Limb>; 4]) -> Option<TrunkFrame> {
        let up_vec = f.fit.torso.b - f.fit.pelvis;
        let up = up_vec.try_normalize(1e-9)?;
        let hips = limbs[2]?.root - limbs[3]?.root;
        let across = (hips - up * hips.dot(&up)).try_normalize(1e-9)?;
        Some(TrunkFrame {
            origin: f.fit.pelvis,
            axes: [up, across, up.cross(&across)],
            height: up_vec.norm(),
        })
    }
    fn local(&self, p: &Point3<f64>) -> Vector3<f64> {
        let d = p - self.origin;
        Vector3::new(
            d.dot(&self.axes[0]),
            d.dot(&self.axes[1]),
            d.dot(&self.axes[2]),
        )
    }
    fn world(&self, v: &Vector3<f64>) -> Point3<f64> {
        self.origin + self.axes[0] * v.x + self.axes[1] * v.y + self.axes[2] * v.z
    }
    fn limb_to_local(&self, l: &Limb) -> [Option<Vector3<f64>>; 3] {
        [
            Some(self.local(&l.root)),
            l.split.map(|s| self.local(&s)),
            Some(self.local(&l.end)),
        ]
    }
}

/// An arm (slot 0 or 1) frame `i` does not show, and how it was placed: its pose in the trunk's
/// axes carried from the nearest frames before and after that saw it (linearly between them, or
/// from the one there is); with none, hanging down the trunk's side opposite the other arm, as
/// long as the other arm (arms lie against the trunk when they hang).
fn place_unseen(
    slot: usize,
    i: usize,
    seen: &[Option<[Option<Limb>; 4]>],
    trunks: &[Option<TrunkFrame>],
    trunk: &TrunkFrame,
    limbs: &[Option<Limb>; 4],
) -> (Limb, String) {
    let seen_at =
        |k: usize| -> Option<(Limb, TrunkFrame)> { Some((seen[k].as_ref()?[slot]?, trunks[k]?)) };
    let before = (0..i).rev().find_map(|k| seen_at(k).map(|x| (k, x)));
    let after = (i + 1..seen.len()).find_map(|k| seen_at(k).map(|x| (k, x)));
    let local = |(l, t): &(Limb, TrunkFrame)| t.limb_to_local(l);
    let radii = |l: &Limb| l.radii;
    let build = |v: [Option<Vector3<f64>>; 3], r: [f64; 2]| -> Option<Limb> {
        Some(Limb {
            root: trunk.world(&v[0]?),
            split: v[1].map(|s| trunk.world(&s)),
            end: trunk.world(&v[2]?),
            radii: r,
        })
    };
    let from_frames = match (&before, &after) {
        (Some((kb, b)), Some((ka, a))) => {
            let t = (i - kb) as f64 / (ka - kb) as f64;
            let (lb, la) = (local(b), local(a));
            let mix: [Option<Vector3<f64>>; 3] = std::array::from_fn(|j| match (lb[j], la[j]) {
                (Some(x), Some(y)) => Some(x + (y - x) * t),
                (x, y) => x.or(y),
            });
            build(mix, radii(&b.0)).map(|l| (l, format!("placed between frames {kb} and {ka}")))
        }
        (Some((k, x)), None) | (None, Some((k, x))) => {
            build(local(x), radii(&x.0)).map(|l| (l, format!("placed as on frame {k}")))
        }
        (None, None) => None,
    };
    from_frames.unwrap_or_else(|| {
        // Hanging: the shoulder mirrors the other one across the trunk's axis (or sits a fifth
        // of the trunk's height to the side), the arm as long as the other, straight down.
        let other = limbs[1 - slot];
        let side = if slot == 0 { 1.0 } else { -1.0 };
        let shoulder = other.map_or_else(
            || Vector3::new(trunk.height * 0.9, side * trunk.height * 0.2, 0.0),
            |o| {
                let v = trunk.local(&o.root);
                Vector3::new(v.x, -v.y, v.z)
            },
        );
        let length = other.map_or(trunk.height * 1.2, |o| (o.end - o.root).norm());
        let root = trunk.world(&shoulder);
        let limb = Limb {
            root,
            split: None,
            end: root - trunk.axes[0] * length,
            radii: other.map_or([0.04, 0.035], |o| o.radii),
        };
        (
            limb,
            "no frame shows it: hung down the trunk's side".to_owned(),
        )
    })
}
