//! Sliders whose label always fits beside them: the bar takes what the panel's width leaves
//! after the number box and the label. egui lets a slider's label run past a narrow panel's
//! edge, where it was cut off ("interpolate up to (s"); in a panel too narrow for the three
//! on one line, the label goes above the slider.

/// Narrowest bar, points (still draggable).
const MIN_BAR: f32 = 40.0;

/// Room for the number box beyond egui's minimum widget width, points (three decimals and
/// the box's padding: "0.020" took 53 points).
const VALUE_SLACK: f32 = 24.0;

/// Adds `slider` labelled `label`, its bar narrowed so the label fits in the width available.
pub(crate) fn slider(ui: &mut egui::Ui, slider: egui::Slider<'_>, label: &str) -> egui::Response {
    let label_w = egui::WidgetText::from(label)
        .into_galley(
            ui,
            Some(egui::TextWrapMode::Extend),
            f32::INFINITY,
            egui::TextStyle::Body,
        )
        .size()
        .x;
    let spacing = ui.spacing().item_spacing.x;
    let value_w = ui.spacing().interact_size.x + VALUE_SLACK;
    let room = ui.available_width() - label_w - value_w - 2.0 * spacing;
    if room < MIN_BAR {
        // Too narrow for the three on one line: the label above, the slider under it.
        let name = ui.label(label);
        return ui
            .scope(|ui| {
                ui.spacing_mut().slider_width =
                    (ui.available_width() - value_w - spacing).max(MIN_BAR);
                ui.add(slider)
            })
            .inner
            .labelled_by(name.id);
    }
    let bar = room.min(ui.spacing().slider_width.max(MIN_BAR));
    ui.scope(|ui| {
        ui.spacing_mut().slider_width = bar;
        ui.add(slider.text(label))
    })
    .inner
}

/// Like [`slider`], greyed out unless `enabled`.
pub(crate) fn slider_enabled(
    ui: &mut egui::Ui,
    enabled: bool,
    s: egui::Slider<'_>,
    label: &str,
) -> egui::Response {
    ui.add_enabled_ui(enabled, |ui| slider(ui, s, label)).inner
}
