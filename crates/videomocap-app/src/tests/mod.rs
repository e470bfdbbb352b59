//! The app driven as a user drives it (egui_kittest): shared set-up and input helpers, and the
//! tests by subject: `session` (open, mark, correct, track, export, recover), `settings` (the
//! side panel's parameters), `desktop` (quit, the path field, strips, a steady layout).

mod desktop;
mod session;
mod settings;

use super::app::App;
use super::intent::Intent;
use super::state::file_dialogs::PreparedDialogs;
use super::state::{Config, State};
use egui_kittest::Harness;
use nalgebra::Point2;
use std::path::{Path, PathBuf};

/// Steps the app until `done` holds (up to 30 s).
pub fn wait(h: &mut Harness<'_, App>, what: &str, done: impl Fn(&State) -> bool) {
    for _ in 0..6000 {
        h.step();
        if done(h.state().state()) {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    panic!(
        "timed out waiting for {what}; status: {}",
        h.state().state().status()
    );
}

/// A press and release without moving.
pub fn click(h: &mut Harness<'_, App>, pos: egui::Pos2) {
    h.hover_at(pos);
    h.step();
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.step();
    h.step();
}

/// A press, six moves and a release.
pub fn drag(h: &mut Harness<'_, App>, from: egui::Pos2, to: egui::Pos2) {
    h.hover_at(from);
    h.step();
    h.drag_at(from);
    h.step();
    for k in 1..=6 {
        h.hover_at(from + (to - from) * (k as f32 / 6.0));
        h.step();
    }
    h.drop_at(to);
    h.step();
    h.step();
}

/// Where image point `p` is on the screen.
pub fn screen(h: &Harness<'_, App>, p: Point2<f64>) -> egui::Pos2 {
    h.state()
        .frame_view()
        .transform()
        .expect("frame drawn")
        .to_screen(p)
}

/// The app with prepared dialogs and its autosave in `state`, opening `video`.
pub fn harness(
    video: Option<PathBuf>,
    dialogs: &PreparedDialogs,
    state: &Path,
) -> Harness<'static, App> {
    let config = Config {
        dialogs: Box::new(dialogs.clone()),
        autosave_dir: Some(state.to_owned()),
        proxy_dir: Some(state.join("proxies")),
    };
    Harness::builder()
        .with_size(egui::vec2(1400.0, 860.0))
        .build_eframe(move |cc| App::with_config(&cc.egui_ctx, video, config))
}

/// Flips `bone` on the current frame.
pub fn flip(h: &mut Harness<'_, App>, bone: videomocap_core::skeleton::Bone) {
    h.state_mut().state_mut().apply(Intent::Flip(bone));
}
