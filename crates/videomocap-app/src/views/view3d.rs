//! The 3D viewport: the current frame's skeleton in the exports' Y-up world, a ground grid and
//! the camera's frustum; orbit by dragging, zoom with the wheel, pan with the middle or right
//! button; clicking a limb asks to flip its depth choice. By default the view follows the
//! subject across the floor (a walker leaves a fixed view within a few steps); panning stops
//! that.

use super::frame_view::side_colour;
use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2};
use nalgebra::{Point3, Vector3};
use videomocap_core::skeleton::{Bone, Joint, PerJoint};

/// What the viewport shows.
#[derive(Default)]
pub struct Scene {
    /// The skeleton of the current frame, world metres.
    pub joints: Option<PerJoint<Point3<f64>>>,
    /// The camera's centre and its image corners at 0.5 m depth, world metres.
    pub camera: Option<(Point3<f64>, [Point3<f64>; 4])>,
    /// Bones that can be flipped (drawn thicker on hover).
    pub flippable: Vec<Bone>,
    /// Points to draw as dots (volume mode), world metres.
    pub cloud: Vec<(Point3<f64>, Color32)>,
    /// Extra line segments (skeleton curve, bodies), world metres.
    pub segments: Vec<(Point3<f64>, Point3<f64>, Stroke)>,
    /// Bones the lift flagged on this frame (drawn red).
    pub flagged: Vec<Bone>,
    /// Bones whose depth the lift was unsure of on this frame (drawn amber).
    pub unsure: Vec<Bone>,
    /// Lines written over the view's top-left corner (what the lift flagged, a stale view).
    pub notes: Vec<String>,
    /// What the view says when it has nothing to draw (`None`: the video mode's "mark, then
    /// Track").
    pub empty_text: Option<String>,
}

/// Colour of a bone the lift flagged.
const FLAGGED: Color32 = Color32::from_rgb(230, 60, 60);

/// Colour of a bone whose depth the lift was unsure of.
const UNSURE: Color32 = Color32::from_rgb(255, 190, 40);

/// An orbiting view around a target point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// Turn about the vertical, radians.
    pub yaw: f32,
    /// Tilt above the horizon, radians.
    pub pitch: f32,
    /// Distance to the target, metres.
    pub distance: f32,
    /// The point looked at.
    pub target: Vector3<f32>,
    /// Keep the target above the skeleton's pelvis on the floor (its height stays).
    pub follow: bool,
}

impl Default for Orbit {
    fn default() -> Self {
        Orbit {
            yaw: 0.5,
            pitch: 0.25,
            distance: 4.5,
            target: Vector3::new(0.0, 0.9, 0.0),
            follow: true,
        }
    }
}

impl Orbit {
    /// The view from the video camera's centre `eye` (world metres) towards `target`, so the
    /// 3D skeleton first reads as the video does (a one-leg balance seen from an arbitrary
    /// side read as standing with legs apart).
    pub fn from_camera(eye: &Point3<f64>, target: Vector3<f32>) -> Orbit {
        let eye = Vector3::new(eye.x as f32, eye.y as f32, eye.z as f32);
        let back = eye - target;
        let distance = back.norm().max(1.0);
        let back = back / distance;
        Orbit {
            yaw: back.x.atan2(back.z),
            pitch: back.y.clamp(-1.0, 1.0).asin().clamp(-1.5, 1.5),
            distance,
            target,
            follow: true,
        }
    }

    fn basis(&self) -> (Vector3<f32>, Vector3<f32>, Vector3<f32>, Vector3<f32>) {
        let back = Vector3::new(
            self.pitch.cos() * self.yaw.sin(),
            self.pitch.sin(),
            self.pitch.cos() * self.yaw.cos(),
        );
        let eye = self.target + back * self.distance;
        let forward = -back;
        let right = forward.cross(&Vector3::y()).normalize();
        let up = right.cross(&forward);
        (eye, right, up, forward)
    }

    /// Screen position of a world point (`None` behind the eye).
    pub fn project(&self, rect: Rect, p: &Point3<f64>) -> Option<Pos2> {
        let (eye, right, up, forward) = self.basis();
        let d = Vector3::new(p.x as f32, p.y as f32, p.z as f32) - eye;
        let z = d.dot(&forward);
        if z < 0.05 {
            return None;
        }
        let f = rect.height() * 1.2;
        Some(rect.center() + Vec2::new(d.dot(&right) / z * f, -d.dot(&up) / z * f))
    }

    /// Draws the scene; returns a bone the user clicked.
    pub fn show(&mut self, ui: &mut egui::Ui, scene: &Scene) -> Option<Bone> {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        if response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            self.yaw -= d.x * 0.01;
            self.pitch = (self.pitch + d.y * 0.01).clamp(-1.5, 1.5);
        }
        if response.dragged_by(egui::PointerButton::Middle)
            || response.dragged_by(egui::PointerButton::Secondary)
        {
            let (_, right, up, _) = self.basis();
            let d = response.drag_delta() * self.distance / (rect.height() * 1.2);
            self.target += -right * d.x + up * d.y;
            self.follow = false;
        }
        if let (true, Some(joints)) = (self.follow, &scene.joints) {
            let pelvis = joints[Joint::Pelvis];
            if pelvis.x.is_finite() && pelvis.z.is_finite() {
                self.target.x = pelvis.x as f32;
                self.target.z = pelvis.z as f32;
            }
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            self.distance = (self.distance * (-scroll * 0.002).exp()).clamp(0.5, 50.0);
        }
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, Color32::from_gray(24));
        let line = |a: &Point3<f64>, b: &Point3<f64>, stroke: Stroke| {
            if let (Some(p), Some(q)) = (self.project(rect, a), self.project(rect, b)) {
                painter.line_segment([p, q], stroke);
            }
        };
        // 6 m of floor in half-metre squares around the target, fixed to the world (it slides
        // by as a followed walker moves).
        let grid = Stroke::new(1.0, Color32::from_gray(70));
        let snap = |v: f32| (f64::from(v) / 0.5).round() * 0.5;
        let (gx, gz) = (snap(self.target.x), snap(self.target.z));
        for k in -6..=6 {
            let v = f64::from(k) * 0.5;
            line(
                &Point3::new(gx + v, 0.0, gz - 3.0),
                &Point3::new(gx + v, 0.0, gz + 3.0),
                grid,
            );
            line(
                &Point3::new(gx - 3.0, 0.0, gz + v),
                &Point3::new(gx + 3.0, 0.0, gz + v),
                grid,
            );
        }
        if let Some((c, corners)) = &scene.camera {
            let s = Stroke::new(1.0, Color32::from_rgb(180, 180, 255));
            for k in 0..4 {
                line(c, &corners[k], s);
                line(&corners[k], &corners[(k + 1) % 4], s);
            }
        }
        for (p, colour) in &scene.cloud {
            if let Some(s) = self.project(rect, p) {
                painter.circle_filled(s, 1.5, *colour);
            }
        }
        for (a, b, stroke) in &scene.segments {
            line(a, b, *stroke);
        }
        let mut clicked = None;
        if let Some(joints) = &scene.joints {
            let hover = response.hover_pos();
            let near_bone = |pos: Pos2| -> Option<Bone> {
                scene
                    .flippable
                    .iter()
                    .filter_map(|b| {
                        let p = self.project(rect, &joints[b.parent])?;
                        let q = self.project(rect, &joints[b.child])?;
                        let d = distance_to_segment(pos, p, q);
                        (d < 8.0).then_some((*b, d))
                    })
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(b, _)| b)
            };
            let hovered = hover.and_then(near_bone);
            for b in Bone::ALL {
                let width = if hovered == Some(b) { 5.0 } else { 2.5 };
                let colour = if scene.flagged.contains(&b) {
                    FLAGGED
                } else if scene.unsure.contains(&b) {
                    UNSURE
                } else {
                    side_colour(b.child)
                };
                line(
                    &joints[b.parent],
                    &joints[b.child],
                    Stroke::new(width, colour),
                );
            }
            for (_, p) in joints.iter() {
                if let Some(s) = self.project(rect, p) {
                    painter.circle_filled(s, 3.0, Color32::WHITE);
                }
            }
            if hovered.is_some() {
                response
                    .clone()
                    .on_hover_text("click to flip this limb's depth on this frame");
            }
            if response.clicked() {
                clicked = response.interact_pointer_pos().and_then(near_bone);
            }
        } else if scene.cloud.is_empty() {
            let text = scene
                .empty_text
                .clone()
                .unwrap_or_else(|| "no 3D skeleton yet: mark, then Track".to_owned());
            let galley = painter.layout(
                text,
                egui::FontId::proportional(14.0),
                Color32::GRAY,
                (rect.width() - 32.0).clamp(100.0, 640.0),
            );
            let at = rect.center() - galley.size() / 2.0;
            painter.galley(at, galley, Color32::GRAY);
        }
        // Notes wrap to the view's width (a narrow 3D panel cut them off).
        let mut y = 8.0;
        for note in &scene.notes {
            let colour = Color32::from_rgb(240, 170, 90);
            let galley = painter.layout(
                note.clone(),
                egui::FontId::proportional(13.0),
                colour,
                (rect.width() - 16.0).max(60.0),
            );
            let height = galley.size().y;
            painter.galley(rect.left_top() + Vec2::new(8.0, y), galley, colour);
            y += height + 3.0;
        }
        clicked
    }
}

fn distance_to_segment(p: Pos2, a: Pos2, b: Pos2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_sq().max(1e-6)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;

    /// A skeleton with every joint at `(x, 1, z)` but the pelvis at `(x, 0.9, z)`.
    fn scene_at(x: f64, z: f64) -> Scene {
        let mut joints = PerJoint::from_fn(|_| Point3::new(x, 1.0, z));
        joints[Joint::Pelvis] = Point3::new(x, 0.9, z);
        Scene {
            joints: Some(joints),
            ..Scene::default()
        }
    }

    #[test]
    fn the_view_follows_the_pelvis_across_the_floor_unless_told_not_to() {
        let mut h = Harness::new_ui_state(
            |ui, (orbit, x): &mut (Orbit, f64)| {
                orbit.show(ui, &scene_at(*x, -2.0));
            },
            (Orbit::default(), 3.0),
        );
        h.run();
        let target = h.state().0.target;
        assert_eq!((target.x, target.y, target.z), (3.0, 0.9, -2.0));
        // The walker moves on: the view goes with them.
        h.state_mut().1 = 4.5;
        h.run();
        assert_eq!(h.state().0.target.x, 4.5);
        // Not following: the view stays where it was.
        h.state_mut().0.follow = false;
        h.state_mut().1 = 7.0;
        h.run();
        assert_eq!(h.state().0.target.x, 4.5);
    }

    /// Seen from the video camera: the target at the view's centre, the camera's own left and
    /// right kept (a point beside the target away from the camera's side shows on that side),
    /// the floor below the horizon.
    #[test]
    fn the_view_from_the_camera_looks_at_the_target_as_the_camera_does() {
        let eye = Point3::new(1.0, 1.6, 4.0);
        let target = Vector3::new(0.0, 0.9, 0.0);
        let o = Orbit::from_camera(&eye, target);
        let rect = Rect::from_min_size(Pos2::ZERO, Vec2::new(400.0, 300.0));
        let at = o.project(rect, &Point3::new(0.0, 0.9, 0.0)).unwrap();
        assert!((at - rect.center()).length() < 1e-3, "{at:?}");
        assert!((o.distance - (eye.coords.cast::<f32>() - target).norm()).abs() < 1e-4);
        // Looking down from 1.6 m: the floor under the target is below the centre.
        let floor = o.project(rect, &Point3::new(0.0, 0.0, 0.0)).unwrap();
        assert!(floor.y > rect.center().y);
        // The camera's right (world +x from this eye, looking towards −z) is on the right.
        let side = o.project(rect, &Point3::new(0.5, 0.9, 0.0)).unwrap();
        assert!(side.x > rect.center().x);
    }
}
