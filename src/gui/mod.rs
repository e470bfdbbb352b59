//! The desktop app (eframe/egui): the only place that uses egui. It calls the library and
//! never the CLI. This first version opens a video, scrubs it with frames decoded on a worker
//! thread, and draws the marks of the first frame; marking, tracking, 3D and export arrive with
//! their issues.

mod app;
mod frame_loader;

use std::path::PathBuf;

/// Opens the main window, optionally on a video or image folder.
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
        Box::new(move |cc| Ok(Box::new(app::ViewerApp::new(&cc.egui_ctx, video)))),
    )
    .map_err(|e| anyhow::anyhow!("the desktop app could not start: {e}"))
}
