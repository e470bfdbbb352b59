//! The desktop app (eframe/egui): the only place that uses egui and rfd. It calls the library
//! and never the CLI: every computation (tracking, lifting, exports, projects) is a library call,
//! heavy ones on worker threads.

mod app;
mod autosave;
mod dialogs;
mod frame_loader;
mod frame_view;
mod jobs;
mod lift_settings;
mod timeline;
mod view3d;
mod volume_view;

use std::path::PathBuf;

/// Opens the main window, optionally on a video, an image folder or a project file.
pub fn run(video: Option<PathBuf>) -> anyhow::Result<()> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("videomocap")
            .with_inner_size([1280.0, 800.0]),
        ..Default::default()
    };
    eframe::run_native(
        "videomocap",
        options,
        Box::new(move |cc| Ok(Box::new(app::App::new(&cc.egui_ctx, video)))),
    )
    .map_err(|e| anyhow::anyhow!("the desktop app could not start: {e}"))
}
