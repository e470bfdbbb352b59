//! The Parameters panel's Lift section: the lift settings a project keeps (the same as the
//! command line's `--lift-settings` file), the ones a user is likely to change.

use super::fitted;
use videomocap_core::lift::LiftParams;

/// "on" or "off", for the hover texts' defaults.
fn on_off(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

/// Edits `l` in place; the caller records the change (undo, autosave).
pub(crate) fn lift_settings_ui(ui: &mut egui::Ui, l: &mut LiftParams) {
    let d = LiftParams::default();
    ui.checkbox(&mut l.refine, "global refinement").on_hover_text(format!(
        "After the per-frame solve, one least-squares pass over the whole clip (reprojection, bone \
         lengths, smooth motion); on the benchmark ten times slower and 0.2 to 2 mm more \
         accurate; default {}",
        on_off(d.refine)
    ));
    ui.checkbox(&mut l.smooth_tracks, "smooth the tracks")
        .on_hover_text(format!(
            "Before the lift, the tracks are smoothed over time (off for tracks that are \
             already clean); default {}",
            on_off(d.smooth_tracks)
        ));
    let width = egui::Slider::new(&mut l.smoothing_s, 0.0..=0.3);
    fitted::slider_enabled(ui, l.smooth_tracks, width, "smoothing (s)").on_hover_text(format!(
        "0: each joint's track is smoothed by as much as its own jitter calls for (nothing \
             for clean tracks); above 0: every joint by a Gaussian this many seconds wide; \
             default {}",
        d.smoothing_s
    ));
    ui.checkbox(&mut l.steady_trunk, "keep the trunk's path steady")
        .on_hover_text(format!(
            "The shoulders' and chest's 3D path is refitted over the whole clip (steadier depth \
             and turn); default {}",
            on_off(d.steady_trunk)
        ));
    ui.checkbox(&mut l.foot_lock, "keep planted feet still")
        .on_hover_text(format!(
            "A foot found planted on the floor (slow in the image, not above the other foot) \
             keeps one depth over its contact and the body follows, so the exported feet do not \
             slide; default {}",
            on_off(d.foot_lock)
        ));
    fitted::slider(
        ui,
        egui::Slider::new(&mut l.arm_swing, 0.0..=3.0),
        "arm swing vs. legs",
    )
    .on_hover_text(format!(
        "When walking or running, how strongly each arm is taken to swing against its own leg \
             when its depth is in doubt (0 = off); default {}",
        d.arm_swing
    ));
    fitted::slider(
        ui,
        egui::Slider::new(&mut l.hands_outside_body, 0.0..=30.0),
        "hands outside the body",
    )
    .on_hover_text(format!(
        "How strongly a hand is kept out of the trunk and the thighs when its depth is in doubt \
         (0 = off); default {}",
        d.hands_outside_body
    ));
    fitted::slider(
        ui,
        egui::Slider::new(&mut l.image_depth, 0.0..=3.0),
        "image depth evidence",
    )
    .on_hover_text(format!(
        "How much the pose network's 3D body counts for which way each bone points in depth \
             and which way the body faces (0 = geometry alone; your flips always win); default {}",
        d.image_depth
    ));
    fitted::slider(
        ui,
        egui::Slider::new(&mut l.pose_prior, 0.0..=3.0),
        "learned pose prior",
    )
    .on_hover_text(format!(
        "How much what bodies usually do (learned from motion capture) counts for which way              each bone points in depth (0 = off: the image and smooth motion alone; your flips              always win); default {}",
        d.pose_prior
    ));
    if ui.button("Defaults").clicked() {
        *l = d;
    }
}
