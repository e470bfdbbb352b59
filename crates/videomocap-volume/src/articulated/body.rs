//! The subject's body read from the clip: the project's typical body scaled to the clip's
//! height (the points' extent), then its lengths, widths and radii fitted to the points of a
//! few frames whose curve showed all five limbs, spread over the clip, the median of each kept
//! and held near the typical proportions (the skeleton curve's own lengths are not read: on a
//! real body's volume its legs end at the toes and its pose may face backwards).

use super::model::{Pose, RADII, SubjectBody};
use super::solve;
use super::{ArticulatedParams, FitPoints, frame_data};
use nalgebra::{Point3, Vector3};
use videomocap_core::skeleton::{Joint, PerJoint, SubjectModel, standing_pose};

/// The capsules' radii of a typical body 1.75 m tall (measured on the proportions of the
/// project's default subject: trunk, girdles, head, limbs; the foot's from a foot about 10 cm
/// wide and 7 cm high), scaled to the subject's height.
const TYPICAL_RADII_M: [f64; RADII] = [0.13, 0.12, 0.06, 0.09, 0.1, 0.05, 0.04, 0.075, 0.055, 0.04];
/// The height [`TYPICAL_RADII_M`] belong to.
const TYPICAL_HEIGHT_M: f64 = 1.75;
/// A typical foot's capsule (ankle → the toes' round end less its radius) as a share of the
/// height: a foot is about 15 % of the height, about 3/4 of it ahead of the ankle.
const TYPICAL_FOOT_SHARE: f64 = 0.09;

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// Picks a frame's left and right offsets (in a part's frame) from its pose and joints.
type Offsets = dyn Fn(&Pose, &PerJoint<Point3<f64>>) -> [Vector3<f64>; 2];

/// A body read from sets of joint positions (medians over the sets; the shoulders and hips
/// where they sit in the chest's and pelvis's frames), the radii the typical ones at its height.
fn of_joints(frames: &[PerJoint<Point3<f64>>]) -> Option<SubjectBody> {
    if frames.is_empty() {
        return None;
    }
    use Joint::*;
    let len = |a: Joint, b: Joint, c: Joint, d: Joint| {
        median(
            frames
                .iter()
                .flat_map(|p| [(p[a] - p[b]).norm(), (p[c] - p[d]).norm()])
                .collect(),
        )
    };
    let one = |a: Joint, b: Joint| len(a, b, a, b);
    let spine_m = [one(Pelvis, Chest)?, one(Chest, Neck)?, one(Neck, HeadTop)?];
    let limb_m = [
        len(LeftShoulder, LeftElbow, RightShoulder, RightElbow)?,
        len(LeftElbow, LeftWrist, RightElbow, RightWrist)?,
        len(LeftHip, LeftKnee, RightHip, RightKnee)?,
        len(LeftKnee, LeftAnkle, RightKnee, RightAnkle)?,
    ];
    // Offsets in the chest's and pelvis's frames (the right side mirrored onto the left).
    let local = |pick: &Offsets| {
        let v: Vec<[Vector3<f64>; 2]> = frames
            .iter()
            .map(|p| pick(&Pose::from_joints(p), p))
            .collect();
        Vector3::from_fn(|k, _| {
            median(
                v.iter()
                    .flat_map(|[l, r]| [l[k], if k == 0 { -r[k] } else { r[k] }])
                    .collect(),
            )
            .unwrap_or(0.0)
        })
    };
    let shoulder = local(&|pose, p| {
        let rc = pose.pelvis * pose.chest;
        [
            rc.inverse() * (p[LeftShoulder] - p[Chest]),
            rc.inverse() * (p[RightShoulder] - p[Chest]),
        ]
    });
    let hip = local(&|pose, p| {
        [
            pose.pelvis.inverse() * (p[LeftHip] - p[Pelvis]),
            pose.pelvis.inverse() * (p[RightHip] - p[Pelvis]),
        ]
    });
    let height = spine_m.iter().sum::<f64>() + limb_m[2] + limb_m[3];
    let scale = height / TYPICAL_HEIGHT_M;
    Some(SubjectBody {
        spine_m,
        limb_m,
        shoulder: Vector3::new(shoulder.x.abs().max(0.05), shoulder.y, shoulder.z),
        hip: Vector3::new(hip.x.abs().max(0.04), hip.y, hip.z),
        foot_m: TYPICAL_FOOT_SHARE * height,
        radius_m: TYPICAL_RADII_M.map(|r| r * scale),
    })
}

/// The project's default subject (its proportions) scaled to `height_m`, as a body.
pub(super) fn typical(height_m: f64) -> Option<SubjectBody> {
    let model = SubjectModel::default();
    let scale = height_m / model.height_m;
    let down = -Vector3::y();
    let joints = standing_pose(
        |b| model.bone_length(b) * scale,
        model.shoulder_width_m * scale,
        Point3::origin(),
        |_| [down; 4],
    );
    of_joints(&[joints])
}

/// The clip's height: the median over frames of the points' extent along +Y (the project's
/// world is Y up), metres; `None` without points.
pub(super) fn clip_height(points: &[FitPoints]) -> Option<f64> {
    median(
        points
            .iter()
            .filter(|p| p.points.len() >= 20)
            .map(|p| {
                let (lo, hi) = p.points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), q| {
                    (lo.min(q.y), hi.max(q.y))
                });
                hi - lo
            })
            .collect(),
    )
}

/// How far (a factor) a refined length or width may be from the typical body's at the
/// subject's scale: the body model has no hands and a capsule for a head, so refined freely on
/// a real body's volume the forearm swallows the hand and the head grows (a mesh take's
/// forearm read 0.35–0.43 m, its head 0.39–0.52).
const LENGTH_BOUND: f64 = 1.15;
/// See [`LENGTH_BOUND`]: the same for the capsules' radii (bodies differ more in girth).
const RADIUS_BOUND: f64 = 1.3;

/// The subject's body: the typical body at the clip's height refined on the points of up to
/// `params.body_frames` clean frames spread over the clip (each fitted pose first, then pose
/// and body together; the median of each quantity kept), then held within [`LENGTH_BOUND`]
/// and [`RADIUS_BOUND`] of the typical body's proportions at the refined body's own scale
/// (the median of its lengths' ratios to the typical ones: the clip's height is the points'
/// extent, too short for a clip that bends or sits through most of its frames).
pub(super) fn read_body(
    points: &[FitPoints],
    curve: &[Option<PerJoint<Point3<f64>>>],
    clean: &[bool],
    params: &ArticulatedParams,
) -> Option<SubjectBody> {
    let start = clip_height(points).and_then(typical)?;
    let usable: Vec<usize> = (0..points.len())
        .filter(|&i| {
            curve[i].is_some()
                && clean.get(i).copied().unwrap_or(false)
                && points[i].points.len() >= 50
        })
        .collect();
    let k = params.body_frames.min(usable.len());
    if k == 0 {
        return Some(start);
    }
    let fits: Vec<SubjectBody> = (0..k)
        .map(|s| {
            let i = usable[s * usable.len() / k];
            let data = frame_data(&points[i]);
            let posed = super::best_start(&start, &data, curve[i].as_ref(), None, true, params);
            solve::fit(&posed.fit.pose, &start, &data, 2 * params.iterations, true).body
        })
        .collect();
    let med = |f: &dyn Fn(&SubjectBody) -> f64, fallback: f64| {
        median(fits.iter().map(f).collect()).unwrap_or(fallback)
    };
    let mut body = start.clone();
    for j in 0..3 {
        body.spine_m[j] = med(&|b| b.spine_m[j], start.spine_m[j]);
    }
    for j in 0..4 {
        body.limb_m[j] = med(&|b| b.limb_m[j], start.limb_m[j]);
    }
    body.shoulder.x = med(&|b| b.shoulder.x, start.shoulder.x);
    body.hip.x = med(&|b| b.hip.x, start.hip.x);
    body.foot_m = med(&|b| b.foot_m, start.foot_m);
    for j in 0..RADII {
        body.radius_m[j] = med(&|b| b.radius_m[j], start.radius_m[j]);
    }
    Some(bounded(body, &start))
}

/// `body` held within [`LENGTH_BOUND`] and [`RADIUS_BOUND`] of `typical` scaled by the
/// median of `body`'s lengths' and widths' ratios to `typical`'s; the trunk split as in
/// `typical` (the chest joint is not seen on the trunk's surface).
fn bounded(mut body: SubjectBody, typical: &SubjectBody) -> SubjectBody {
    let t = typical;
    let mut ratios: Vec<f64> = (0..3)
        .map(|j| body.spine_m[j] / t.spine_m[j])
        .chain((0..4).map(|j| body.limb_m[j] / t.limb_m[j]))
        .collect();
    ratios.push(body.shoulder.x / t.shoulder.x);
    ratios.push(body.hip.x / t.hip.x);
    let s = median(ratios).unwrap_or(1.0);
    let hold = |v: f64, t: f64, b: f64| v.clamp(s * t / b, s * t * b);
    for j in 0..3 {
        body.spine_m[j] = hold(body.spine_m[j], t.spine_m[j], LENGTH_BOUND);
    }
    for j in 0..4 {
        body.limb_m[j] = hold(body.limb_m[j], t.limb_m[j], LENGTH_BOUND);
    }
    body.shoulder.x = hold(body.shoulder.x, t.shoulder.x, LENGTH_BOUND);
    body.hip.x = hold(body.hip.x, t.hip.x, LENGTH_BOUND);
    body.foot_m = hold(body.foot_m, t.foot_m, LENGTH_BOUND);
    for j in 0..RADII {
        body.radius_m[j] = hold(body.radius_m[j], t.radius_m[j], RADIUS_BOUND);
    }
    let trunk = body.spine_m[0] + body.spine_m[1];
    let share = t.spine_m[0] / (t.spine_m[0] + t.spine_m[1]).max(1e-9);
    body.spine_m = [share * trunk, (1.0 - share) * trunk, body.spine_m[2]];
    body
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refined_body_keeps_its_scale_and_loses_a_forearm_that_swallowed_the_hand() {
        let t = typical(1.75).expect("a typical body");
        // Every length 10 % longer (a taller subject), the forearm half as long again.
        let mut b = t.clone();
        b.spine_m = b.spine_m.map(|l| l * 1.1);
        b.limb_m = b.limb_m.map(|l| l * 1.1);
        b.shoulder.x *= 1.1;
        b.hip.x *= 1.1;
        b.limb_m[1] *= 1.5;
        b.radius_m[4] *= 2.0;
        let held = bounded(b.clone(), &t);
        assert!(
            (held.limb_m[0] - b.limb_m[0]).abs() < 1e-9,
            "the scale is kept"
        );
        let forearm = 1.1 * t.limb_m[1] * LENGTH_BOUND;
        assert!(
            (held.limb_m[1] - forearm).abs() < 1e-9,
            "{}",
            held.limb_m[1]
        );
        assert!((held.radius_m[4] - 1.1 * t.radius_m[4] * RADIUS_BOUND).abs() < 1e-9);
        let trunk = held.spine_m[0] + held.spine_m[1];
        assert!((trunk - 1.1 * (t.spine_m[0] + t.spine_m[1])).abs() < 1e-9);
    }
}
