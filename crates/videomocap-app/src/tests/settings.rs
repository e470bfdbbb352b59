use super::*;
use egui_kittest::kittest::Queryable;
use videomocap_core::project::Project;
use videomocap_core::track::TrackerParams;

/// The app on a fresh project in `dir` with the Parameters panel's Tracker section open.
fn with_tracker_panel(dir: &Path) -> Harness<'static, App> {
    let mut h = with_empty_project(dir);
    h.get_by_label("Tracker").click();
    h.run();
    h
}

/// The pull of short limbs back to full length, and the forearms' own, are each set from the
/// Parameters panel on its own (the others stay), and each is an
/// undoable project setting.
#[test]
fn the_short_limb_pulls_are_set_in_the_tracker_settings() {
    type Get = fn(&TrackerParams) -> f32;
    let pulls: [(&str, Get); 2] = [
        ("keep limbs long", |t| t.short_penalty),
        ("keep forearms long", |t| t.forearm_short_penalty),
    ];
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_tracker_panel(dir.path());
    let now = |h: &Harness<'static, App>| {
        let t = h.state().state().project().unwrap().settings.tracker;
        pulls.map(|(_, get)| get(&t))
    };
    let defaults = pulls.map(|(_, get)| get(&TrackerParams::default()));
    assert_eq!(now(&h), defaults);
    for (k, (label, _)) in pulls.iter().enumerate() {
        h.get_by_role_and_label(egui::accesskit::Role::Slider, label)
            .set_value_accesskit(2.0);
        h.run();
        let mut want = defaults;
        want[k] = 2.0;
        assert_eq!(now(&h), want, "{label} set on its own");
        h.state_mut().state_mut().apply(Intent::Undo);
        assert_eq!(now(&h), defaults, "{label} undone");
    }
}

/// The tracks' smoothing window (off by default) is set from the Parameters panel, an
/// undoable project setting.
#[test]
fn the_track_smoothing_is_an_undoable_tracker_setting() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_tracker_panel(dir.path());
    let now = |h: &Harness<'static, App>| {
        h.state()
            .state()
            .project()
            .unwrap()
            .settings
            .tracker
            .smooth_s
    };
    assert_eq!(now(&h), TrackerParams::default().smooth_s);
    h.get_by_role_and_label(egui::accesskit::Role::Slider, "smooth tracks (s)")
        .set_value_accesskit(0.02);
    h.run();
    assert_eq!(now(&h), 0.02);
    h.state_mut().state_mut().apply(Intent::Undo);
    assert_eq!(now(&h), TrackerParams::default().smooth_s);
}

/// The arms' foreground weight is set from the Parameters panel, an undoable setting.
#[test]
fn the_background_weight_is_an_undoable_tracker_setting() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_tracker_panel(dir.path());
    let now = |h: &Harness<'static, App>| {
        h.state()
            .state()
            .project()
            .unwrap()
            .settings
            .tracker
            .arm_foreground
    };
    let d = TrackerParams::default();
    assert_eq!(now(&h), d.arm_foreground);
    h.get_by_role_and_label(egui::accesskit::Role::Slider, "arms vs. background")
        .set_value_accesskit(0.0);
    h.run();
    assert_eq!(now(&h), 0.0);
    h.state_mut().state_mut().apply(Intent::Undo);
    assert_eq!(now(&h), d.arm_foreground, "undone");
}

/// The tracker's switches (the pose network, the hip patch, the chain refinement) can each be turned off from the
/// Parameters panel, and each is an undoable project setting.
#[test]
fn each_tracker_switch_is_an_undoable_setting() {
    type Get = fn(&TrackerParams) -> bool;
    let switches: [(&str, Get); 3] = [
        ("use the pose network", |t| t.network),
        ("hold the hips when the back bends", |t| t.hip_patch),
        ("refine each limb as one chain", |t| t.chain_refine),
    ];
    for (label, get) in switches {
        let dir = tempfile::tempdir().unwrap();
        let mut h = with_tracker_panel(dir.path());
        let on =
            |h: &Harness<'static, App>| get(&h.state().state().project().unwrap().settings.tracker);
        assert!(on(&h), "{label} starts on");
        h.get_by_label(label).click();
        h.run();
        assert!(!on(&h), "{label} turned off");
        h.state_mut().state_mut().apply(Intent::Undo);
        assert!(on(&h), "{label} back on after undo");
    }
}

/// The lift's global refinement and the foot lock can be turned off from the Parameters
/// panel: undoable project settings, which the next lift uses.
#[test]
fn the_global_refinement_is_switched_in_the_lift_settings() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_empty_project(dir.path());
    let refine = |h: &Harness<'_, App>| h.state().state().project().unwrap().settings.lift.refine;
    assert!(refine(&h));
    h.get_by_label("Lift").click();
    h.run();
    h.get_by_label("global refinement").click();
    h.run();
    assert!(!refine(&h));
    h.state_mut().state_mut().apply(Intent::Undo);
    assert!(refine(&h));
    // The foot lock likewise (on by default, as in the exports).
    let lock = |h: &Harness<'_, App>| h.state().state().project().unwrap().settings.lift.foot_lock;
    assert!(lock(&h));
    h.get_by_label("keep planted feet still").click();
    h.run();
    assert!(!lock(&h));
    h.state_mut().state_mut().apply(Intent::Undo);
    assert!(lock(&h));
}

/// The lift's panel shows the nine settings a user may change, each by a name
/// that says what it does.
#[test]
fn the_lift_panel_shows_the_nine_settings() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_empty_project(dir.path());
    h.get_by_label("Lift").click();
    h.run();
    for label in [
        "global refinement",
        "smooth the tracks",
        "keep the trunk's path steady",
        "keep planted feet still",
    ] {
        h.get_by_label(label);
    }
    for label in [
        "smoothing (s)",
        "arm swing vs. legs",
        "hands outside the body",
        "image depth evidence",
        "learned pose prior",
    ] {
        h.get_by_role_and_label(egui::accesskit::Role::Slider, label);
    }
}

/// The shoulder spring is part of the chain refinement: its slider is greyed out while the
/// chain refinement is off.
#[test]
fn the_shoulder_spring_is_greyed_out_without_the_chain_refinement() {
    use egui_kittest::kittest::NodeT;
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_tracker_panel(dir.path());
    let disabled = |h: &Harness<'_, App>| {
        h.get_by_role_and_label(egui::accesskit::Role::Slider, "shoulder spring")
            .accesskit_node()
            .is_disabled()
    };
    assert!(!disabled(&h));
    h.get_by_label("refine each limb as one chain").click();
    h.run();
    assert!(
        !h.state()
            .state()
            .project()
            .unwrap()
            .settings
            .tracker
            .chain_refine
    );
    assert!(disabled(&h));
}

/// A length ticked as known in the Parameters panel goes into the project's settings (and
/// from there to the lift), and unticked leaves it again.
#[test]
fn a_known_length_is_ticked_into_the_project() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_empty_project(dir.path());
    h.get_by_label("Lengths you know").click();
    h.run();
    assert_eq!(
        h.state().state().project().unwrap().settings.lengths.thigh,
        None
    );
    h.get_by_label("thigh").click();
    h.run();
    let thigh = h.state().state().project().unwrap().settings.lengths.thigh;
    assert!(thigh.is_some_and(|t| t > 0.0), "{thigh:?}");
    let known = h
        .state()
        .state()
        .project()
        .unwrap()
        .settings
        .lengths
        .known();
    assert_eq!(known.bones.len(), 2);
    h.get_by_label("thigh").click();
    h.run();
    assert_eq!(
        h.state().state().project().unwrap().settings.lengths.thigh,
        None
    );
}

/// A slider drag changes the settings many times but is one undo step.
#[test]
fn a_settings_drag_is_one_undo_step() {
    let dir = tempfile::tempdir().unwrap();
    let dialogs = PreparedDialogs::default();
    let mut h = harness(None, &dialogs, &dir.path().join("state"));
    h.state_mut()
        .state_mut()
        .set_project_for_test(Project::new(dir.path().join("v.mp4")));
    let mut s = h.state().state().project().unwrap().settings;
    for k in 0..5 {
        s.height_m = 1.6 + 0.01 * f64::from(k);
        h.state_mut().state_mut().apply(Intent::Settings {
            settings: Box::new(s),
            dragging: true,
        });
    }
    s.height_m = 1.9;
    h.state_mut().state_mut().apply(Intent::Settings {
        settings: Box::new(s),
        dragging: false,
    });
    h.state_mut().state_mut().apply(Intent::Undo);
    assert!((h.state().state().project().unwrap().settings.height_m - 1.64).abs() < 1e-9);
    h.state_mut().state_mut().apply(Intent::Undo);
    assert!((h.state().state().project().unwrap().settings.height_m - 1.70).abs() < 1e-9);
}

/// A pose network that could not load is named in the Tracker panel (tracking goes on with VBA
/// alone), as a tracking job reports it.
#[test]
fn a_network_that_could_not_load_is_shown_in_the_tracker_panel() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_tracker_panel(dir.path());
    let shown = |h: &Harness<'static, App>| h.query_by_label_contains("could not load").is_some();
    assert!(!shown(&h));
    h.state_mut()
        .state_mut()
        .report_network_problem_for_test("model checksum mismatch".to_owned());
    h.run();
    assert!(shown(&h));
    assert!(
        h.query_by_label_contains("model checksum mismatch")
            .is_some(),
        "the reason is named"
    );
}
