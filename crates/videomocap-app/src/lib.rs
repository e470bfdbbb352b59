//! The desktop app (eframe/egui): the only place that uses egui and rfd. It calls the library
//! and never the CLI: every computation (tracking, lifting, exports, projects) is a library call,
//! heavy ones on worker threads.
//!
//! - `state`: what the app knows and does, in plain Rust (open, edit, track, lift, export,
//!   save, quit), with the workers it owns (frame loader, jobs, autosave, file dialogs).
//! - `views`: the menu bar, side panel, timeline, frame view, 3D view, status bar and windows;
//!   each reads the state and returns `intent::Intent`s.
//! - `app`: the frame loop joining the two.

mod app;
mod intent;
mod state;
mod views;

use std::path::PathBuf;

/// Opens the main window, optionally on a video, an image folder or a project file.
pub fn run(video: Option<PathBuf>) -> anyhow::Result<()> {
    let options = eframe::NativeOptions {
        viewport: viewport(),
        ..Default::default()
    };
    eframe::run_native(
        "videomocap",
        options,
        Box::new(move |cc| Ok(Box::new(app::App::new(&cc.egui_ctx, video)))),
    )
    .map_err(|e| anyhow::anyhow!("the desktop app could not start: {e}"))
}

/// The main window: maximised, so it fills the screen whatever its size (a fixed 1280×800
/// overflowed a laptop's screen and left a large one mostly empty); 1280×800 when un-maximised,
/// never smaller than the panels need.
fn viewport() -> egui::ViewportBuilder {
    egui::ViewportBuilder::default()
        .with_title("videomocap")
        .with_inner_size([1280.0, 800.0])
        .with_min_inner_size([960.0, 600.0])
        .with_maximized(true)
}

#[cfg(test)]
mod tests;
