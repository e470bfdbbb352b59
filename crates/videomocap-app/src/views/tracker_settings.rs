//! The side panel's Tracker section: every tracker setting a project keeps (the same as the
//! command line's `--tracker-settings` file), with what it does and its default on hover.

use super::fitted;
use videomocap_core::track::TrackerParams;

/// "on" or "off", for the hover texts' defaults.
fn on_off(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

/// Edits `t` in place; the caller turns the change into an undoable edit.
pub(crate) fn tracker_settings_ui(ui: &mut egui::Ui, t: &mut TrackerParams) {
    let d = TrackerParams::default();
    ui.checkbox(&mut t.network, "use the pose network")
        .on_hover_text(format!("A pose network (BlazePose, run on this computer) looks at every frame around the person you marked; where it sees a joint elsewhere than the tracker and is sure, its place is taken. Your marks and corrections always win. Off: the tracker alone; default {}", on_off(d.network)));
    fitted::slider(ui, egui::Slider::new(&mut t.weak_reliability, 0.0..=1.0), "weak below")
        .on_hover_text(format!("Reliability under which a joint counts as weak (orange) and may be interpolated; default {}", d.weak_reliability));
    fitted::slider(
        ui,
        egui::Slider::new(&mut t.max_gap_s, 0.0..=2.0),
        "interpolate up to (s)",
    )
    .on_hover_text(format!(
        "Longest weak run filled by interpolation between reliable frames; default {} s",
        d.max_gap_s
    ));
    fitted::slider(ui, egui::Slider::new(&mut t.smooth_s, 0.0..=0.1).fixed_decimals(3), "smooth tracks (s)")
        .on_hover_text(format!("The finished tracks are smoothed over time by a window this wide (standard deviation), each frame counting as much as it is reliable, so a weak frame between sound ones moves most; your own marks stay put. For 2D work: the lift smooths by the jitter it finds and gets less on smoothed tracks (0 = off); default {} s", d.smooth_s));
    fitted::slider(ui, egui::Slider::new(&mut t.working_stature_px, 100.0..=800.0), "working size (px)")
        .on_hover_text(format!("Frames are shrunk so the person is about this tall while tracking (faster, smoother); default {} px", d.working_stature_px));
    fitted::slider(
        ui,
        egui::Slider::new(&mut t.limb_range_deg, 5.0..=90.0),
        "limb search (°)",
    )
    .on_hover_text(format!(
        "How far a limb may turn between frames in the search; default {}°",
        d.limb_range_deg
    ));
    fitted::slider(ui, egui::Slider::new(&mut t.short_penalty, 0.0..=20.0), "keep limbs long")
        .on_hover_text(format!("How strongly a limb is pulled back to its full length when it looks shorter (legs crossing); lower it for limbs pointing at the camera, such as a seated person's thighs seen from the front; default {}", d.short_penalty));
    fitted::slider(ui, egui::Slider::new(&mut t.forearm_short_penalty, 0.0..=40.0), "keep forearms long")
        .on_hover_text(format!("The same pull for the forearms: raise it (12) when a forearm crossing the body, or a sleeve of its colour, shrinks towards the elbow and the wrist falls short; check the 3D view after; default {}", d.forearm_short_penalty));
    ui.checkbox(&mut t.hip_patch, "hold the hips when the back bends")
        .on_hover_text(format!("A patch around the hips holds the pelvis when the spine bends (a bow, a reach), and the trunk is re-hung from the neck to it; default {}", on_off(d.hip_patch)));
    ui.checkbox(&mut t.chain_refine, "refine each limb as one chain")
        .on_hover_text(format!("After each limb's two segments are found, the elbow or knee and the wrist or ankle are nudged together so both segments fit; default {}", on_off(d.chain_refine)));
    // The spring is part of the chain refinement: greyed out without it.
    fitted::slider_enabled(ui, t.chain_refine, egui::Slider::new(&mut t.shoulder_spring, 0.0..=0.5), "shoulder spring")
        .on_hover_text(format!("Cost per square pixel that a shoulder pays for leaving the place the rigid trunk gives it, so it can rise with a raised arm (part of the chain refinement); higher holds it closer; 0 holds it on the trunk; default {}", d.shoulder_spring));
    fitted::slider(ui, egui::Slider::new(&mut t.arm_foreground, 0.0..=1.0), "arms vs. background")
        .on_hover_text(format!("With a camera that stands still, the background is the median of 25 frames, and an arm's blocks must stand out from it where they did on the marked frame, so a forearm no longer settles on a wall of its colour; ignored when the camera moves (0 = off); default {}", d.arm_foreground));
    if ui.button("Defaults").clicked() {
        *t = d;
    }
}
