//! Tracking with the pose network's evidence (`track_video` with a network): every frame has
//! what the network saw, the user's joints stay where they were placed, and a re-track after a
//! correction that reuses the earlier network output gives what a fresh run gives, and an edit
//! history replayed (corrections, the network turned off and on, an undo) ends where a fresh
//! run with the same keys and settings does, byte for byte, with the earlier runs' network
//! output and VBA's passes (`TrackJob::previous_passes`) as caches.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::FrameIndex;
use videomocap_core::formats::{KeyFrames, Marks};
use videomocap_core::network::PoseNetwork;
use videomocap_core::skeleton::Joint;
use videomocap_core::track::{TrackJob, TrackerParams, track_video};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::synth::{ProceduralMotion, View, render_small_clip};

#[test]
fn tracking_with_the_network_keeps_the_keys_and_a_retrack_reuses_what_it_saw() {
    let dir = tempfile::tempdir().unwrap();
    let clip = render_small_clip(dir.path(), ProceduralMotion::Walk, 10, View::Oblique).unwrap();
    let marks = Marks::load(&clip.marks).unwrap();
    let network = Arc::new(PoseNetwork::bundled().unwrap());
    let mut video = Video::open(&clip.video, &OpenOptions::default()).unwrap();
    let job = TrackJob::from_marks(&marks, TrackerParams::default(), 1)
        .with_network(Some(network.clone()));
    let mut calls = 0;
    let first = track_video(
        &mut video,
        &job,
        &mut |p| {
            calls += 1;
            assert!(p.done <= p.total, "{} of {}", p.done, p.total);
        },
        &AtomicBool::new(false),
    )
    .unwrap();
    assert!(calls >= 10);
    let seen = first.network.clone().expect("the network ran");
    assert_eq!(seen.len(), 10);
    assert!(seen.iter().all(|f| f.crop.is_some()));
    for j in Joint::ALL {
        assert_eq!(
            first.tracks.frames[0].points[j].pos, marks.points[j],
            "{j:?} moved off the mark"
        );
    }

    // A correction on frame 6 moves the left wrist 3 px: every crop stays where it was, so the
    // network's output is reused as it was, and is what a fresh run sees.
    let mut keys = KeyFrames::from_marks(&marks);
    let moved =
        first.tracks.frames[6].points[Joint::LeftWrist].pos + nalgebra::Vector2::new(3.0, 0.0);
    keys.set(FrameIndex(6), Joint::LeftWrist, moved);
    let retrack = TrackJob {
        keys: keys.clone(),
        previous_network: first.network.clone(),
        ..job.clone()
    };
    let again = track_video(&mut video, &retrack, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    assert_eq!(again.tracks.frames[6].points[Joint::LeftWrist].pos, moved);
    let fresh = TrackJob {
        keys,
        ..job.clone()
    };
    let fresh = track_video(&mut video, &fresh, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    assert_eq!(again.network, first.network);
    assert_eq!(fresh.network, first.network);
    assert_eq!(again.tracks, fresh.tracks);

    // Turned off by the setting: VBA alone, nothing from the network.
    let off = TrackJob {
        params: TrackerParams {
            network: false,
            ..TrackerParams::default()
        },
        ..job
    };
    let alone = track_video(&mut video, &off, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    assert!(alone.network.is_none());
}

/// Tracking is a function of the video, the keys and the settings (issue 90): an app's edit
/// history, each step re-tracked with what the step before left (its background and the
/// network's output as caches), ends with the tracks of one fresh run, byte for byte.
#[test]
fn an_edit_history_replayed_gives_the_tracks_of_a_fresh_run() {
    let dir = tempfile::tempdir().unwrap();
    let clip = render_small_clip(dir.path(), ProceduralMotion::Walk, 12, View::Side).unwrap();
    let marks = Marks::load(&clip.marks).unwrap();
    let network = Arc::new(PoseNetwork::bundled().unwrap());
    let mut video = Video::open(&clip.video, &OpenOptions::default()).unwrap();
    let on = TrackerParams::default();
    let off = TrackerParams {
        network: false,
        ..on
    };
    let marked = KeyFrames::from_marks(&marks);
    let mut corrected = marked.clone();
    let neck = marks.points[Joint::Neck] + nalgebra::Vector2::new(4.0, -3.0);
    corrected.set(FrameIndex(3), Joint::Neck, neck);
    let mut pelvis_moved = corrected.clone();
    let pelvis = marks.points[Joint::Pelvis] + nalgebra::Vector2::new(-5.0, 2.0);
    pelvis_moved.set(FrameIndex(8), Joint::Pelvis, pelvis);
    // Track, correct the neck, turn the network off, on, move the pelvis, undo it.
    let history = [
        (&marked, on),
        (&corrected, on),
        (&corrected, off),
        (&corrected, on),
        (&pelvis_moved, on),
        (&corrected, on),
    ];
    let (mut background, mut seen, mut passes) = (None, None, None);
    let mut runs = Vec::new();
    for (keys, params) in history {
        let job = TrackJob {
            keys: keys.clone(),
            params,
            threads: 2,
            background: background.clone(),
            network: Some(network.clone()),
            previous_network: seen.clone(),
            previous_passes: passes.clone(),
        };
        let out = track_video(&mut video, &job, &mut |_| {}, &AtomicBool::new(false)).unwrap();
        background = out.background.clone();
        passes = out.passes.clone();
        if out.network.is_some() {
            seen = out.network.clone();
        }
        runs.push(out);
    }
    let text = |t: &videomocap_core::formats::Tracks2d| t.to_json_value().to_string();
    // The network on, off, on again: the first and the last of these give the same tracks.
    assert_eq!(text(&runs[1].tracks), text(&runs[3].tracks));
    assert_eq!(runs[1].spans, runs[3].spans);
    // The network off changes them (so the comparison above can fail).
    assert_ne!(text(&runs[1].tracks), text(&runs[2].tracks));
    let replayed = runs.pop().unwrap();
    let mut fresh_video = Video::open(&clip.video, &OpenOptions::default()).unwrap();
    let fresh = track_video(
        &mut fresh_video,
        &TrackJob {
            keys: corrected.clone(),
            params: on,
            threads: 2,
            background: None,
            network: Some(network),
            previous_network: None,
            previous_passes: None,
        },
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(text(&replayed.tracks), text(&fresh.tracks));
    assert_eq!(replayed.spans, fresh.spans);
    assert_eq!(replayed.tracks.frames[3].points[Joint::Neck].pos, neck);
}

/// A reader of a video that cannot make a second reader of itself: tracking on it runs the
/// network after VBA's passes, on the calling thread only.
struct NoSecondReader(Box<dyn videomocap_core::video::VideoSource>);

impl videomocap_core::video::VideoSource for NoSecondReader {
    fn info(&self) -> &videomocap_core::video::VideoInfo {
        self.0.info()
    }
    fn time_of(&self, index: usize) -> f64 {
        self.0.time_of(index)
    }
    fn decode(
        &mut self,
        index: usize,
    ) -> Result<image::RgbImage, videomocap_core::video::VideoError> {
        self.0.decode(index)
    }
    fn output_size(&mut self, size: Option<(u32, u32)>) -> bool {
        self.0.output_size(size)
    }
}

/// The network run ahead of VBA's passes on its own thread (issue 95) is only a cache: with it
/// and without it (a video that cannot be read twice at once), the tracks and what the network
/// saw are the same, byte for byte, on the marks alone and with corrections, one of them a
/// pelvis placed a torso away from the network's (a key that refuses the network's body, where
/// the network's chain needs VBA's).
#[test]
fn the_network_run_ahead_of_vba_changes_nothing() {
    use videomocap_core::video::{DEFAULT_SEQUENCE_FPS, ImageSequence};
    let dir = tempfile::tempdir().unwrap();
    let clip = render_small_clip(dir.path(), ProceduralMotion::Walk, 12, View::Oblique).unwrap();
    let marks = Marks::load(&clip.marks).unwrap();
    let network = Arc::new(PoseNetwork::bundled().unwrap());
    let marked = KeyFrames::from_marks(&marks);
    let mut corrected = marked.clone();
    let torso = marks.points[Joint::Neck] - marks.points[Joint::Pelvis];
    corrected.set(
        FrameIndex(5),
        Joint::Pelvis,
        marks.points[Joint::Pelvis] + torso,
    );
    corrected.set(
        FrameIndex(9),
        Joint::LeftWrist,
        marks.points[Joint::LeftWrist] + nalgebra::Vector2::new(3.0, 0.0),
    );
    let text = |t: &videomocap_core::formats::Tracks2d| t.to_json_value().to_string();
    for keys in [&marked, &corrected] {
        let job = TrackJob {
            keys: keys.clone(),
            params: TrackerParams::default(),
            threads: 2,
            background: None,
            network: Some(network.clone()),
            previous_network: None,
            previous_passes: None,
        };
        let mut ahead = Video::open(&clip.video, &OpenOptions::default()).unwrap();
        assert!(ahead.reopen(0).is_some(), "a video file can be read twice");
        let source = Box::new(ImageSequence::open(&clip.video, DEFAULT_SEQUENCE_FPS).unwrap());
        let mut after = Video::from_source(Box::new(NoSecondReader(source)), 1 << 26);
        assert!(after.reopen(0).is_none());
        let cancel = AtomicBool::new(false);
        let with = track_video(&mut ahead, &job, &mut |_| {}, &cancel).unwrap();
        let without = track_video(&mut after, &job, &mut |_| {}, &cancel).unwrap();
        assert!(with.network.is_some());
        assert_eq!(with.network, without.network);
        assert_eq!(text(&with.tracks), text(&without.tracks));
        assert_eq!(with.spans, without.spans);
        assert_eq!(ahead.info().width, after.info().width);
        assert!(without.network.unwrap().iter().all(|f| f.crop.is_some()));
    }
}

/// The network is left out where it adds nothing (issue 95, item 3): sitting down, some
/// frames go without it, never two in a row nor on the marked frame, and each has the
/// network's evidence all the same (its neighbours' midway, or the network after all); the
/// marks and a correction of a limb or the pelvis on a frame left out stay where they were
/// placed, and that correction leaves the network's chain as it was: every frame keeps its crop
/// and every other frame its choice, and a frame the network ran on in both runs saw the same (a
/// re-track runs none of them again).
#[test]
fn the_network_is_left_out_on_some_frames_and_keys_stay_where_they_were_placed() {
    let dir = tempfile::tempdir().unwrap();
    let clip = render_small_clip(dir.path(), ProceduralMotion::SitDown, 16, View::Oblique).unwrap();
    let marks = Marks::load(&clip.marks).unwrap();
    let network = Arc::new(PoseNetwork::bundled().unwrap());
    let mut video = Video::open(&clip.video, &OpenOptions::default()).unwrap();
    let job = TrackJob::from_marks(&marks, TrackerParams::default(), 2)
        .with_network(Some(network.clone()));
    let first = track_video(&mut video, &job, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    let seen = first.network.clone().unwrap();
    let left_out: Vec<usize> = (0..seen.len()).filter(|&t| seen[t].skipped).collect();
    assert!(!left_out.is_empty(), "no frame left out");
    assert!(!seen[0].skipped);
    assert!(left_out.windows(2).all(|w| w[1] > w[0] + 1), "{left_out:?}");
    assert!(left_out.iter().all(|&t| seen[t].joints.is_some()));
    for j in Joint::ALL {
        assert_eq!(first.tracks.frames[0].points[j].pos, marks.points[j]);
    }
    // The left wrist corrected on a frame left out, then (separately) the pelvis nudged there:
    // the pelvis key is looked at by the network, and every other frame is as it was.
    let t = left_out[0];
    for joint in [Joint::LeftWrist, Joint::Pelvis] {
        let mut keys = KeyFrames::from_marks(&marks);
        let moved = first.tracks.frames[t].points[joint].pos + nalgebra::Vector2::new(4.0, 0.0);
        keys.set(FrameIndex(t), joint, moved);
        let retrack = TrackJob {
            keys,
            previous_network: Some(seen.clone()),
            ..job.clone()
        };
        let again =
            track_video(&mut video, &retrack, &mut |_| {}, &AtomicBool::new(false)).unwrap();
        assert_eq!(again.tracks.frames[t].points[joint].pos, moved);
        let after = again.network.unwrap();
        assert_eq!(after[t].skipped, joint != Joint::Pelvis, "{joint:?}");
        for (s, (a, b)) in seen.iter().zip(&after).enumerate() {
            assert_eq!(a.crop, b.crop, "{joint:?}, frame {s}");
            assert_eq!(a.next, b.next, "{joint:?}, frame {s}");
            if s != t {
                assert_eq!(a.skipped, b.skipped, "{joint:?}, frame {s}");
            }
            if !a.skipped && !b.skipped {
                assert_eq!(a, b, "{joint:?}, frame {s}");
            }
        }
    }
}
