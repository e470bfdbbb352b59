//! The left side panel: the marking guide while marking; the parameters (camera, the subject's
//! height and known lengths, tracker and lift settings); how much of the tracks is weak, with
//! the weak spans to jump to. In volume mode: the layers drawn and the pipeline's warnings.

use super::fitted;
use super::{lift_settings, marking, tracker_settings};
use crate::intent::Intent;
use crate::state::volume::VolumeSequence;
use crate::state::{Outdated, State};
use videomocap_core::lift::default_focal;
use videomocap_core::project::Settings;

/// Draws the panel; what the user changed goes to `out`.
pub(crate) fn show(ui: &mut egui::Ui, state: &State, out: &mut Vec<Intent>) {
    if let Some(v) = state.volume() {
        volume(ui, v, state.current_frame(), out);
        return;
    }
    if let Some((k, joint)) = state.asking() {
        marking::show(ui, k, joint, state.marking_view(), out);
    }
    ui.heading("Parameters");
    parameters(ui, state, out);
    ui.separator();
    weak(ui, state, out);
}

fn volume(ui: &mut egui::Ui, v: &VolumeSequence, current: usize, out: &mut Vec<Intent>) {
    ui.heading("Point volumes");
    let mut layers = v.layers;
    ui.checkbox(&mut layers.points, "points (coloured by body)");
    ui.checkbox(&mut layers.curve, "skeleton curve");
    ui.checkbox(&mut layers.bodies, "head sphere, torso and limb cylinders");
    if layers != v.layers {
        out.push(Intent::VolumeLayers(layers));
    }
    let Some(p) = &v.processed else { return };
    ui.label(format!("left/right from: {:?}", p.assembled.sides_from));
    if let Some(Err(e)) = p.results.get(current) {
        ui.colored_label(egui::Color32::from_rgb(240, 160, 60), e.to_string());
    }
    ui.separator();
    ui.heading("Warnings");
    egui::ScrollArea::vertical()
        .max_height(300.0)
        .show(ui, |ui| {
            if p.assembled.warnings.is_empty() {
                ui.label("none");
            }
            for w in &p.assembled.warnings {
                ui.label(w);
            }
        });
}

fn parameters(ui: &mut egui::Ui, state: &State, out: &mut Vec<Intent>) {
    let Some(before) = state.project().map(|p| p.settings) else {
        ui.weak("Open a video first");
        return;
    };
    let mut settings = before;
    camera_and_height(ui, state, &mut settings);
    known_lengths(ui, state, &mut settings);
    ui.collapsing("Tracker", |ui| {
        if let Some(why) = state.network_problem() {
            ui.colored_label(
                ui.visuals().warn_fg_color,
                format!("The pose network could not load ({why}): tracking uses VBA alone."),
            );
        }
        tracker_settings::tracker_settings_ui(ui, &mut settings.tracker);
    });
    for o in state.outdated() {
        if let Outdated::Tracks(what) = o {
            offer(ui, &what, "Track again (T)", Intent::Track, out);
        }
    }
    ui.collapsing("Lift", |ui| {
        lift_settings::lift_settings_ui(ui, &mut settings.lift);
    });
    for o in state.outdated() {
        if let Outdated::Skeleton(what) = o {
            offer(ui, &what, "Lift again", Intent::Lift, out);
        }
    }
    let dragging = ui.ctx().dragged_id().is_some();
    if settings != before {
        out.push(Intent::Settings {
            settings: Box::new(settings),
            dragging,
        });
    } else if !dragging {
        out.push(Intent::SettingsReleased);
    }
}

/// The focal length (known or the default 60°) and the subject's height.
fn camera_and_height(ui: &mut egui::Ui, state: &State, settings: &mut Settings) {
    let default_f = state
        .video_info()
        .map_or(1000.0, |i| default_focal(i.width, i.height));
    let mut given = settings.focal_px.is_some();
    let mut f = settings.focal_px.unwrap_or(default_f);
    ui.checkbox(&mut given, "Focal length known")
        .on_hover_text("Off: 60° across the image's longer side (a typical phone or webcam). On: give the focal length in pixels (from calibration, or focal mm × image width px / sensor width mm).");
    ui.add_enabled(
        given,
        egui::DragValue::new(&mut f)
            .range(50.0..=20000.0)
            .suffix(" px"),
    )
    .on_hover_text(format!("Focal length in pixels; default {default_f:.0} px"));
    settings.focal_px = given.then_some(f);
    fitted::slider(ui, egui::Slider::new(&mut settings.height_m, 1.0..=2.3), "subject height (m)")
        .on_hover_text("The subject's stature (default 1.70 m): every length is read from the video and this fixes their overall scale, so the 3D skeleton's size and depth follow it. Lengths you know (below) set the scale instead.");
}

/// What the lift read of the body, and the lengths the user knows.
fn known_lengths(ui: &mut egui::Ui, state: &State, settings: &mut Settings) {
    let fit = state.subject_fit();
    // One line whether or not a lift has read the lengths (the whole reading on hover), so the
    // panel below does not jump when it arrives.
    let line = match fit {
        Some(_) => "body lengths: read from the video (hover for each)",
        None => "body lengths: read from the video when lifted",
    };
    let label = ui.label(egui::RichText::new(line).small().weak());
    if let Some(fit) = fit {
        label.on_hover_text(fit.to_string());
    }
    let read = |name: &str| {
        fit.and_then(|f| f.parts.iter().find(|p| p.name == name))
            .map(|p| p.metres)
    };
    ui.collapsing("Lengths you know", |ui| {
        ui.label(egui::RichText::new("Measured on the person (joint centre to joint centre), each kept as given and setting the scale of the rest instead of the height.").small().weak());
        egui::Grid::new("known lengths").num_columns(2).show(ui, |ui| {
            for (name, value) in settings.lengths.fields_mut() {
                let mut known = value.is_some();
                ui.checkbox(&mut known, name);
                // Ticked, a part starts at what the last lift read.
                let mut v = value.or_else(|| read(name)).unwrap_or(0.3);
                if known {
                    ui.add(egui::DragValue::new(&mut v).range(0.05..=1.0).speed(0.005).suffix(" m"));
                } else {
                    ui.label(egui::RichText::new(read(name).map_or_else(|| "not read yet".to_owned(), |m| format!("read {m:.3} m"))).weak());
                }
                *value = known.then_some(v);
                ui.end_row();
            }
        });
    });
}

/// A result out of date under the settings: what changed, and a button to make it again.
fn offer(ui: &mut egui::Ui, what: &str, button: &str, intent: Intent, out: &mut Vec<Intent>) {
    egui::Frame::group(ui.style()).show(ui, |ui| {
        ui.colored_label(egui::Color32::from_rgb(240, 170, 90), format!("{what}."));
        if ui.button(button).clicked() {
            out.push(intent);
        }
    });
}

/// How much is weak (joint-frames and the share of the clip), then the spans to jump to.
fn weak(ui: &mut egui::Ui, state: &State, out: &mut Vec<Intent>) {
    ui.heading("Weak tracking");
    let Some(share) = state.weak_share() else {
        ui.weak("nothing tracked yet");
        return;
    };
    ui.label(format!(
        "{} joint-frames weak: {:.1} % of the clip",
        share.joint_frames,
        share.share() * 100.0
    ))
    .on_hover_text(
        "Each joint on each frame counts once when its tracking was unsure (orange), filled in \
         (blue) or lost (red) and you have not placed it. Correcting a joint makes this fall.",
    );
    egui::ScrollArea::vertical()
        .max_height(220.0)
        .show(ui, |ui| {
            for s in state.spans() {
                let text = format!(
                    "{} frames {}–{} ({}, {:.2})",
                    s.joint, s.start, s.end, s.kind, s.min_reliability
                );
                if ui.link(text).clicked() {
                    out.push(Intent::GoTo(s.start.get()));
                }
            }
        });
}
