//! The side panel's marking guide: which joint to click next, how it is defined, and a small
//! body diagram with it highlighted.

use crate::intent::Intent;
use videomocap_core::skeleton::{Bone, Joint, MarkingView};

/// Draws the guide for joint `k` of [`Joint::MARKING_ORDER`], in the words and with the diagram
/// for a subject seen from the front or from behind; Skip, Done and the view go to `out`.
pub(crate) fn show(
    ui: &mut egui::Ui,
    k: usize,
    joint: Joint,
    view: MarkingView,
    out: &mut Vec<Intent>,
) {
    let behind = view == MarkingView::Behind;
    ui.heading("Marking");
    ui.label(format!("{} of 16: {}", k + 1, joint_words(joint)));
    if let Some(side) = side_words(joint, behind) {
        ui.label(side);
    }
    ui.label(egui::RichText::new(joint.definition(view)).italics());
    if joint == Joint::Pelvis {
        ui.label(
            egui::RichText::new("the cross on the frame is halfway between the hips you placed")
                .small()
                .weak(),
        );
    }
    body_diagram(ui, joint, behind);
    let mut from_behind = behind;
    if ui
        .checkbox(&mut from_behind, "seen from behind")
        .on_hover_text(
            "For a subject with their back to the camera: the diagram is mirrored and the \
             joints are described by what shows on the back (follows the shoulders or hips \
             once both are placed)",
        )
        .changed()
    {
        out.push(Intent::SeenFromBehind(from_behind));
    }
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

/// The joint in words: "left shoulder".
pub(crate) fn joint_words(joint: Joint) -> String {
    joint.name().replace('_', " ")
}

/// Which side of the image the subject's own left or right lies on, for a side's joint.
pub(crate) fn side_words(joint: Joint, behind: bool) -> Option<String> {
    let name = joint.name();
    let left = name.starts_with("left");
    if !left && !name.starts_with("right") {
        return None;
    }
    let own = if left { "left" } else { "right" };
    // Facing the camera the subject's left is on the image's right; from behind, on its left.
    let image = if left != behind { "right" } else { "left" };
    let view = if behind {
        "seen from behind"
    } else {
        "facing you"
    };
    Some(format!(
        "the subject's own {own}: on the image's {image} ({view})"
    ))
}

/// A small view of the body with `asking` highlighted: from the front (the subject's left on
/// the right), or mirrored from behind.
fn body_diagram(ui: &mut egui::Ui, asking: Joint, behind: bool) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(120.0, 170.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    let mirror = if behind { -1.0 } else { 1.0 };
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
        egui::pos2(
            rect.center().x + mirror * x * 160.0,
            rect.top() + 5.0 + y * 160.0,
        )
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
