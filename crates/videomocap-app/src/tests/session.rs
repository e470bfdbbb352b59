use super::*;
use crate::state::ExportKind;
use crate::state::frame_loader::FrameLoader;
use crate::state::frame_loader::ProxyStatus;
use egui_kittest::kittest::Queryable;
use videomocap_core::formats::FrameIndex;
use videomocap_core::formats::Marks;
use videomocap_core::project::Project;
use videomocap_core::skeleton::{Bone, Joint};

/// A video with far-apart keyframes gets a seek proxy in the cache folder, the status bar
/// says so, and seeks end on the full frame (the preview only stands in meanwhile).
#[test]
fn a_long_gop_video_gets_fast_seeking_and_seeks_end_on_the_full_frame() {
    let dir = tempfile::tempdir().unwrap();
    let clip = dir.path().join("long.mp4");
    crate::state::frame_loader::tests::long_gop_clip(&clip, 120);
    let dialogs = PreparedDialogs::default();
    let state = dir.path().join("state");
    let mut h = harness(Some(clip), &dialogs, &state);
    wait(&mut h, "the proxy", |a| {
        a.loader().and_then(FrameLoader::proxy) == Some(&ProxyStatus::Ready)
    });
    h.step();
    h.get_by_label("fast seeking");
    assert_eq!(std::fs::read_dir(state.join("proxies")).unwrap().count(), 1);
    wait(&mut h, "frame 0", |a| a.shown() == Some(0) && !a.preview());
    let fitted = h.state().frame_view().transform().expect("frame drawn");
    h.key_press(egui::Key::End);
    wait(&mut h, "the last frame, full size", |a| {
        a.shown() == Some(119) && !a.preview()
    });
    let texture = h.state().state().texture().map(|t| t.size());
    assert_eq!(texture, Some([320, 240]));
    // The picture stays where it was: previews are drawn over the frame's own size.
    let after = h.state().frame_view().transform().expect("frame drawn");
    assert_eq!(
        fitted.to_screen(Point2::new(10.0, 10.0)),
        after.to_screen(Point2::new(10.0, 10.0))
    );
}

#[test]
fn arrow_keys_step_through_frames_and_stop_at_the_ends() {
    let dir = tempfile::tempdir().unwrap();
    for i in 0..12 {
        image::RgbImage::from_pixel(8, 6, image::Rgb([i * 20, 0, 0]))
            .save(dir.path().join(format!("f{i}.png")))
            .unwrap();
    }
    let dialogs = PreparedDialogs::default();
    let mut h = harness(
        Some(dir.path().to_owned()),
        &dialogs,
        &dir.path().join("state"),
    );
    wait(&mut h, "the folder to open", |a| a.frame_count() == 12);
    h.key_press(egui::Key::ArrowRight);
    h.step();
    assert_eq!(h.state().state().current_frame(), 1);
    h.key_press_modifiers(egui::Modifiers::SHIFT, egui::Key::ArrowRight);
    h.step();
    assert_eq!(h.state().state().current_frame(), 11);
    h.key_press(egui::Key::Home);
    h.step();
    assert_eq!(h.state().state().current_frame(), 0);
}

/// A fresh app that opens the point-volume folder `vols` through File ▸ Open point volumes.
fn open_point_volumes(vols: &std::path::Path, state: &std::path::Path) -> Harness<'static, App> {
    let dialogs = PreparedDialogs::default();
    dialogs.answers.borrow_mut().push_back(vols.to_owned());
    let mut h = harness(None, &dialogs, state);
    h.step();
    h.get_by_label("File").click();
    h.run_steps(3);
    h.get_by_label("Open point volumes…").click();
    h.run_steps(3);
    h
}

/// Volume mode: File ▸ Open point volumes processes a folder of PLY frames off the UI
/// thread, then the 3D viewport shows the frame's points, skeleton curve, bodies and
/// skeleton; arrow keys step through the frames.
#[test]
fn volume_mode_opens_a_point_volume_folder_and_steps_through_it() {
    let dir = tempfile::tempdir().unwrap();
    let vols = dir.path().join("vols");
    let motion = videomocap_testkit::synth::procedural(
        videomocap_testkit::synth::ProceduralMotion::March,
        &videomocap_core::skeleton::SubjectModel::default(),
        6,
        10.0,
    );
    videomocap_testkit::synth::write_volume_sequence(
        &motion,
        &vols,
        &videomocap_testkit::synth::VoxelParams::default(),
        |_, _| {},
    )
    .unwrap();
    let mut h = open_point_volumes(&vols, &dir.path().join("state"));
    assert!(
        h.state().state().volume().is_some(),
        "{}",
        h.state().state().status()
    );
    wait(&mut h, "the volumes to be processed", |a| {
        a.frame_count() == 6
    });
    assert!(!h.state().state().busy());
    assert!(
        h.state().state().status().contains("6 with a five-limb"),
        "{}",
        h.state().state().status()
    );
    let scene = crate::views::scene::scene(h.state().state());
    assert!(scene.joints.is_some());
    assert!(scene.cloud.len() > 500, "{} points", scene.cloud.len());
    assert!(scene.segments.len() > 50, "curve and bodies drawn");
    h.key_press(egui::Key::ArrowRight);
    h.step();
    assert_eq!(h.state().state().current_frame(), 1);
    // Hiding the points leaves the curve and the skeleton.
    h.get_by_label("points (coloured by body)").click();
    h.step();
    let scene = crate::views::scene::scene(h.state().state());
    assert!(scene.cloud.is_empty() && scene.joints.is_some());
}

/// A session that died with unsaved work on a video that also has a saved project: the app
/// asks one question at a time (recovery first; the two windows opened one over the other),
/// and once the work is recovered it offers no older project over it.
#[test]
fn recovery_comes_before_the_project_beside_and_wins() {
    let dir = tempfile::tempdir().unwrap();
    let sample = videomocap_testkit::repo_root().join("sample_videos/synth_walk_oblique");
    let video = dir.path().join("clip.mp4");
    std::fs::copy(sample.join("video.mp4"), &video).unwrap();
    let marks = Marks::load(&sample.join("marks.json")).unwrap();
    let saved = Project::new(video.clone());
    saved
        .save(&dir.path().join("clip.videomocap.json"))
        .unwrap();
    let state = dir.path().join("state");
    std::fs::create_dir(&state).unwrap();
    let mut unsaved = Project::new(video.clone());
    unsaved.keys = videomocap_core::track::KeyFrames::from_marks(&marks);
    let autosave = crate::state::autosave::Autosaver::new(&state);
    unsaved.save(autosave.path()).unwrap();
    let dialogs = PreparedDialogs::default();
    let mut h = harness(Some(video.clone()), &dialogs, &state);
    wait(&mut h, "the clip to open", |a| a.frame_count() == 60);
    h.run_steps(2);
    assert!(h.state().state().offers_recovery());
    assert!(
        h.query_by_label("Open the project").is_none(),
        "the project is not offered over the recovery"
    );
    h.get_by_label("Recover").click();
    h.run_steps(2);
    wait(&mut h, "the recovered clip", |a| a.frame_count() == 60);
    h.run_steps(2);
    assert_eq!(h.state().state().project().unwrap().keys, unsaved.keys);
    assert!(
        h.query_by_label("Open the project").is_none(),
        "no older project offered over recovered work"
    );
}

/// A folder of broken PLY files: the 3D view says what went wrong with which file and what
/// to do (it said "mark, then Track", the video mode's hint), and so does the status line.
#[test]
fn broken_point_volumes_are_explained_in_the_3d_view() {
    let dir = tempfile::tempdir().unwrap();
    let vols = dir.path().join("vols");
    std::fs::create_dir(&vols).unwrap();
    let cut_short = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n\
                     property float y\nproperty float z\nend_header\n1 2 3\n";
    for k in 0..3 {
        std::fs::write(vols.join(format!("frame_{k:04}.ply")), cut_short).unwrap();
    }
    let mut h = open_point_volumes(&vols, &dir.path().join("state"));
    let scene = crate::views::scene::scene(h.state().state());
    let text = scene.empty_text.unwrap_or_default();
    assert!(
        h.state().state().busy() || text.contains("could not"),
        "while processing: {text}"
    );
    wait(&mut h, "the volumes to fail", |s| !s.busy());
    let scene = crate::views::scene::scene(h.state().state());
    let text = scene.empty_text.unwrap_or_default();
    assert!(
        text.contains("could not be turned into a skeleton")
            && text.contains("frame_0000.ply")
            && text.contains("PLY, XYZ or voxel"),
        "{text}"
    );
    assert!(!text.contains("mark, then Track"));
    assert!(
        h.state().state().status().contains("frame_0000.ply"),
        "{}",
        h.state().state().status()
    );
}

/// The whole session a user has: open a clip, mark 16 joints by clicking, drag one, undo,
/// track and lift, scrub, orbit the 3D view, export a BVH, and after the app dies, recover
/// the work from the autosave.
#[test]
fn mark_drag_undo_track_scrub_orbit_export_and_recover() {
    let dir = tempfile::tempdir().unwrap();
    let sample = videomocap_testkit::repo_root().join("sample_videos/synth_walk_oblique");
    let video = dir.path().join("clip.mp4");
    std::fs::copy(sample.join("video.mp4"), &video).unwrap();
    let truth = Marks::load(&sample.join("marks.json")).unwrap();
    let state = dir.path().join("state");
    let dialogs = PreparedDialogs::default();
    let mut h = harness(Some(video.clone()), &dialogs, &state);
    wait(&mut h, "the clip to open", |a| {
        a.frame_count() == 60 && a.shown() == Some(0)
    });
    assert!(
        h.state().state().project().unwrap().keys.frames.is_empty(),
        "no marks beside the copy"
    );

    // Mark: the guide asks for each joint in turn; click where it is.
    h.key_press(egui::Key::M);
    h.step();
    for j in Joint::MARKING_ORDER {
        assert_eq!(h.state().state().asking().map(|(_, j)| j), Some(j));
        let pos = screen(&h, truth.points[j]);
        click(&mut h, pos);
    }
    assert_eq!(
        h.state().state().asking().map(|(_, j)| j),
        None,
        "the guide ends after 16 joints"
    );
    let marks = h
        .state()
        .state()
        .project()
        .unwrap()
        .marks()
        .expect("all 16 marked");
    for j in Joint::ALL {
        assert!((marks.points[j] - truth.points[j]).norm() < 0.5, "{j:?}");
    }

    // Drag the left wrist 30 screen points right, then undo.
    let wrist = truth.points[Joint::LeftWrist];
    let from = screen(&h, wrist);
    drag(&mut h, from, from + egui::vec2(30.0, 0.0));
    let moved =
        h.state().state().project().unwrap().keys.frames[&FrameIndex(0)][Joint::LeftWrist].unwrap();
    assert!(
        moved.x - wrist.x > 5.0,
        "dragged to {moved:?} from {wrist:?}"
    );
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.step();
    let back =
        h.state().state().project().unwrap().keys.frames[&FrameIndex(0)][Joint::LeftWrist].unwrap();
    assert!(
        (back - marks.points[Joint::LeftWrist]).norm() < 1e-9,
        "undo puts it back"
    );

    // Where the weak list starts before the lift (it must not jump when the lengths arrive).
    let weak_top = h.get_by_label("Weak tracking").rect().top();
    // Track (and lift) in the background.
    h.key_press(egui::Key::T);
    h.step();
    assert!(h.state().state().busy());
    wait(&mut h, "tracking and lifting", |a| {
        !a.busy() && a.project().is_some_and(|p| p.skeleton.is_some())
    });
    assert_eq!(
        h.state()
            .state()
            .project()
            .unwrap()
            .tracks
            .as_ref()
            .unwrap()
            .frames
            .len(),
        60
    );
    // A walk plants its feet: the lift held them (contact flags, drawn on the timeline) and
    // a contact is not a problem (the status's flagged count leaves them out).
    let skeleton = h
        .state()
        .state()
        .project()
        .unwrap()
        .skeleton
        .clone()
        .unwrap();
    let planted = skeleton
        .frames
        .iter()
        .filter(|f| f.flags.iter().any(|g| g.starts_with("contact:")))
        .count();
    assert!(planted >= 10, "{planted} frames with a planted foot");
    let flagged = skeleton.frames.iter().filter(|f| f.flagged()).count();
    assert!(
        h.state()
            .state()
            .status()
            .contains(&format!("({flagged} frames flagged)")),
        "{}",
        h.state().state().status()
    );
    // The Parameters panel has the lengths the lift used and where each came from (on hover
    // of its one line: the tooltip is not in the accessibility tree), and the weak list below
    // has not moved.
    h.step();
    assert_eq!(h.get_by_label("Weak tracking").rect().top(), weak_top);
    h.get_by_label_contains("body lengths: read from the video (hover");
    assert!(h.state().state().subject_fit().is_some());

    // Scrub.
    for _ in 0..3 {
        h.key_press(egui::Key::ArrowRight);
        h.step();
    }
    assert_eq!(h.state().state().current_frame(), 3);
    wait(&mut h, "frame 3", |a| a.shown() == Some(3));

    // Correct a joint on frame 3 by dragging it: frame 3 becomes a key frame for it and
    // tracking re-runs from there, keeping the correction.
    let wrist = h.state().state().points(3)[Joint::LeftWrist].unwrap().0;
    let before = h
        .state()
        .state()
        .project()
        .unwrap()
        .tracks
        .as_ref()
        .unwrap()
        .frames[3]
        .points;
    let moved_to = wrist + nalgebra::Vector2::new(6.0, -4.0);
    let (from, to) = (screen(&h, wrist), screen(&h, moved_to));
    drag(&mut h, from, to);
    assert!(
        h.state().state().busy(),
        "re-tracking: {}",
        h.state().state().status()
    );
    wait(&mut h, "re-tracking and lifting", |a| {
        !a.busy() && a.project().is_some_and(|p| p.skeleton.is_some())
    });
    let p = h.state().state().project().unwrap();
    let key = p.keys.frames[&FrameIndex(3)][Joint::LeftWrist].unwrap();
    assert!((key - moved_to).norm() < 1.5, "key {key} vs {moved_to}");
    let tracked = &p.tracks.as_ref().unwrap().frames[3].points[Joint::LeftWrist];
    assert!((tracked.pos - key).norm() < 1e-9, "the track keeps the key");
    // The joints not dragged stay where they were on frame 3 (the re-track starts from
    // what the user saw there, not from the marks of frame 0).
    let after = &p.tracks.as_ref().unwrap().frames[3].points;
    let marked = p.marks().unwrap().points;
    let mut kept = 0;
    for j in Joint::ALL.into_iter().filter(|&j| j != Joint::LeftWrist) {
        if before[j].confidence >= p.settings.tracker.weak_reliability {
            assert!((after[j].pos - before[j].pos).norm() < 1e-6, "{}", j.name());
            kept += usize::from((before[j].pos - marked[j]).norm() > 1.0);
        }
    }
    assert!(
        kept >= 3,
        "too few joints moved since frame 0 to tell ({kept})"
    );

    // Flip a limb's depth on this frame (the first limb whose two depths differ here: one
    // whose image is longer than the bone says it cannot flip): an override is recorded and
    // the lift re-runs; after undoing it, the earlier result's choices are still known and it
    // flips again.
    let flips_before = h.state().state().project().unwrap().overrides.len();
    let flipped = Bone::ALL[4..].iter().find(|&&bone| {
        flip(&mut h, bone);
        h.state().state().project().unwrap().overrides.len() == flips_before + 1
    });
    assert!(flipped.is_some(), "{}", h.state().state().status());
    wait(&mut h, "the lift after a flip", |a| !a.busy());
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.step();
    assert_eq!(
        h.state().state().project().unwrap().overrides.len(),
        flips_before
    );
    flip(&mut h, Bone::ALL[7]);
    assert!(
        !h.state().state().status().contains("not known"),
        "{}",
        h.state().state().status()
    );
    wait(&mut h, "the lift after the second flip", |a| !a.busy());

    // Orbit the 3D view by dragging in it (the right-hand panel).
    let before = h.state().orbit();
    drag(&mut h, egui::pos2(1200.0, 400.0), egui::pos2(1260.0, 420.0));
    assert!(
        (h.state().orbit().yaw - before.yaw).abs() > 0.1,
        "the view turned"
    );

    // Export a BVH through the menu (the dialog answers with a path).
    let export = |h: &mut Harness<'_, App>, kind: ExportKind, name: &str| {
        let path = dir.path().join(name);
        dialogs.answers.borrow_mut().push_back(path.clone());
        h.get_by_label("Export").click();
        h.run_steps(3);
        h.get_by_label(kind.label()).click();
        h.run_steps(3);
        path
    };
    let bvh = export(&mut h, ExportKind::Bvh, "out.bvh");
    assert!(
        h.state().state().status().contains("Wrote"),
        "{}",
        h.state().state().status()
    );
    let read = videomocap_core::bvh::Bvh::load(&bvh).unwrap();
    assert_eq!(read.frame_count(), 60);
    // And with Mixamo's bone names, for retargeting: the same motion.
    let mixamo = export(&mut h, ExportKind::BvhMixamo, "out.mixamo.bvh");
    let text = std::fs::read_to_string(&mixamo).unwrap();
    assert!(text.contains("ROOT mixamorig:Hips"), "{}", &text[..60]);
    let read_mixamo = videomocap_core::bvh::Bvh::load(&mixamo).unwrap();
    assert_eq!(read_mixamo.frame(30), read.frame(30));

    // The app dies without saving: the autosave holds the work, and the next start offers it.
    h.state_mut().state_mut().flush_autosave();
    let autosave = h.state().state().autosave_path().unwrap();
    assert!(autosave.is_file());
    let expected = h.state().state().project().unwrap().clone();
    drop(h);
    let mut h = harness(None, &dialogs, &state);
    h.step();
    assert!(h.state().state().offers_recovery());
    h.get_by_label("Recover").click();
    h.run_steps(2);
    wait(&mut h, "the recovered clip", |a| a.frame_count() == 60);
    let p = h.state().state().project().unwrap();
    assert_eq!(p.keys, expected.keys);
    assert_eq!(p.tracks, expected.tracks);
    assert!(p.skeleton.is_some());
    // Recent files survive the restart.
    assert_eq!(h.state().state().recent().first(), Some(&video));

    // The recovered work is not in a project file: opening another video asks first.
    let other = dir.path().join("other");
    std::fs::create_dir(&other).unwrap();
    image::RgbImage::new(8, 6)
        .save(other.join("f0.png"))
        .unwrap();
    h.state_mut().state_mut().apply(Intent::Open(other.clone()));
    h.run_steps(3);
    assert!(h.state().state().leaving().is_some());
    h.get_by_label("Cancel").click();
    h.run_steps(2);
    assert!(h.state().state().leaving().is_none());
    assert_eq!(
        h.state().state().project().unwrap().video,
        video,
        "cancel keeps the work"
    );
    let saved = dir.path().join("saved.videomocap.json");
    dialogs.answers.borrow_mut().push_back(saved.clone());
    h.state_mut().state_mut().apply(Intent::Open(other.clone()));
    h.run_steps(3);
    h.get_by_label("Save").click();
    h.run_steps(2);
    assert!(
        saved.is_file(),
        "saved before opening: {}",
        h.state().state().status()
    );
    assert_eq!(Project::load(&saved).unwrap().keys, expected.keys);
    wait(&mut h, "the other folder", |a| a.frame_count() == 1);
    // Recent lists what opened, and the saved project in place of its bare video.
    assert_eq!(
        h.state().state().recent()[..2],
        [other.clone(), saved.clone()]
    );
    assert!(!h.state().state().recent().contains(&video));
    // Opening the video alone again offers the project saved for it.
    h.state_mut().state_mut().apply(Intent::Open(video.clone()));
    wait(&mut h, "the clip again", |a| a.frame_count() == 60);
    assert_eq!(h.state().state().project_beside(), Some(saved.as_path()));
    h.run_steps(2);
    h.get_by_label("Open the project").click();
    h.run_steps(2);
    wait(&mut h, "the project", |a| a.frame_count() == 60);
    assert!(h.state().state().project_beside().is_none());
    assert_eq!(h.state().state().project().unwrap().keys, expected.keys);
    assert_eq!(h.state().state().recent().first(), Some(&saved));
    // A project that does not open is not listed (the clip stays open).
    let broken = dir.path().join("broken.videomocap.json");
    std::fs::write(&broken, "{ not a project").unwrap();
    h.state_mut()
        .state_mut()
        .apply(Intent::Open(broken.clone()));
    h.run_steps(2);
    assert!(!h.state().state().recent().contains(&broken));
}
