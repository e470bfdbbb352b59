//! The app driven as a user drives it (egui_kittest): shared set-up and input helpers, and the
//! tests by subject: `session` (open, mark, correct, track, export, recover), `settings` (the
//! side panel's parameters), `desktop` (quit, the path field, strips, a steady layout), `walk`
//! (what a new user's walk through the app found: flags, doubt, layout, marking, re-track,
//! Recent).

mod desktop;
mod session;
mod settings;
mod walk;

use super::app::App;
use super::intent::Intent;
use super::state::file_dialogs::PreparedDialogs;
use super::state::{Config, State};
use egui_kittest::Harness;
use nalgebra::Point2;
use std::path::{Path, PathBuf};

/// Steps the app until `done` holds (up to 30 s).
pub(crate) fn wait(h: &mut Harness<'_, App>, what: &str, done: impl Fn(&State) -> bool) {
    for _ in 0..6000 {
        h.step();
        if done(h.state().state()) {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    panic!(
        "timed out waiting for {what}; status: {}",
        h.state().state().status()
    );
}

/// A press and release without moving.
pub(crate) fn click(h: &mut Harness<'_, App>, pos: egui::Pos2) {
    h.hover_at(pos);
    h.step();
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.step();
    h.step();
}

/// A press, six moves and a release.
pub(crate) fn drag(h: &mut Harness<'_, App>, from: egui::Pos2, to: egui::Pos2) {
    h.hover_at(from);
    h.step();
    h.drag_at(from);
    h.step();
    for k in 1..=6 {
        h.hover_at(from + (to - from) * (k as f32 / 6.0));
        h.step();
    }
    h.drop_at(to);
    h.step();
    h.step();
}

/// Where image point `p` is on the screen.
pub(crate) fn screen(h: &Harness<'_, App>, p: Point2<f64>) -> egui::Pos2 {
    h.state()
        .frame_view()
        .transform()
        .expect("frame drawn")
        .to_screen(p)
}

/// The app with prepared dialogs and its autosave in `state`, opening `video`.
pub(crate) fn harness(
    video: Option<PathBuf>,
    dialogs: &PreparedDialogs,
    state: &Path,
) -> Harness<'static, App> {
    let config = Config {
        dialogs: Box::new(dialogs.clone()),
        autosave_dir: Some(state.to_owned()),
        proxy_dir: Some(state.join("proxies")),
    };
    Harness::builder()
        .with_size(egui::vec2(1400.0, 860.0))
        .build_eframe(move |cc| App::with_config(&cc.egui_ctx, video, config))
}

/// Flips `bone` on the current frame.
pub(crate) fn flip(h: &mut Harness<'_, App>, bone: videomocap_core::skeleton::Bone) {
    h.state_mut().state_mut().apply(Intent::Flip(bone));
}

/// A camera of 640×480 pixels (focal 600 px) and a person standing 3 m in front of it, in
/// camera space (metres, Y down).
pub(crate) fn standing_person() -> (
    videomocap_core::camera::PinholeCamera,
    videomocap_core::skeleton::PerJoint<nalgebra::Point3<f64>>,
) {
    use videomocap_core::skeleton::{Joint, PerJoint};
    let body = PerJoint::from_fn(|j| {
        let side = if j.name().starts_with("left") {
            1.0
        } else if j.name().starts_with("right") {
            -1.0
        } else {
            0.0
        };
        let (x, y) = match j {
            Joint::HeadTop => (0.0, -0.8),
            Joint::Neck => (0.0, -0.6),
            Joint::Chest => (0.0, -0.45),
            Joint::LeftShoulder | Joint::RightShoulder => (0.2, -0.5),
            Joint::LeftElbow | Joint::RightElbow => (0.25, -0.2),
            Joint::LeftWrist | Joint::RightWrist => (0.28, 0.05),
            Joint::LeftHip | Joint::RightHip => (0.1, 0.0),
            Joint::LeftKnee | Joint::RightKnee => (0.1, 0.45),
            Joint::LeftAnkle | Joint::RightAnkle => (0.1, 0.9),
            Joint::Pelvis => (0.0, 0.0),
        };
        nalgebra::Point3::new(side * x, y, 3.0)
    });
    (
        videomocap_core::camera::PinholeCamera::centred(600.0, 640, 480),
        body,
    )
}

/// A project on `video` with `n` frames tracked and lifted: the [`standing_person`] on every
/// frame, frame 0 flagged with `flags_0`.
pub(crate) fn lifted_project(
    video: PathBuf,
    n: usize,
    flags_0: &[&str],
) -> videomocap_core::project::Project {
    use videomocap_core::formats::{
        Frame3d, FrameIndex, FrameTracks, PointSource, Skeleton3d, SourceInfo, TrackedPoint,
        Tracks2d,
    };
    use videomocap_core::skeleton::PerJoint;
    let (camera, body) = standing_person();
    let mut p = videomocap_core::project::Project::new(video.clone());
    p.tracks = Some(std::sync::Arc::new(Tracks2d {
        source: SourceInfo {
            path: video,
            width: camera.width,
            height: camera.height,
            fps: 30.0,
            frame_count: n,
        },
        frames: (0..n)
            .map(|i| FrameTracks {
                index: FrameIndex(i),
                body3d: None,
                points: PerJoint::from_fn(|j| TrackedPoint {
                    pos: camera.project(&body[j]).expect("in front"),
                    confidence: 0.9,
                    source: PointSource::Tracked,
                }),
            })
            .collect(),
    }));
    p.skeleton = Some(std::sync::Arc::new(Skeleton3d {
        camera,
        fps: Some(30.0),
        bone_lengths_m: Default::default(),
        frames: (0..n)
            .map(|i| Frame3d {
                index: FrameIndex(i),
                points: body,
                flags: if i == 0 {
                    flags_0.iter().map(|f| (*f).to_owned()).collect()
                } else {
                    Vec::new()
                },
            })
            .collect(),
    }));
    p
}

/// The app with a new project on a video that is never opened, state kept under `dir`, one
/// frame drawn.
fn with_empty_project(dir: &Path) -> Harness<'static, App> {
    let mut h = harness(None, &PreparedDialogs::default(), &dir.join("state"));
    h.state_mut()
        .state_mut()
        .set_project_for_test(videomocap_core::project::Project::new(dir.join("v.mp4")));
    h.run();
    h
}
