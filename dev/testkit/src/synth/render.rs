//! A z-buffered ray caster for the synthetic person (the capsule body of `capsules`, or the
//! MakeHuman mesh) over a textured background, seen by a pinhole camera; optional sensor noise
//! and brightness flicker.

use super::appearance::{Appearance, value_noise};
use super::capsules::{Body, RoundCone};
use super::mesh::MeshError;
use image::{Rgb, RgbImage};
use nalgebra::{Point2, Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::skeleton::PerJoint;

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
    use crate::synth::appearance::Material;

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
