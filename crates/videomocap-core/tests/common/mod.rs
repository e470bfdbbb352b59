//! Helpers shared by the integration tests.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use std::path::Path;
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::Marks;
use videomocap_core::track::{TrackJob, TrackerParams, track_video};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::eval::{ClipScore, score_tracks};
use videomocap_testkit::synth::GroundTruth;

/// Tracks `video` (a file or a folder of frames) from the marks in `dir` with `params` on two
/// threads, and scores it against the truth in `dir` (`marks.json`, `gt.json`).
pub(crate) fn track_and_score(dir: &Path, video: &Path, params: TrackerParams) -> ClipScore {
    let gt = GroundTruth::load(&dir.join("gt.json")).unwrap();
    let marks = Marks::load(&dir.join("marks.json")).unwrap();
    let mut video = Video::open(video, &OpenOptions::default()).unwrap();
    let job = TrackJob::from_marks(&marks, params, 2);
    let out = track_video(&mut video, &job, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    score_tracks(&gt, &out.tracks).unwrap()
}
