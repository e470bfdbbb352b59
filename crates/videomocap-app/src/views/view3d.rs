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
pub(crate) struct Scene {
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
    /// Bones whose depth the lift was unsure of on this frame (drawn thick in [`DOUBT`]).
    pub unsure: Vec<Bone>,
    /// A bone to pick out (the one under the pointer in the list of unsure limbs).
    pub highlight: Option<Bone>,
    /// Ankles the lift found planted on the floor (a [`PLANTED`] ring under each).
    pub planted: Vec<Joint>,
    /// The frame's skeleton before the user's last flip on it (drawn grey under the new one).
    pub ghost: Option<PerJoint<Point3<f64>>>,
    /// Lines written over the view's top-left corner (what the lift flagged, a stale view).
    pub notes: Vec<Note>,
    /// What the view says when it has nothing to draw (`None`: the video mode's "mark, then
    /// Track").
    pub empty_text: Option<String>,
}

/// Whether a note over the 3D view is a problem to look at or information.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum NoteKind {
    /// Something to check or act on (orange).
    Warning,
    /// A state worth knowing, nothing to do (grey).
    Info,
}

/// A line written over the 3D view.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Note {
    /// The words.
    pub text: String,
    /// Problem or information.
    pub kind: NoteKind,
}

impl Note {
    /// Something to check or act on.
    pub(crate) fn warning(text: String) -> Note {
        Note {
            text,
            kind: NoteKind::Warning,
        }
    }

    /// A state worth knowing.
    pub(crate) fn info(text: String) -> Note {
        Note {
            text,
            kind: NoteKind::Info,
        }
    }

    fn colour(&self) -> Color32 {
        match self.kind {
            NoteKind::Warning => Color32::from_rgb(240, 170, 90),
            NoteKind::Info => Color32::from_gray(200),
        }
    }
}

/// Colour of a bone the lift flagged.
pub(crate) const FLAGGED: Color32 = Color32::from_rgb(230, 60, 60);

/// Colour of a bone whose depth the lift was unsure of: magenta, the hue farthest from every
/// other colour of the view (the sides' cyan and orange, the middle's yellow, the flagged red,
/// the frustum's lavender); the amber it replaced sat next to the middle's yellow.
pub(crate) const DOUBT: Color32 = Color32::from_rgb(255, 40, 255);

/// Width of an unsure bone, points (a normal bone is 2.5: a short hip segment drawn thin in
/// a doubt colour went unseen).
const DOUBT_WIDTH: f32 = 6.0;

/// Colour of a planted foot (the 3D view's ring under the ankle and the timeline's bar).
pub(crate) const PLANTED: Color32 = Color32::from_rgb(150, 100, 50);

/// The orbit's default lens: the focal length over the view's height (about 45° seen top to
/// bottom).
const DEFAULT_LENS: f32 = 1.2;

/// An orbiting view around a target point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Orbit {
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
    /// Focal length over the view's height (the view through the video camera has the
    /// camera's own).
    pub lens: f32,
}

impl Default for Orbit {
    fn default() -> Self {
        Orbit {
            yaw: 0.5,
            pitch: 0.25,
            distance: 4.5,
            target: Vector3::new(0.0, 0.9, 0.0),
            follow: true,
            lens: DEFAULT_LENS,
        }
    }
}

impl Orbit {
    /// The view from the video camera's centre `eye` (world metres) towards `target`, so the
    /// 3D skeleton first reads as the video does (a one-leg balance seen from an arbitrary
    /// side read as standing with legs apart).
    pub(crate) fn from_camera(eye: &Point3<f64>, target: Vector3<f32>) -> Orbit {
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
            lens: DEFAULT_LENS,
        }
    }

    /// The view through the video camera itself: from its centre `eye`, along its optical axis
    /// (through the middle of the frustum's image `corners` at 0.5 m), with its field of view
    /// fitted into a view of `view_aspect` (width over height) as the frame view fits the
    /// video, so the skeleton lies as it does over the video. `depth_m` is how far along the
    /// axis the view turns about (the subject's distance). Not following: the camera stands.
    /// `None` for a degenerate frustum.
    pub(crate) fn through_camera(
        eye: &Point3<f64>,
        corners: &[Point3<f64>; 4],
        depth_m: f64,
        view_aspect: f32,
    ) -> Option<Orbit> {
        let centre = corners.iter().map(|c| c.coords).sum::<Vector3<f64>>() / 4.0;
        let axis = centre - eye.coords;
        let forward = axis.try_normalize(1e-9)?;
        let across = (corners[1] - corners[0]).norm();
        let down = (corners[3] - corners[0]).norm();
        if down < 1e-9 || across < 1e-9 {
            return None;
        }
        // At `axis`'s depth the image is `down` tall: focal over image height.
        let f_over_h = axis.norm() / down;
        let fit = (f64::from(view_aspect) / (across / down)).min(1.0);
        let depth = depth_m.max(0.5);
        let target = eye.coords + forward * depth;
        let back = -forward.cast::<f32>();
        Some(Orbit {
            yaw: back.x.atan2(back.z),
            pitch: back.y.clamp(-1.0, 1.0).asin(),
            distance: depth as f32,
            target: target.cast::<f32>(),
            follow: false,
            lens: (f_over_h * fit) as f32,
        })
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
    pub(crate) fn project(&self, rect: Rect, p: &Point3<f64>) -> Option<Pos2> {
        let (eye, right, up, forward) = self.basis();
        let d = Vector3::new(p.x as f32, p.y as f32, p.z as f32) - eye;
        let z = d.dot(&forward);
        if z < 0.05 {
            return None;
        }
        let f = rect.height() * self.lens;
        Some(rect.center() + Vec2::new(d.dot(&right) / z * f, -d.dot(&up) / z * f))
    }

    /// Draws the scene; returns a bone the user clicked.
    pub(crate) fn show(&mut self, ui: &mut egui::Ui, scene: &Scene) -> Option<Bone> {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        self.steer(ui, &response, rect, scene);
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, Color32::from_gray(24));
        let pen = Pen {
            orbit: self,
            painter: &painter,
            rect,
        };
        pen.floor();
        pen.camera_cloud_and_segments(scene);
        let clicked = match &scene.joints {
            Some(joints) => pen.skeleton(scene, joints, &response),
            None => {
                if scene.cloud.is_empty() {
                    pen.empty_text(scene);
                }
                None
            }
        };
        pen.notes(scene);
        clicked
    }

    /// Turns (left drag), pans (middle or right drag, which stops following the pelvis),
    /// follows the pelvis, and zooms (scroll over the view).
    fn steer(&mut self, ui: &egui::Ui, response: &egui::Response, rect: Rect, scene: &Scene) {
        if response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            self.yaw -= d.x * 0.01;
            self.pitch = (self.pitch + d.y * 0.01).clamp(-1.5, 1.5);
        }
        if response.dragged_by(egui::PointerButton::Middle)
            || response.dragged_by(egui::PointerButton::Secondary)
        {
            let (_, right, up, _) = self.basis();
            let d = response.drag_delta() * self.distance / (rect.height() * self.lens);
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
    }
}

/// What draws the scene: the orbit's projection onto the view's rectangle.
struct Pen<'a> {
    orbit: &'a Orbit,
    painter: &'a egui::Painter,
    rect: Rect,
}

impl Pen<'_> {
    fn project(&self, p: &Point3<f64>) -> Option<Pos2> {
        self.orbit.project(self.rect, p)
    }

    fn line(&self, a: &Point3<f64>, b: &Point3<f64>, stroke: Stroke) {
        if let (Some(p), Some(q)) = (self.project(a), self.project(b)) {
            self.painter.line_segment([p, q], stroke);
        }
    }

    /// 6 m of floor in half-metre squares around the target, fixed to the world (it slides by as
    /// a followed walker moves).
    fn floor(&self) {
        let grid = Stroke::new(1.0, Color32::from_gray(70));
        let snap = |v: f32| (f64::from(v) / 0.5).round() * 0.5;
        let (gx, gz) = (snap(self.orbit.target.x), snap(self.orbit.target.z));
        for k in -6..=6 {
            let v = f64::from(k) * 0.5;
            self.line(
                &Point3::new(gx + v, 0.0, gz - 3.0),
                &Point3::new(gx + v, 0.0, gz + 3.0),
                grid,
            );
            self.line(
                &Point3::new(gx - 3.0, 0.0, gz + v),
                &Point3::new(gx + 3.0, 0.0, gz + v),
                grid,
            );
        }
    }

    /// The camera's frustum, the point cloud and the scene's own segments.
    fn camera_cloud_and_segments(&self, scene: &Scene) {
        if let Some((c, corners)) = &scene.camera {
            let s = Stroke::new(1.0, Color32::from_rgb(180, 180, 255));
            for k in 0..4 {
                self.line(c, &corners[k], s);
                self.line(&corners[k], &corners[(k + 1) % 4], s);
            }
        }
        for (p, colour) in &scene.cloud {
            if let Some(s) = self.project(p) {
                self.painter.circle_filled(s, 1.5, *colour);
            }
        }
        for (a, b, stroke) in &scene.segments {
            self.line(a, b, *stroke);
        }
    }

    /// The flippable bone nearest `pos` on screen (within 8 px).
    fn near_bone(&self, scene: &Scene, joints: &PerJoint<Point3<f64>>, pos: Pos2) -> Option<Bone> {
        scene
            .flippable
            .iter()
            .filter_map(|b| {
                let p = self.project(&joints[b.parent])?;
                let q = self.project(&joints[b.child])?;
                let d = distance_to_segment(pos, p, q);
                (d < 8.0).then_some((*b, d))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(b, _)| b)
    }

    /// The ghost, the planted feet's rings, the bones (flagged, unsure, hovered) and the joints;
    /// returns the flippable bone clicked.
    fn skeleton(
        &self,
        scene: &Scene,
        joints: &PerJoint<Point3<f64>>,
        response: &egui::Response,
    ) -> Option<Bone> {
        let hovered = response
            .hover_pos()
            .and_then(|pos| self.near_bone(scene, joints, pos));
        if let Some(ghost) = &scene.ghost {
            let grey = Stroke::new(2.0, Color32::from_gray(110));
            for b in Bone::ALL {
                self.line(&ghost[b.parent], &ghost[b.child], grey);
            }
        }
        for ankle in &scene.planted {
            let a = joints[*ankle];
            let ring = |t: f64| Point3::new(a.x + 0.12 * t.cos(), 0.0, a.z + 0.12 * t.sin());
            for k in 0..12 {
                let t = std::f64::consts::TAU * f64::from(k) / 12.0;
                let dt = std::f64::consts::TAU / 12.0;
                self.line(&ring(t), &ring(t + dt), Stroke::new(2.5, PLANTED));
            }
        }
        for b in Bone::ALL {
            let (mut width, colour) = if scene.flagged.contains(&b) {
                (2.5, FLAGGED)
            } else if scene.unsure.contains(&b) {
                (DOUBT_WIDTH, DOUBT)
            } else {
                (2.5, side_colour(b.child))
            };
            if hovered == Some(b) || scene.highlight == Some(b) {
                width += 3.0;
                self.line(
                    &joints[b.parent],
                    &joints[b.child],
                    Stroke::new(width + 4.0, Color32::WHITE),
                );
            }
            self.line(
                &joints[b.parent],
                &joints[b.child],
                Stroke::new(width, colour),
            );
        }
        for (_, p) in joints.iter() {
            if let Some(s) = self.project(p) {
                self.painter.circle_filled(s, 3.0, Color32::WHITE);
            }
        }
        if hovered.is_some() {
            response
                .clone()
                .on_hover_text("click to flip this limb's depth on this frame");
        }
        if response.clicked() {
            return response
                .interact_pointer_pos()
                .and_then(|pos| self.near_bone(scene, joints, pos));
        }
        None
    }

    /// What the view says when it has nothing to draw.
    fn empty_text(&self, scene: &Scene) {
        let text = scene
            .empty_text
            .clone()
            .unwrap_or_else(|| "no 3D skeleton yet: mark, then Track".to_owned());
        let galley = self.painter.layout(
            text,
            egui::FontId::proportional(14.0),
            Color32::GRAY,
            (self.rect.width() - 32.0).clamp(100.0, 640.0),
        );
        let at = self.rect.center() - galley.size() / 2.0;
        self.painter.galley(at, galley, Color32::GRAY);
    }

    /// The notes, wrapped to the view's width (a narrow 3D panel cut them off).
    fn notes(&self, scene: &Scene) {
        let mut y = 8.0;
        for note in &scene.notes {
            let colour = note.colour();
            let galley = self.painter.layout(
                note.text.clone(),
                egui::FontId::proportional(13.0),
                colour,
                (self.rect.width() - 16.0).max(60.0),
            );
            let height = galley.size().y;
            self.painter
                .galley(self.rect.left_top() + Vec2::new(8.0, y), galley, colour);
            y += height + 3.0;
        }
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

    /// Through the video camera: a pinhole camera's frustum corners land on the corners of the
    /// video fitted into the view (as the frame view draws it), its axis at the centre.
    #[test]
    fn the_view_through_the_camera_lies_as_the_video_does() {
        // A 1080×1920 portrait camera, focal 1663 px, at 1.5 m looking along −z, tilted down
        // 10° about its x axis; corners at 0.5 m.
        let (w, h, f) = (1080.0, 1920.0, 1663.0);
        let eye = Point3::new(0.2, 1.5, 3.0);
        let tilt = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), -0.17);
        let ray = |u: f64, v: f64| {
            let d = tilt * Vector3::new((u - w / 2.0) / f, -(v - h / 2.0) / f, -1.0);
            eye + d * 0.5
        };
        let corners = [ray(0.0, 0.0), ray(w, 0.0), ray(w, h), ray(0.0, h)];
        let rect = Rect::from_min_size(Pos2::new(10.0, 20.0), Vec2::new(400.0, 500.0));
        let o = Orbit::through_camera(&eye, &corners, 3.0, rect.aspect_ratio()).unwrap();
        assert!(!o.follow);
        // The video fitted into 400×500: scale min(400/1080, 500/1920) = 500/1920.
        let scale = (400.0 / w).min(500.0 / h) as f32;
        let fitted = Rect::from_center_size(rect.center(), Vec2::new(w as f32, h as f32) * scale);
        let at = |u: f64, v: f64| o.project(rect, &ray(u, v)).unwrap();
        for (got, want) in [
            (at(0.0, 0.0), fitted.left_top()),
            (at(w, h), fitted.right_bottom()),
            (at(w / 2.0, h / 2.0), fitted.center()),
        ] {
            assert!((got - want).length() < 0.5, "{got:?} vs {want:?}");
        }
    }

    /// CIE L*a*b* of an sRGB colour (D65).
    fn lab(c: Color32) -> [f64; 3] {
        let lin = |v: u8| {
            let v = f64::from(v) / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        let (r, g, b) = (lin(c.r()), lin(c.g()), lin(c.b()));
        let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
        let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
        let f = |t: f64| {
            if t > 0.008856 {
                t.cbrt()
            } else {
                7.787 * t + 16.0 / 116.0
            }
        };
        [
            116.0 * f(y) - 16.0,
            500.0 * (f(x) - f(y)),
            200.0 * (f(y) - f(z)),
        ]
    }

    /// The doubt colour stands apart from every other colour of the 3D view by a colour
    /// difference (CIE76 ΔE) of at least 60; the amber it replaced was 24 from the middle's
    /// yellow.
    #[test]
    fn the_doubt_colour_is_far_from_every_limb_colour() {
        let others = [
            side_colour(Joint::LeftElbow),
            side_colour(Joint::RightElbow),
            side_colour(Joint::Chest),
            FLAGGED,
            PLANTED,
            Color32::WHITE,
            Color32::from_rgb(180, 180, 255),
        ];
        let d = |a: Color32, b: Color32| {
            let (p, q) = (lab(a), lab(b));
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        };
        for c in others {
            assert!(d(DOUBT, c) >= 60.0, "{c:?}: ΔE {:.0}", d(DOUBT, c));
        }
        assert!(d(Color32::from_rgb(255, 190, 40), side_colour(Joint::Chest)) < 60.0);
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
