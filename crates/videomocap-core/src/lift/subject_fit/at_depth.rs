//! The whole-clip reading of the subject's parts (see the parent module's text): each group's
//! upper envelope at its depth in a first lift, one metric scale, each group held within
//! [`LIMB_RANGE`] of the table, the chest placed, the known lengths kept, read as named steps
//! by [`fit_at_depth`].

use super::{
    ChestDrop, ENVELOPE_QUANTILE, FrameView, LENGTH_MARGIN, LIMB_RANGE, LengthOrigin,
    MIN_LIMB_FRAMES, PartLength, SubjectFit, place_chest, quantile, stature_stack,
};
use crate::formats::KnownLengths;
use crate::lift::LiftError;
use crate::skeleton::{Bone, Joint, SubjectModel};

/// What a whole-clip reading measures: each bone group's (or breadth's) image length times the
/// depth of the joint it hangs from, in a first lift, in one unit common to every group (the
/// first lift's scale); the group's upper envelope over the clip is its length in that unit.
/// Each group: its name, its joint pairs, and the joint whose depth scales its image.
const GROUPS: [Group; 8] = {
    use Joint::*;
    [
        ("trunk", &[(Pelvis, Neck)], Some(Pelvis)),
        ("head", &[(Neck, HeadTop)], None),
        (
            "upper arm",
            &[(LeftShoulder, LeftElbow), (RightShoulder, RightElbow)],
            None,
        ),
        (
            "forearm",
            &[(LeftElbow, LeftWrist), (RightElbow, RightWrist)],
            None,
        ),
        ("thigh", &[(LeftHip, LeftKnee), (RightHip, RightKnee)], None),
        (
            "shank",
            &[(LeftKnee, LeftAnkle), (RightKnee, RightAnkle)],
            None,
        ),
        (
            "shoulders apart",
            &[(LeftShoulder, RightShoulder)],
            Some(Chest),
        ),
        ("hips apart", &[(LeftHip, RightHip)], Some(Pelvis)),
    ]
};

/// A part of the body read from the clip: its name, its joint pairs, and the joint whose depth
/// scales its image (`None`: each pair's first joint).
type Group = (&'static str, &'static [(Joint, Joint)], Option<Joint>);

/// The upper envelope (the [`ENVELOPE_QUANTILE`]) over the frames of a group's image length times
/// its depth (see [`GROUPS`]); `None` without depths or with too few frames.
fn measure_at_depth(
    views: &[FrameView<'_>],
    pairs: &[(Joint, Joint)],
    depth_of: Option<Joint>,
) -> Option<f64> {
    let lengths: Vec<f64> = views
        .iter()
        .flat_map(|v| {
            pairs.iter().filter_map(move |&(a, b)| {
                // The depth of the bone's parent end (the trunk's depth for the trunk and
                // the widths): on the dev split from exact 2D, 110.7 mm against 114.6 with
                // the body's depth for every part (perspective: a near limb looks longer).
                let z = v.depth?[depth_of.unwrap_or(a)].z;
                (v.all_trusted(&[a, b]) && z.is_finite() && z > 0.0)
                    .then(|| (v.points[b] - v.points[a]).norm() * z)
            })
        })
        .collect();
    if lengths.len() < MIN_LIMB_FRAMES * pairs.len() {
        return None;
    }
    quantile(lengths, ENVELOPE_QUANTILE)
}

/// The bones each group of [`GROUPS`] sets (both sides; none for the shoulder width, which is
/// not a bone). The trunk's two bones and the hips' two halves add up to their group's length,
/// the sides of a limb are each its length.
fn group_bones(g: usize) -> Vec<Bone> {
    use Joint::*;
    let both = |a: [Joint; 2], b: [Joint; 2]| vec![Bone::new(a[0], b[0]), Bone::new(a[1], b[1])];
    match g {
        0 => vec![Bone::new(Pelvis, Chest), Bone::new(Chest, Neck)],
        1 => vec![Bone::new(Neck, HeadTop)],
        2 => both([LeftShoulder, RightShoulder], [LeftElbow, RightElbow]),
        3 => both([LeftElbow, RightElbow], [LeftWrist, RightWrist]),
        4 => both([LeftHip, RightHip], [LeftKnee, RightKnee]),
        5 => both([LeftKnee, RightKnee], [LeftAnkle, RightAnkle]),
        7 => vec![Bone::new(Pelvis, LeftHip), Bone::new(Pelvis, RightHip)],
        _ => Vec::new(),
    }
}

/// The index of the shoulder width in [`GROUPS`].
const SHOULDER_GROUP: usize = 6;

/// A group's length in `subject` (the mean of its two sides).
fn group_length(g: usize, subject: &SubjectModel) -> f64 {
    if g == SHOULDER_GROUP {
        return subject.shoulder_width_m;
    }
    let bones = group_bones(g);
    let sum: f64 = bones.iter().map(|b| subject.bone_length(*b)).sum();
    match g {
        0 | 7 => sum,
        _ => sum / bones.len() as f64,
    }
}

/// A group's length as the user gave it, when every bone of it (or, for a pair of sides, either
/// side: their mean) is known.
fn known_group(g: usize, known: &KnownLengths) -> Option<f64> {
    if g == SHOULDER_GROUP {
        return known.shoulder_width_m;
    }
    let bones = group_bones(g);
    let given: Vec<f64> = bones
        .iter()
        .filter_map(|b| known.bones.get(b).copied())
        .collect();
    match g {
        0 | 7 => (given.len() == bones.len()).then(|| given.iter().sum()),
        _ => (!given.is_empty()).then(|| given.iter().sum::<f64>() / given.len() as f64),
    }
}

/// The image may show a known bone this much longer than its given length (perspective, the
/// envelope's slack, the tracks' noise) before the length is called contradicted.
const CONTRADICTION_FACTOR: f64 = 1.25;

/// The whole-clip reading (see [`GROUPS`]): every group's envelope length in the first lift's
/// unit; the metric scale from the lengths the user knows (the median of known ÷ measured over
/// the measured groups they give), else from the stature stack at the stated height; each
/// group not given held within [`LIMB_RANGE`] of the table; the chest's drop as [`fit`] reads
/// it; and the known lengths exactly. `Ok(None)` when a group of the stature stack could not
/// be measured (and nothing known sets the scale).
pub(super) fn fit_at_depth(
    subject: &SubjectModel,
    views: &[FrameView<'_>],
    known: &KnownLengths,
) -> Result<Option<(SubjectModel, SubjectFit)>, LiftError> {
    let measured: Vec<Option<f64>> = GROUPS
        .iter()
        .map(|(_, pairs, depth)| measure_at_depth(views, pairs, *depth))
        .collect();
    let given: Vec<Option<f64>> = (0..GROUPS.len()).map(|g| known_group(g, known)).collect();
    let Some(scale) = metric_scale(subject, &measured, &given) else {
        return Ok(None);
    };
    check_known(&measured, &given, scale.per_unit)?;
    let factor = group_factors(subject, &measured, &given, scale.per_unit);
    let (out, chest_drop, restack) = scaled_subject(subject, views, known, &factor, &scale);
    let limbs = GROUPS
        .iter()
        .zip(&factor)
        .zip(&measured)
        .filter(|(_, m)| m.is_some())
        .map(|(((name, _, _), f), _)| (*name, *f))
        .collect();
    let parts = part_lengths(subject, &out, &measured, &given, &factor, scale.per_unit);
    Ok(Some((
        out,
        SubjectFit {
            chest_drop,
            limbs,
            stature_scale: restack,
            parts,
            scale_from_given: scale.from_known,
        },
    )))
}

/// Metres per unit of the first lift, and whether the user's lengths set it.
struct Scale {
    per_unit: f64,
    from_known: bool,
}

/// The metric scale: the median of known ÷ measured over the measured groups the user gives,
/// else the stature stack at the stated height over its measured length; `None` when neither
/// can be had.
fn metric_scale(
    subject: &SubjectModel,
    measured: &[Option<f64>],
    given: &[Option<f64>],
) -> Option<Scale> {
    let mut ratios: Vec<f64> = measured
        .iter()
        .zip(given)
        .filter_map(|(m, k)| Some(k.as_ref()? / m.as_ref()?))
        .collect();
    ratios.sort_by(f64::total_cmp);
    if let Some(&per_unit) = ratios.get(ratios.len() / 2) {
        return Some(Scale {
            per_unit,
            from_known: true,
        });
    }
    let stack_units = [5, 4, 0, 1]
        .iter()
        .map(|&g| measured[g])
        .sum::<Option<f64>>()?;
    Some(Scale {
        per_unit: stature_stack(subject) / stack_units,
        from_known: false,
    })
}

/// Refuses a known length the image shows far longer than it can be.
fn check_known(
    measured: &[Option<f64>],
    given: &[Option<f64>],
    scale: f64,
) -> Result<(), LiftError> {
    for (g, (m, k)) in measured.iter().zip(given).enumerate() {
        if let (Some(m), Some(k)) = (m, k)
            && scale * m > CONTRADICTION_FACTOR * k
        {
            return Err(LiftError::LengthContradicted {
                name: GROUPS[g].0,
                given_m: *k,
                seen_m: scale * m,
            });
        }
    }
    Ok(())
}

/// Each group's length over the table's: the user's where given, else the reading held within
/// [`LIMB_RANGE`] (below it the clip never showed the part square, a side view's shoulders:
/// the table's, not the range's end).
fn group_factors(
    subject: &SubjectModel,
    measured: &[Option<f64>],
    given: &[Option<f64>],
    scale: f64,
) -> Vec<f64> {
    (0..GROUPS.len())
        .map(|g| {
            let t = group_length(g, subject);
            match (given[g], measured[g]) {
                (Some(k), _) => k / t,
                (None, Some(m)) if scale * m / t < LIMB_RANGE.0 => 1.0,
                (None, Some(m)) => (scale * m / t).min(LIMB_RANGE.1),
                (None, None) => 1.0,
            }
        })
        .collect()
}

/// The subject with each group scaled by its factor, the chest placed, the stature stack held
/// at the height (unless the user's lengths set the scale: the returned restack factor), the
/// read bones' doubt, and the known lengths exactly.
fn scaled_subject(
    subject: &SubjectModel,
    views: &[FrameView<'_>],
    known: &KnownLengths,
    factor: &[f64],
    scale: &Scale,
) -> (SubjectModel, Option<ChestDrop>, f64) {
    use Joint::*;
    let mut out = subject.clone();
    for (g, f) in factor.iter().enumerate() {
        for b in group_bones(g) {
            out.bone_length_m[b.index()] = subject.bone_length(b) * f;
        }
    }
    out.shoulder_width_m = subject.shoulder_width_m * factor[SHOULDER_GROUP];
    let chest_drop = place_chest(&mut out, subject, views, factor[SHOULDER_GROUP]);
    let restack = if scale.from_known {
        1.0
    } else {
        stature_stack(subject) / stature_stack(&out)
    };
    // The bones hung by a depth root (the step after eq. 9) and read, not given, are as
    // uncertain as the reading: the lift leans them towards lying square to their rays.
    for (k, b) in Bone::ALL.iter().enumerate() {
        if ![Pelvis, Chest].contains(&b.parent) && !known.bones.contains_key(b) {
            out.length_doubt[k] = LENGTH_MARGIN;
        }
    }
    out.bone_length_m.iter_mut().for_each(|l| *l *= restack);
    out.shoulder_width_m *= restack;
    for (b, &l) in &known.bones {
        out.bone_length_m[b.index()] = l;
    }
    if let Some(w) = known.shoulder_width_m {
        out.shoulder_width_m = w;
    }
    (out, chest_drop, restack)
}

/// Each group's final length and where it came from, for the user.
fn part_lengths(
    subject: &SubjectModel,
    out: &SubjectModel,
    measured: &[Option<f64>],
    given: &[Option<f64>],
    factor: &[f64],
    scale: f64,
) -> Vec<PartLength> {
    (0..GROUPS.len())
        .map(|g| PartLength {
            name: GROUPS[g].0,
            metres: group_length(g, out),
            origin: match (given[g], measured[g]) {
                (Some(_), _) => LengthOrigin::Given,
                (None, None) => LengthOrigin::Table,
                (None, Some(m)) if scale * m / group_length(g, subject) < LIMB_RANGE.0 => {
                    LengthOrigin::Unseen
                }
                (None, Some(_)) if factor[g] >= LIMB_RANGE.1 - 1e-12 => LengthOrigin::Held,
                (None, Some(_)) => LengthOrigin::Read,
            },
        })
        .collect()
}
