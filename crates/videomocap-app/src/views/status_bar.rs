//! The status bar at the bottom: the status line (what was done, written, or why not) on the
//! left; on the right the running job's progress with Cancel, else the seek proxy's state. It
//! keeps one height whatever it shows, so the frame above never moves.

use crate::intent::Intent;
use crate::state::State;
use crate::state::frame_loader::ProxyStatus;

/// The bar's height, points (the progress bar and the Cancel button fit in it).
pub(crate) const HEIGHT: f32 = 26.0;

/// Draws the bar; Cancel goes to `out`.
pub(crate) fn show(ui: &mut egui::Ui, state: &State, out: &mut Vec<Intent>) {
    ui.horizontal_centered(|ui| {
        ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
            progress(ui, state, out);
            seek_status(ui, state);
            ui.with_layout(egui::Layout::left_to_right(egui::Align::Center), |ui| {
                ui.add(egui::Label::new(state.status()).truncate())
                    .on_hover_text(state.status());
            });
        });
    });
}

/// The running job: what, how far, how fast, how long left, and Cancel.
fn progress(ui: &mut egui::Ui, state: &State, out: &mut Vec<Intent>) {
    let Some(job) = state.job() else { return };
    if ui.button("Cancel").clicked() {
        out.push(Intent::Cancel);
    }
    let (share, _, _) = job.rate();
    let text = job.progress_text();
    ui.add(
        egui::ProgressBar::new(share)
            .desired_width(360.0)
            .desired_height(HEIGHT - 8.0)
            .text(text),
    );
}

/// The right end of the status bar: the seek proxy's progress, and whether the frame shown
/// is its preview.
fn seek_status(ui: &mut egui::Ui, state: &State) {
    let Some(loader) = state.loader() else {
        return;
    };
    let gap = loader.info().map_or(0, |i| i.keyframe_interval);
    match loader.proxy() {
        Some(ProxyStatus::Building(done, total)) => {
            let f = *done as f32 / (*total).max(1) as f32;
            let paused = if state.busy() {
                " (paused while tracking)"
            } else {
                ""
            };
            ui.add(
                egui::ProgressBar::new(f)
                    .desired_width(140.0)
                    .text(format!("fast seeking {:.0} %{paused}", f * 100.0)),
            )
            .on_hover_text(format!(
                "Keyframes in this video are up to {gap} frames apart, so a seek decodes up \
                 to {gap} frames. A small copy with a keyframe every {} frames is being made \
                 once (kept in the cache folder) to show any frame at once; the full frame \
                 follows. Tracking always reads the video itself.",
                videomocap_core::video::proxy::PROXY_GOP
            ));
        }
        Some(ProxyStatus::Ready) => {
            let text = if state.preview() {
                "preview (full frame decoding)"
            } else {
                "fast seeking"
            };
            ui.weak(text).on_hover_text(format!(
                "Keyframes in this video are up to {gap} frames apart: a seek first shows \
                 the frame from a small copy, then the full frame."
            ));
        }
        _ => {}
    }
}
