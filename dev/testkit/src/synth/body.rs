//! Bodies that are not the lift's own model, for the benchmark suite: a subject's segment lengths
//! drawn around the proportions table ([`BodyShape`]), a shoulder girdle that rides with the arms
//! (so the key triangle flexes, as a real one does), and the joints placed as a particular
//! annotator would place them ([`JointDefinitions`]).

use super::Motion;
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use videomocap_core::skeleton::{BONE_COUNT, Bone, Joint, PerJoint, Proportions};

/// Height of the ankle joint over the sole, as a fraction of stature (Winter's table; also what
/// `synth::normalise_orientation` puts the lowest ankle at).
const ANKLE_HEIGHT: f64 = 0.039;

/// The bones whose lengths, stacked, make the standing height over the ankle.
const STANDING_CHAIN: [(Joint, Joint); 5] = [
    (Joint::LeftKnee, Joint::LeftAnkle),
    (Joint::LeftHip, Joint::LeftKnee),
    (Joint::Pelvis, Joint::Chest),
    (Joint::Chest, Joint::Neck),
    (Joint::Neck, Joint::HeadTop),
];

/// One subject's body: every bone's length, metres.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyShape {
    /// Length of each bone of [`Bone::ALL`], in that order, metres.
    pub bone_length_m: [f64; BONE_COUNT],
    /// The height the segments were drawn for, metres (the ankle's height over the sole is
    /// 3.9 % of it).
    pub drawn_height_m: f64,
}

impl BodyShape {
    /// A body drawn from `seed`: a height uniform in 1.50–1.95 m, then every segment, the
    /// shoulders' and the hips' half-widths included, uniform within ±`spread` (0.12: ±12 %) of
    /// the proportions table at that height; left and right alike.
    pub fn drawn(seed: u64, spread: f64) -> BodyShape {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed ^ 0x00B0_D1E5);
        let height = rng.random_range(1.50..=1.95);
        let table = Proportions::default();
        let mut factor = [1.0; BONE_COUNT];
        for (k, bone) in Bone::ALL.iter().enumerate() {
            // The right side takes its left twin's factor, drawn first (Bone::ALL lists left
            // before right).
            let twin = Bone::new(bone.parent.mirrored(), bone.child.mirrored());
            factor[k] = match Bone::ALL.iter().position(|b| *b == twin) {
                Some(t) if t < k => factor[t],
                _ => 1.0 + rng.random_range(-spread..=spread),
            };
        }
        let bone_length_m = std::array::from_fn(|k| {
            let b = Bone::ALL[k];
            table.fraction_between(b.parent, b.child) * height * factor[k]
        });
        BodyShape {
            bone_length_m,
            drawn_height_m: height,
        }
    }

    /// The length of `bone`, metres.
    pub fn length(&self, bone: Bone) -> f64 {
        self.bone_length_m[bone.index()]
    }

    /// The standing height, sole to vertex, metres: the ankle's height over the sole, the shank,
    /// the thigh, the spine, the neck and the head stacked. It is the height a person would
    /// state; the benchmarks give it to the lift.
    pub fn stature_m(&self) -> f64 {
        ANKLE_HEIGHT * self.drawn_height_m
            + STANDING_CHAIN
                .iter()
                .map(|&(a, b)| self.length(Bone::new(a, b)))
                .sum::<f64>()
    }
}

/// The motion carried onto another body: each bone keeps its direction on every frame and takes
/// the body's length times the motion's own flex there (its length on that frame over its mean
/// over the clip), centre outwards; the path of the pelvis scales with the legs, and the lowest
/// ankle goes back to its height over the floor.
pub fn retarget(motion: &Motion, body: &BodyShape) -> Motion {
    let n = motion.frames.len().max(1) as f64;
    let mean: [f64; BONE_COUNT] = std::array::from_fn(|k| {
        let b = Bone::ALL[k];
        motion
            .frames
            .iter()
            .map(|p| (p[b.child] - p[b.parent]).norm())
            .sum::<f64>()
            / n
    });
    let leg = |len: &dyn Fn(Bone) -> f64| {
        len(Bone::new(Joint::LeftHip, Joint::LeftKnee))
            + len(Bone::new(Joint::LeftKnee, Joint::LeftAnkle))
    };
    let leg_ratio = leg(&|b| body.length(b)) / leg(&|b| mean[b.index()]).max(1e-9);
    let origin = motion
        .frames
        .first()
        .map_or(Point3::origin(), |p| p[Joint::Pelvis]);
    let mut frames: Vec<PerJoint<Point3<f64>>> = motion
        .frames
        .iter()
        .map(|old| {
            let mut new = *old;
            new[Joint::Pelvis] = origin + (old[Joint::Pelvis] - origin) * leg_ratio;
            for (k, b) in Bone::ALL.iter().enumerate() {
                let v = old[b.child] - old[b.parent];
                let scale = if mean[k] > 1e-9 {
                    body.bone_length_m[k] / mean[k]
                } else {
                    1.0
                };
                new[b.child] = new[b.parent] + v * scale;
            }
            new
        })
        .collect();
    let lowest = frames
        .iter()
        .flat_map(|f| [f[Joint::LeftAnkle].y, f[Joint::RightAnkle].y])
        .fold(f64::INFINITY, f64::min);
    let lift = ANKLE_HEIGHT * body.drawn_height_m - lowest;
    if lift.is_finite() {
        for f in &mut frames {
            for p in f.0.iter_mut() {
                p.y += lift;
            }
        }
    }
    Motion {
        frames,
        fps: motion.fps,
        origin: motion.origin.clone(),
    }
}

/// The trunk's frame on one pose (Y-up world): up (pelvis to neck), left (hip to hip, square to
/// up) and forward (`left × up`).
fn trunk_axes(p: &PerJoint<Point3<f64>>) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let up = (p[Joint::Neck] - p[Joint::Pelvis])
        .try_normalize(1e-9)
        .unwrap_or_else(Vector3::y);
    let across = p[Joint::LeftHip] - p[Joint::RightHip];
    let left = (across - up * up.dot(&across))
        .try_normalize(1e-9)
        .unwrap_or_else(Vector3::x);
    (up, left, left.cross(&up))
}

/// The shoulder girdle riding with the arms (scapulohumeral rhythm): a shoulder rises along the
/// trunk by up to 2 % of stature as its upper arm goes from 30° to overhead, and moves forward by
/// up to 1.2 % as the arm reaches forward; the arm below moves with it. The chest stays, so the
/// key triangle (both shoulders and the chest) flexes as a real one does, by a few centimetres.
pub fn shoulder_girdle(motion: &mut Motion, stature_m: f64) {
    for p in &mut motion.frames {
        let (up, _, forward) = trunk_axes(p);
        for (shoulder, elbow, wrist) in [
            (Joint::LeftShoulder, Joint::LeftElbow, Joint::LeftWrist),
            (Joint::RightShoulder, Joint::RightElbow, Joint::RightWrist),
        ] {
            let Some(arm) = (p[elbow] - p[shoulder]).try_normalize(1e-9) else {
                continue;
            };
            // 0 hanging, 1 overhead.
            let elevation = (-arm.dot(&up)).clamp(-1.0, 1.0).acos() / std::f64::consts::PI;
            let rise = 0.02 * stature_m * ((elevation - 1.0 / 6.0) / (5.0 / 6.0)).max(0.0);
            let reach = 0.012 * stature_m * arm.dot(&forward).max(0.0);
            let shift = up * rise + forward * reach;
            for j in [shoulder, elbow, wrist] {
                p[j] += shift;
            }
        }
    }
}

/// Where one annotator puts the joints that have no single obvious point on the body (the neck,
/// the chest, the head's top, the hips and so the pelvis): a fixed offset per joint in the
/// trunk's frame, metres (left, up, forward), the hips mirrored.
#[derive(Debug, Clone, PartialEq)]
pub struct JointDefinitions {
    /// Offset of each joint: (left, up, forward) in the trunk's frame, metres.
    pub offsets: PerJoint<Vector3<f64>>,
}

impl JointDefinitions {
    /// The model's own definitions (no offsets).
    pub fn exact() -> JointDefinitions {
        JointDefinitions {
            offsets: PerJoint::from_fn(|_| Vector3::zeros()),
        }
    }

    /// One annotator's definitions, drawn from `seed`: the neck up to 3 cm up or down and 2 cm
    /// forward or back, the chest (on the skin of the sternum or on the spine's line) up to 4 cm
    /// up or down and 0–5 cm forward, the head's top 2 cm either way, the hips 2 cm in or out,
    /// 3 cm up or down and 2 cm forward or back (both alike), the pelvis at their midpoint.
    pub fn drawn(seed: u64) -> JointDefinitions {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed ^ 0xA770_7A7E);
        let mut u = |r: f64| rng.random_range(-r..=r);
        let mut offsets = PerJoint::from_fn(|_| Vector3::zeros());
        offsets[Joint::Neck] = Vector3::new(0.0, u(0.03), u(0.02));
        let chest_forward = 0.025 + u(0.025);
        offsets[Joint::Chest] = Vector3::new(0.0, u(0.04), chest_forward);
        offsets[Joint::HeadTop] = Vector3::new(0.0, u(0.02), u(0.02));
        let (out, up, fwd) = (u(0.02), u(0.03), u(0.02));
        offsets[Joint::LeftHip] = Vector3::new(out, up, fwd);
        offsets[Joint::RightHip] = Vector3::new(-out, up, fwd);
        offsets[Joint::Pelvis] = Vector3::new(0.0, up, fwd);
        JointDefinitions { offsets }
    }

    /// The joints of a pose (Y-up world) as this annotator defines them.
    pub fn apply(&self, pose: &PerJoint<Point3<f64>>) -> PerJoint<Point3<f64>> {
        let (up, left, forward) = trunk_axes(pose);
        pose.map(|j, p| {
            let o = self.offsets[j];
            p + left * o.x + up * o.y + forward * o.z
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::{ProceduralMotion, procedural};
    use videomocap_core::skeleton::SubjectModel;

    #[test]
    fn drawn_bodies_vary_within_their_bounds_and_keep_left_and_right_alike() {
        let table = Proportions::default();
        let mut statures = Vec::new();
        for seed in 0..50 {
            let body = BodyShape::drawn(seed, 0.12);
            for (k, b) in Bone::ALL.iter().enumerate() {
                let f = body.bone_length_m[k]
                    / (table.fraction_between(b.parent, b.child) * body.drawn_height_m);
                assert!((0.88 - 1e-9..=1.12 + 1e-9).contains(&f), "{b:?}: {f}");
                let twin = Bone::new(b.parent.mirrored(), b.child.mirrored());
                assert_eq!(body.bone_length_m[k], body.length(twin));
            }
            statures.push(body.stature_m());
        }
        let (lo, hi) = statures
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), s| (l.min(*s), h.max(*s)));
        assert!(lo > 1.35 && hi < 2.1 && hi - lo > 0.25, "{lo}–{hi}");
    }

    #[test]
    fn a_retargeted_motion_has_the_bodys_lengths() {
        let motion = procedural(ProceduralMotion::Wave, &SubjectModel::default(), 30, 30.0);
        let body = BodyShape::drawn(3, 0.12);
        let moved = retarget(&motion, &body);
        for p in &moved.frames {
            for b in Bone::ALL {
                let len = (p[b.child] - p[b.parent]).norm();
                assert!((len - body.length(b)).abs() < 1e-9, "{b:?}");
            }
        }
    }

    #[test]
    fn raised_arms_lift_the_shoulders_so_the_key_triangle_flexes() {
        // Jumping jacks: the arms go from hanging to overhead and back.
        let mut motion = procedural(
            ProceduralMotion::JumpingJacks,
            &SubjectModel::default(),
            60,
            30.0,
        );
        let side = |p: &PerJoint<Point3<f64>>| (p[Joint::RightShoulder] - p[Joint::Chest]).norm();
        let before: Vec<f64> = motion.frames.iter().map(side).collect();
        shoulder_girdle(&mut motion, 1.7);
        let after: Vec<f64> = motion.frames.iter().map(side).collect();
        let spread = |v: &[f64]| {
            v.iter().cloned().fold(0.0, f64::max) - v.iter().cloned().fold(9.0, f64::min)
        };
        assert!(spread(&before) < 1e-6);
        assert!(spread(&after) > 0.01, "{}", spread(&after));
    }
}
