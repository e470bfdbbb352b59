//! The second pass across frames (paper §4): consistent limb labels by the least sum of squared
//! distances between neighbouring frames, static segment lengths from articulated frames (used
//! to place the elbow or knee of a straight limb), and the 16-joint skeleton3d. Beyond the
//! paper, which assigns no left and right: the side of each labelled limb is voted from the
//! direction knees bend (forwards), or elbows (backwards) when no knee ever bends.
//!
//! Frames that gave no pose are interpolated between their good neighbours (flagged
//! `interpolated`) or, before the first and after the last good frame, left out.

use super::{FrameProblem, FrameResult};
use crate::camera::PinholeCamera;
use crate::formats::{Frame3d, Skeleton3d};
use crate::skeleton::{Bone, Joint, PerJoint, SubjectModel};
use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;

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
    /// right leg); `None` for frames without a pose.
    pub slots: Vec<Option<[usize; 4]>>,
    /// One sentence per frame that had a problem.
    pub warnings: Vec<String>,
    /// How left and right were decided.
    pub sides_from: SidesFrom,
}

type Limb = super::bodies::LimbFit;

fn limb_distance(a: &Limb, b: &Limb) -> f64 {
    let mut d = (a.root - b.root).norm_squared() + (a.end - b.end).norm_squared();
    if let (Some(x), Some(y)) = (a.split, b.split) {
        d += (x - y).norm_squared();
    }
    d
}

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
            let name = names.get(i).map_or("?", String::as_str);
            warnings.push(format!("frame {i} ({name}): {e}; interpolated or left out"));
        }
    }
    // 1. Consistent labels: limb k of each frame keeps the label of the nearest limb (least sum
    //    of squared distances) of the previous frame with a pose.
    let mut order: Vec<Option<[usize; 4]>> = vec![None; results.len()];
    let mut previous: Option<[Limb; 4]> = None;
    for (i, r) in results.iter().enumerate() {
        let Ok(f) = r else { continue };
        let l = &f.fit.limbs;
        let mut o = [0, 1, 2, 3];
        if let Some(p) = &previous {
            if limb_distance(&l[1], &p[0]) + limb_distance(&l[0], &p[1])
                < limb_distance(&l[0], &p[0]) + limb_distance(&l[1], &p[1])
            {
                o.swap(0, 1);
            }
            if limb_distance(&l[3], &p[2]) + limb_distance(&l[2], &p[3])
                < limb_distance(&l[2], &p[2]) + limb_distance(&l[3], &p[3])
            {
                o.swap(2, 3);
            }
        }
        previous = Some(o.map(|k| l[k]));
        order[i] = Some(o);
    }
    let labelled = |i: usize| -> Option<[Limb; 4]> {
        let (Ok(f), Some(o)) = (&results[i], order[i]) else {
            return None;
        };
        Some(o.map(|k| f.fit.limbs[k]))
    };

    // 2. Static lengths from articulated frames.
    let mut sums = [[0.0f64; 2]; 4];
    let mut counts = [0usize; 4];
    for i in 0..results.len() {
        let Some(limbs) = labelled(i) else { continue };
        for (k, l) in limbs.iter().enumerate() {
            if let Some(s) = l.split {
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
    let fraction: [f64; 4] = std::array::from_fn(|k| {
        if counts[k] > 0 {
            sums[k][0] / (sums[k][0] + sums[k][1]).max(1e-12)
        } else {
            default_fraction(k)
        }
    });
    // The chest joint (sternum) sits on the trunk axis at the subject's proportion of the way
    // from the neck to the pelvis; the chest branch node itself lies at the shoulders.
    let chest_fraction = {
        let neck_chest = model.length_to(Joint::Neck);
        let chest_pelvis = model.length_to(Joint::Chest);
        neck_chest / (neck_chest + chest_pelvis)
    };

    // 3. Sides, voted frame by frame: left = up × front, where front is the way knees bend
    //    (or, if no knee ever bends, the opposite of the way elbows bend). The arms then take
    //    the side of the leg below them.
    let mut votes = [0i64; 2]; // arms, legs: > 0 means label 0 is the left one
    let mut sides_from = SidesFrom::Arbitrary;
    let sign = |x: f64| if x > 0.0 { 1 } else { -1 };
    for pass in [SidesFrom::Knees, SidesFrom::Elbows] {
        for (i, r) in results.iter().enumerate() {
            let (Some(l), Ok(f)) = (labelled(i), r) else {
                continue;
            };
            let up = f.fit.torso.b - f.fit.torso.a;
            let fronts: Vec<Vector3<f64>> = match pass {
                SidesFrom::Knees => [2, 3].iter().filter_map(|&k| bend(&l[k])).collect(),
                _ => [0, 1]
                    .iter()
                    .filter_map(|&k| bend(&l[k]).map(|b| -b))
                    .collect(),
            };
            let Some(front) = fronts
                .iter()
                .sum::<Vector3<f64>>()
                .try_normalize(1e-12)
                .filter(|_| !fronts.is_empty())
            else {
                continue;
            };
            let left = up.cross(&front);
            votes[1] += sign((l[2].root - l[3].root).dot(&left));
            sides_from = pass;
        }
        if sides_from != SidesFrom::Arbitrary {
            break;
        }
    }
    for i in 0..results.len() {
        if let Some(l) = labelled(i) {
            votes[0] += sign((l[0].root - l[1].root).dot(&(l[2].root - l[3].root)));
        }
    }
    let swap_legs = votes[1] < 0;
    // Arm 0 is on leg 0's side when votes[0] > 0; it is the left arm when that leg is left.
    let swap_arms = (votes[0] < 0) != swap_legs;

    // Labels → slots (left arm, right arm, left leg, right leg), in one place.
    let to_slots = |mut x: [usize; 4]| {
        if swap_arms {
            x.swap(0, 1);
        }
        if swap_legs {
            x.swap(2, 3);
        }
        x
    };
    let slots: Vec<Option<[usize; 4]>> = order.iter().map(|o| o.map(to_slots)).collect();
    let frac = to_slots([0, 1, 2, 3]).map(|label| fraction[label]);

    // 4. The 16 joints.
    let pose = |i: usize| -> Option<PerJoint<Point3<f64>>> {
        let (Ok(f), Some(s)) = (&results[i], slots[i]) else {
            return None;
        };
        let limbs = s.map(|k| f.fit.limbs[k]);
        let mid = |k: usize| {
            let l = &limbs[k];
            l.split
                .unwrap_or_else(|| l.root + (l.end - l.root) * frac[k])
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
    };
    let poses: Vec<Option<PerJoint<Point3<f64>>>> = (0..results.len()).map(pose).collect();
    let good: Vec<usize> = (0..poses.len()).filter(|&i| poses[i].is_some()).collect();
    let mut frames = Vec::new();
    if let (Some(&first), Some(&last)) = (good.first(), good.last()) {
        let mut before = first;
        for i in first..=last {
            if let Some(p) = &poses[i] {
                before = i;
                frames.push(Frame3d {
                    index: i,
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
                index: i,
                points: PerJoint::from_fn(|j| a[j] + (b[j] - a[j]) * t),
                flags: vec!["interpolated".to_owned()],
            });
        }
    }
    // Static lengths (§4's second pass): each bone's median length over the frames; every
    // frame is rebuilt outwards from the pelvis keeping its bone directions, so that the
    // skeleton is rigid (and its BVH reproduces it exactly).
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
    for f in &mut frames {
        let old = f.points;
        for (b, len) in Bone::ALL.iter().zip(&lengths) {
            let dir = (old[b.child] - old[b.parent])
                .try_normalize(1e-12)
                .unwrap_or(Vector3::y());
            f.points[b.child] = f.points[b.parent] + dir * *len;
        }
    }
    let bone_lengths_m: BTreeMap<String, f64> = Bone::ALL
        .iter()
        .zip(&lengths)
        .map(|(b, l)| (b.key(), l.max(1e-6)))
        .collect();
    Assembled {
        skeleton: Skeleton3d {
            // The volume has no camera; a nominal one keeps the file format whole.
            camera: PinholeCamera::centred(1000.0, 1000, 1000),
            fps: Some(fps),
            bone_lengths_m,
            frames,
        },
        slots,
        warnings,
        sides_from,
    }
}
