//! The articulated body the fit poses: the product's 16-joint skeleton with the subject's segment
//! lengths, the shoulders and hips at fixed places in the chest and pelvis, and a capsule (a
//! round-ended cylinder) on each segment, and on each foot one forward of its ankle, rigid with
//! its shank (a real body's feet are in its volume: without them the shank reaches for the toes
//! and the knee's bend, which tells the body's front, reverses). A [`Pose`] is the root (pelvis
//! position and frame), a ball joint at the spine's base, the neck, both shoulders and both
//! hips, and a hinge at each elbow and knee; `Pose::posed` is its forward kinematics, [`Pose::from_joints`] the inverse
//! (a pose from 16 joint positions, as the skeleton curve gives them).
//!
//! Frames are orthonormal: x to the subject's left, y up, z to the front. At rest (every local
//! rotation the identity) the spine and head point up (+y) and the limbs hang down (−y).

use nalgebra::{Matrix3, Point3, Rotation3, UnitQuaternion, Vector3};
use videomocap_core::skeleton::{Joint, PerJoint};

/// The rigid parts of the model, each moved by the degrees of freedom of its chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Part {
    Pelvis,
    Chest,
    Head,
    UpperArm(usize),
    Forearm(usize),
    Thigh(usize),
    Shank(usize),
    Foot(usize),
}

/// Radius classes: one per segment kind, left and right alike.
pub(crate) const RADII: usize = 10;

/// A capsule's far end: a joint of the skeleton, or a foot's toe (left 0, right 1; not one of
/// the 16 joints).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum End {
    Joint(Joint),
    Toe(usize),
}

/// One capsule: from joint `a` to `b` on `part`; when `cap` says so the far end is pulled
/// in by the radius (the head top is the body's surface; a wrist or ankle is the centre of the
/// limb's end, the hand beyond it).
#[derive(Debug, Clone, Copy)]
pub(crate) struct SegmentDef {
    pub a: Joint,
    pub b: End,
    pub part: Part,
    /// Index into [`SubjectBody::radius_m`].
    pub radius: usize,
    /// Whether the capsule's far end lies one radius short of joint `b`.
    pub cap: bool,
}

/// The capsules of the model.
pub(crate) const SEGMENTS: [SegmentDef; 15] = {
    use Joint::*;
    const fn s(a: Joint, b: Joint, part: Part, radius: usize, cap: bool) -> SegmentDef {
        SegmentDef {
            a,
            b: End::Joint(b),
            part,
            radius,
            cap,
        }
    }
    const fn foot(a: Joint, k: usize) -> SegmentDef {
        SegmentDef {
            a,
            b: End::Toe(k),
            part: Part::Foot(k),
            radius: 9,
            cap: false,
        }
    }
    [
        s(Pelvis, Chest, Part::Chest, 0, false),
        s(Chest, Neck, Part::Chest, 1, false),
        s(LeftShoulder, RightShoulder, Part::Chest, 2, false),
        s(LeftHip, RightHip, Part::Pelvis, 3, false),
        s(Neck, HeadTop, Part::Head, 4, true),
        s(LeftShoulder, LeftElbow, Part::UpperArm(0), 5, false),
        s(LeftElbow, LeftWrist, Part::Forearm(0), 6, false),
        s(RightShoulder, RightElbow, Part::UpperArm(1), 5, false),
        s(RightElbow, RightWrist, Part::Forearm(1), 6, false),
        s(LeftHip, LeftKnee, Part::Thigh(0), 7, false),
        s(LeftKnee, LeftAnkle, Part::Shank(0), 8, false),
        s(RightHip, RightKnee, Part::Thigh(1), 7, false),
        s(RightKnee, RightAnkle, Part::Shank(1), 8, false),
        foot(LeftAnkle, 0),
        foot(RightAnkle, 1),
    ]
};

/// The subject's body: lengths, where the shoulders and hips sit, and the capsules' radii.
#[derive(Debug, Clone, PartialEq)]
pub struct SubjectBody {
    /// Pelvis → chest, chest → neck, neck → head top, metres.
    pub spine_m: [f64; 3],
    /// Shoulder → elbow, elbow → wrist, hip → knee, knee → ankle (left and right alike), metres.
    pub limb_m: [f64; 4],
    /// The left shoulder in the chest's frame, from the chest joint (the right one mirrored).
    pub shoulder: Vector3<f64>,
    /// The left hip in the pelvis's frame, from the pelvis joint (the right one mirrored).
    pub hip: Vector3<f64>,
    /// Ankle → the foot capsule's far end, metres (towards the front, `FOOT_TILT` down from
    /// square to the shank).
    pub foot_m: f64,
    /// Capsule radii: lower trunk, upper trunk, shoulder girdle, hip girdle, head, upper arm,
    /// forearm, thigh, shank, foot; metres.
    pub radius_m: [f64; RADII],
}

/// The limits of the joints (radians): elbows and knees bend one way only, from straight to
/// this far; the spine and neck tilt at most so far from their rest.
pub(crate) const HINGE_MAX: f64 = 2.6;
/// See [`HINGE_MAX`]: the spine's largest tilt from the pelvis.
pub(crate) const SPINE_MAX: f64 = 1.0;
/// See [`HINGE_MAX`]: the head's largest tilt from the chest.
pub(crate) const NECK_MAX: f64 = 1.0;
/// See [`HINGE_MAX`]: how far a thigh may point behind the hips (hyperextension), as the sine
/// of the angle from straight down.
pub(crate) const THIGH_BACK_SIN: f64 = 0.6;
/// See [`HINGE_MAX`]: how far a thigh may turn about its own axis from its rest (the swing–twist
/// split about the bone), radians; a hip turns about 40° either way. Without it a body turned
/// round bends its knees forwards by turning each thigh half a turn, and the knee's bend no
/// longer tells the body's front from its back.
pub(crate) const THIGH_TWIST_MAX: f64 = 0.7;

/// A pose of the model: global frame of the pelvis, local rotations of the chest (about the
/// pelvis), head (about the neck), upper arms and thighs, and the elbow and knee angles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Pelvis position.
    pub root: Point3<f64>,
    /// The pelvis's frame (world from pelvis).
    pub pelvis: Rotation3<f64>,
    /// Chest in the pelvis's frame.
    pub chest: Rotation3<f64>,
    /// Head in the chest's frame.
    pub head: Rotation3<f64>,
    /// Upper arms (left, right) in the chest's frame.
    pub upper_arm: [Rotation3<f64>; 2],
    /// Thighs (left, right) in the pelvis's frame.
    pub thigh: [Rotation3<f64>; 2],
    /// Elbow bends (0 straight), radians.
    pub elbow: [f64; 2],
    /// Knee bends (0 straight), radians.
    pub knee: [f64; 2],
}

/// A posed model: the joints and each part's global frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Posed {
    pub joints: PerJoint<Point3<f64>>,
    /// Global frames of the chest, upper arms and thighs.
    pub chest: Matrix3<f64>,
    pub upper_arm: [Matrix3<f64>; 2],
    pub thigh: [Matrix3<f64>; 2],
    /// The feet's far ends (left, right).
    pub toe: [Point3<f64>; 2],
}

impl Posed {
    /// Where segment `s`'s capsule axis ends (before any `cap`).
    pub(crate) fn end(&self, s: &SegmentDef) -> Point3<f64> {
        match s.b {
            End::Joint(j) => self.joints[j],
            End::Toe(k) => self.toe[k],
        }
    }
}

/// Mirrors a left-side offset to the right (x flips).
fn mirror(v: &Vector3<f64>, side: usize) -> Vector3<f64> {
    if side == 0 {
        *v
    } else {
        Vector3::new(-v.x, v.y, v.z)
    }
}

/// A forearm's direction in its upper arm's frame (bent towards the front).
pub(crate) fn forearm_dir(angle: f64) -> Vector3<f64> {
    Vector3::new(0.0, -angle.cos(), angle.sin())
}

/// A shank's direction in its thigh's frame (bent towards the back).
pub(crate) fn shank_dir(angle: f64) -> Vector3<f64> {
    Vector3::new(0.0, -angle.cos(), -angle.sin())
}

/// How far the foot points down from square to its shank (towards the front), radians: the
/// ankle sits about 8 cm above the floor and the toes' middle about 3 cm, 15–20 cm ahead
/// (not tuned).
pub(crate) const FOOT_TILT: f64 = 0.3;

/// A foot's direction in its thigh's frame, the knee bent by `angle` (rigid with the shank).
pub(crate) fn foot_dir(angle: f64) -> Vector3<f64> {
    Vector3::new(0.0, -(angle + FOOT_TILT).sin(), (angle + FOOT_TILT).cos())
}

/// Which side's joints of a limb part: shoulder, elbow, wrist, hip, knee, ankle of the left
/// (`k` = 0) or right side.
pub(crate) fn side_joints(k: usize) -> [Joint; 6] {
    use Joint::*;
    if k == 0 {
        [
            LeftShoulder,
            LeftElbow,
            LeftWrist,
            LeftHip,
            LeftKnee,
            LeftAnkle,
        ]
    } else {
        [
            RightShoulder,
            RightElbow,
            RightWrist,
            RightHip,
            RightKnee,
            RightAnkle,
        ]
    }
}

impl Pose {
    /// Forward kinematics.
    pub(crate) fn posed(&self, body: &SubjectBody) -> Posed {
        use Joint::*;
        let mut j = PerJoint([Point3::origin(); 16]);
        let rp = *self.pelvis.matrix();
        let rc = rp * self.chest.matrix();
        let rh = rc * self.head.matrix();
        let up = Vector3::y();
        j[Pelvis] = self.root;
        j[Chest] = self.root + rc * up * body.spine_m[0];
        j[Neck] = j[Chest] + rc * up * body.spine_m[1];
        j[HeadTop] = j[Neck] + rh * up * body.spine_m[2];
        let ua = [0, 1].map(|k| rc * self.upper_arm[k].matrix());
        let th = [0, 1].map(|k| rp * self.thigh[k].matrix());
        let mut toe = [Point3::origin(); 2];
        for k in 0..2 {
            let [sh, el, wr, hp, kn, an] = side_joints(k);
            j[sh] = j[Chest] + rc * mirror(&body.shoulder, k);
            j[el] = j[sh] - ua[k] * up * body.limb_m[0];
            j[wr] = j[el] + ua[k] * forearm_dir(self.elbow[k]) * body.limb_m[1];
            j[hp] = self.root + rp * mirror(&body.hip, k);
            j[kn] = j[hp] - th[k] * up * body.limb_m[2];
            j[an] = j[kn] + th[k] * shank_dir(self.knee[k]) * body.limb_m[3];
            toe[k] = j[an] + th[k] * foot_dir(self.knee[k]) * body.foot_m;
        }
        Posed {
            joints: j,
            chest: rc,
            upper_arm: ua,
            thigh: th,
            toe,
        }
    }

    /// The pose whose bones point as the joints `p` say (lengths are the body's; the elbows'
    /// and knees' bends from the angles `p` shows, within the limits).
    pub fn from_joints(p: &PerJoint<Point3<f64>>) -> Pose {
        use Joint::*;
        let left = (p[LeftHip] - p[RightHip]) + (p[LeftShoulder] - p[RightShoulder]) * 0.5;
        let pelvis = frame(p[Chest] - p[Pelvis], p[LeftHip] - p[RightHip]);
        let chest_g = frame(p[Neck] - p[Pelvis], left);
        let head_g = frame(p[HeadTop] - p[Neck], chest_g * Vector3::x());
        let chest = pelvis.inverse() * chest_g;
        let head = chest_g.inverse() * head_g;
        let limb = |parent: &Rotation3<f64>, a: Joint, b: Joint, c: Joint, bend_front: bool| {
            let d1 = (p[b] - p[a])
                .try_normalize(1e-9)
                .unwrap_or(-(parent * Vector3::y()));
            let d2 = (p[c] - p[b]).try_normalize(1e-9).unwrap_or(d1);
            let angle = d1.dot(&d2).clamp(-1.0, 1.0).acos().min(HINGE_MAX);
            // The hinge plane: the forearm bends to the upper arm's front, the shank to the
            // thigh's back; a straight limb keeps its parent's front.
            let bent = d2 - d1 * d1.dot(&d2);
            let front = if bent.norm() > 1e-3 {
                if bend_front { bent } else { -bent }
            } else {
                parent * Vector3::z()
            };
            let y = -d1;
            let x = y.cross(&front).try_normalize(1e-9).unwrap_or_else(|| {
                y.cross(&(parent * Vector3::x()))
                    .cross(&y)
                    .try_normalize(1e-9)
                    .unwrap_or(Vector3::x())
            });
            let g = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, x.cross(&y)]));
            (parent.inverse() * g, angle)
        };
        let (ua0, e0) = limb(&chest_g, LeftShoulder, LeftElbow, LeftWrist, true);
        let (ua1, e1) = limb(&chest_g, RightShoulder, RightElbow, RightWrist, true);
        let (th0, k0) = limb(&pelvis, LeftHip, LeftKnee, LeftAnkle, false);
        let (th1, k1) = limb(&pelvis, RightHip, RightKnee, RightAnkle, false);
        let mut pose = Pose {
            root: p[Pelvis],
            pelvis,
            chest,
            head,
            upper_arm: [ua0, ua1],
            thigh: [th0, th1],
            elbow: [e0, e1],
            knee: [k0, k1],
        };
        pose.limit();
        pose
    }

    /// Brings the pose within the joints' limits.
    pub(crate) fn limit(&mut self) {
        for a in self.elbow.iter_mut().chain(self.knee.iter_mut()) {
            *a = a.clamp(0.0, HINGE_MAX);
        }
        self.chest = cap_rotation(&self.chest, SPINE_MAX);
        self.head = cap_rotation(&self.head, NECK_MAX);
        for t in &mut self.thigh {
            *t = cap_twist(t, THIGH_TWIST_MAX);
            // The thigh's direction in the pelvis frame may not point far behind.
            let d = *t * -Vector3::y();
            if d.z < -THIGH_BACK_SIN {
                let flat = Vector3::new(d.x, d.y, 0.0);
                let target = flat.try_normalize(1e-9).unwrap_or(-Vector3::y())
                    * (1.0 - THIGH_BACK_SIN * THIGH_BACK_SIN).sqrt()
                    - Vector3::z() * THIGH_BACK_SIN;
                if let Some(r) = Rotation3::rotation_between(&d, &target) {
                    *t = r * *t;
                }
            }
        }
    }
}

/// `r` turned back towards the identity so that its angle is at most `max`.
fn cap_rotation(r: &Rotation3<f64>, max: f64) -> Rotation3<f64> {
    let v = r.scaled_axis();
    let a = v.norm();
    if a > max {
        Rotation3::from_scaled_axis(v * (max / a))
    } else {
        *r
    }
}

/// `r` with its turn about its own y axis (the twist of its swing–twist split) at most `max`.
fn cap_twist(r: &Rotation3<f64>, max: f64) -> Rotation3<f64> {
    let q = UnitQuaternion::from_rotation_matrix(r);
    let (w, y) = (q.w, q.j);
    let norm = (w * w + y * y).sqrt();
    if norm < 1e-9 {
        // Swung half a turn: the twist is not defined.
        return *r;
    }
    let twist = 2.0 * (y / norm).atan2(w / norm);
    // The twist's angle in (−π, π].
    let twist =
        (twist + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    if twist.abs() <= max {
        return *r;
    }
    let keep = Rotation3::from_axis_angle(&Vector3::y_axis(), twist.clamp(-max, max));
    let undo = Rotation3::from_axis_angle(&Vector3::y_axis(), -twist);
    r * undo * keep
}

/// An orthonormal frame with y along `up` and x along `left` made square to it.
pub(crate) fn frame(up: Vector3<f64>, left: Vector3<f64>) -> Rotation3<f64> {
    let y = up.try_normalize(1e-9).unwrap_or(Vector3::y());
    let x = (left - y * left.dot(&y))
        .try_normalize(1e-9)
        .or_else(|| y.cross(&Vector3::z()).try_normalize(1e-9))
        .unwrap_or(Vector3::x());
    Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, x.cross(&y)]))
}

impl Pose {
    /// Standing at the origin, facing +z, limbs hanging straight.
    pub(crate) fn default_standing() -> Pose {
        Pose {
            root: Point3::origin(),
            pelvis: Rotation3::identity(),
            chest: Rotation3::identity(),
            head: Rotation3::identity(),
            upper_arm: [Rotation3::identity(); 2],
            thigh: [Rotation3::identity(); 2],
            elbow: [0.0; 2],
            knee: [0.0; 2],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body() -> SubjectBody {
        SubjectBody {
            spine_m: [0.25, 0.25, 0.25],
            limb_m: [0.3, 0.25, 0.42, 0.4],
            shoulder: Vector3::new(0.18, 0.2, 0.0),
            hip: Vector3::new(0.1, -0.02, 0.0),
            foot_m: 0.15,
            radius_m: [0.12; RADII],
        }
    }

    #[test]
    fn a_pose_read_back_from_its_own_joints_gives_the_same_joints() {
        let b = body();
        let pose = Pose {
            root: Point3::new(0.3, 1.0, -0.2),
            pelvis: Rotation3::from_euler_angles(0.1, 0.7, -0.2),
            chest: Rotation3::from_euler_angles(0.2, 0.1, 0.05),
            head: Rotation3::from_euler_angles(-0.2, 0.3, 0.0),
            upper_arm: [
                Rotation3::from_euler_angles(0.4, 0.2, -1.0),
                Rotation3::from_euler_angles(-0.5, 0.1, 0.8),
            ],
            thigh: [
                Rotation3::from_euler_angles(-0.6, 0.0, 0.1),
                Rotation3::from_euler_angles(0.3, 0.1, -0.1),
            ],
            elbow: [0.8, 1.5],
            knee: [0.3, 1.2],
        };
        let j = pose.posed(&b).joints;
        let again = Pose::from_joints(&j).posed(&b).joints;
        for (joint, p) in j.iter() {
            let d = (p - again[joint]).norm();
            // The chest's twist is read from the hips and shoulders together: a few mm off.
            assert!(d < 0.03, "{} moved {d} m", joint.name());
        }
    }

    #[test]
    fn knees_bend_backwards_and_elbows_forwards_at_rest() {
        let b = body();
        let mut pose = Pose::from_joints(&Pose::default_standing().posed(&b).joints);
        pose.elbow = [1.0, 1.0];
        pose.knee = [1.0, 1.0];
        let j = pose.posed(&b).joints;
        assert!(j[Joint::LeftWrist].z > j[Joint::LeftElbow].z);
        assert!(j[Joint::LeftAnkle].z < j[Joint::LeftKnee].z);
        // The feet point forwards and a little down, bent with the knee.
        let toe = pose.posed(&b).toe[0];
        let standing = Pose::default_standing().posed(&b);
        assert!(standing.toe[0].z > standing.joints[Joint::LeftAnkle].z + 0.1);
        assert!(standing.toe[0].y < standing.joints[Joint::LeftAnkle].y);
        assert!(toe.z > j[Joint::LeftAnkle].z);
    }

    #[test]
    fn a_thigh_turned_about_its_own_axis_is_turned_back_within_the_limit() {
        // A swing (about an axis square to the bone) after the turn about the bone.
        let axis = nalgebra::Unit::new_normalize(Vector3::new(-0.8, 0.0, 0.3));
        let swing = Rotation3::from_axis_angle(&axis, 0.9);
        let mut pose = Pose::default_standing();
        pose.thigh[0] = swing * Rotation3::from_axis_angle(&Vector3::y_axis(), 2.5);
        pose.thigh[1] = swing * Rotation3::from_axis_angle(&Vector3::y_axis(), -0.3);
        let before = pose.thigh;
        pose.limit();
        // The bone's direction is kept; the turn about it is capped, a small one left alone.
        let along = |r: &Rotation3<f64>| r * Vector3::y();
        assert!((along(&pose.thigh[0]) - along(&before[0])).norm() < 1e-9);
        let twist = (swing.inverse() * pose.thigh[0]).angle();
        assert!((twist - THIGH_TWIST_MAX).abs() < 1e-9, "twist {twist}");
        assert!((pose.thigh[1].matrix() - before[1].matrix()).norm() < 1e-9);
    }

    #[test]
    fn limits_straighten_a_knee_bent_the_wrong_way_and_cap_the_spine() {
        let mut pose = Pose::default_standing();
        pose.knee = [-0.5, 3.5];
        pose.chest = Rotation3::from_euler_angles(2.0, 0.0, 0.0);
        pose.limit();
        assert_eq!(pose.knee, [0.0, HINGE_MAX]);
        assert!(pose.chest.angle() <= SPINE_MAX + 1e-9);
    }
}
