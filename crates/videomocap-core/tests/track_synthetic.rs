//! Tracking on rendered clips with known joints: accuracy floors, the CLI's output file, and
//! bad input (too short a video, marks off the image).

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

mod common;

use std::path::Path;
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::FrameIndex;
use videomocap_core::formats::{Marks, PointSource};
use videomocap_core::skeleton::Joint;
use videomocap_core::track::{TrackError, TrackJob, TrackerParams, track_video};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::eval::{ClipScore, score_tracks};
use videomocap_testkit::synth::{
    GroundTruth, MotionSource, ProceduralMotion, SynthParams, VideoOutput, View, render_clip,
    render_small_clip,
};

fn render(dir: &Path, motion: ProceduralMotion, frames: usize, view: View) {
    render_small_clip(dir, motion, frames, view).unwrap();
}

/// A motion-capture file of `tests/data`, from its start.
fn bundled_bvh(file: &str) -> MotionSource {
    bundled_bvh_from(file, 0.0)
}

/// A motion-capture file of `tests/data`, from `start_s` seconds in.
fn bundled_bvh_from(file: &str, start_s: f64) -> MotionSource {
    MotionSource::Bvh {
        path: videomocap_testkit::repo_root()
            .join("tests/data")
            .join(file),
        start_s,
    }
}

/// Renders a side view of `bvh` (from `tests/data`) into `dir` as `bench track`'s suite clip
/// number `k` is rendered (its background and noise seeds, the room photograph behind):
/// `frames` frames at `fps`, the person `person_px` tall, as PNG frames.
fn render_side_view(dir: &Path, bvh: &str, frames: usize, fps: u32, person_px: f64, k: u64) {
    let (motion, output) = (bundled_bvh(bvh), VideoOutput::PngSequence);
    render_suite_like(
        dir,
        motion,
        View::Side,
        (frames, fps),
        person_px,
        (k, Some("pose2sim_room.jpg")),
        output,
    );
}

/// Renders `motion` seen from `view` into `dir` as `bench track`'s suite clip
/// number `k` of `(k, photo)` is rendered (its background and noise seeds; the photograph
/// `photo` of `assets/backgrounds` behind, else the generated background): `(frames, fps)`,
/// the person `person_px` tall, as `output` (the suite's clips are H.264, whose artefacts some
/// failures need).
fn render_suite_like(
    dir: &Path,
    motion: MotionSource,
    view: View,
    (frames, fps): (usize, u32),
    person_px: f64,
    (k, photo): (u64, Option<&str>),
    output: VideoOutput,
) {
    let mut params = SynthParams {
        motion,
        frames,
        fps,
        view,
        person_px,
        background_seed: 11 + k,
        background_image: photo.map(|name| {
            videomocap_testkit::repo_root()
                .join("assets/backgrounds")
                .join(name)
        }),
        output,
        ..SynthParams::default()
    };
    params.effects.seed = 100 + k;
    render_clip(&params, dir, &mut |_, _| {}, &AtomicBool::new(false)).unwrap();
}

fn job(marks: &Marks, threads: usize) -> TrackJob {
    TrackJob::from_marks(marks, TrackerParams::default(), threads)
}

/// Asserts the clip's PCK@0.2 is at least `floor`, reporting the mean error if not.
fn assert_pck(s: &ClipScore, floor: f64) {
    assert!(
        s.overall.pck02() >= floor,
        "PCK@0.2 {:.3}, mean {:.1} px",
        s.overall.pck02(),
        s.overall.mean_px()
    );
}

/// Tracks the clip rendered into `dir` (PNG frames) from its marks with `params`, two threads,
/// and scores it against the clip's truth.
fn track_rendered(dir: &Path, params: TrackerParams) -> ClipScore {
    common::track_and_score(dir, &dir.join("frames"), params)
}

/// Tracks the clip rendered in `dir` with `params`; returns `joint`'s mean error (pixels) and
/// the clip's PCK@0.2.
fn joint_and_pck(dir: &Path, joint: Joint, params: TrackerParams) -> (f64, f64) {
    let s = track_rendered(dir, params);
    (s.per_joint[joint].mean_px(), s.overall.pck02())
}

/// Tracks the clip rendered into `dir` as H.264 with `params`; returns the mean error
/// (pixels) of `joints`, averaged over them, and the clip's PCK@0.2.
fn joints_and_pck_mp4(dir: &Path, joints: &[Joint], params: TrackerParams) -> (f64, f64) {
    let s = common::track_and_score(dir, &dir.join("video.mp4"), params);
    let px = joints
        .iter()
        .map(|&j| s.per_joint[j].mean_px())
        .sum::<f64>()
        / joints.len() as f64;
    (px, s.overall.pck02())
}

#[test]
fn a_waving_person_is_tracked_within_a_fifth_of_the_torso() {
    let dir = tempfile::tempdir().unwrap();
    render(dir.path(), ProceduralMotion::Wave, 30, View::Frontal);
    let gt = GroundTruth::load(&dir.path().join("gt.json")).unwrap();
    let marks = Marks::load(&dir.path().join("marks.json")).unwrap();
    let mut video = Video::open(&dir.path().join("frames"), &OpenOptions::default()).unwrap();
    let mut seen = 0;
    let out = track_video(
        &mut video,
        &job(&marks, 2),
        &mut |p| {
            assert!(p.done <= p.total);
            seen += 1;
        },
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(out.tracks.frames.len(), 30);
    assert!(seen >= 30, "progress reported {seen} times");
    let s = score_tracks(&gt, &out.tracks).unwrap();
    assert_pck(&s, 0.9);
    // The marked frame is returned exactly, with full confidence.
    for j in Joint::ALL {
        let p = out.tracks.frames[0].points[j];
        assert!((p.pos - marks.points[j]).norm() < 1e-9);
        assert_eq!(p.confidence, 1.0);
        assert_eq!(p.source, PointSource::Tracked);
    }
    // Every confidence is a reliability in [0, 1].
    assert!(out.tracks.frames.iter().all(|f| {
        f.points
            .0
            .iter()
            .all(|p| (0.0..=1.0).contains(&p.confidence))
    }));
}

#[test]
fn one_thread_and_two_threads_give_the_same_tracks() {
    let dir = tempfile::tempdir().unwrap();
    render(
        dir.path(),
        ProceduralMotion::JumpingJacks,
        12,
        View::Frontal,
    );
    let marks = Marks::load(&dir.path().join("marks.json")).unwrap();
    let mut a = Video::open(&dir.path().join("frames"), &OpenOptions::default()).unwrap();
    let one = track_video(
        &mut a,
        &job(&marks, 1),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .unwrap();
    let two = track_video(
        &mut a,
        &job(&marks, 2),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(one.tracks, two.tracks);
}

/// A side-on walk of `frames` frames tracked from its marks, and the re-track job of the user
/// dragging the left ankle on frame `corrected` to its true place: (reference, the open video,
/// the first result, the job).
fn walk_with_a_correction(
    dir: &Path,
    frames: usize,
    corrected: usize,
) -> (
    GroundTruth,
    Video,
    videomocap_core::track::TrackOutput,
    TrackJob,
) {
    render(dir, ProceduralMotion::Walk, frames, View::Side);
    let gt = GroundTruth::load(&dir.join("gt.json")).unwrap();
    let marks = Marks::load(&dir.join("marks.json")).unwrap();
    let mut video = Video::open(&dir.join("frames"), &OpenOptions::default()).unwrap();
    let first = track_video(
        &mut video,
        &job(&marks, 2),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .unwrap();
    let mut j = job(&marks, 2);
    j.keys.set(
        FrameIndex(corrected),
        Joint::LeftAnkle,
        gt.frames[corrected].points2d()[Joint::LeftAnkle],
    );
    (gt, video, first, j)
}

#[test]
fn a_correction_on_a_later_frame_is_kept_and_anchors_the_track() {
    let dir = tempfile::tempdir().unwrap();
    // The user drags the left ankle on frame 10 to its true place and re-tracks from there.
    let (gt, mut video, first, j) = walk_with_a_correction(dir.path(), 20, 10);
    let truth = gt.frames[10].points2d()[Joint::LeftAnkle];
    let again = track_video(&mut video, &j, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    let p = again.tracks.frames[10].points[Joint::LeftAnkle];
    assert!((p.pos - truth).norm() < 1e-9);
    assert_eq!(p.confidence, 1.0);
    // The correction is tracked backwards too: the frames before it take the backward pass
    // where it holds better, so the ankle just before frame 10 is no further from the truth
    // than it was, and the head, reliable in both passes, stays where it was.
    let ankle_error = |t: &videomocap_core::formats::Tracks2d| -> f64 {
        (5..10)
            .map(|f| {
                (t.frames[f].points[Joint::LeftAnkle].pos
                    - gt.frames[f].points2d()[Joint::LeftAnkle])
                    .norm()
            })
            .sum::<f64>()
            / 5.0
    };
    let (before, after) = (ankle_error(&first.tracks), ankle_error(&again.tracks));
    assert!(
        after <= before + 1.0,
        "ankle before the key: {before:.1} px -> {after:.1} px"
    );
    for f in 0..10 {
        let (now, was) = (
            again.tracks.frames[f].points[Joint::HeadTop],
            first.tracks.frames[f].points[Joint::HeadTop],
        );
        assert!(
            (now.pos - was.pos).norm() < 3.0,
            "frame {f}: head top moved"
        );
    }
}

/// A re-track that reuses the first run's background (as the app does) gives the same tracks
/// as one that reads the clip again.
#[test]
fn a_retrack_reusing_the_background_is_a_fresh_run() {
    let dir = tempfile::tempdir().unwrap();
    let (_, mut video, first, mut j) = walk_with_a_correction(dir.path(), 48, 30);
    assert!(
        first.background.is_some(),
        "the default settings use a background"
    );
    let fresh = track_video(&mut video, &j, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    j.background = first.background.clone();
    let reused = track_video(&mut video, &j, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    assert_eq!(fresh.tracks, reused.tracks);
}

#[test]
fn a_one_frame_video_is_refused_with_its_name() {
    let dir = tempfile::tempdir().unwrap();
    render(dir.path(), ProceduralMotion::Wave, 1, View::Frontal);
    let marks = Marks::load(&dir.path().join("marks.json")).unwrap();
    let mut video = Video::open(&dir.path().join("frames"), &OpenOptions::default()).unwrap();
    let err = track_video(
        &mut video,
        &job(&marks, 1),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .unwrap_err();
    assert!(matches!(err, TrackError::TooShort { frames: 1, .. }));
    assert!(err.to_string().contains("frames"), "{err}");
}

/// A person taller than the working stature in an MP4: the decoder delivers working-size frames
/// while tracking, and the video is full size again afterwards.
#[cfg(feature = "ffmpeg")]
#[test]
fn a_tall_person_is_tracked_on_frames_the_decoder_shrinks() {
    let dir = tempfile::tempdir().unwrap();
    let params = SynthParams {
        motion: MotionSource::Procedural(ProceduralMotion::Wave),
        frames: 20,
        view: View::Frontal,
        width: 320,
        height: 240,
        focal_px: 300.0,
        person_px: 200.0,
        output: VideoOutput::Mp4,
        ..SynthParams::default()
    };
    render_clip(&params, dir.path(), &mut |_, _| {}, &AtomicBool::new(false)).unwrap();
    let gt = GroundTruth::load(&dir.path().join("gt.json")).unwrap();
    let marks = Marks::load(&dir.path().join("marks.json")).unwrap();
    let mut video = Video::open(&dir.path().join("video.mp4"), &OpenOptions::default()).unwrap();
    let tracker = TrackerParams {
        working_stature_px: 110.0,
        ..TrackerParams::default()
    };
    let out = track_video(
        &mut video,
        &TrackJob::from_marks(&marks, tracker, 1),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .unwrap();
    // The person (about 200 px) is brought to the working stature: a factor near 200 / 110.
    assert!((1.5..2.2).contains(&out.shrink), "shrink {}", out.shrink);
    assert_eq!((video.info().width, video.info().height), (320, 240));
    assert_eq!(video.frame(3).unwrap().image.dimensions(), (320, 240));
    // Tracks are in video pixels, at the accuracy of the full-size test above.
    assert_eq!(out.tracks.source.width, 320);
    let s = score_tracks(&gt, &out.tracks).unwrap();
    assert_pck(&s, 0.85);
}

/// Walking obliquely towards the camera the person grows by 1.85× over four seconds. The head
/// block zooms with them and every bone's length limit follows its zoom; with the limits fixed
/// at the marked size the trunk stopped growing and the hips and feet fell behind (this clip:
/// PCK@0.2 0.682 before, 0.860 after).
#[test]
fn a_person_walking_towards_the_camera_is_followed_as_they_grow() {
    let dir = tempfile::tempdir().unwrap();
    render(dir.path(), ProceduralMotion::Walk, 120, View::Oblique);
    let gt = GroundTruth::load(&dir.path().join("gt.json")).unwrap();
    let stature = |k: usize| {
        let p = &gt.frames[k].points2d;
        let (a, b) = (p[Joint::HeadTop.index()], p[Joint::LeftAnkle.index()]);
        (a[0] - b[0]).hypot(a[1] - b[1])
    };
    let growth = stature(119) / stature(0);
    let s = track_rendered(dir.path(), TrackerParams::default());
    assert!(growth > 1.4, "the person grows {growth:.2}×");
    assert_pck(&s, 0.85);
}

/// A bow seen from the side: the spine bends and the hips stay. The rigid trunk hung from the
/// neck kept its angle and swung the pelvis away with the neck; the hip patch holds the pelvis
/// (measured: pelvis 41.8 → 0.5 px, PCK@0.2 0.579 → 0.940).
#[test]
fn a_bow_from_the_side_keeps_the_pelvis_where_the_hips_are() {
    let dir = tempfile::tempdir().unwrap();
    render(dir.path(), ProceduralMotion::Bend, 60, View::Side);
    let pelvis_error = |hip_patch: bool| {
        let params = TrackerParams {
            hip_patch,
            ..TrackerParams::default()
        };
        joint_and_pck(dir.path(), Joint::Pelvis, params)
    };
    let (without, _) = pelvis_error(false);
    let (with, pck) = pelvis_error(true);
    assert!(
        with < 0.25 * without,
        "pelvis {with:.1} px with the patch, {without:.1} px without"
    );
    assert!(pck >= 0.85, "PCK@0.2 {pck:.3}");
}

/// Running seen from the side (CMU 02_03): the swinging shank locked onto the other leg, folded
/// back over its thigh, and stayed there. Knees cannot fold that far, so the match is refused
/// and the shank held until it is found again (measured without the chain refinement: left
/// ankle 18.2 px without the fold check, 4.4 px with it; the check is a fitted constant since
/// issue 92, so this asserts half the figure without it). The chain refinement alone also keeps
/// the shank on its leg (1.3 px), so the fold check is measured without it.
#[test]
fn a_running_shank_never_folds_back_onto_its_thigh() {
    let dir = tempfile::tempdir().unwrap();
    let params = SynthParams {
        motion: bundled_bvh("cmu_02_03_run.bvh"),
        frames: 45,
        view: View::Side,
        width: 320,
        height: 240,
        focal_px: 300.0,
        person_px: 120.0,
        output: VideoOutput::PngSequence,
        ..SynthParams::default()
    };
    render_clip(&params, dir.path(), &mut |_, _| {}, &AtomicBool::new(false)).unwrap();
    let params = TrackerParams {
        chain_refine: false,
        ..TrackerParams::default()
    };
    let (ankle, pck) = joint_and_pck(dir.path(), Joint::LeftAnkle, params);
    println!("left ankle {ankle:.1} px, PCK@0.2 {pck:.3}");
    assert!(
        ankle < 9.1,
        "left ankle {ankle:.1} px (18.2 without the fold check)"
    );
    // Measured 0.775 with the check (2026-12-06).
    assert!(pck >= 0.75, "PCK@0.2 {pck:.3}");
}

/// Walking across the view (CMU 02_01, side view): where the legs cross, a thigh and shank
/// matched the other leg at half their length and, with the length search centred on the last
/// length, never grew back. A limb block shorter than its full image length now pays for it
/// (`short_penalty`), so it regains its length when the leg reappears (measured: knees and
/// ankles 29.0 → 17.5 px, left ankle 36.1 → 9.5 px, PCK@0.2 0.738 → 0.801).
#[test]
fn a_leg_shortened_where_the_legs_cross_grows_back() {
    let dir = tempfile::tempdir().unwrap();
    let fps = SynthParams::default().fps;
    render_side_view(dir.path(), "cmu_02_01_walk.bvh", 86, fps, 300.0, 0);
    let run = |short_penalty: f32| {
        let s = track_rendered(
            dir.path(),
            TrackerParams {
                short_penalty,
                ..TrackerParams::default()
            },
        );
        let legs = [
            Joint::LeftKnee,
            Joint::LeftAnkle,
            Joint::RightKnee,
            Joint::RightAnkle,
        ];
        let legs_px = legs.iter().map(|&j| s.per_joint[j].mean_px()).sum::<f64>() / 4.0;
        (legs_px, s.overall.pck02())
    };
    let (legs_off, pck_off) = run(0.0);
    let (legs_on, pck_on) = run(TrackerParams::default().short_penalty);
    assert!(
        legs_on < 0.75 * legs_off,
        "legs {legs_on:.1} px with, {legs_off:.1} px without"
    );
    assert!(
        pck_on > pck_off,
        "PCK@0.2 {pck_on:.3} with, {pck_off:.3} without"
    );
}

/// Walking towards the camera at 60 frames/s (CMU 02_01, as `bench track`'s
/// walk_toward_frontal): the left forearm, weak for a frame as it passes the dark post behind
/// it, was once searched over the whole wide range (±100°) and flipped up onto the background
/// for 20 frames (left wrist 21.6 px). Limited to what a limb turns in a frame
/// (`wide_speed_deg_s`, 4000 °/s: ±67° at 60 frames/s) it stayed on the arm (9.0 px). Since
/// the special cases were pruned (2026-11-28) the forearm stays on the arm with or without the
/// limit (8.7 px both), so this checks that it still does, without the arms' background lane.
#[test]
fn a_forearm_weak_for_a_frame_stays_on_the_arm() {
    let dir = tempfile::tempdir().unwrap();
    render_suite_like(
        dir.path(),
        bundled_bvh_from("cmu_02_01_walk.bvh", 1.0),
        View::Frontal,
        (111, 60),
        450.0,
        (1, Some("pose2sim_floor.jpg")),
        VideoOutput::Mp4,
    );
    let params = TrackerParams {
        arm_foreground: 0.0,
        ..TrackerParams::default()
    };
    let (wrist_px, pck) = joints_and_pck_mp4(dir.path(), &[Joint::LeftWrist], params);
    println!("left wrist {wrist_px:.1} px; PCK@0.2 {pck:.3}");
    assert!(wrist_px < 12.0, "left wrist {wrist_px:.1} px off");
    assert!(pck > 0.95, "PCK@0.2 {pck:.3}");
}
