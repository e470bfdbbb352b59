//! What a new user's walk through the app found (issue 93), each as the user meets it: the 3D
//! view's flags in words and the unsure limbs as links, the view through the camera, the
//! layout and zoom kept across restarts, setting labels that fit, marking words and order, a
//! re-track offered when the network is switched, and Recent listing a project in place of
//! its video.

use super::*;
use egui_kittest::kittest::{NodeT, Queryable};
use videomocap_core::formats::FrameIndex;
use videomocap_core::lift::{BoneDepth, Root};
use videomocap_core::project::Project;
use videomocap_core::skeleton::{BONE_COUNT, Bone, Joint, MarkingView};

/// The bundled synthetic clip (60 frames, 640×480), with its marks beside it.
fn sample_clip() -> PathBuf {
    videomocap_testkit::repo_root().join("sample_videos/synth_walk_oblique/video.mp4")
}

/// The app on a lifted project of `n` frames (no video behind it), frame 0 flagged `flags`,
/// the lift unsure of the left forearm on frame 0.
fn with_lifted(dir: &Path, flags: &[&str]) -> Harness<'static, App> {
    let mut h = harness(None, &PreparedDialogs::default(), &dir.join("state"));
    let mut p = lifted_project(dir.join("v.mp4"), 3, flags);
    for j in [Joint::Chest, Joint::Neck] {
        let at = p.tracks.as_ref().unwrap().frames[0].points[j].pos;
        p.keys.set(FrameIndex(0), j, at);
    }
    h.state_mut().state_mut().set_project_for_test(p);
    let sure = BoneDepth {
        root: Root::Near,
        single_root: false,
        margin: 2.0 * videomocap_core::lift::UNSURE_MARGIN,
    };
    let mut bones = vec![[sure; BONE_COUNT]; 3];
    bones[0][Bone::new(Joint::LeftElbow, Joint::LeftWrist).index()].margin = 0.0;
    h.state_mut().state_mut().set_depth_choices_for_test(bones);
    h.run_steps(3);
    h
}

/// A bone too long on the user's own marks is named with what to do; a planted foot reads as
/// information, not "flagged: contact:left_ankle"; the unsure forearm is a link, and clicking
/// it flips that bone on this frame, the pose before kept to show the change.
#[test]
fn the_3d_view_names_what_it_flags_and_its_unsure_limbs_flip_from_a_list() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_lifted(dir.path(), &["too_long:chest-neck", "contact:left_ankle"]);
    let scene = crate::views::scene::scene(h.state().state());
    let text: Vec<&str> = scene.notes.iter().map(|n| n.text.as_str()).collect();
    assert!(
        text.iter()
            .any(|t| t.contains("The neck (chest to neck, red)") && t.contains("your own marks")),
        "{text:?}"
    );
    assert!(
        text.iter().any(|t| t.starts_with("Left foot planted")),
        "{text:?}"
    );
    assert!(!text.iter().any(|t| t.contains("contact:")), "{text:?}");
    assert_eq!(scene.planted, [Joint::LeftAnkle]);
    let forearm = Bone::new(Joint::LeftElbow, Joint::LeftWrist);
    assert_eq!(scene.unsure, [forearm]);

    h.get_by_label("left forearm").click();
    h.run_steps(2);
    let s = h.state().state();
    assert_eq!(
        s.project()
            .unwrap()
            .overrides
            .get(&(FrameIndex(0), forearm)),
        Some(&Root::Far),
        "{}",
        s.status()
    );
    assert!(
        s.status().contains("left forearm flipped"),
        "{}",
        s.status()
    );
    let ghost = s.flip_ghost().expect("the pose before the flip");
    assert_eq!((ghost.frame, ghost.bone), (0, forearm));
}

/// "View from the camera" looks through the video camera: each joint lies in the 3D view
/// where the video shows it, the video fitted into the view as the frame view fits it.
#[test]
fn the_view_from_the_camera_puts_the_joints_where_the_video_shows_them() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_lifted(dir.path(), &[]);
    h.get_by_label("View from the camera").click();
    h.run_steps(2);
    let orbit = h.state().orbit();
    assert!(!orbit.follow, "the camera stands still");
    let canvas = h.state().view3d_canvas();
    let scene = crate::views::scene::scene(h.state().state());
    let joints = scene.joints.expect("a skeleton");
    let (camera, body) = standing_person();
    let (w, hgt) = (camera.width as f32, camera.height as f32);
    let scale = (canvas.width() / w).min(canvas.height() / hgt);
    for j in [Joint::HeadTop, Joint::LeftWrist, Joint::RightAnkle] {
        let image = camera.project(&body[j]).unwrap();
        let want = canvas.center()
            + egui::vec2(image.x as f32 - w / 2.0, image.y as f32 - hgt / 2.0) * scale;
        let got = orbit.project(canvas, &joints[j]).unwrap();
        assert!((got - want).length() < 2.0, "{j}: {got:?} vs {want:?}");
    }
}

/// The tracks were made with the pose network on; switching it off says the tracks no longer
/// match and offers to track again; switching it back takes the offer away.
#[test]
fn switching_the_pose_network_offers_to_track_again() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_lifted(dir.path(), &[]);
    assert!(h.state().state().outdated().is_empty());
    h.get_by_label("Tracker").click();
    h.run();
    h.get_by_label("use the pose network").click();
    h.run();
    assert_eq!(
        h.state().state().outdated(),
        [crate::state::Outdated::Tracks(
            "These tracks were made with the pose network on; it is off now".to_owned()
        )]
    );
    assert!(
        h.state().state().status().contains("Track again (T)"),
        "{}",
        h.state().state().status()
    );
    h.get_by_label("Track again (T)");
    h.get_by_label("use the pose network").click();
    h.run();
    assert!(h.state().state().outdated().is_empty());
    assert!(h.query_by_label("Track again (T)").is_none());
}

/// The side panel's setting labels fit beside their sliders at the panel's width (a label ran
/// past the edge, cut: "interpolate up to (s"), and the panel keeps its width.
#[test]
fn every_setting_label_fits_the_side_panel() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_empty_project(dir.path());
    let width = h.state().layout().side_px.expect("drawn");
    h.get_by_label("Tracker").click();
    h.run();
    h.get_by_label("Lift").click();
    h.run();
    let labels = [
        "weak below",
        "interpolate up to (s)",
        "smooth tracks (s)",
        "working size (px)",
        "limb search (°)",
        "keep limbs long",
        "keep forearms long",
        "shoulder spring",
        "arms vs. background",
        "subject height (m)",
        "smoothing (s)",
        "arm swing vs. legs",
        "hands outside the body",
        "image depth evidence",
    ];
    for label in labels {
        let node = h
            .get_all_by_value(label)
            .find(|n| n.accesskit_node().role() == egui::accesskit::Role::Label)
            .unwrap_or_else(|| panic!("no label {label}"));
        assert!(
            node.rect().max.x <= width,
            "{label} ends at {} past the panel's {width}",
            node.rect().max.x
        );
    }
    h.run_steps(3);
    assert_eq!(
        h.state().layout().side_px,
        Some(width),
        "the panel kept its width"
    );
}

/// The 3D view's width and the frame's zoom on a video are what the user left them at, after
/// a restart.
#[test]
fn the_panel_widths_and_the_zoom_are_kept_across_restarts() {
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("state");
    let dialogs = PreparedDialogs::default();
    let open = |state: &Path| {
        let mut h = harness(Some(sample_clip()), &dialogs, state);
        wait(&mut h, "the clip", |s| s.shown() == Some(0));
        h.run_steps(3);
        h
    };
    let mut h = open(&state);
    let rect = h.state().view3d_rect();
    assert!(
        rect.width() < 320.0,
        "narrower than it was: {}",
        rect.width()
    );
    // Wider by 120 points: drag its edge.
    let edge = egui::pos2(rect.left(), rect.center().y);
    drag(&mut h, edge, edge - egui::vec2(120.0, 0.0));
    h.run_steps(2);
    let widened = h.state().view3d_rect().width();
    assert!((widened - rect.width() - 120.0).abs() < 3.0, "{widened}");
    // Zoom in over the frame.
    let centre = screen(&h, nalgebra::Point2::new(320.0, 180.0));
    h.hover_at(centre);
    h.step();
    for _ in 0..5 {
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: egui::vec2(0.0, 120.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Unknown,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
    }
    h.run_steps(20);
    let zoom = h.state().frame_view().zoom_state();
    assert!(zoom.zoom > 1.5, "{zoom:?}");
    drop(h);

    let h = open(&state);
    assert!(
        (h.state().view3d_rect().width() - widened).abs() < 1.0,
        "{} vs {widened}",
        h.state().view3d_rect().width()
    );
    assert_eq!(h.state().frame_view().zoom_state(), zoom);
}

/// The marking guide asks for both hips, then the pelvis with a cross halfway between them;
/// from behind (the left shoulder placed on the image's left), the chest is described on the
/// spine, not the breastbone.
#[test]
fn the_hips_come_before_the_pelvis_and_the_words_follow_a_subject_seen_from_behind() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = with_empty_project(dir.path());
    h.get_by_label("Edit").click();
    h.run();
    h.get_by_label("Mark joints (M)").click();
    h.run();
    let s = h.state_mut().state_mut();
    // Head, neck, chest; the left shoulder on the image's left: seen from behind.
    let mut placed = Vec::new();
    let x_of = |j: Joint| match j {
        Joint::LeftShoulder | Joint::LeftElbow | Joint::LeftWrist => 20.0,
        Joint::LeftHip => 24.0,
        Joint::RightHip => 36.0,
        _ => 40.0,
    };
    while let Some((_, j)) = s.asking().filter(|(_, j)| *j != Joint::Pelvis) {
        placed.push(j);
        s.apply(Intent::Click(nalgebra::Point2::new(x_of(j), 30.0)));
    }
    assert_eq!(s.asking().map(|(_, j)| j), Some(Joint::Pelvis));
    assert!(placed.contains(&Joint::LeftHip) && placed.contains(&Joint::RightHip));
    assert_eq!(s.marking_hint(), Some(nalgebra::Point2::new(30.0, 30.0)));
    assert_eq!(s.marking_view(), MarkingView::Behind);
    assert!(
        Joint::Chest
            .definition(s.marking_view())
            .contains("lower tips of the shoulder blades")
    );
    h.run();
    h.get_by_label_contains("halfway between the hips");
}

/// Opening a video whose saved project is offered, then the project: File ▸ Recent lists the
/// project in place of the video, and opening the video alone again keeps it so.
#[test]
fn recent_lists_a_saved_project_in_place_of_its_video() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("clip.mp4");
    std::fs::copy(sample_clip(), &video).unwrap();
    let project = dir.path().join("clip.videomocap.json");
    Project::new(video.clone()).save(&project).unwrap();
    let mut h = harness(
        Some(video.clone()),
        &PreparedDialogs::default(),
        &dir.path().join("state"),
    );
    wait(&mut h, "the clip", |s| s.project_beside().is_some());
    h.run_steps(2);
    h.get_by_label("Open the project").click();
    h.run_steps(2);
    wait(&mut h, "the project", |s| s.frame_count() == 60);
    assert_eq!(h.state().state().recent(), std::slice::from_ref(&project));
    h.state_mut().state_mut().apply(Intent::Open(video.clone()));
    wait(&mut h, "the clip again", |s| s.project_beside().is_some());
    assert_eq!(h.state().state().recent(), [project]);
}

/// On a desktop without file dialogs, an export into a folder that does not exist is refused
/// with the folder named once, and "Create the folder" makes it and writes the file.
#[test]
fn an_export_into_a_missing_folder_offers_to_create_it() {
    let dir = tempfile::tempdir().unwrap();
    let dialogs = PreparedDialogs::default();
    dialogs.unavailable.set(true);
    let mut h = harness(Some(sample_clip()), &dialogs, &dir.path().join("state"));
    wait(&mut h, "the clip and its marks", |s| {
        s.shown() == Some(0) && s.project().is_some_and(|p| p.marks().is_some())
    });
    h.state_mut()
        .state_mut()
        .apply(Intent::Export(crate::state::ExportKind::Marks));
    let target = dir.path().join("new/folder/marks.json");
    h.state_mut()
        .state_mut()
        .apply(Intent::PathEdited(target.display().to_string()));
    h.run_steps(2);
    h.get_by_label("OK").click();
    h.run_steps(3);
    assert!(!target.exists());
    let folder = target.parent().unwrap().display().to_string();
    let status = h.state().state().status().to_owned();
    assert_eq!(status.matches(&folder).count(), 1, "{status}");
    assert!(status.contains("does not exist"), "{status}");
    h.get_by_label("Create the folder").click();
    h.run_steps(3);
    assert!(target.is_file(), "{}", h.state().state().status());
    assert!(h.state().state().path_request().is_none());
    assert_eq!(
        h.state().state().status(),
        format!("Wrote {}", target.display())
    );
}

/// A portrait clip keeps its height once tracked: the timeline folds its sixteen strips into
/// one (the video lost 180 points to them); "each joint" unfolds them, and that choice is
/// kept across a restart. (A landscape clip beside the panels gets the strips unfolded: the
/// desktop tests hover a joint's strip.)
#[test]
fn a_tracked_portrait_clip_keeps_its_height_and_the_strips_unfold_on_asking() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("portrait");
    std::fs::create_dir(&frames).unwrap();
    for i in 0..3u8 {
        image::RgbImage::from_pixel(108, 192, image::Rgb([i * 60, 40, 40]))
            .save(frames.join(format!("f{i}.png")))
            .unwrap();
    }
    let state = dir.path().join("state");
    let open = |h: &mut Harness<'static, App>| {
        wait(h, "the folder", |s| {
            s.frame_count() == 3 && s.shown() == Some(0)
        });
        h.run_steps(3);
        let before = h.state().central_rect().height();
        let p = lifted_project(frames.clone(), 3, &[]);
        h.state_mut().state_mut().set_project_for_test(p);
        h.run_steps(4);
        assert!(h.state().state().strips().is_some());
        before
    };
    let dialogs = PreparedDialogs::default();
    let mut h = harness(Some(frames.clone()), &dialogs, &state);
    let before = open(&mut h);
    let tracked = h.state().central_rect().height();
    assert!(!h.state().timeline_unfolded(), "folded by default");
    assert!(
        before - tracked < 40.0,
        "the strips took {} points from the video",
        before - tracked
    );
    h.get_by_label("each joint").click();
    h.run_steps(4);
    assert!(h.state().timeline_unfolded());
    let unfolded = h.state().central_rect().height();
    assert!(tracked - unfolded > 150.0, "{tracked} → {unfolded}");
    drop(h);

    let mut h = harness(Some(frames.clone()), &dialogs, &state);
    open(&mut h);
    assert!(h.state().timeline_unfolded(), "the user's choice is kept");
}

/// A landscape clip shows a strip per joint: the bundled 640×480 walk beside the panels loses
/// less than a tenth of its height to them.
#[test]
fn a_landscape_clip_shows_a_strip_per_joint() {
    let dir = tempfile::tempdir().unwrap();
    let dialogs = PreparedDialogs::default();
    let mut h = harness(Some(sample_clip()), &dialogs, &dir.path().join("state"));
    wait(&mut h, "the clip", |s| s.shown() == Some(0));
    h.run_steps(3);
    let p = lifted_project(sample_clip(), 60, &[]);
    h.state_mut().state_mut().set_project_for_test(p);
    h.run_steps(4);
    assert!(h.state().timeline_unfolded());
}
