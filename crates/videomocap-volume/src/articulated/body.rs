//! The subject's body read from the clip: first from the skeleton curve's joints on the frames
//! whose curve showed all five limbs (median lengths; the shoulders and hips where they sit in
//! the chest's and pelvis's frames), the radii from a typical body scaled to that height; then
//! the lengths, widths and radii fitted to the points of a few of those frames, spread over the
//! clip, and the median of each kept.

use super::model::{Pose, RADII, SubjectBody};
use super::solve;
use super::{ArticulatedParams, FitPoints, frame_data};
use nalgebra::{Point3, Vector3};
use videomocap_core::skeleton::{Joint, PerJoint, SubjectModel, standing_pose};

/// The capsules' radii of a typical body 1.75 m tall (measured on the proportions of the
/// project's default subject: trunk, girdles, head, limbs), scaled to the subject's height.
const TYPICAL_RADII_M: [f64; RADII] = [0.13, 0.12, 0.06, 0.09, 0.1, 0.05, 0.04, 0.075, 0.055];
/// The height [`TYPICAL_RADII_M`] belong to.
const TYPICAL_HEIGHT_M: f64 = 1.75;

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

/// The first reading: from the curve's joints on the clean frames (`clean[i]`: frame i's curve
/// showed all five limbs; every posed frame when none did).
fn from_curve(curve: &[Option<PerJoint<Point3<f64>>>], clean: &[bool]) -> Option<SubjectBody> {
    let mut frames: Vec<&PerJoint<Point3<f64>>> = curve
        .iter()
        .enumerate()
        .filter(|(i, _)| clean.get(*i).copied().unwrap_or(false))
        .filter_map(|(_, p)| p.as_ref())
        .collect();
    if frames.is_empty() {
        frames = curve.iter().flatten().collect();
    }
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
    from_curve(&[Some(joints)], &[true])
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

/// The curve's reading checked against the typical body of the clip's height: a length more
/// than [`PLAUSIBLE`] times off the typical one (the curve misnamed a limb on most frames) is
/// the typical one.
fn plausible(curve: SubjectBody, typical: &SubjectBody) -> SubjectBody {
    let fix = |v: f64, t: f64| {
        if v.is_finite() && v < PLAUSIBLE * t && v > t / PLAUSIBLE {
            v
        } else {
            t
        }
    };
    let mut b = curve;
    for k in 0..3 {
        b.spine_m[k] = fix(b.spine_m[k], typical.spine_m[k]);
    }
    for k in 0..4 {
        b.limb_m[k] = fix(b.limb_m[k], typical.limb_m[k]);
    }
    b.shoulder.x = fix(b.shoulder.x, typical.shoulder.x);
    b.hip.x = fix(b.hip.x, typical.hip.x);
    b.radius_m = typical.radius_m;
    b
}

/// How far (a factor) a length the curve read may be from the typical body's.
const PLAUSIBLE: f64 = 1.4;

/// The subject's body: the curve's reading refined on the points of up to
/// `params.body_frames` clean frames spread over the clip (each fitted pose first, then pose
/// and body together; the median of each quantity kept).
pub(super) fn read_body(
    points: &[FitPoints],
    curve: &[Option<PerJoint<Point3<f64>>>],
    clean: &[bool],
    params: &ArticulatedParams,
) -> Option<SubjectBody> {
    let typical = clip_height(points).and_then(typical);
    let start = match (from_curve(curve, clean), &typical) {
        (Some(c), Some(t)) => plausible(c, t),
        (c, t) => c.or_else(|| t.clone())?,
    };
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
    for j in 0..RADII {
        body.radius_m[j] = med(&|b| b.radius_m[j], start.radius_m[j]);
    }
    // Where the chest joint splits the trunk is not seen on its surface: the trunk's length is
    // the points', its split the typical body's.
    if let Some(t) = &typical {
        let trunk = body.spine_m[0] + body.spine_m[1];
        let share = t.spine_m[0] / (t.spine_m[0] + t.spine_m[1]).max(1e-9);
        body.spine_m = [share * trunk, (1.0 - share) * trunk, body.spine_m[2]];
    }
    Some(body)
}
