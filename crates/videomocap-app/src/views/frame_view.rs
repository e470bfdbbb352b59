//! The video frame with the skeleton drawn on it: fit, zoom at the cursor (wheel), pan (middle
//! button, or drag with Space held), joint names on hover, click to place a mark, drag a joint
//! to correct it.

use crate::state::layout::FrameZoom;
use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2};
use nalgebra::Point2;
use videomocap_core::formats::{PointSource, TrackedPoint};
use videomocap_core::skeleton::{Bone, Joint, PerJoint};

/// How a drawn joint was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PointState {
    /// Placed by hand on this frame.
    Key,
    /// Tracked with good reliability.
    Tracked,
    /// Tracked with low reliability.
    Weak,
    /// Filled in across an occlusion.
    Interpolated,
    /// Outside the image: the tracker's estimate.
    OffFrame,
    /// In a weak run too long to fill: the tracker's guess.
    Lost,
}

impl PointState {
    /// The state of a tracked point that was not placed by hand; `weak` is the tracker's
    /// reliability threshold.
    pub(crate) fn of(p: &TrackedPoint, weak: f32) -> PointState {
        match p.source {
            PointSource::Interpolated => PointState::Interpolated,
            PointSource::OffFrame => PointState::OffFrame,
            PointSource::Lost => PointState::Lost,
            PointSource::Tracked if p.confidence < weak => PointState::Weak,
            PointSource::Tracked => PointState::Tracked,
        }
    }

    /// The state in words (the timeline's hover).
    pub(crate) fn word(self) -> &'static str {
        match self {
            PointState::Key => "placed by you (white)",
            PointState::Tracked => "tracked (green)",
            PointState::Weak => "weak: the tracker is unsure (orange)",
            PointState::Interpolated => "filled in between sound frames (blue)",
            PointState::OffFrame => "off the frame: an estimate (purple)",
            PointState::Lost => "lost: a guess (red)",
        }
    }

    /// Colour used in the frame view and the timeline.
    pub(crate) fn colour(self) -> Color32 {
        match self {
            PointState::Key => Color32::WHITE,
            PointState::Tracked => Color32::from_rgb(60, 200, 90),
            PointState::Weak => Color32::from_rgb(240, 150, 30),
            PointState::Interpolated => Color32::from_rgb(80, 140, 255),
            PointState::OffFrame => Color32::from_rgb(170, 110, 230),
            PointState::Lost => Color32::from_rgb(220, 50, 50),
        }
    }
}

/// What to draw on the frame.
pub(crate) struct Overlay {
    /// Each joint's position and state, when known on this frame.
    pub points: PerJoint<Option<(Point2<f64>, PointState)>>,
    /// The joint the marking guide asks for next.
    pub asking: Option<Joint>,
    /// Where that joint lies by its definition, from the joints placed (drawn as a cross).
    pub hint: Option<Point2<f64>>,
}

/// What the user did in the view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum ViewEvent {
    /// A click (no drag) at this image position.
    Click(Point2<f64>),
    /// A joint dragged to a new image position (on release).
    Moved(Joint, Point2<f64>),
}

/// Maps image pixels (centres at integers) to the screen and back.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Transform {
    centre: Pos2,
    image_centre: Vec2,
    scale: f32,
}

impl Transform {
    /// Screen position of an image point.
    pub(crate) fn to_screen(self, p: Point2<f64>) -> Pos2 {
        self.centre + (Vec2::new(p.x as f32, p.y as f32) - self.image_centre) * self.scale
    }

    /// Image point under a screen position.
    pub(crate) fn to_image(self, s: Pos2) -> Point2<f64> {
        let v = (s - self.centre) / self.scale + self.image_centre;
        Point2::new(f64::from(v.x), f64::from(v.y))
    }
}

/// A joint held with the primary button: where it was pressed, where it is now, and whether
/// the pointer has moved since (a drag starts at the first movement, however quick).
#[derive(Debug, Clone, Copy)]
struct Grab {
    joint: Joint,
    pressed_at: Pos2,
    at: Point2<f64>,
    moved: bool,
}

/// Zoom and pan of the frame view, and a joint being dragged.
#[derive(Debug, Clone, Default)]
pub(crate) struct FrameView {
    /// 1 = the frame fits the view.
    zoom: f32,
    /// Image point at the view's centre (`None` = the image centre).
    centre: Option<Vec2>,
    grab: Option<Grab>,
    last: Option<Transform>,
}

/// The zoom's range: a quarter of the fitted frame to 40 times it.
const MIN_ZOOM: f32 = 0.25;
/// See [`MIN_ZOOM`].
const MAX_ZOOM: f32 = 40.0;

/// Pick radius for joints, screen points.
const PICK_PX: f32 = 10.0;

/// A held joint follows the pointer once it has moved this far (screen points), however soon
/// after the press: a hand's jitter on a click stays below it, egui's own drag threshold (6
/// points, or a long press) missed quick short corrections.
const DRAG_START_PX: f32 = 2.0;

impl FrameView {
    /// Back to fitting the whole frame.
    pub(crate) fn fit(&mut self) {
        self.zoom = 1.0;
        self.centre = None;
    }

    /// The zoom and the image point at the view's centre (kept across restarts per video).
    pub(crate) fn zoom_state(&self) -> FrameZoom {
        FrameZoom {
            zoom: if self.zoom > 0.0 { self.zoom } else { 1.0 },
            centre: self.centre.map(|c| [c.x, c.y]),
        }
    }

    /// Zooms as `z` says (a zoom kept from an earlier session).
    pub(crate) fn set_zoom_state(&mut self, z: FrameZoom) {
        self.zoom = if z.zoom.is_finite() {
            z.zoom.clamp(MIN_ZOOM, MAX_ZOOM)
        } else {
            1.0
        };
        self.centre = z
            .centre
            .filter(|c| c.iter().all(|v| v.is_finite()))
            .map(|c| Vec2::new(c[0], c[1]));
    }

    /// The transform of the last frame drawn (tests use it to click on joints).
    #[cfg(test)]
    pub(crate) fn transform(&self) -> Option<Transform> {
        self.last
    }

    fn transform_for(&self, rect: Rect, size: Vec2) -> Transform {
        let zoom = if self.zoom > 0.0 { self.zoom } else { 1.0 };
        let fit = (rect.width() / size.x).min(rect.height() / size.y);
        Transform {
            centre: rect.center(),
            image_centre: self.centre.unwrap_or(size * 0.5 - Vec2::splat(0.5)),
            scale: fit * zoom,
        }
    }

    /// Draws the frame and the overlay; returns what the user did. `size` is the frame's size
    /// in pixels, which the texture is stretched over (a seek preview is smaller).
    pub(crate) fn show(
        &mut self,
        ui: &mut egui::Ui,
        texture: &egui::TextureHandle,
        size: Vec2,
        overlay: &Overlay,
    ) -> Option<ViewEvent> {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let panning = self.zoom_and_pan(ui, &response, rect, size);
        let t = self.transform_for(rect, size);
        self.last = Some(t);
        let painter = ui.painter_at(rect);
        let image_rect = Rect::from_min_max(
            t.to_screen(Point2::new(-0.5, -0.5)),
            t.to_screen(Point2::new(
                f64::from(size.x) - 0.5,
                f64::from(size.y) - 0.5,
            )),
        );
        painter.image(
            texture.id(),
            image_rect,
            Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
            Color32::WHITE,
        );
        let event = self.grab_or_click(ui, &response, &t, overlay, panning);
        self.draw_overlay(&painter, &response, &t, overlay);
        event
    }

    /// Zooms at the cursor (the image point under it stays put) and pans (middle drag, or
    /// Space with a left drag); returns whether the view is panning.
    fn zoom_and_pan(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        rect: Rect,
        size: Vec2,
    ) -> bool {
        let space = ui.input(|i| i.key_down(egui::Key::Space));
        if let Some(hover) = response.hover_pos() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let t = self.transform_for(rect, size);
                let under = t.to_image(hover);
                self.zoom =
                    (self.zoom.max(1e-3) * (scroll * 0.002).exp()).clamp(MIN_ZOOM, MAX_ZOOM);
                let scale = self.transform_for(rect, size).scale;
                let p = Vec2::new(under.x as f32, under.y as f32);
                self.centre = Some(p - (hover - rect.center()) / scale);
            }
        }
        let t = self.transform_for(rect, size);
        let panning = response.dragged_by(egui::PointerButton::Middle)
            || (space && response.dragged_by(egui::PointerButton::Primary));
        if panning {
            let c = self.centre.unwrap_or(t.image_centre);
            self.centre = Some(c - response.drag_delta() / t.scale);
        }
        panning
    }

    /// A joint grabbed, dragged and let go (moved), or a click on the image.
    fn grab_or_click(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        t: &Transform,
        overlay: &Overlay,
        panning: bool,
    ) -> Option<ViewEvent> {
        let (pressed, down, released, pointer) = ui.input(|i| {
            (
                i.pointer.primary_pressed(),
                i.pointer.primary_down(),
                i.pointer.primary_released(),
                i.pointer.interact_pos(),
            )
        });
        if !panning && pressed && response.hovered() {
            self.grab = pointer.and_then(|pos| {
                nearest_joint(overlay, t, pos).map(|joint| Grab {
                    joint,
                    pressed_at: pos,
                    at: t.to_image(pos),
                    moved: false,
                })
            });
        }
        if let (Some(g), Some(pos)) = (&mut self.grab, pointer)
            && (down || released)
            && (g.moved || pos.distance(g.pressed_at) >= DRAG_START_PX)
        {
            g.moved = true;
            g.at = t.to_image(pos);
        }
        if !released {
            return None;
        }
        match self.grab.take() {
            Some(g) if g.moved => Some(ViewEvent::Moved(g.joint, g.at)),
            _ => {
                if !panning
                    && response.clicked()
                    && let Some(pos) = response.interact_pointer_pos()
                {
                    Some(ViewEvent::Click(t.to_image(pos)))
                } else {
                    None
                }
            }
        }
    }

    /// The skeleton (bones, then joints; the dragged one where it is being dragged), the hovered
    /// joint's name, the hint's cross and what the marking asks for.
    fn draw_overlay(
        &self,
        painter: &egui::Painter,
        response: &egui::Response,
        t: &Transform,
        overlay: &Overlay,
    ) {
        let at = |j: Joint| -> Option<(Point2<f64>, PointState)> {
            match self.grab {
                Some(g) if g.joint == j && g.moved => Some((g.at, PointState::Key)),
                _ => overlay.points[j],
            }
        };
        for bone in Bone::ALL {
            if let (Some((a, _)), Some((b, _))) = (at(bone.parent), at(bone.child)) {
                painter.line_segment(
                    [t.to_screen(a), t.to_screen(b)],
                    Stroke::new(2.0, side_colour(bone.child)),
                );
            }
        }
        let hovered = response
            .hover_pos()
            .and_then(|pos| nearest_joint(overlay, t, pos));
        for j in Joint::ALL {
            if let Some((p, state)) = at(j) {
                let s = t.to_screen(p);
                painter.circle_filled(s, 4.5, state.colour());
                painter.circle_stroke(s, 4.5, Stroke::new(1.0, Color32::BLACK));
                if state == PointState::Key {
                    painter.circle_stroke(s, 7.5, Stroke::new(1.5, Color32::WHITE));
                }
                if hovered == Some(j) {
                    painter.text(
                        s + Vec2::new(10.0, -10.0),
                        egui::Align2::LEFT_BOTTOM,
                        super::marking::joint_words(j),
                        egui::FontId::proportional(14.0),
                        Color32::WHITE,
                    );
                }
            }
        }
        if let Some(h) = overlay.hint {
            let s = t.to_screen(h);
            let stroke = Stroke::new(2.0, Color32::YELLOW);
            for d in [Vec2::new(7.0, 7.0), Vec2::new(7.0, -7.0)] {
                painter.line_segment([s - d, s + d], stroke);
            }
        }
        if let (Some(j), Some(pos)) = (overlay.asking, response.hover_pos()) {
            painter.text(
                pos + Vec2::new(14.0, 14.0),
                egui::Align2::LEFT_TOP,
                format!("click: {}", super::marking::joint_words(j)),
                egui::FontId::proportional(14.0),
                Color32::YELLOW,
            );
        }
    }
}

/// The overlay's joint nearest `pos` on screen, within [`PICK_PX`].
fn nearest_joint(overlay: &Overlay, t: &Transform, pos: Pos2) -> Option<Joint> {
    Joint::ALL
        .into_iter()
        .filter_map(|j| {
            let (p, _) = overlay.points[j]?;
            let d = t.to_screen(p).distance(pos);
            (d <= PICK_PX).then_some((j, d))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(j, _)| j)
}

/// Bone colour by the side of the body (subject's left cyan, right orange, middle yellow).
pub(crate) fn side_colour(j: Joint) -> Color32 {
    let name = j.name();
    if name.starts_with("left") {
        Color32::from_rgb(0, 200, 255)
    } else if name.starts_with("right") {
        Color32::from_rgb(255, 120, 40)
    } else {
        Color32::from_rgb(255, 220, 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;

    /// The view over a 100×100 grey frame with the left wrist at (50, 50), and what it reported.
    struct Bench {
        view: FrameView,
        texture: Option<egui::TextureHandle>,
        events: Vec<ViewEvent>,
    }

    fn bench() -> Harness<'static, Bench> {
        Harness::new_ui_state(
            |ui, b: &mut Bench| {
                let texture = b
                    .texture
                    .get_or_insert_with(|| {
                        ui.ctx().load_texture(
                            "frame",
                            egui::ColorImage::new([100, 100], vec![Color32::GRAY; 100 * 100]),
                            egui::TextureOptions::LINEAR,
                        )
                    })
                    .clone();
                let mut points = PerJoint::from_fn(|_| None);
                points[Joint::LeftWrist] = Some((Point2::new(50.0, 50.0), PointState::Tracked));
                let overlay = Overlay {
                    points,
                    asking: None,
                    hint: None,
                };
                if let Some(e) = b.view.show(ui, &texture, Vec2::new(100.0, 100.0), &overlay) {
                    b.events.push(e);
                }
            },
            Bench {
                view: FrameView::default(),
                texture: None,
                events: Vec::new(),
            },
        )
    }

    /// A correction of a few points done at once (press, one small move, release on the next
    /// frames) is a drag of the joint, not a click.
    #[test]
    fn a_quick_short_drag_moves_the_joint() {
        let mut h = bench();
        h.run();
        let t = h.state().view.transform().expect("drawn");
        let from = t.to_screen(Point2::new(50.0, 50.0));
        h.hover_at(from);
        h.step();
        h.drag_at(from);
        h.step();
        h.hover_at(from + Vec2::new(3.0, 0.0));
        h.step();
        h.drop_at(from + Vec2::new(3.0, 0.0));
        h.step();
        let events = &h.state().events;
        assert_eq!(events.len(), 1, "{events:?}");
        let ViewEvent::Moved(j, p) = events[0] else {
            panic!("not a move: {events:?}");
        };
        assert_eq!(j, Joint::LeftWrist);
        let want = t.to_image(from + Vec2::new(3.0, 0.0));
        assert!((p - want).norm() < 1e-6, "{p} vs {want}");
    }

    /// A press and release in place is a click, not a move.
    #[test]
    fn a_press_and_release_in_place_is_a_click() {
        let mut h = bench();
        h.run();
        let t = h.state().view.transform().expect("drawn");
        let at = t.to_screen(Point2::new(50.0, 50.0));
        h.hover_at(at);
        h.step();
        h.drag_at(at);
        h.step();
        h.drop_at(at);
        h.step();
        h.step();
        assert!(
            matches!(h.state().events[..], [ViewEvent::Click(_)]),
            "{:?}",
            h.state().events
        );
    }
}
