//! The app's windows over the main view: "recover unsaved work?", "save changes?" (before
//! opening something else or quitting), the path field shown when no file dialog can be, the
//! shortcuts (F1) and the user guide (Help ▸ User guide).

use crate::intent::Intent;
use crate::state::{Leave, SaveAnswer, State};
use std::path::PathBuf;

/// The user guide, built into the app.
const GUIDE: &str = include_str!("../../../../docs/guide.md");

/// The guide as the window shows it: without its screenshot (the app draws no images) and
/// with "▸", which egui's fonts lack, as ">".
static GUIDE_SHOWN: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    let mut text = GUIDE.replace('▸', ">");
    while let Some(start) = text.find("![") {
        let Some(end) = text[start..]
            .find("](")
            .and_then(|k| text[start + k..].find(')').map(|e| start + k + e + 1))
        else {
            break;
        };
        text.replace_range(start..end, "");
    }
    text
});

/// The keyboard and mouse shortcuts listed in the F1 window.
pub(crate) const SHORTCUTS: &[(&str, &str)] = &[
    ("Left / Right", "previous / next frame"),
    ("Shift + Left / Right", "ten frames back / forward"),
    ("Home / End", "first / last frame"),
    ("Space", "play / pause (hold and drag: pan)"),
    ("Wheel", "zoom at the cursor (frame and 3D view)"),
    ("Middle drag", "pan"),
    ("M", "mark the 16 joints on this frame"),
    ("Esc", "stop marking, close this window"),
    ("Drag a joint", "correct it: key frame, re-track from here"),
    ("T", "track and lift"),
    ("Ctrl+Z / Ctrl+Shift+Z", "undo / redo"),
    ("Ctrl+S", "save the project"),
    ("Ctrl+Q", "quit (asks to save unsaved changes)"),
    ("Click a limb (3D)", "flip its depth on this frame"),
    ("F1", "this help"),
];

/// Draws whichever windows the state asks for; answers go to `out`. `guide` keeps the guide's
/// rendering between frames.
pub(crate) fn show(
    ctx: &egui::Context,
    state: &State,
    guide: &mut egui_commonmark::CommonMarkCache,
    out: &mut Vec<Intent>,
) {
    if state.offers_recovery() {
        recovery(ctx, out);
    }
    if let Some(to) = state.leaving() {
        save_changes(ctx, to, out);
    } else if let Some(project) = state.project_beside()
        && !state.offers_recovery()
    {
        // One question at a time: both windows open in the middle, one over the other.
        project_beside(ctx, project, out);
    }
    if state.path_request().is_some() {
        path_field(ctx, state, out);
    }
    if state.show_help() {
        let mut open = true;
        egui::Window::new("Shortcuts")
            .open(&mut open)
            .show(ctx, |ui| {
                egui::Grid::new("keys").show(ui, |ui| {
                    for (k, what) in SHORTCUTS {
                        ui.label(egui::RichText::new(*k).strong());
                        ui.label(*what);
                        ui.end_row();
                    }
                });
            });
        if !open {
            out.push(Intent::Help(false));
        }
    }
    if state.show_guide() {
        let mut open = true;
        egui::Window::new("User guide")
            .open(&mut open)
            .default_size([640.0, 560.0])
            .vscroll(true)
            .show(ctx, |ui| {
                egui_commonmark::CommonMarkViewer::new().show(ui, guide, &GUIDE_SHOWN);
            });
        if !open {
            out.push(Intent::Guide(false));
        }
    }
}

/// A centred window that cannot be moved or folded.
fn modal(title: &str) -> egui::Window<'_> {
    egui::Window::new(title)
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
}

fn recovery(ctx: &egui::Context, out: &mut Vec<Intent>) {
    modal("Recover unsaved work?").show(ctx, |ui| {
        ui.label("videomocap did not close cleanly last time. Recover the autosaved session?");
        ui.horizontal(|ui| {
            if ui.button("Recover").clicked() {
                out.push(Intent::AnswerRecovery(true));
            }
            if ui.button("Discard").clicked() {
                out.push(Intent::AnswerRecovery(false));
            }
        });
    });
}

fn project_beside(ctx: &egui::Context, project: &std::path::Path, out: &mut Vec<Intent>) {
    modal("A saved project for this video").show(ctx, |ui| {
        ui.label(format!(
            "{} holds earlier work on this video (marks, corrections, results).",
            project.display()
        ));
        ui.horizontal(|ui| {
            if ui.button("Open the project").clicked() {
                out.push(Intent::Open(project.to_owned()));
            }
            if ui.button("Not now").clicked() {
                out.push(Intent::DismissProjectBeside);
            }
        });
    });
}

fn save_changes(ctx: &egui::Context, to: &Leave, out: &mut Vec<Intent>) {
    let then = match to {
        Leave::Open(p) => format!("Save them before opening {}?", p.display()),
        Leave::Quit => "Save them before quitting?".to_owned(),
    };
    modal("Save changes?").show(ctx, |ui| {
        ui.label("The current project has changes that are not saved to a project file.");
        ui.label(then);
        ui.horizontal(|ui| {
            if ui.button("Save").clicked() {
                out.push(Intent::AnswerSave(SaveAnswer::Save));
            }
            if ui.button("Don't save").clicked() {
                out.push(Intent::AnswerSave(SaveAnswer::Discard));
            }
            if ui.button("Cancel").clicked() || ui.input(|i| i.key_pressed(egui::Key::Escape)) {
                out.push(Intent::AnswerSave(SaveAnswer::Cancel));
            }
        });
    });
}

/// The path field: the default folder and name filled in; Enter or the button confirms.
fn path_field(ctx: &egui::Context, state: &State, out: &mut Vec<Intent>) {
    let Some(request) = state.path_request() else {
        return;
    };
    modal(&request.title).show(ctx, |ui| {
        ui.label("No file dialog can be shown on this desktop. Type the path:");
        let mut text = request.text.clone();
        let edit = ui.add(
            egui::TextEdit::singleline(&mut text)
                .desired_width(520.0)
                .id_salt("path field"),
        );
        // The field holds the keyboard while the window is open: type, then Enter.
        if !edit.has_focus() && !edit.lost_focus() {
            edit.request_focus();
        }
        if text != request.text {
            out.push(Intent::PathEdited(text.clone()));
        }
        if let Some(e) = &request.error {
            ui.colored_label(egui::Color32::from_rgb(240, 120, 80), e);
        }
        let enter = edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        ui.horizontal(|ui| {
            if request.missing_folder.is_some() && ui.button("Create the folder").clicked() {
                out.push(Intent::CreateFolder);
            }
            if ui.button("OK").clicked() || enter {
                out.push(Intent::PathChosen(Some(PathBuf::from(text.trim()))));
            }
            if ui.button("Cancel").clicked() || ui.input(|i| i.key_pressed(egui::Key::Escape)) {
                out.push(Intent::PathChosen(None));
            }
        });
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_guide_is_shown_without_images_or_glyphs_the_fonts_lack() {
        assert!(GUIDE.contains("![") && GUIDE.contains('▸'));
        assert!(!GUIDE_SHOWN.contains("![") && !GUIDE_SHOWN.contains('▸'));
        assert!(GUIDE_SHOWN.contains("Export to Blender"));
    }
}
