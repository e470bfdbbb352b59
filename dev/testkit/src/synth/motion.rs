//! Motions that drive synthetic clips: real motion capture (BVH, any rig in the mapping table)
//! or procedural motions built from the subject's bone lengths. Both come out as the 16 joints in
//! a world frame: metres, Y up, the subject facing +Z at the first frame (so its left is +X).

use nalgebra::{Point3, Rotation3, Unit, Vector3};
use std::f64::consts::PI;
use std::path::Path;
use videomocap_core::bvh::{Bvh, BvhError, map_to_model};
use videomocap_core::skeleton::{Joint, PerJoint, SubjectModel, standing_pose};

/// A posed body per frame in the world frame (metres, Y up).
#[derive(Debug, Clone)]
pub struct Motion {
    /// Joint positions per output frame.
    pub frames: Vec<PerJoint<Point3<f64>>>,
    /// Output frames per second.
    pub fps: f64,
    /// Where the motion came from (file name or procedural kind), for the record.
    pub origin: String,
}

/// The procedural motions (for tests that need no files).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProceduralMotion {
    /// Walking forward at 1.2 m/s, 1 stride per second.
    Walk,
    /// The same walk on a treadmill: the feet go back with the belt and the body stays put (a
    /// gait lab's set-up; it keeps the person's size in the image while seen at an angle).
    Treadmill,
    /// Standing and waving the right hand above the head.
    Wave,
    /// Jumping jacks at one per second.
    JumpingJacks,
    /// Sitting down on an (unseen) chair and standing up again, one cycle per 4 s.
    SitDown,
    /// Bending forward from the hips to touch the shins and back, one cycle per 3 s.
    Bend,
    /// Marching on the spot: knees up to the waist, arms swinging a little away from the body,
    /// one step per half second (the paper's first motion).
    March,
}

impl ProceduralMotion {
    /// Parses `walk`, `treadmill`, `wave`, `jumping-jacks`, `sit-down`, `bend` or `march`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "walk" => Some(Self::Walk),
            "treadmill" => Some(Self::Treadmill),
            "wave" => Some(Self::Wave),
            "jumping-jacks" | "jumping_jacks" => Some(Self::JumpingJacks),
            "sit-down" | "sit_down" | "sit" => Some(Self::SitDown),
            "bend" => Some(Self::Bend),
            "march" => Some(Self::March),
            _ => None,
        }
    }

    /// The name accepted by [`ProceduralMotion::from_name`].
    pub fn name(self) -> &'static str {
        match self {
            Self::Walk => "walk",
            Self::Treadmill => "treadmill",
            Self::Wave => "wave",
            Self::JumpingJacks => "jumping-jacks",
            Self::SitDown => "sit-down",
            Self::Bend => "bend",
            Self::March => "march",
        }
    }
}

/// Limb angles of a simple kinematic body, radians.
#[derive(Debug, Clone, Copy, Default)]
struct LimbAngles {
    /// Rotation away from the body's middle in the frontal plane (0 = hanging down).
    abduction: f64,
    /// Rotation forward in the sagittal plane (0 = hanging down).
    flexion: f64,
    /// Bend of the elbow or knee (0 = straight).
    bend: f64,
}

/// Places the 16 joints of a body standing at `pelvis` (Y up, facing +Z, left = +X).
fn pose(
    subject: &SubjectModel,
    pelvis: Point3<f64>,
    arms: [LimbAngles; 2],
    legs: [LimbAngles; 2],
) -> PerJoint<Point3<f64>> {
    standing_pose(
        |b| subject.bone_length(b),
        subject.shoulder_width_m,
        pelvis,
        |sign| {
            let side = usize::from(sign < 0.0);
            let (upper, lower) = limb_directions(arms[side], sign, 1.0);
            // Knees bend backwards, elbows forwards.
            let (thigh, shank) = limb_directions(legs[side], sign, -1.0);
            [upper, lower, thigh, shank]
        },
    )
}

/// Directions of the upper and lower segments of a limb hanging from its root; the lower one
/// bends forwards (`bend_sign` 1, an elbow) or backwards (−1, a knee).
fn limb_directions(a: LimbAngles, side_sign: f64, bend_sign: f64) -> (Vector3<f64>, Vector3<f64>) {
    let down = -Vector3::y();
    // Abduction turns about the forward axis, towards the body's own side.
    let abduct = Rotation3::from_axis_angle(&Vector3::z_axis(), side_sign * a.abduction);
    // Flexion turns about the left axis, bringing "down" towards forward (+Z).
    let flex = Rotation3::from_axis_angle(&Unit::new_normalize(-Vector3::x()), a.flexion);
    let turn = flex * abduct;
    let upper = turn * down;
    // The bend turns the lower segment about the limb's hinge: the body's right-to-left axis
    // carried along by the same turns, so the elbow or knee bends in the limb's own plane
    // however the limb is raised (a thigh raised to the front keeps its knee a hinge).
    let axis = Unit::new_normalize(turn * -Vector3::x());
    let lower = Rotation3::from_axis_angle(&axis, bend_sign * a.bend) * upper;
    (upper, lower)
}

/// Turns everything above the pelvis forward about the pelvis by `pitch` radians (bending at the
/// hips: the head moves towards +Z).
fn pitch_upper_body(mut p: PerJoint<Point3<f64>>, pitch: f64) -> PerJoint<Point3<f64>> {
    use Joint::*;
    let r = Rotation3::from_axis_angle(&Vector3::x_axis(), pitch);
    let pelvis = p[Pelvis];
    for j in [
        Chest,
        Neck,
        HeadTop,
        LeftShoulder,
        LeftElbow,
        LeftWrist,
        RightShoulder,
        RightElbow,
        RightWrist,
    ] {
        p[j] = pelvis + r * (p[j] - pelvis);
    }
    p
}

/// Moves a pose so its lower ankle is `ankle_height` above the floor (y = 0) and the ankles'
/// mean is at x = z = 0 (the feet stay put while the body moves above them).
fn on_ground(p: PerJoint<Point3<f64>>, ankle_height: f64) -> PerJoint<Point3<f64>> {
    let (l, r) = (p[Joint::LeftAnkle], p[Joint::RightAnkle]);
    let shift = Vector3::new(
        -(l.x + r.x) / 2.0,
        ankle_height - l.y.min(r.y),
        -(l.z + r.z) / 2.0,
    );
    p.map(|_, q| q + shift)
}

/// Builds a procedural motion of `frames` frames at `fps`.
pub fn procedural(
    kind: ProceduralMotion,
    subject: &SubjectModel,
    frames: usize,
    fps: f64,
) -> Motion {
    let leg_len = subject.length_to(Joint::LeftKnee) + subject.length_to(Joint::LeftAnkle);
    let ankle_height = 0.039 * subject.height_m;
    let body = Body {
        subject,
        leg_len,
        ankle_height,
        stand: leg_len + ankle_height,
    };
    let out = (0..frames)
        .map(|i| {
            let t = i as f64 / fps;
            let w = 2.0 * PI * t; // one cycle per second
            match kind {
                ProceduralMotion::Walk => walk(&body, w, t, 1.2),
                ProceduralMotion::Treadmill => walk(&body, w, t, 0.0),
                ProceduralMotion::Wave => wave(&body, w),
                ProceduralMotion::SitDown => sit_down(&body, w),
                ProceduralMotion::Bend => bend(&body, w),
                ProceduralMotion::March => march(&body, w),
                ProceduralMotion::JumpingJacks => jumping_jacks(&body, w),
            }
        })
        .collect();
    Motion {
        frames: out,
        fps,
        origin: kind.name().to_owned(),
    }
}

/// The body a procedural motion poses: the subject, its leg's length, the ankle's height above
/// the floor, and the pelvis's height standing.
struct Body<'a> {
    subject: &'a SubjectModel,
    leg_len: f64,
    ankle_height: f64,
    stand: f64,
}

/// A walk at `speed` m/s along +Z (0: on a treadmill), at phase `w` and time `t`.
fn walk(body: &Body<'_>, w: f64, t: f64, speed: f64) -> PerJoint<Point3<f64>> {
    let (subject, stand) = (body.subject, body.stand);
    let hip = 0.42 * w.sin();
    let legs = [
        LimbAngles {
            flexion: hip,
            bend: 0.1 + 0.55 * (w + 0.9 * PI).sin().max(0.0),
            ..Default::default()
        },
        LimbAngles {
            flexion: -hip,
            bend: 0.1 + 0.55 * (w - 0.1 * PI).sin().max(0.0),
            ..Default::default()
        },
    ];
    let arms = [
        LimbAngles {
            abduction: 0.12,
            flexion: -0.35 * w.sin(),
            bend: 0.3,
        },
        LimbAngles {
            abduction: 0.12,
            flexion: 0.35 * w.sin(),
            bend: 0.3,
        },
    ];
    let pelvis = Point3::new(0.0, stand - 0.03 + 0.02 * (2.0 * w).cos(), speed * t);
    pose(subject, pelvis, arms, legs)
}

/// The right arm waving overhead.
fn wave(body: &Body<'_>, w: f64) -> PerJoint<Point3<f64>> {
    let (subject, stand) = (body.subject, body.stand);
    let arms = [
        LimbAngles {
            abduction: 0.15,
            flexion: 0.1,
            bend: 0.2,
        },
        LimbAngles {
            abduction: 2.3,
            flexion: 0.2,
            bend: 0.5 + 0.45 * (1.5 * w).sin(),
        },
    ];
    let legs = [LimbAngles {
        abduction: 0.06,
        ..Default::default()
    }; 2];
    let pelvis = Point3::new(0.03 * (0.5 * w).sin(), stand - 0.01, 0.0);
    pose(subject, pelvis, arms, legs)
}

/// Sitting down and standing up again, once per 4 s.
fn sit_down(body: &Body<'_>, w: f64) -> PerJoint<Point3<f64>> {
    let (subject, ankle_height) = (body.subject, body.ankle_height);
    // 0 standing … 1 seated, smooth, one cycle per 4 s
    let s = 0.5 - 0.5 * (w / 4.0).cos();
    let legs = [LimbAngles {
        abduction: 0.08,
        flexion: 1.45 * s,
        bend: 1.5 * s,
    }; 2];
    let arms = [LimbAngles {
        abduction: 0.15,
        flexion: 0.6 * s,
        bend: 0.4 + 0.6 * s,
    }; 2];
    let p = pose(subject, Point3::origin(), arms, legs);
    let p = pitch_upper_body(p, 0.35 * (PI * s).sin() + 0.1 * s);
    on_ground(p, ankle_height)
}

/// Bending forwards and up again, once per 3 s.
fn bend(body: &Body<'_>, w: f64) -> PerJoint<Point3<f64>> {
    let (subject, ankle_height) = (body.subject, body.ankle_height);
    let pitch = 1.25 * (0.5 - 0.5 * (w / 3.0).cos());
    let legs = [LimbAngles {
        abduction: 0.06,
        flexion: -0.1 * pitch,
        bend: 0.15 * pitch,
    }; 2];
    let arms = [LimbAngles {
        abduction: 0.1,
        flexion: pitch,
        bend: 0.2,
    }; 2];
    let p = pose(subject, Point3::origin(), arms, legs);
    on_ground(pitch_upper_body(p, pitch), ankle_height)
}

/// Marching on the spot, knees high.
fn march(body: &Body<'_>, w: f64) -> PerJoint<Point3<f64>> {
    let (subject, stand) = (body.subject, body.stand);
    let lift = |phase: f64| (phase.sin().max(0.0)).powf(0.8);
    let (a, b) = (lift(w), lift(w + PI));
    let legs = [
        LimbAngles {
            abduction: 0.05,
            flexion: 1.3 * a,
            bend: 0.1 + 1.6 * a,
        },
        LimbAngles {
            abduction: 0.05,
            flexion: 1.3 * b,
            bend: 0.1 + 1.6 * b,
        },
    ];
    let arms = [
        LimbAngles {
            abduction: 0.35,
            flexion: 0.6 * (w + PI).sin(),
            bend: 0.5 + 0.4 * b,
        },
        LimbAngles {
            abduction: 0.35,
            flexion: 0.6 * w.sin(),
            bend: 0.5 + 0.4 * a,
        },
    ];
    let pelvis = Point3::new(0.0, stand - 0.01, 0.0);
    pose(subject, pelvis, arms, legs)
}

/// Jumping jacks.
fn jumping_jacks(body: &Body<'_>, w: f64) -> PerJoint<Point3<f64>> {
    let (subject, stand, leg_len) = (body.subject, body.stand, body.leg_len);
    let phase = 0.5 - 0.5 * w.cos(); // 0 closed … 1 open
    let arms = [LimbAngles {
        abduction: 0.15 + 2.55 * phase,
        flexion: 0.0,
        bend: 0.15,
    }; 2];
    let legs = [LimbAngles {
        abduction: 0.04 + 0.3 * phase,
        ..Default::default()
    }; 2];
    let hop = 0.08 * (2.0 * w).sin().max(0.0);
    let drop = leg_len * (1.0 - (0.04 + 0.3 * phase).cos());
    let pelvis = Point3::new(0.0, stand - drop + hop, 0.0);
    pose(subject, pelvis, arms, legs)
}

/// Reads a BVH, maps it onto the 16 joints, resamples it to `fps` from `start_s` seconds for
/// `frames` frames (fewer if the file ends), and turns it so that Y is up and the subject faces
/// +Z at the first frame.
pub fn from_bvh(path: &Path, start_s: f64, frames: usize, fps: f64) -> Result<Motion, BvhError> {
    let bvh = Bvh::load(path)?;
    let mapped = map_to_model(&bvh, path)?;
    let n = mapped.frames.len();
    let mut out = Vec::with_capacity(frames);
    for i in 0..frames {
        let t = (start_s + i as f64 / fps) * mapped.fps;
        if t > (n - 1) as f64 {
            break;
        }
        let f0 = t.floor() as usize;
        let f1 = (f0 + 1).min(n - 1);
        let a = t - f0 as f64;
        out.push(PerJoint::from_fn(|j| {
            mapped.frames[f0][j] + (mapped.frames[f1][j] - mapped.frames[f0][j]) * a
        }));
    }
    if out.is_empty() {
        return Err(BvhError::NoFrames {
            path: path.to_owned(),
        });
    }
    let name = path
        .file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned();
    Ok(normalise_orientation(Motion {
        frames: out,
        fps,
        origin: name,
    }))
}

/// Rotates a motion so that the trunk's mean direction is +Y, the subject faces +Z at the first
/// frame, and the lowest ankle over the clip is at 3.9% of the stature above Y = 0 (Winter's
/// ankle height) — roughly standing on the floor.
pub fn normalise_orientation(mut motion: Motion) -> Motion {
    let Some(first) = motion.frames.first().cloned() else {
        return motion;
    };
    let trunk: Vector3<f64> = motion
        .frames
        .iter()
        .map(|p| p[Joint::Neck] - p[Joint::Pelvis])
        .sum();
    let up = trunk.try_normalize(1e-9).unwrap_or_else(Vector3::y);
    let left = (first[Joint::LeftHip] - first[Joint::RightHip])
        + (first[Joint::LeftShoulder] - first[Joint::RightShoulder]);
    let left = (left - up * up.dot(&left))
        .try_normalize(1e-9)
        .unwrap_or_else(|| {
            // Degenerate: any horizontal direction.
            up.cross(&Vector3::z())
                .try_normalize(1e-9)
                .unwrap_or_else(Vector3::x)
        });
    let forward = left.cross(&up);
    // Rows map world axes: new X = left, new Y = up, new Z = forward.
    let r = nalgebra::Matrix3::from_rows(&[left.transpose(), up.transpose(), forward.transpose()]);
    let origin = first[Joint::Pelvis];
    for frame in &mut motion.frames {
        for p in frame.0.iter_mut() {
            *p = Point3::from(r * (*p - origin));
        }
    }
    let lowest = motion
        .frames
        .iter()
        .flat_map(|f| [f[Joint::LeftAnkle].y, f[Joint::RightAnkle].y])
        .fold(f64::INFINITY, f64::min);
    let stature = stature_of(&motion);
    let lift = 0.039 * stature - lowest;
    for frame in &mut motion.frames {
        for p in frame.0.iter_mut() {
            p.y += lift;
        }
    }
    motion
}

/// Rough stature of the body in a motion: leg, trunk and head lengths of the first frame,
/// over their share of stature in the proportions table (0.961).
pub fn stature_of(motion: &Motion) -> f64 {
    let Some(p) = motion.frames.first() else {
        return 0.0;
    };
    let d = |a: Joint, b: Joint| (p[a] - p[b]).norm();
    (d(Joint::LeftAnkle, Joint::LeftKnee)
        + d(Joint::LeftKnee, Joint::LeftHip)
        + d(Joint::Pelvis, Joint::Chest)
        + d(Joint::Chest, Joint::Neck)
        + d(Joint::Neck, Joint::HeadTop))
        / 0.961
}

#[cfg(test)]
mod tests {
    use super::*;
    use videomocap_core::skeleton::Bone;

    #[test]
    fn procedural_bodies_keep_their_bone_lengths() {
        let s = SubjectModel::default();
        for kind in [
            ProceduralMotion::Walk,
            ProceduralMotion::Wave,
            ProceduralMotion::JumpingJacks,
        ] {
            let m = procedural(kind, &s, 40, 30.0);
            for p in &m.frames {
                for b in Bone::ALL {
                    let d = (p[b.child] - p[b.parent]).norm();
                    assert!((d - s.bone_length(b)).abs() < 1e-9, "{kind:?} {}", b.key());
                }
            }
        }
    }

    #[test]
    fn the_subjects_left_is_plus_x_and_knees_bend_backwards() {
        let s = SubjectModel::default();
        let m = procedural(ProceduralMotion::Walk, &s, 30, 30.0);
        for p in &m.frames {
            assert!(p[Joint::LeftHip].x > p[Joint::RightHip].x);
            for (hip, knee, ankle) in [
                (Joint::LeftHip, Joint::LeftKnee, Joint::LeftAnkle),
                (Joint::RightHip, Joint::RightKnee, Joint::RightAnkle),
            ] {
                // The knee is ahead of the hip–ankle line (it bends with the shank going back).
                let mid = nalgebra::center(&p[hip], &p[ankle]);
                assert!(p[knee].z >= mid.z - 1e-9);
            }
        }
    }

    #[test]
    fn a_seated_knee_bends_in_the_legs_own_plane() {
        // Seated at 2 s: thighs raised 1.45 rad to the front, knees bent 1.5 rad. The shank
        // hangs down from the knee and bends about the hinge, not sideways.
        let s = SubjectModel::default();
        let m = procedural(ProceduralMotion::SitDown, &s, 61, 30.0);
        let p = &m.frames[60];
        for (hip, knee, ankle) in [
            (Joint::LeftHip, Joint::LeftKnee, Joint::LeftAnkle),
            (Joint::RightHip, Joint::RightKnee, Joint::RightAnkle),
        ] {
            let thigh = (p[knee] - p[hip]).normalize();
            let shank = p[ankle] - p[knee];
            let bend = shank - thigh * thigh.dot(&shank);
            assert!(bend.y < -0.8 * bend.norm(), "{hip}: {bend:?}");
            assert!(bend.x.abs() < 0.1 * bend.norm(), "{hip}: {bend:?}");
        }
    }

    #[test]
    fn motion_capture_is_turned_upright_and_facing_forward() {
        let path = crate::repo_root().join("tests/data/cmu_02_01_walk.bvh");
        let m = from_bvh(&path, 0.0, 60, 30.0).unwrap();
        assert_eq!(m.frames.len(), 60);
        let p = &m.frames[0];
        assert!(p[Joint::HeadTop].y > p[Joint::Neck].y && p[Joint::Neck].y > p[Joint::Pelvis].y);
        assert!(p[Joint::LeftHip].x > p[Joint::RightHip].x);
        let stature = stature_of(&m);
        assert!((1.4..2.1).contains(&stature), "stature {stature}");
    }
}
