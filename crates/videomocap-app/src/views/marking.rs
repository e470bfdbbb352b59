//! The side panel's marking guide: which joint to click next, how it is defined, and a small
//! body diagram with it highlighted.

use crate::intent::Intent;
use videomocap_core::skeleton::{Bone, Joint};

/// Draws the guide for joint `k` of [`Joint::ALL`]; Skip and Done go to `out`.
pub fn show(ui: &mut egui::Ui, k: usize, joint: Joint, out: &mut Vec<Intent>) {
    ui.heading("Marking");
    ui.label(format!("{} of 16: {}", k + 1, joint.name()));
    ui.label(egui::RichText::new(joint.definition()).italics());
    body_diagram(ui, joint);
    ui.horizontal(|ui| {
        if ui.button("Skip").clicked() {
            out.push(Intent::SkipJoint);
        }
        if ui.button("Done (Esc)").clicked() {
            out.push(Intent::StopMarking);
        }
    });
    ui.separator();
}

/// A small front view of the body with `asking` highlighted.
fn body_diagram(ui: &mut egui::Ui, asking: Joint) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(120.0, 170.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    // Front view: the subject's left on the image's right.
    let at = |j: Joint| -> egui::Pos2 {
        let (x, y) = match j {
            Joint::HeadTop => (0.0, 0.0),
            Joint::Neck => (0.0, 0.16),
            Joint::Chest => (0.0, 0.27),
            Joint::Pelvis => (0.0, 0.48),
            Joint::LeftShoulder => (0.2, 0.19),
            Joint::LeftElbow => (0.26, 0.35),
            Joint::LeftWrist => (0.3, 0.5),
            Joint::RightShoulder => (-0.2, 0.19),
            Joint::RightElbow => (-0.26, 0.35),
            Joint::RightWrist => (-0.3, 0.5),
            Joint::LeftHip => (0.1, 0.48),
            Joint::LeftKnee => (0.11, 0.72),
            Joint::LeftAnkle => (0.12, 0.95),
            Joint::RightHip => (-0.1, 0.48),
            Joint::RightKnee => (-0.11, 0.72),
            Joint::RightAnkle => (-0.12, 0.95),
        };
        egui::pos2(rect.center().x + x * 160.0, rect.top() + 5.0 + y * 160.0)
    };
    for b in Bone::ALL {
        painter.line_segment(
            [at(b.parent), at(b.child)],
            egui::Stroke::new(2.0, egui::Color32::GRAY),
        );
    }
    for j in Joint::ALL {
        let (r, c) = if j == asking {
            (6.0, egui::Color32::YELLOW)
        } else {
            (3.0, egui::Color32::LIGHT_GRAY)
        };
        painter.circle_filled(at(j), r, c);
    }
}
