//! The synthetic person as primitives: textured tapered capsules (round cones) for trunk and
//! limbs, an ellipsoid head with hair; ray intersection and shading for the ray caster
//! (`render`).

use super::appearance::{Appearance, Material};
use nalgebra::{Point3, Vector3};
use videomocap_core::skeleton::{Joint, PerJoint};

/// Radii of the body's primitives as fractions of stature (a slim adult in clothes).
mod radius {
    pub(super) const NECK: f64 = 0.030;
    pub(super) const SPINE_CHEST: f64 = 0.080;
    pub(super) const SPINE_PELVIS: f64 = 0.070;
    pub(super) const SHOULDER_GIRDLE: f64 = 0.045;
    pub(super) const HIP_GIRDLE: f64 = 0.060;
    pub(super) const UPPER_ARM: (f64, f64) = (0.032, 0.026);
    pub(super) const FOREARM: (f64, f64) = (0.025, 0.019);
    pub(super) const THIGH: (f64, f64) = (0.050, 0.034);
    pub(super) const SHANK: (f64, f64) = (0.033, 0.024);
    /// Head semi-axes: up, across, front-back.
    pub(super) const HEAD: (f64, f64, f64) = (0.068, 0.050, 0.058);
}

/// A tapered capsule: the union of spheres swept from `a` (radius `ra`) to `b` (radius `rb`).
#[derive(Debug, Clone, Copy)]
pub(super) struct RoundCone {
    pub(super) a: Vector3<f64>,
    pub(super) b: Vector3<f64>,
    pub(super) ra: f64,
    pub(super) rb: f64,
    /// A unit vector across the axis, for the texture's angle.
    pub(super) across: Vector3<f64>,
    pub(super) material: Material,
    /// Texture phase so that parts do not look alike.
    pub(super) seed: f64,
}

impl RoundCone {
    /// Exact signed distance (Quílez, "distance functions", round cone).
    pub(super) fn sdf(&self, p: &Vector3<f64>) -> f64 {
        let ba = self.b - self.a;
        let l2 = ba.dot(&ba);
        let rr = self.ra - self.rb;
        let a2 = l2 - rr * rr;
        let il2 = 1.0 / l2;
        let pa = p - self.a;
        let y = pa.dot(&ba);
        let z = y - l2;
        let x2 = (pa * l2 - ba * y).norm_squared();
        let y2 = y * y * l2;
        let z2 = z * z * l2;
        let k = rr.signum() * rr * rr * x2;
        if z.signum() * a2 * z2 > k {
            return (x2 + z2).sqrt() * il2 - self.rb;
        }
        if y.signum() * a2 * y2 < k {
            return (x2 + y2).sqrt() * il2 - self.ra;
        }
        ((x2 * a2 * il2).sqrt() + y * rr) * il2 - self.ra
    }

    pub(super) fn bounding_sphere(&self) -> (Vector3<f64>, f64) {
        let c = (self.a + self.b) / 2.0;
        (c, (self.b - self.a).norm() / 2.0 + self.ra.max(self.rb))
    }

    pub(super) fn normal(&self, p: &Vector3<f64>) -> Vector3<f64> {
        const H: f64 = 1e-4;
        let d = |v: Vector3<f64>| self.sdf(&(p + v));
        Vector3::new(
            d(Vector3::x() * H) - d(-Vector3::x() * H),
            d(Vector3::y() * H) - d(-Vector3::y() * H),
            d(Vector3::z() * H) - d(-Vector3::z() * H),
        )
        .try_normalize(1e-12)
        .unwrap_or_else(|| -Vector3::z())
    }
}

/// The head: an ellipsoid with semi-axes along `up`, `side` and `front`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Head {
    pub(super) centre: Vector3<f64>,
    /// Rows: unit up, side, front; scaled by 1/semi-axis so that the surface is the unit sphere.
    pub(super) to_unit: nalgebra::Matrix3<f64>,
    pub(super) up: Vector3<f64>,
    pub(super) front: Vector3<f64>,
}

/// What a camera ray hits first.
#[derive(Debug, Clone, Copy)]
pub(super) enum Hit {
    Cone(usize),
    Head,
}

/// The person posed for one frame, in camera space.
pub(super) struct Body {
    pub(super) cones: Vec<RoundCone>,
    pub(super) appearance: Appearance,
    pub(super) head: Head,
    /// Radius around each joint used for the visibility test, metres.
    pub(super) joint_radius: PerJoint<f64>,
}

pub(super) fn v(p: &Point3<f64>) -> Vector3<f64> {
    p.coords
}

/// The trunk's, the girdles' and the limbs' round cones, in drawing order (each cone's texture
/// seed is its place): joints, radii over stature at each end, and material.
const LIMB_CONES: [(Joint, Joint, f64, f64, Material); 12] = {
    use Joint::*;
    [
        (
            Chest,
            Pelvis,
            radius::SPINE_CHEST,
            radius::SPINE_PELVIS,
            Material::Shirt,
        ),
        (
            Neck,
            Chest,
            radius::SPINE_CHEST * 0.8,
            radius::SPINE_CHEST,
            Material::Shirt,
        ),
        (
            LeftShoulder,
            RightShoulder,
            radius::SHOULDER_GIRDLE,
            radius::SHOULDER_GIRDLE,
            Material::Shirt,
        ),
        (
            LeftHip,
            RightHip,
            radius::HIP_GIRDLE,
            radius::HIP_GIRDLE,
            Material::Trousers,
        ),
        (
            LeftShoulder,
            LeftElbow,
            radius::UPPER_ARM.0,
            radius::UPPER_ARM.1,
            Material::Shirt,
        ),
        (
            LeftElbow,
            LeftWrist,
            radius::FOREARM.0,
            radius::FOREARM.1,
            Material::Skin,
        ),
        (
            RightShoulder,
            RightElbow,
            radius::UPPER_ARM.0,
            radius::UPPER_ARM.1,
            Material::Shirt,
        ),
        (
            RightElbow,
            RightWrist,
            radius::FOREARM.0,
            radius::FOREARM.1,
            Material::Skin,
        ),
        (
            LeftHip,
            LeftKnee,
            radius::THIGH.0,
            radius::THIGH.1,
            Material::Trousers,
        ),
        (
            LeftKnee,
            LeftAnkle,
            radius::SHANK.0,
            radius::SHANK.1,
            Material::Trousers,
        ),
        (
            RightHip,
            RightKnee,
            radius::THIGH.0,
            radius::THIGH.1,
            Material::Trousers,
        ),
        (
            RightKnee,
            RightAnkle,
            radius::SHANK.0,
            radius::SHANK.1,
            Material::Trousers,
        ),
    ]
};

/// Each joint's radius over stature (the cone end it sits in).
fn joint_radius(j: Joint) -> f64 {
    use Joint::*;
    match j {
        HeadTop => radius::HEAD.2,
        Neck => radius::SPINE_CHEST * 0.8,
        Chest => radius::SPINE_CHEST,
        Pelvis => radius::SPINE_PELVIS,
        LeftShoulder | RightShoulder => radius::SHOULDER_GIRDLE,
        LeftElbow | RightElbow => radius::UPPER_ARM.1,
        LeftWrist | RightWrist => radius::FOREARM.1,
        LeftHip | RightHip => radius::HIP_GIRDLE,
        LeftKnee | RightKnee => radius::THIGH.1,
        LeftAnkle | RightAnkle => radius::SHANK.1,
    }
}

impl Body {
    /// Builds the primitives for joints given in camera space, for a subject of `stature_m`
    /// in the default clothes.
    pub(super) fn new(points: &PerJoint<Point3<f64>>, stature_m: f64) -> Body {
        Body::dressed(points, stature_m, Appearance::default())
    }

    /// [`Body::new`] in the given clothes (loose clothes widen the clothed parts).
    pub(super) fn dressed(
        points: &PerJoint<Point3<f64>>,
        stature_m: f64,
        appearance: Appearance,
    ) -> Body {
        use Joint::*;
        let s = stature_m;
        let p = |j: Joint| v(&points[j]);
        let up = (p(Neck) - p(Pelvis))
            .try_normalize(1e-9)
            .unwrap_or(-Vector3::y());
        let left = (p(LeftShoulder) - p(RightShoulder)) + (p(LeftHip) - p(RightHip));
        let left = (left - up * up.dot(&left))
            .try_normalize(1e-9)
            .unwrap_or(Vector3::x());
        let front = left.cross(&up);
        let across_of = |a: Vector3<f64>, b: Vector3<f64>| {
            let axis = (b - a).try_normalize(1e-9).unwrap_or(up);
            let c = front - axis * axis.dot(&front);
            c.try_normalize(1e-6)
                .or_else(|| (left - axis * axis.dot(&left)).try_normalize(1e-6))
                .unwrap_or(Vector3::x())
        };
        let mut cones = Vec::new();
        let mut cone = |a: Joint, b: Joint, ra: f64, rb: f64, material: Material| {
            let (pa, pb) = (p(a), p(b));
            let k = if material == Material::Skin {
                s
            } else {
                s * appearance.looseness
            };
            cones.push(RoundCone {
                a: pa,
                b: pb,
                ra: ra * k,
                rb: rb * k,
                across: across_of(pa, pb),
                material,
                seed: cones.len() as f64 * 1.7,
            });
        };
        for (a, b, ra, rb, material) in LIMB_CONES {
            cone(a, b, ra, rb, material);
        }
        // Neck column from the neck joint to the base of the skull.
        let head_up = (p(HeadTop) - p(Neck)).try_normalize(1e-9).unwrap_or(up);
        let (ha, hs, hf) = radius::HEAD;
        let centre = p(HeadTop) - head_up * ha * s;
        cone(Neck, Neck, radius::NECK, radius::NECK, Material::Skin);
        if let Some(last) = cones.last_mut() {
            last.b = centre;
        }
        let side = (left - head_up * head_up.dot(&left))
            .try_normalize(1e-9)
            .unwrap_or(left);
        let hfront = side.cross(&head_up);
        let to_unit = nalgebra::Matrix3::from_rows(&[
            (head_up / (ha * s)).transpose(),
            (side / (hs * s)).transpose(),
            (hfront / (hf * s)).transpose(),
        ]);
        let joint_radius = PerJoint::from_fn(|j| s * joint_radius(j));
        Body {
            cones,
            appearance,
            head: Head {
                centre,
                to_unit,
                up: head_up,
                front: hfront,
            },
            joint_radius,
        }
    }

    /// Whether `p` lies inside the body (for voxelising it: `synth --volume`).
    pub(super) fn contains(&self, p: &Point3<f64>) -> bool {
        let p = v(p);
        (self.head.to_unit * (p - self.head.centre)).norm_squared() <= 1.0
            || self.cones.iter().any(|c| {
                let (centre, r) = c.bounding_sphere();
                (p - centre).norm_squared() <= r * r && c.sdf(&p) <= 0.0
            })
    }

    /// An axis-aligned box holding the whole body: (lowest corner, highest corner).
    pub(super) fn bounds(&self) -> (Point3<f64>, Point3<f64>) {
        let (mut lo, mut hi) = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        let head_r = 1.0
            / self
                .head
                .to_unit
                .row(0)
                .norm()
                .min(self.head.to_unit.row(1).norm())
                .min(self.head.to_unit.row(2).norm());
        let spheres = self
            .cones
            .iter()
            .map(|c| c.bounding_sphere())
            .chain(std::iter::once((self.head.centre, head_r)));
        for (c, r) in spheres {
            lo = lo.inf(&(c - Vector3::repeat(r)));
            hi = hi.sup(&(c + Vector3::repeat(r)));
        }
        (Point3::from(lo), Point3::from(hi))
    }

    /// First hit along the ray `t·dir` (from the camera centre) within `t < t_max`.
    pub(super) fn cast(
        &self,
        dir: &Vector3<f64>,
        bounds: &[(usize, f64, f64)],
    ) -> Option<(f64, Hit)> {
        let mut best: Option<(f64, Hit)> = None;
        for &(i, t_in, t_out) in bounds {
            if best.is_some_and(|(t, _)| t <= t_in) {
                continue;
            }
            let c = &self.cones[i];
            let mut t = t_in;
            for _ in 0..64 {
                let d = c.sdf(&(dir * t));
                if d < 1e-4 {
                    if best.is_none_or(|(bt, _)| t < bt) {
                        best = Some((t, Hit::Cone(i)));
                    }
                    break;
                }
                t += d;
                if t > t_out {
                    break;
                }
            }
        }
        // Ray–ellipsoid: in the head's unit-sphere coordinates.
        let o = self.head.to_unit * (-self.head.centre);
        let d = self.head.to_unit * dir;
        let (a, b, c) = (d.dot(&d), 2.0 * o.dot(&d), o.dot(&o) - 1.0);
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let t = (-b - disc.sqrt()) / (2.0 * a);
            if t > 0.0 && best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, Hit::Head));
            }
        }
        best
    }

    pub(super) fn shade(&self, hit: Hit, p: &Vector3<f64>, light: &Vector3<f64>) -> [f64; 3] {
        let (normal, base) = match hit {
            Hit::Cone(i) => {
                let c = &self.cones[i];
                let axis = c.b - c.a;
                let len = axis.norm().max(1e-9);
                let u = (p - c.a).dot(&axis) / len; // metres along the bone
                let radial = (p - c.a) - axis * ((p - c.a).dot(&axis) / (len * len));
                let other = axis.cross(&c.across) / len;
                let angle = radial.dot(&other).atan2(radial.dot(&c.across));
                (
                    c.normal(p),
                    self.appearance.colour(c.material, u, angle, c.seed),
                )
            }
            Hit::Head => {
                let local = self.head.to_unit * (p - self.head.centre);
                let n = (self.head.to_unit.transpose() * local)
                    .try_normalize(1e-12)
                    .unwrap_or(-Vector3::z());
                let rel = (p - self.head.centre).try_normalize(1e-12).unwrap_or(n);
                let hair = rel.dot(&self.head.up) > 0.25 || rel.dot(&self.head.front) < -0.35;
                let colour = if hair {
                    let streak = 0.85 + 0.15 * (rel.dot(&self.head.up) * 40.0).sin();
                    self.appearance.hair.map(|c| c * streak)
                } else {
                    self.appearance.face
                };
                (n, colour)
            }
        };
        let lambert = normal.dot(&-light).max(0.0);
        let k = 0.35 + 0.65 * lambert;
        base.map(|c| c * k)
    }
}
