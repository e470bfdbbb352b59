//! Volume mode: a processed point-volume sequence shown in the 3D viewport — the frame's points
//! coloured by the body they were assigned to, the skeleton curve, the fitted head sphere, torso
//! and limb cylinders, and the 16-joint skeleton — all moved into the exports' Y-up world.

use super::frame_view::side_colour;
use super::view3d::Scene;
use egui::{Color32, Stroke};
use nalgebra::{Point3, Vector3};
use std::path::PathBuf;
use std::sync::Arc;
use videomocap::export::WorldSkeleton;
use videomocap::skeleton::Joint;
use videomocap::volume::bodies::Cylinder;
use videomocap::volume::{Part, Processed};

/// Most points drawn per frame (the rest are skipped evenly; drawing stays fast).
const MAX_POINTS: usize = 6000;

/// What volume mode holds.
pub struct VolumeView {
    /// The sequence directory.
    pub dir: PathBuf,
    /// The pipeline's output, once the job has finished.
    pub processed: Option<Arc<Processed>>,
    /// The skeleton in the Y-up world (also the map for points, curve and bodies).
    pub world: Option<WorldSkeleton>,
    /// Draw the points.
    pub show_points: bool,
    /// Draw the skeleton curve.
    pub show_curve: bool,
    /// Draw the fitted bodies.
    pub show_bodies: bool,
}

impl VolumeView {
    /// A sequence about to be processed.
    pub fn new(dir: PathBuf) -> VolumeView {
        VolumeView {
            dir,
            processed: None,
            world: None,
            show_points: true,
            show_curve: true,
            show_bodies: true,
        }
    }

    /// Number of frames (0 until processed).
    pub fn frame_count(&self) -> usize {
        self.processed.as_ref().map_or(0, |p| p.files.len())
    }

    /// Takes the pipeline's result.
    pub fn set(&mut self, processed: Processed) {
        self.world = WorldSkeleton::new(&processed.assembled.skeleton, None).ok();
        self.processed = Some(Arc::new(processed));
    }

    /// The scene of frame `index`.
    pub fn scene(&self, index: usize) -> Scene {
        let mut scene = Scene {
            joints: None,
            camera: None,
            flippable: Vec::new(),
            cloud: Vec::new(),
            segments: Vec::new(),
        };
        let (Some(p), Some(world)) = (&self.processed, &self.world) else {
            return scene;
        };
        let to_world = |q: &Point3<f64>| world.world.to_world(q);
        scene.joints = world
            .indices
            .binary_search(&index)
            .ok()
            .map(|k| world.frames[k]);
        let Some(Ok(frame)) = p.results.get(index) else {
            return scene;
        };
        // Fitted limb k sits in slot s (0 left arm, 1 right arm, 2 left leg, 3 right leg).
        let slot_of = |k: u8| {
            p.assembled
                .slots
                .get(index)
                .copied()
                .flatten()
                .and_then(|s| s.iter().position(|&x| x == usize::from(k)))
                .unwrap_or(usize::from(k))
        };
        let limb_colour = |k: u8, lower: bool| {
            let c = side_colour(if slot_of(k) % 2 == 0 {
                Joint::LeftElbow
            } else {
                Joint::RightElbow
            });
            if lower { c.gamma_multiply(0.6) } else { c }
        };
        if self.show_points {
            let step = frame.points.len().div_ceil(MAX_POINTS).max(1);
            for (q, part) in frame.points.iter().zip(&frame.fit.parts).step_by(step) {
                let colour = match part {
                    Part::Head => Color32::from_rgb(230, 200, 120),
                    Part::Torso => Color32::from_gray(150),
                    Part::Upper(k) => limb_colour(*k, false),
                    Part::Lower(k) => limb_colour(*k, true),
                };
                scene.cloud.push((to_world(q), colour));
            }
        }
        if self.show_curve {
            let stroke = Stroke::new(1.5, Color32::from_rgb(120, 230, 120));
            let c = &frame.curve;
            for (i, parent) in c.parents.iter().enumerate() {
                if let Some(j) = parent {
                    scene
                        .segments
                        .push((to_world(&c.points[*j]), to_world(&c.points[i]), stroke));
                }
            }
        }
        if self.show_bodies {
            let stroke = Stroke::new(1.0, Color32::from_rgba_unmultiplied(200, 200, 255, 140));
            let f = &frame.fit;
            let mut push = |a: Point3<f64>, b: Point3<f64>| {
                scene.segments.push((to_world(&a), to_world(&b), stroke));
            };
            sphere(f.head_centre, f.head_radius, &mut push);
            cylinder(&f.torso, &mut push);
            for l in &f.limbs {
                let knee = l.split.unwrap_or_else(|| nalgebra::center(&l.root, &l.end));
                for (a, b, r) in [(l.root, knee, l.radii[0]), (knee, l.end, l.radii[1])] {
                    cylinder(&Cylinder { a, b, radius: r }, &mut push);
                }
            }
        }
        scene
    }
}

/// Two unit vectors across `axis`.
fn across(axis: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if axis.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = axis.cross(&helper).normalize();
    (u, axis.cross(&u))
}

/// A wire cylinder: rings at both ends and four lines along it.
fn cylinder(c: &Cylinder, push: &mut impl FnMut(Point3<f64>, Point3<f64>)) {
    let Some(axis) = (c.b - c.a).try_normalize(1e-9) else {
        return;
    };
    let (u, v) = across(&axis);
    let at = |centre: &Point3<f64>, t: f64| centre + (u * t.cos() + v * t.sin()) * c.radius;
    let n = 12;
    for k in 0..n {
        let (t0, t1) = (
            std::f64::consts::TAU * f64::from(k) / f64::from(n),
            std::f64::consts::TAU * f64::from(k + 1) / f64::from(n),
        );
        push(at(&c.a, t0), at(&c.a, t1));
        push(at(&c.b, t0), at(&c.b, t1));
        if k % 3 == 0 {
            push(at(&c.a, t0), at(&c.b, t0));
        }
    }
}

/// A wire sphere: three great circles.
fn sphere(centre: Point3<f64>, r: f64, push: &mut impl FnMut(Point3<f64>, Point3<f64>)) {
    let n = 16;
    for (a, b) in [
        (Vector3::x(), Vector3::y()),
        (Vector3::y(), Vector3::z()),
        (Vector3::z(), Vector3::x()),
    ] {
        for k in 0..n {
            let t0 = std::f64::consts::TAU * f64::from(k) / f64::from(n);
            let t1 = std::f64::consts::TAU * f64::from(k + 1) / f64::from(n);
            push(
                centre + (a * t0.cos() + b * t0.sin()) * r,
                centre + (a * t1.cos() + b * t1.sin()) * r,
            );
        }
    }
}
