//! The menu bar: File (open, recent, save, quit), Edit (undo and redo naming the edit, marking),
//! Track, Export and Help. It reads the state and returns what the user chose.

use crate::intent::Intent;
use crate::state::{Choose, ExportKind, State};

/// Draws the menu bar; the user's choices go to `out`.
pub(crate) fn show(ui: &mut egui::Ui, state: &State, out: &mut Vec<Intent>) {
    egui::MenuBar::new().ui(ui, |ui| {
        ui.menu_button("File", |ui| file(ui, state, out));
        ui.menu_button("Edit", |ui| edit(ui, state, out));
        ui.menu_button("Track", |ui| {
            let can = !state.busy() && state.project().is_some();
            if ui
                .add_enabled(can, egui::Button::new("Track and lift (T)"))
                .clicked()
            {
                ui.close();
                out.push(Intent::Track);
            }
            let tracked = state.project().is_some_and(|p| p.tracks.is_some());
            if ui
                .add_enabled(can && tracked, egui::Button::new("Lift to 3D again"))
                .clicked()
            {
                ui.close();
                out.push(Intent::Lift);
            }
        });
        ui.menu_button("Export", |ui| {
            for kind in ExportKind::ALL {
                if ui.button(kind.label()).clicked() {
                    ui.close();
                    out.push(Intent::Export(kind));
                }
            }
        });
        ui.menu_button("Help", |ui| {
            if ui.button("User guide").clicked() {
                ui.close();
                out.push(Intent::Guide(true));
            }
            if ui.button("Shortcuts (F1)").clicked() {
                ui.close();
                out.push(Intent::Help(true));
            }
        });
    });
}

fn file(ui: &mut egui::Ui, state: &State, out: &mut Vec<Intent>) {
    let open: [(&str, Choose); 4] = [
        ("Open video…", Choose::Video),
        ("Open image folder…", Choose::ImageFolder),
        ("Open point volumes…", Choose::PointVolumes),
        ("Open project…", Choose::Project),
    ];
    for (label, what) in open {
        if ui.button(label).clicked() {
            ui.close();
            out.push(Intent::Choose(what));
        }
    }
    ui.menu_button("Recent", |ui| {
        if state.recent().is_empty() {
            ui.weak("nothing opened yet");
        }
        for p in state.recent() {
            if ui.button(p.display().to_string()).clicked() {
                ui.close();
                out.push(Intent::Open(p.clone()));
            }
        }
    });
    ui.separator();
    let open = state.project().is_some();
    if ui
        .add_enabled(open, egui::Button::new("Save project (Ctrl+S)"))
        .clicked()
    {
        ui.close();
        out.push(Intent::Save);
    }
    if ui
        .add_enabled(open, egui::Button::new("Save project as…"))
        .clicked()
    {
        ui.close();
        out.push(Intent::SaveAs);
    }
    if ui
        .add_enabled(open, egui::Button::new("Load marks…"))
        .clicked()
    {
        ui.close();
        out.push(Intent::Choose(Choose::Marks));
    }
    ui.separator();
    if ui.button("Quit (Ctrl+Q)").clicked() {
        ui.close();
        out.push(Intent::Quit);
    }
}

fn edit(ui: &mut egui::Ui, state: &State, out: &mut Vec<Intent>) {
    let undo = state.undo_name().map_or_else(
        || "Undo (Ctrl+Z)".to_owned(),
        |w| format!("Undo {w} (Ctrl+Z)"),
    );
    if ui
        .add_enabled(state.undo_name().is_some(), egui::Button::new(undo))
        .clicked()
    {
        ui.close();
        out.push(Intent::Undo);
    }
    let redo = state.redo_name().map_or_else(
        || "Redo (Ctrl+Shift+Z)".to_owned(),
        |w| format!("Redo {w} (Ctrl+Shift+Z)"),
    );
    if ui
        .add_enabled(state.redo_name().is_some(), egui::Button::new(redo))
        .clicked()
    {
        ui.close();
        out.push(Intent::Redo);
    }
    if ui
        .add_enabled(
            state.project().is_some(),
            egui::Button::new("Mark joints (M)"),
        )
        .clicked()
    {
        ui.close();
        out.push(Intent::StartMarking);
    }
    let mut move_limb = state.move_limb();
    if ui
        .checkbox(&mut move_limb, "Dragging a joint moves the limb below it")
        .changed()
    {
        out.push(Intent::MoveLimb(move_limb));
    }
}
