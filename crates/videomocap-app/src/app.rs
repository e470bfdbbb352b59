//! The window's frame loop: take in what the workers sent, read the keyboard, lay out the views
//! (menu bar, status bar, timeline, side panel, 3D view, frame view, windows), then carry out
//! the intents they returned. The state lives in [`State`]; this shell keeps only what belongs
//! to the screen (the frame view's zoom, the 3D view's orbit, the guide's rendering).

use super::intent::Intent;
use super::state::layout::{DEFAULT_SIDE_PX, DEFAULT_VIEW3D_PX, Layout};
use super::state::{Config, State};
use super::views::frame_view::{FrameView, Overlay, ViewEvent};
use super::views::keys::SpaceKey;
use super::views::view3d::{self, Orbit};
use super::views::{keys, menu, scene, side_panel, status_bar, timeline, windows};
use std::path::PathBuf;

/// The share of the frame's height the timeline's strips may take by default: a 4:3 clip in a
/// 1440 × 900 window loses 2 % to them and shows them; a portrait clip would lose a fifth and
/// gets one folded strip.
const STRIPS_MAY_TAKE: f32 = 0.1;

/// The desktop app.
pub(crate) struct App {
    state: State,
    frame_view: FrameView,
    orbit: Orbit,
    space: SpaceKey,
    guide: egui_commonmark::CommonMarkCache,
    /// How many times something was opened when the views last reset to it.
    opened: u64,
    /// The window was fitted to its screen (once, on the first frame that knows the screen).
    fitted: bool,
    /// The 3D view was aimed from the video camera since the last open.
    aimed: bool,
    /// The panels' widths and the zoom per video, kept across restarts.
    layout: Layout,
    /// The layout changed since it was last written.
    layout_changed: bool,
    /// Where the 3D view's panel was drawn last (tests drag its edge).
    view3d_rect: egui::Rect,
    /// Where the 3D view drew its scene last.
    view3d_canvas: egui::Rect,
    /// Where the frame view's panel was drawn last, and whether the timeline's strips were
    /// unfolded then (what decides the strips' default).
    central: (egui::Rect, bool),
}

impl App {
    /// A window with the desktop's dialogs and autosave, opening `path` (a video, an image
    /// folder or a project) if given.
    pub(crate) fn new(ctx: &egui::Context, path: Option<PathBuf>) -> App {
        App::with_config(ctx, path, Config::default())
    }

    /// A window with the given dialogs and autosave directory.
    pub(crate) fn with_config(ctx: &egui::Context, path: Option<PathBuf>, config: Config) -> App {
        let mut state = State::new(ctx, config);
        if let Some(p) = path {
            state.apply(Intent::Open(p));
        }
        let layout = Layout::load(state.state_dir());
        App {
            state,
            frame_view: FrameView::default(),
            orbit: Orbit::default(),
            space: SpaceKey::default(),
            guide: egui_commonmark::CommonMarkCache::default(),
            opened: 0,
            fitted: false,
            aimed: false,
            layout,
            layout_changed: false,
            view3d_rect: egui::Rect::NOTHING,
            view3d_canvas: egui::Rect::NOTHING,
            central: (egui::Rect::NOTHING, true),
        }
    }

    /// The layout kept across restarts (tests).
    #[cfg(test)]
    pub(crate) fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Where the 3D view's panel was drawn last.
    #[cfg(test)]
    pub(crate) fn view3d_rect(&self) -> egui::Rect {
        self.view3d_rect
    }

    /// Where the 3D view drew its scene last.
    #[cfg(test)]
    pub(crate) fn view3d_canvas(&self) -> egui::Rect {
        self.view3d_canvas
    }

    /// The video the frame view shows (its zoom is kept per video).
    fn video(&self) -> Option<PathBuf> {
        self.state.project().map(|p| p.video.clone())
    }

    /// Keeps a panel's width once the user has let go of it.
    fn keep_width(
        &mut self,
        ctx: &egui::Context,
        which: fn(&mut Layout) -> &mut Option<f32>,
        px: f32,
    ) {
        if ctx.input(|i| i.pointer.any_down()) {
            return;
        }
        let kept = which(&mut self.layout);
        if kept.is_none_or(|k| (k - px).abs() > 0.5) {
            *kept = Some(px);
            self.layout_changed = true;
        }
    }

    /// Keeps the frame view's zoom on this video, and writes the layout once nothing is held.
    fn keep_layout(&mut self, ctx: &egui::Context) {
        if let Some(video) = self.video()
            && self.state.texture().is_some()
            && self.layout.set_zoom(&video, self.frame_view.zoom_state())
        {
            self.layout_changed = true;
        }
        if self.layout_changed && !ctx.input(|i| i.pointer.any_down()) {
            self.layout.save(self.state.state_dir());
            self.layout_changed = false;
        }
    }

    /// Whether the timeline shows a strip per joint: the user's choice if they made one, else
    /// only where the strips take little height the video needs: the frame, fitted to the
    /// panel, keeps at least [`STRIPS_MAY_TAKE`]'s complement of its height with them (a
    /// landscape clip beside the panels). A portrait clip keeps the height: one folded strip.
    fn each_joint(&self) -> bool {
        if let Some(choice) = self.layout.each_joint {
            return choice;
        }
        let (central, unfolded) = self.central;
        let Some(info) = self.state.video_info().filter(|i| i.width > 0) else {
            return true;
        };
        if central == egui::Rect::NOTHING {
            return true;
        }
        let extra = timeline::UNFOLDED_EXTRA_H;
        let folded_room = central.height() + if unfolded { extra } else { 0.0 };
        let fitted = central.width() * info.height as f32 / info.width as f32;
        let folded = fitted.min(folded_room);
        let with_strips = fitted.min(folded_room - extra);
        with_strips >= (1.0 - STRIPS_MAY_TAKE) * folded
    }

    /// Whether the timeline showed a strip per joint last (tests).
    #[cfg(test)]
    pub(crate) fn timeline_unfolded(&self) -> bool {
        self.central.1
    }

    /// Where the frame view's panel was drawn last (tests).
    #[cfg(test)]
    pub(crate) fn central_rect(&self) -> egui::Rect {
        self.central.0
    }

    /// The app's state (tests read it).
    #[cfg(test)]
    pub(crate) fn state(&self) -> &State {
        &self.state
    }

    /// The app's state, to act on it directly (tests).
    #[cfg(test)]
    pub(crate) fn state_mut(&mut self) -> &mut State {
        &mut self.state
    }

    /// The frame view's mapping (tests click through it).
    #[cfg(test)]
    pub(crate) fn frame_view(&self) -> &FrameView {
        &self.frame_view
    }

    /// The 3D view's orbit.
    #[cfg(test)]
    pub(crate) fn orbit(&self) -> Orbit {
        self.orbit
    }

    /// Files dropped on the window open like File ▸ Open.
    fn dropped(ctx: &egui::Context, out: &mut Vec<Intent>) {
        let dropped = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_owned())
                .find(|p| !p.as_os_str().is_empty())
        });
        if let Some(p) = dropped {
            out.push(Intent::Open(p));
        }
    }

    /// The 3D view with its header (reset, the view through the camera, follow) and the
    /// limbs whose depth is unsure, each a link that flips it; a clicked limb asks for a flip.
    fn view3d(&mut self, ui: &mut egui::Ui, out: &mut Vec<Intent>) {
        let mut scene = scene::scene(&self.state);
        // The first skeleton after opening is seen from the video camera, the floor below.
        if !self.aimed
            && let (Some((eye, _)), Some(joints)) = (&scene.camera, &scene.joints)
        {
            let p = joints[videomocap_core::skeleton::Joint::Pelvis];
            self.orbit =
                Orbit::from_camera(eye, nalgebra::Vector3::new(p.x as f32, 0.9, p.z as f32));
            self.aimed = true;
        }
        let camera_eye = scene.camera.map(|(eye, _)| eye);
        let mut through_camera = false;
        // Wrapped: a narrow 3D view keeps its width (its buttons go on a second line).
        ui.horizontal_wrapped(|ui| {
            ui.label(if self.state.volume().is_some() {
                "3D (point volumes)"
            } else {
                "3D"
            });
            if ui.button("Reset view").clicked() {
                self.orbit = match camera_eye {
                    Some(eye) => Orbit::from_camera(&eye, self.orbit.target),
                    None => Orbit::default(),
                };
            }
            through_camera = ui
                .add_enabled(
                    scene.camera.is_some(),
                    egui::Button::new("View from the camera"),
                )
                .on_hover_text(
                    "Look through the video camera, with its field of view: the skeleton lies \
                     as it does over the video (drag to turn away, Reset view to come back)",
                )
                .clicked();
            ui.checkbox(&mut self.orbit.follow, "Follow").on_hover_text(
                "Keep the view on the subject as they move across the floor (panning turns it off)",
            );
        });
        if !scene.unsure.is_empty() {
            ui.horizontal_wrapped(|ui| {
                ui.label(egui::RichText::new("Depth unsure:").color(view3d::DOUBT));
                for &bone in &scene.unsure {
                    let link = ui.link(bone.plain_name()).on_hover_text(format!(
                        "Flip the {}'s depth on this frame and lift again (Ctrl+Z undoes)",
                        bone.plain_name()
                    ));
                    if link.hovered() {
                        scene.highlight = Some(bone);
                    }
                    if link.clicked() {
                        out.push(Intent::Flip(bone));
                    }
                }
            });
        }
        if through_camera && let Some((eye, corners)) = &scene.camera {
            let rect = ui.available_rect_before_wrap();
            // Turn about the subject's depth along the axis (3 m without a skeleton).
            let axis = (corners
                .iter()
                .map(|c| c.coords)
                .sum::<nalgebra::Vector3<f64>>()
                / 4.0
                - eye.coords)
                .normalize();
            let depth = scene.joints.as_ref().map_or(3.0, |j| {
                (j[videomocap_core::skeleton::Joint::Pelvis] - eye).dot(&axis)
            });
            if let Some(o) = Orbit::through_camera(eye, corners, depth, rect.aspect_ratio()) {
                self.orbit = o;
            }
        }
        self.view3d_canvas = ui.available_rect_before_wrap();
        if let Some(bone) = self.orbit.show(ui, &scene) {
            out.push(Intent::Flip(bone));
        }
    }

    /// The frame with the skeleton on it; clicks and drags become intents.
    fn frame(&mut self, ui: &mut egui::Ui, out: &mut Vec<Intent>) {
        let Some(texture) = self.state.texture() else {
            ui.centered_and_justified(|ui| ui.label(self.state.status()));
            return;
        };
        let current = self.state.current_frame();
        let overlay = Overlay {
            points: self.state.points(current),
            asking: self.state.asking().map(|(_, j)| j),
            hint: self.state.marking_hint(),
        };
        let size = self.state.video_info().map_or_else(
            || texture.size_vec2(),
            |i| egui::vec2(i.width as f32, i.height as f32),
        );
        match self.frame_view.show(ui, texture, size, &overlay) {
            Some(ViewEvent::Click(p)) => out.push(Intent::Click(p)),
            Some(ViewEvent::Moved(j, p)) => out.push(Intent::Moved(j, p)),
            None => {}
        }
    }
}

impl eframe::App for App {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        let mut out = Vec::new();
        App::dropped(&ctx, &mut out);
        self.state.receive();
        if self.state.opened() != self.opened {
            self.opened = self.state.opened();
            self.frame_view.fit();
            if let Some(zoom) = self.video().and_then(|v| self.layout.zoom_of(&v)) {
                self.frame_view.set_zoom_state(zoom);
            }
            self.orbit = Orbit::default();
            self.aimed = false;
        }
        if !self.fitted {
            self.fitted = fit_to_screen(&ctx);
        }
        keys::read(&ctx, &self.state, &mut self.space, &mut out);
        // The window's close button asks like File ▸ Quit.
        if ctx.input(|i| i.viewport().close_requested()) && !self.state.quitting() {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            out.push(Intent::Quit);
        }
        egui::Panel::top("menu").show(ui, |ui| menu::show(ui, &self.state, &mut out));
        // Fixed height: the job's progress shows here without moving the frame above.
        egui::Panel::bottom("status")
            .exact_size(status_bar::HEIGHT)
            .show(ui, |ui| status_bar::show(ui, &self.state, &mut out));
        let each_joint = self.each_joint();
        if self.state.frame_count() > 0 {
            let fold = egui::Panel::bottom("timeline")
                .show(ui, |ui| {
                    timeline::show(ui, &self.state, each_joint, &mut out)
                })
                .inner;
            if fold {
                self.layout.each_joint = Some(!each_joint);
                self.layout_changed = true;
            }
        }
        let side = egui::Panel::left("side")
            .resizable(true)
            .default_size(self.layout.side_px.unwrap_or(DEFAULT_SIDE_PX))
            .show(ui, |ui| {
                egui::ScrollArea::vertical()
                    .show(ui, |ui| side_panel::show(ui, &self.state, &mut out));
            });
        self.keep_width(&ctx, |l| &mut l.side_px, side.response.rect.width());
        if self.state.volume().is_some() {
            // Volume mode: the 3D viewport fills the window.
            egui::CentralPanel::default().show(ui, |ui| self.view3d(ui, &mut out));
        } else {
            // Resizable, its width kept across restarts; narrower by default than it was, so
            // the video gets the room.
            let view3d = egui::Panel::right("3d")
                .resizable(true)
                .min_size(160.0)
                .default_size(self.layout.view3d_px.unwrap_or(DEFAULT_VIEW3D_PX))
                .show(ui, |ui| self.view3d(ui, &mut out));
            self.view3d_rect = view3d.response.rect;
            self.keep_width(&ctx, |l| &mut l.view3d_px, view3d.response.rect.width());
            let central = egui::CentralPanel::default().show(ui, |ui| self.frame(ui, &mut out));
            self.central = (
                central.response.rect,
                each_joint && self.state.strips().is_some(),
            );
        }
        self.keep_layout(&ctx);
        windows::show(&ctx, &self.state, &mut self.guide, &mut out);
        for intent in out {
            self.state.apply(intent);
        }
        if self.state.quitting() {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        if self.state.playing() {
            self.state.play(f64::from(ctx.input(|i| i.stable_dt)));
            ctx.request_repaint();
        }
    }
}

/// Where no window manager maximises the window (the viewport asks it to), sizes it to most of
/// its screen, centred; `false` until the screen's size is known.
fn fit_to_screen(ctx: &egui::Context) -> bool {
    let (monitor, maximized) = ctx.input(|i| (i.viewport().monitor_size, i.viewport().maximized));
    let Some(monitor) = monitor else {
        return false;
    };
    if maximized != Some(true) {
        let size = fitted_size(monitor);
        ctx.send_viewport_cmd(egui::ViewportCommand::InnerSize(size));
        ctx.send_viewport_cmd(egui::ViewportCommand::OuterPosition(
            ((monitor - size) / 2.0).to_pos2(),
        ));
    }
    true
}

/// The window's size on a screen of `monitor` points: nine tenths of it, at least the panels'
/// minimum (960×600).
pub(crate) fn fitted_size(monitor: egui::Vec2) -> egui::Vec2 {
    (monitor * 0.9).max(egui::vec2(960.0, 600.0))
}
