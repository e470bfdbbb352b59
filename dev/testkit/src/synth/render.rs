//! A z-buffered ray caster for the synthetic person: textured tapered capsules (round cones) for
//! trunk and limbs, an ellipsoid head with hair, over a textured background, seen by a pinhole
//! camera; optional sensor noise and brightness flicker.

use super::appearance::{Appearance, Material, value_noise};
use super::mesh::MeshError;
use image::{Rgb, RgbImage};
use nalgebra::{Point2, Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::skeleton::{Joint, PerJoint};

/// Radii of the body's primitives as fractions of stature (a slim adult in clothes).
mod radius {
    pub const NECK: f64 = 0.030;
    pub const SPINE_CHEST: f64 = 0.080;
    pub const SPINE_PELVIS: f64 = 0.070;
    pub const SHOULDER_GIRDLE: f64 = 0.045;
    pub const HIP_GIRDLE: f64 = 0.060;
    pub const UPPER_ARM: (f64, f64) = (0.032, 0.026);
    pub const FOREARM: (f64, f64) = (0.025, 0.019);
    pub const THIGH: (f64, f64) = (0.050, 0.034);
    pub const SHANK: (f64, f64) = (0.033, 0.024);
    /// Head semi-axes: up, across, front-back.
    pub const HEAD: (f64, f64, f64) = (0.068, 0.050, 0.058);
}

/// A tapered capsule: the union of spheres swept from `a` (radius `ra`) to `b` (radius `rb`).
#[derive(Debug, Clone, Copy)]
struct RoundCone {
    a: Vector3<f64>,
    b: Vector3<f64>,
    ra: f64,
    rb: f64,
    /// A unit vector across the axis, for the texture's angle.
    across: Vector3<f64>,
    material: Material,
    /// Texture phase so that parts do not look alike.
    seed: f64,
}

impl RoundCone {
    /// Exact signed distance (Quílez, "distance functions", round cone).
    fn sdf(&self, p: &Vector3<f64>) -> f64 {
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

    fn bounding_sphere(&self) -> (Vector3<f64>, f64) {
        let c = (self.a + self.b) / 2.0;
        (c, (self.b - self.a).norm() / 2.0 + self.ra.max(self.rb))
    }

    fn normal(&self, p: &Vector3<f64>) -> Vector3<f64> {
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
struct Head {
    centre: Vector3<f64>,
    /// Rows: unit up, side, front; scaled by 1/semi-axis so that the surface is the unit sphere.
    to_unit: nalgebra::Matrix3<f64>,
    up: Vector3<f64>,
    front: Vector3<f64>,
}

/// What a camera ray hits first.
#[derive(Debug, Clone, Copy)]
enum Hit {
    Cone(usize),
    Head,
}

/// The person posed for one frame, in camera space.
pub struct Body {
    cones: Vec<RoundCone>,
    appearance: Appearance,
    head: Head,
    /// Radius around each joint used for the visibility test, metres.
    joint_radius: PerJoint<f64>,
}

fn v(p: &Point3<f64>) -> Vector3<f64> {
    p.coords
}

impl Body {
    /// Builds the primitives for joints given in camera space, for a subject of `stature_m`
    /// in the default clothes.
    pub fn new(points: &PerJoint<Point3<f64>>, stature_m: f64) -> Body {
        Body::dressed(points, stature_m, Appearance::default())
    }

    /// [`Body::new`] in the given clothes (loose clothes widen the clothed parts).
    pub fn dressed(points: &PerJoint<Point3<f64>>, stature_m: f64, appearance: Appearance) -> Body {
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
        cone(
            Chest,
            Pelvis,
            radius::SPINE_CHEST,
            radius::SPINE_PELVIS,
            Material::Shirt,
        );
        cone(
            Neck,
            Chest,
            radius::SPINE_CHEST * 0.8,
            radius::SPINE_CHEST,
            Material::Shirt,
        );
        cone(
            LeftShoulder,
            RightShoulder,
            radius::SHOULDER_GIRDLE,
            radius::SHOULDER_GIRDLE,
            Material::Shirt,
        );
        cone(
            LeftHip,
            RightHip,
            radius::HIP_GIRDLE,
            radius::HIP_GIRDLE,
            Material::Trousers,
        );
        for (sh, el, wr) in [
            (LeftShoulder, LeftElbow, LeftWrist),
            (RightShoulder, RightElbow, RightWrist),
        ] {
            cone(
                sh,
                el,
                radius::UPPER_ARM.0,
                radius::UPPER_ARM.1,
                Material::Shirt,
            );
            cone(el, wr, radius::FOREARM.0, radius::FOREARM.1, Material::Skin);
        }
        for (hip, kn, an) in [
            (LeftHip, LeftKnee, LeftAnkle),
            (RightHip, RightKnee, RightAnkle),
        ] {
            cone(
                hip,
                kn,
                radius::THIGH.0,
                radius::THIGH.1,
                Material::Trousers,
            );
            cone(kn, an, radius::SHANK.0, radius::SHANK.1, Material::Trousers);
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
        let joint_radius = PerJoint::from_fn(|j| {
            s * match j {
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
        });
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
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        let p = v(p);
        (self.head.to_unit * (p - self.head.centre)).norm_squared() <= 1.0
            || self.cones.iter().any(|c| {
                let (centre, r) = c.bounding_sphere();
                (p - centre).norm_squared() <= r * r && c.sdf(&p) <= 0.0
            })
    }

    /// An axis-aligned box holding the whole body: (lowest corner, highest corner).
    pub fn bounds(&self) -> (Point3<f64>, Point3<f64>) {
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
    fn cast(&self, dir: &Vector3<f64>, bounds: &[(usize, f64, f64)]) -> Option<(f64, Hit)> {
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

    fn shade(&self, hit: Hit, p: &Vector3<f64>, light: &Vector3<f64>) -> [f64; 3] {
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

/// Renders a static textured background (floor and wall with noise and shapes), seeded.
pub fn background(width: u32, height: u32, seed: u64) -> RgbImage {
    let horizon = f64::from(height) * 0.62;
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let shapes: Vec<(f64, f64, f64, f64, [f64; 3])> = (0..12)
        .map(|_| {
            let w = rng.random_range(0.05..0.25) * f64::from(width);
            let h = rng.random_range(0.05..0.35) * f64::from(height);
            let x = rng.random_range(0.0..f64::from(width));
            let y = rng.random_range(0.0..horizon);
            let c = [
                rng.random_range(60.0..200.0),
                rng.random_range(60.0..200.0),
                rng.random_range(60.0..200.0),
            ];
            (x, y, w, h, c)
        })
        .collect();
    RgbImage::from_fn(width, height, |x, y| {
        let (fx, fy) = (f64::from(x), f64::from(y));
        let mut noise = 0.0;
        let mut amp = 0.5;
        let mut freq = 1.0 / 64.0;
        for octave in 0..4 {
            noise += amp * value_noise(fx * freq, fy * freq, seed + octave);
            amp *= 0.5;
            freq *= 2.0;
        }
        let mut c = if fy < horizon {
            [
                150.0 + 60.0 * noise,
                140.0 + 50.0 * noise,
                120.0 + 40.0 * noise,
            ]
        } else {
            // Floor: perspective-ish tiles.
            let depth = (fy - horizon + 8.0) / f64::from(height);
            let tile = (((fx - f64::from(width) / 2.0) * 0.02 / depth).floor() as i64
                + (0.6 / depth).floor() as i64)
                & 1;
            let t = tile as f64;
            [
                110.0 + 50.0 * t + 40.0 * noise,
                90.0 + 40.0 * t + 30.0 * noise,
                70.0 + 30.0 * t + 20.0 * noise,
            ]
        };
        for &(sx, sy, sw, sh, sc) in &shapes {
            if fy < horizon && fx >= sx && fx < sx + sw && fy >= sy && fy < (sy + sh).min(horizon) {
                c = sc.map(|v| v * (0.85 + 0.3 * noise));
            }
        }
        Rgb(c.map(|v| v.clamp(0.0, 255.0) as u8))
    })
}

/// Per-frame image effects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorEffects {
    /// Standard deviation of Gaussian sensor noise, in 8-bit levels (0 = none).
    pub noise_sigma: f64,
    /// Relative amplitude of brightness flicker (0.05 = ±5%).
    pub flicker: f64,
    /// Random seed.
    pub seed: u64,
}

/// The result of rendering one frame.
pub struct Rendered {
    /// The image.
    pub image: RgbImage,
    /// Joint positions in the image.
    pub points2d: PerJoint<Point2<f64>>,
    /// Whether each joint is seen (on the image and not hidden behind another body part).
    pub visible: PerJoint<bool>,
}

/// What a person's body is drawn as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Surface {
    /// The mannequin: tapered capsules and an ellipsoid head, ray-cast (quick tests).
    #[default]
    Capsules,
    /// MakeHuman's skinned mesh, rasterised (benchmark suite v4, `synth`'s default).
    Mesh,
}

/// One person to draw: joints in camera space, stature, clothes, body.
#[derive(Debug, Clone, Copy)]
pub struct Figure<'a> {
    /// The 16 joints in camera space, metres.
    pub points: &'a PerJoint<Point3<f64>>,
    /// Stature, metres (sizes the body's parts).
    pub stature_m: f64,
    /// Clothes, skin and hair.
    pub appearance: Appearance,
    /// The body drawn.
    pub surface: Surface,
}

/// Renders the subject over `background`, with `others` (people or things moving behind it)
/// drawn first; the ground truth (points, visibility) is the subject's.
pub fn render_frame(
    camera: &PinholeCamera,
    subject: &Figure,
    others: &[Figure],
    background: &RgbImage,
    effects: &SensorEffects,
    frame_index: usize,
) -> Result<Rendered, MeshError> {
    let mut image = background.clone();
    for other in others {
        draw(camera, other, &mut image)?;
    }
    let (body, depth) = draw(camera, subject, &mut image)?;
    apply_effects(&mut image, effects, frame_index);
    let points = subject.points;
    let (w, h) = (camera.width, camera.height);
    let points2d = points.map(|_, p| camera.project(p).unwrap_or(Point2::new(-1e6, -1e6)));
    let visible = PerJoint::from_fn(|j| {
        let p2 = points2d[j];
        if !camera.contains(&p2) {
            return false;
        }
        let (px, py) = (p2.x.round() as u32, p2.y.round() as u32);
        let surface = depth[(py.min(h - 1) * w + px.min(w - 1)) as usize];
        // Seen when the nearest surface there is the joint's own (no more than its body radius
        // plus 3 cm in front of it).
        surface >= points[j].z - body.joint_radius[j] - 0.03
    });
    Ok(Rendered {
        image,
        points2d,
        visible,
    })
}

/// Draws `figure` over `image`; its mannequin (whose joint radii the visibility test reads)
/// and its depth per pixel.
fn draw(
    camera: &PinholeCamera,
    figure: &Figure,
    image: &mut RgbImage,
) -> Result<(Body, Vec<f64>), MeshError> {
    let body = Body::dressed(figure.points, figure.stature_m, figure.appearance);
    let depth = match figure.surface {
        Surface::Capsules => paint(camera, &body, image),
        Surface::Mesh => super::mesh::paint(
            camera,
            figure.points,
            figure.stature_m,
            &figure.appearance,
            image,
        )?,
    };
    Ok((body, depth))
}

/// Draws `body` over `image` (z-buffered against itself) and returns its depth per pixel
/// (infinite where it is not).
fn paint(camera: &PinholeCamera, body: &Body, image: &mut RgbImage) -> Vec<f64> {
    let (w, h) = (camera.width, camera.height);
    // Screen-space bounds of each cone from its bounding sphere.
    let spheres: Vec<(Vector3<f64>, f64)> =
        body.cones.iter().map(RoundCone::bounding_sphere).collect();
    let boxes: Vec<Option<[f64; 4]>> = spheres
        .iter()
        .map(|(c, r)| {
            if c.z - r <= 0.01 {
                return None;
            }
            let p = camera.project(&Point3::from(*c))?;
            let rad = camera.focal_px * r / (c.z - r) + 2.0;
            Some([p.x - rad, p.y - rad, p.x + rad, p.y + rad])
        })
        .collect();
    let light = Vector3::new(0.3, 0.8, 0.5).normalize(); // from upper left, behind the camera
    let mut depth = vec![f64::INFINITY; (w * h) as usize];
    let rows: Vec<(u32, Vec<[u8; 3]>, Vec<f64>)> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut colours = Vec::with_capacity(w as usize);
            let mut depths = Vec::with_capacity(w as usize);
            let mut bounds = Vec::with_capacity(body.cones.len());
            for x in 0..w {
                let dir = camera.ray(&Point2::new(f64::from(x), f64::from(y)));
                bounds.clear();
                for (i, b) in boxes.iter().enumerate() {
                    let Some(b) = b else { continue };
                    let (fx, fy) = (f64::from(x), f64::from(y));
                    if fx < b[0] || fx > b[2] || fy < b[1] || fy > b[3] {
                        continue;
                    }
                    let (c, r) = spheres[i];
                    let tc = c.dot(&dir);
                    let d2 = c.norm_squared() - tc * tc;
                    if d2 > r * r {
                        continue;
                    }
                    let half = (r * r - d2).sqrt();
                    bounds.push((i, (tc - half).max(0.0), tc + half));
                }
                match body.cast(&dir, &bounds) {
                    Some((t, hit)) => {
                        let p = dir * t;
                        colours.push(
                            body.shade(hit, &p, &light)
                                .map(|c| c.clamp(0.0, 255.0) as u8),
                        );
                        depths.push(p.z);
                    }
                    None => {
                        colours.push([0, 0, 0]);
                        depths.push(f64::INFINITY);
                    }
                }
            }
            (y, colours, depths)
        })
        .collect();
    for (y, colours, depths) in rows {
        for (x, (c, z)) in colours.into_iter().zip(depths).enumerate() {
            if z.is_finite() {
                image.put_pixel(x as u32, y, Rgb(c));
                depth[(y * w) as usize + x] = z;
            }
        }
    }
    depth
}

/// Sensor noise and flicker on a finished frame (seeded per frame).
pub(crate) fn apply_effects(image: &mut RgbImage, effects: &SensorEffects, frame_index: usize) {
    if effects.noise_sigma <= 0.0 && effects.flicker <= 0.0 {
        return;
    }
    let mut rng = rand::rngs::StdRng::seed_from_u64(
        effects.seed ^ (frame_index as u64).wrapping_mul(0x9E37_79B9),
    );
    let gain = 1.0 + effects.flicker * rng.random_range(-1.0..1.0);
    let normal = Normal::new(0.0, effects.noise_sigma.max(1e-9)).ok();
    for px in image.pixels_mut() {
        for c in px.0.iter_mut() {
            let n = match (&normal, effects.noise_sigma > 0.0) {
                (Some(d), true) => d.sample(&mut rng),
                _ => 0.0,
            };
            *c = (f64::from(*c) * gain + n).clamp(0.0, 255.0) as u8;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_cone_distance_is_exact_on_simple_points() {
        let c = RoundCone {
            a: Vector3::zeros(),
            b: Vector3::new(0.0, 1.0, 0.0),
            ra: 0.2,
            rb: 0.2,
            across: Vector3::x(),
            material: Material::Skin,
            seed: 0.0,
        };
        assert!((c.sdf(&Vector3::new(1.0, 0.5, 0.0)) - 0.8).abs() < 1e-12);
        assert!((c.sdf(&Vector3::new(0.0, 2.0, 0.0)) - 0.8).abs() < 1e-12);
        assert!((c.sdf(&Vector3::new(0.0, 0.5, 0.0)) + 0.2).abs() < 1e-12);
    }
}
