//! Tracking with the pose network's evidence (`track_video` with a network): every frame has
//! what the network saw, the user's joints stay where they were placed, and a re-track after a
//! correction that reuses the earlier network output gives what a fresh run gives.

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

    // A correction on frame 6.
    let mut keys = KeyFrames::from_marks(&marks);
    let moved =
        first.tracks.frames[6].points[Joint::LeftWrist].pos + nalgebra::Vector2::new(3.0, 0.0);
    keys.set(FrameIndex(6), Joint::LeftWrist, moved);
    let retrack = TrackJob {
        keys: keys.clone(),
        from: Some(6),
        previous: Some(first.tracks.clone()),
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
    // A wrist moved leaves every crop where it was: the network's output is reused as it was,
    // and is what a fresh run sees.
    assert_eq!(again.network, first.network);
    assert_eq!(fresh.network, first.network);

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
