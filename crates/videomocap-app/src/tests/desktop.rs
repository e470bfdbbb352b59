use super::*;
use crate::views::scene::scene;
use crate::views::timeline::short_name;
use egui_kittest::kittest::Queryable;
use videomocap_core::formats::{FrameTracks, PointSource, SourceInfo, TrackedPoint, Tracks2d};
use videomocap_core::project::Project;
use videomocap_core::skeleton::{Joint, PerJoint};

/// The bundled synthetic clip, with its marks beside it (loaded on open).
fn sample_clip() -> PathBuf {
    videomocap_testkit::repo_root().join("sample_videos/synth_walk_oblique/video.mp4")
}

/// Opens the sample clip and waits for its first frame and marks.
fn with_sample(dialogs: &PreparedDialogs, state: &Path) -> Harness<'static, App> {
    let mut h = harness(Some(sample_clip()), dialogs, state);
    wait(&mut h, "the clip and its marks", |s| {
        s.shown() == Some(0) && s.project().is_some_and(|p| p.marks().is_some())
    });
    h.run_steps(2);
    h
}

/// The path field's request (it must be showing).
fn path_field(h: &Harness<'_, App>) -> crate::state::PathRequest {
    h.state()
        .state()
        .path_request()
        .cloned()
        .expect("the path field")
}

/// Types `path` into the path field and presses OK.
fn answer_path(h: &mut Harness<'_, App>, path: &Path) {
    h.state_mut()
        .state_mut()
        .apply(Intent::PathEdited(path.display().to_string()));
    h.run_steps(2);
    h.get_by_label("OK").click();
    h.run_steps(3);
}

/// On a desktop where no file dialog can be shown, Export and Save open the app's own path
/// field with the folder and name filled in; a path that cannot be written keeps the window
/// open saying why; a good one writes the file and the status line names it.
#[test]
fn without_a_file_dialog_the_path_field_asks_and_the_status_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let dialogs = PreparedDialogs::default();
    dialogs.unavailable.set(true);
    let mut h = with_sample(&dialogs, &dir.path().join("state"));

    h.get_by_label("Export").click();
    h.run_steps(3);
    h.get_by_label("Marks (marks.json)…").click();
    h.run_steps(3);
    let request = path_field(&h);
    let proposed = sample_clip().with_file_name("video.marks.json");
    assert_eq!(request.text, proposed.display().to_string());
    assert!(
        h.state().state().status().contains("No file dialog"),
        "{}",
        h.state().state().status()
    );
    h.get_by_label_contains("Type the path");

    // A folder that does not exist: the window stays and says why.
    let bad = dir.path().join("missing/folder/marks.json");
    answer_path(&mut h, &bad);
    let request = h.state().state().path_request().cloned();
    assert!(
        request.as_ref().and_then(|r| r.error.as_ref()).is_some(),
        "{request:?}"
    );
    assert!(!bad.exists());

    let good = dir.path().join("marks.json");
    answer_path(&mut h, &good);
    assert!(h.state().state().path_request().is_none());
    assert!(good.is_file());
    assert_eq!(
        h.state().state().status(),
        format!("Wrote {}", good.display())
    );

    // Save goes straight to the path field now (the dialog is known to be missing).
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    h.run_steps(3);
    let request = path_field(&h);
    assert_eq!(
        request.text,
        sample_clip()
            .with_file_name("video.videomocap.json")
            .display()
            .to_string()
    );
    let project = dir.path().join("p.videomocap.json");
    answer_path(&mut h, &project);
    assert!(project.is_file(), "{}", h.state().state().status());
    assert_eq!(
        h.state().state().status(),
        format!("Saved {}", project.display())
    );
}

/// A dialog the user closes writes nothing, and the status line says so.
#[test]
fn a_cancelled_export_says_nothing_was_written() {
    let dir = tempfile::tempdir().unwrap();
    let dialogs = PreparedDialogs::default();
    let mut h = with_sample(&dialogs, &dir.path().join("state"));
    h.state_mut()
        .state_mut()
        .apply(Intent::Export(crate::state::ExportKind::Bvh));
    assert_eq!(
        h.state().state().status(),
        "Export cancelled: nothing written"
    );
    assert!(h.state().state().path_request().is_none());
}

/// Ctrl+Q and the window's close button ask Save / Don't save / Cancel when there are unsaved
/// changes; Cancel stays; Don't save quits and leaves no recovery prompt for the next start.
/// With nothing unsaved, Quit quits at once.
#[test]
fn quitting_asks_to_save_unsaved_work_and_leaves_no_recovery_prompt() {
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("state");
    let dialogs = PreparedDialogs::default();
    let mut h = with_sample(&dialogs, &state);
    assert!(!h.state().state().dirty(), "opening is not an edit");
    h.state_mut().state_mut().apply(Intent::StartMarking);
    h.state_mut()
        .state_mut()
        .apply(Intent::Click(Point2::new(100.0, 50.0)));
    assert!(h.state().state().dirty());
    h.state_mut().state_mut().flush_autosave();
    assert!(h.state().state().autosave_path().unwrap().is_file());

    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Q);
    h.run_steps(3);
    assert_eq!(
        h.state().state().leaving(),
        Some(&crate::state::Leave::Quit)
    );
    h.get_by_label("Save them before quitting?");
    h.get_by_label("Cancel").click();
    h.run_steps(2);
    assert!(h.state().state().leaving().is_none());
    assert!(!h.state().state().quitting(), "cancel stays");

    // The window's close button asks the same.
    h.input_mut()
        .viewports
        .entry(egui::ViewportId::ROOT)
        .or_default()
        .events
        .push(egui::ViewportEvent::Close);
    h.run_steps(2);
    assert_eq!(
        h.state().state().leaving(),
        Some(&crate::state::Leave::Quit)
    );
    h.get_by_label("Don't save").click();
    h.run_steps(2);
    assert!(h.state().state().quitting());
    let autosave = h.state().state().autosave_path().unwrap();
    assert!(
        !autosave.exists(),
        "a deliberate quit leaves nothing to recover"
    );
    drop(h);

    let mut h = harness(None, &dialogs, &state);
    h.step();
    assert!(!h.state().state().offers_recovery());

    // Nothing unsaved: Quit quits at once.
    h.state_mut().state_mut().apply(Intent::Quit);
    assert!(h.state().state().quitting());
    assert!(h.state().state().leaving().is_none());
}

/// Tracks for `n` frames of an image folder (the points inside 8×6): the left wrist weak on frames 3–5.
fn weak_wrist_tracks(dir: &Path, n: usize) -> Tracks2d {
    Tracks2d {
        source: SourceInfo {
            path: dir.to_owned(),
            width: 8,
            height: 6,
            fps: 30.0,
            frame_count: n,
        },
        frames: (0..n)
            .map(|i| FrameTracks {
                index: videomocap_core::formats::FrameIndex(i),
                body3d: None,
                points: PerJoint::from_fn(|j| TrackedPoint {
                    pos: Point2::new(4.0, 3.0),
                    confidence: if j == Joint::LeftWrist && (3..=5).contains(&i) {
                        0.1
                    } else {
                        0.9
                    },
                    source: PointSource::Tracked,
                }),
            })
            .collect(),
    }
}

/// The reliability strips carry their joints' names, hovering one names the joint, the frame
/// and the state there, and the side panel says how much is weak (joint-frames and the share
/// of the clip), not how many fragments. A 16:9 clip beside the panels shows a strip per joint
/// by default (they take no height the video needs).
#[test]
fn strips_are_named_and_the_panel_says_how_much_is_weak() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    for i in 0..12 {
        image::RgbImage::from_pixel(16, 9, image::Rgb([i * 20, 0, 0]))
            .save(frames.join(format!("f{i:02}.png")))
            .unwrap();
    }
    let mut h = harness(
        Some(frames.clone()),
        &PreparedDialogs::default(),
        &dir.path().join("state"),
    );
    wait(&mut h, "the folder", |s| s.frame_count() == 12);
    let mut p = Project::new(frames.clone());
    p.tracks = Some(std::sync::Arc::new(weak_wrist_tracks(&frames, 12)));
    h.state_mut().state_mut().set_project_for_test(p);
    h.run_steps(2);

    assert!(h.state().timeline_unfolded(), "a strip per joint");
    // 3 of 12 × 16 joint-frames.
    let share = h.state().state().weak_share().unwrap();
    assert_eq!((share.joint_frames, share.total), (3, 192));
    h.get_by_label("3 joint-frames weak: 1.6 % of the clip");

    // Every strip has its own short name.
    let names: std::collections::BTreeSet<&str> = Joint::ALL.into_iter().map(short_name).collect();
    assert_eq!(names.len(), 16);

    // Hover the left wrist's strip on frame 4: the tooltip names joint, frame and state.
    let strip = h
        .state()
        .state()
        .strips()
        .map(|s| s.state_at(Joint::LeftWrist, 4));
    assert_eq!(
        strip,
        Some(Some(crate::views::frame_view::PointState::Weak))
    );
    let at = timeline_point(&h, Joint::LeftWrist, 4);
    h.hover_at(at);
    h.run_steps(3);
    h.get_by_label_contains("left wrist · frame 4 · weak");
}

/// The screen point of `joint`'s strip at `frame` (from the timeline's layout: the scrubber's
/// rail, then the tick rows, then one strip per joint).
fn timeline_point(h: &Harness<'_, App>, joint: Joint, frame: usize) -> egui::Pos2 {
    let slider = h.get_by_role_and_label(egui::accesskit::Role::Slider, "frame");
    let rail = slider.rect();
    let frames = h.state().state().frame_count();
    let radius = rail.height() / 2.5;
    let (left, right) = (rail.min.x + radius, rail.max.x - radius);
    let x = left + (right - left) * frame as f32 / (frames - 1) as f32;
    let y =
        rail.max.y + 4.0 + 12.0 + crate::views::timeline::STRIP_H * (joint.index() as f32 + 0.5);
    egui::pos2(x, y)
}

/// While tracking and lifting run, the frame stays where it was (the progress shows in the
/// status bar; the strips come once the tracks are in), and while a re-track's lift runs the
/// 3D view keeps the last skeleton, saying so.
#[test]
fn progress_moves_nothing_and_the_last_skeleton_stays_during_a_job() {
    let dir = tempfile::tempdir().unwrap();
    let dialogs = PreparedDialogs::default();
    let mut h = with_sample(&dialogs, &dir.path().join("state"));
    let here = |h: &Harness<'_, App>| {
        h.state()
            .frame_view()
            .transform()
            .expect("frame drawn")
            .to_screen(Point2::new(10.0, 10.0))
    };
    let before = here(&h);
    h.key_press(egui::Key::T);
    h.step();
    assert!(h.state().state().busy());
    h.run_steps(3);
    assert_eq!(here(&h), before, "the progress bar moved the frame");
    h.get_by_label("Cancel");
    wait(&mut h, "tracking and lifting", |s| {
        !s.busy() && s.project().is_some_and(|p| p.skeleton.is_some())
    });
    h.run_steps(2);
    // The strips arrived with the tracks (before them the timeline is the scrubber alone, so a
    // portrait clip has the height): the frame made room once, and stays from then on.
    assert_ne!(here(&h), before);
    let before = here(&h);

    // Track again: once the new tracks are in, the old 3D no longer belongs to them, and while
    // the lift makes the new one the view keeps the old, saying so.
    h.state_mut().state_mut().apply(Intent::Track);
    wait(&mut h, "the re-lift", |s| {
        s.busy() && s.project().is_some_and(|p| p.skeleton.is_none())
    });
    let shown = scene(h.state().state());
    assert!(shown.joints.is_some(), "the 3D view kept a skeleton");
    assert!(
        shown
            .notes
            .iter()
            .any(|n| n.text.contains("last 3D result"))
    );
    assert_eq!(here(&h), before);
    wait(&mut h, "the lift", |s| !s.busy());
    assert!(scene(h.state().state()).joints.is_some());
}

/// The window opens maximised (fitting whatever screen it is on), with a floor under which the
/// panels would clip.
#[test]
fn the_window_opens_maximised_with_a_minimum_size() {
    let v = crate::viewport();
    assert_eq!(v.maximized, Some(true));
    assert_eq!(v.min_inner_size, Some(egui::vec2(960.0, 600.0)));
    // Where no window manager maximises it, it takes most of the screen, whatever its size.
    assert_eq!(
        crate::app::fitted_size(egui::vec2(2560.0, 1440.0)),
        egui::vec2(2304.0, 1296.0)
    );
    assert_eq!(
        crate::app::fitted_size(egui::vec2(1000.0, 600.0)),
        egui::vec2(960.0, 600.0)
    );
}
