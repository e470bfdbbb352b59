//! The main window: menu, frame view with the marks drawn, timeline scrubber, status bar.

use super::frame_loader::FrameLoader;
use egui::{Color32, Pos2, Rect, Stroke, Vec2};
use std::path::{Path, PathBuf};
use videomocap::formats::Marks;
use videomocap::skeleton::Bone;
use videomocap::video::{OpenOptions, Video};

/// State of the viewer.
pub struct ViewerApp {
    loader: Option<FrameLoader>,
    /// Frame the user asked for.
    current: usize,
    /// Frame the texture shows.
    shown: Option<usize>,
    texture: Option<egui::TextureHandle>,
    marks: Option<Marks>,
    status: String,
}

impl ViewerApp {
    /// A window, opening `video` if given.
    pub fn new(ctx: &egui::Context, video: Option<PathBuf>) -> ViewerApp {
        let mut app = ViewerApp {
            loader: None,
            current: 0,
            shown: None,
            texture: None,
            marks: None,
            status: "Open a video with File ▸ Open".to_owned(),
        };
        if let Some(path) = video {
            app.open(ctx, &path);
        }
        app
    }

    /// Opens a video or image folder; marks.json beside it is loaded if present.
    pub fn open(&mut self, ctx: &egui::Context, path: &Path) {
        match Video::open(path, &OpenOptions::default()) {
            Ok(video) => {
                let info = video.info().clone();
                self.marks = path
                    .parent()
                    .map(|d| d.join("marks.json"))
                    .filter(|m| m.is_file())
                    .and_then(|m| Marks::load(&m).ok())
                    .filter(|m| m.check_in_frame(path, info.width, info.height).is_ok());
                let loader = FrameLoader::spawn(video, ctx.clone());
                self.current = self
                    .marks
                    .as_ref()
                    .map_or(0, |m| m.frame.min(info.frame_count - 1));
                loader.request(self.current);
                self.loader = Some(loader);
                self.shown = None;
                self.texture = None;
                self.status = format!(
                    "{}   {}×{}   {:.2} fps   {} frames",
                    info.path.file_name().unwrap_or_default().to_string_lossy(),
                    info.width,
                    info.height,
                    info.fps,
                    info.frame_count
                );
            }
            Err(e) => self.status = format!("Cannot open: {e}"),
        }
    }

    /// Number of frames of the open video (0 when none).
    pub fn frame_count(&self) -> usize {
        self.loader.as_ref().map_or(0, |l| l.info().frame_count)
    }

    /// The frame the user is on.
    pub fn current_frame(&self) -> usize {
        self.current
    }

    fn go_to(&mut self, index: usize) {
        let n = self.frame_count();
        if n == 0 {
            return;
        }
        let index = index.min(n - 1);
        if index != self.current {
            self.current = index;
            if let Some(l) = &self.loader {
                l.request(index);
            }
        }
    }

    fn handle_keys(&mut self, ctx: &egui::Context) {
        let (left, right, home, end, shift) = ctx.input(|i| {
            (
                i.key_pressed(egui::Key::ArrowLeft),
                i.key_pressed(egui::Key::ArrowRight),
                i.key_pressed(egui::Key::Home),
                i.key_pressed(egui::Key::End),
                i.modifiers.shift,
            )
        });
        let step = if shift { 10 } else { 1 };
        if left {
            self.go_to(self.current.saturating_sub(step));
        }
        if right {
            self.go_to(self.current + step);
        }
        if home {
            self.go_to(0);
        }
        if end {
            self.go_to(self.frame_count().saturating_sub(1));
        }
    }

    fn receive_frames(&mut self, ctx: &egui::Context) {
        let Some(loader) = &self.loader else { return };
        match loader.poll() {
            Some(Ok(frame)) => {
                let size = [frame.image.width() as usize, frame.image.height() as usize];
                let image = egui::ColorImage::from_rgb(size, frame.image.as_raw());
                self.texture = Some(ctx.load_texture("frame", image, egui::TextureOptions::LINEAR));
                self.shown = Some(frame.index);
            }
            Some(Err(e)) => self.status = format!("{e}"),
            None => {}
        }
    }

    fn frame_view(&self, ui: &mut egui::Ui) {
        let Some(texture) = &self.texture else {
            ui.centered_and_justified(|ui| ui.label(&self.status));
            return;
        };
        let available = ui.available_rect_before_wrap();
        let size = texture.size_vec2();
        let scale = (available.width() / size.x).min(available.height() / size.y);
        let shown = Rect::from_center_size(available.center(), size * scale);
        ui.painter().image(
            texture.id(),
            shown,
            Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
            Color32::WHITE,
        );
        // ui_from_image: pixel centres at integers, so pixel (0,0) covers [-0.5, 0.5].
        let ui_from_image = |x: f64, y: f64| {
            shown.min + Vec2::new((x as f32 + 0.5) * scale, (y as f32 + 0.5) * scale)
        };
        if let Some(marks) = self.marks.as_ref().filter(|m| Some(m.frame) == self.shown) {
            let painter = ui.painter();
            for bone in Bone::ALL {
                let a = marks.points[bone.parent];
                let b = marks.points[bone.child];
                painter.line_segment(
                    [ui_from_image(a.x, a.y), ui_from_image(b.x, b.y)],
                    Stroke::new(2.0, Color32::from_rgb(255, 220, 0)),
                );
            }
            for (_, p) in marks.points.iter() {
                painter.circle_filled(ui_from_image(p.x, p.y), 4.0, Color32::from_rgb(0, 200, 255));
            }
        }
        ui.allocate_rect(available, egui::Sense::hover());
    }
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.receive_frames(&ctx);
        self.handle_keys(&ctx);
        egui::Panel::top("menu").show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.menu_button("File", |ui| {
                    if ui.button("Open…").clicked() {
                        ui.close();
                        if let Some(path) = rfd::FileDialog::new().pick_file() {
                            self.open(&ctx, &path);
                        }
                    }
                });
            });
        });
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.label(&self.status);
        });
        let n = self.frame_count();
        if n > 0 {
            egui::Panel::bottom("timeline").show(ui, |ui| {
                ui.horizontal(|ui| {
                    let mut index = self.current;
                    ui.spacing_mut().slider_width = (ui.available_width() - 160.0).max(100.0);
                    ui.add(egui::Slider::new(&mut index, 0..=n - 1).text("frame"));
                    self.go_to(index);
                    let fps = self.loader.as_ref().map_or(1.0, |l| l.info().fps);
                    ui.label(format!("{:.2} s", self.current_frame() as f64 / fps));
                });
            });
        }
        egui::CentralPanel::default().show(ui, |ui| self.frame_view(ui));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;

    #[test]
    fn arrow_keys_step_through_frames_and_stop_at_the_ends() {
        let dir = tempfile::tempdir().unwrap();
        for i in 0..12 {
            image::RgbImage::from_pixel(8, 6, image::Rgb([i * 20, 0, 0]))
                .save(dir.path().join(format!("f{i}.png")))
                .unwrap();
        }
        let path = dir.path().to_owned();
        let mut harness = Harness::new_eframe(|cc| ViewerApp::new(&cc.egui_ctx, Some(path)));
        harness.run();
        assert_eq!(harness.state().frame_count(), 12);
        harness.key_press(egui::Key::ArrowRight);
        harness.run();
        assert_eq!(harness.state().current_frame(), 1);
        harness.key_press_modifiers(egui::Modifiers::SHIFT, egui::Key::ArrowRight);
        harness.run();
        assert_eq!(harness.state().current_frame(), 11);
        harness.key_press(egui::Key::Home);
        harness.run();
        assert_eq!(harness.state().current_frame(), 0);
    }
}
