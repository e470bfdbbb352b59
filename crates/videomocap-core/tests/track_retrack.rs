//! Re-tracks with what the earlier run's passes computed (`TrackJob::previous_passes`, issue
//! 95): an edit history replayed with the cache carried from run to run gives, after every
//! edit, the tracks of a fresh run with the same keys, byte for byte; and a re-track whose
//! frames were all kept decodes none.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use videomocap_core::formats::{FrameIndex, KeyFrames, Marks, Tracks2d};
use videomocap_core::skeleton::Joint;
use videomocap_core::track::{TrackJob, TrackOutput, TrackerParams, track_video};
use videomocap_core::video::{
    DEFAULT_SEQUENCE_FPS, ImageSequence, Video, VideoError, VideoInfo, VideoSource,
};
use videomocap_testkit::synth::{ProceduralMotion, View, render_small_clip};

/// A reader of the clip that counts the frames it decodes.
struct Counting {
    inner: Box<dyn VideoSource>,
    decoded: Arc<AtomicUsize>,
    reopened: Arc<AtomicUsize>,
}

impl VideoSource for Counting {
    fn info(&self) -> &VideoInfo {
        self.inner.info()
    }
    fn time_of(&self, index: usize) -> f64 {
        self.inner.time_of(index)
    }
    fn decode(&mut self, index: usize) -> Result<image::RgbImage, VideoError> {
        self.decoded.fetch_add(1, Ordering::Relaxed);
        self.inner.decode(index)
    }
    /// A second reader counting into the same counts (a re-track's backward pass runs on one,
    /// beside the forward pass).
    fn reopen(&self) -> Option<Box<dyn VideoSource>> {
        self.reopened.fetch_add(1, Ordering::Relaxed);
        Some(Box::new(Counting {
            inner: self.inner.reopen()?,
            decoded: self.decoded.clone(),
            reopened: self.reopened.clone(),
        }))
    }
}

/// Tracks the clip at `path` as the app does (the video opened anew for each run), returning
/// the result, the frames decoded and the second readers made.
fn track(path: &std::path::Path, job: &TrackJob) -> (TrackOutput, usize, usize) {
    let (decoded, reopened) = (Arc::default(), Arc::default());
    let source = Counting {
        inner: Box::new(ImageSequence::open(path, DEFAULT_SEQUENCE_FPS).unwrap()),
        decoded: Arc::clone(&decoded),
        reopened: Arc::clone(&reopened),
    };
    // No frame cache in the video: every frame a run reads is decoded or taken from the job.
    let mut video = Video::from_source(Box::new(source), 0);
    let out = track_video(&mut video, job, &mut |_| {}, &AtomicBool::new(false)).unwrap();
    let count = |c: &AtomicUsize| c.load(Ordering::Relaxed);
    (out, count(&decoded), count(&reopened))
}

fn text(t: &Tracks2d) -> String {
    t.to_json_value().to_string()
}

#[test]
fn an_edit_history_with_the_passes_cache_gives_the_tracks_of_fresh_runs() {
    let dir = tempfile::tempdir().unwrap();
    let n = 32;
    let clip = render_small_clip(dir.path(), ProceduralMotion::Walk, n, View::Oblique).unwrap();
    let marks = Marks::load(&clip.marks).unwrap();
    // Shrunk to a working stature below the person's (frames box-filtered to the working size,
    // the kept frames at that size).
    {
        let working_stature_px = 120.0;
        let params = TrackerParams {
            network: false,
            working_stature_px,
            ..TrackerParams::default()
        };
        let job = TrackJob::from_marks(&marks, params, 2);
        let (first, _, _) = track(&clip.video, &job);
        let at = |f: usize, j: Joint| first.tracks.frames[f].points[j].pos;
        let shift = nalgebra::Vector2::new(3.0, -2.0);
        // Corrections: a wrist mid-clip (the backward pass starts there), a pelvis later (the
        // last key moves), a whole pose earlier, the wrist undone, a knee on the last frame,
        // an ankle on a frame just after a checkpoint.
        let mut history: Vec<KeyFrames> = vec![KeyFrames::from_marks(&marks)];
        let mut keys = history[0].clone();
        keys.set(
            FrameIndex(18),
            Joint::LeftWrist,
            at(18, Joint::LeftWrist) + shift,
        );
        history.push(keys.clone());
        keys.set(FrameIndex(26), Joint::Pelvis, at(26, Joint::Pelvis) - shift);
        history.push(keys.clone());
        for j in Joint::ALL {
            keys.set(FrameIndex(12), j, at(12, j) + shift);
        }
        history.push(keys.clone());
        let mut undone = KeyFrames::from_marks(&marks);
        for (f, k) in keys.frames.iter().filter(|(f, _)| f.get() != 18) {
            for j in Joint::ALL {
                if let Some(p) = k[j] {
                    undone.set(*f, j, p);
                }
            }
        }
        history.push(undone.clone());
        keys = undone;
        keys.set(
            FrameIndex(n - 1),
            Joint::RightKnee,
            at(n - 1, Joint::RightKnee) + shift,
        );
        history.push(keys.clone());
        keys.set(
            FrameIndex(9),
            Joint::LeftAnkle,
            at(9, Joint::LeftAnkle) + shift,
        );
        history.push(keys.clone());
        let (mut background, mut passes) = (first.background.clone(), first.passes.clone());
        let (mut last, mut at_once) = (None, 0);
        for (step, keys) in history.into_iter().enumerate() {
            let cached = TrackJob {
                keys: keys.clone(),
                background: background.clone(),
                previous_passes: passes.clone(),
                ..job.clone()
            };
            let (again, decoded, reopened) = track(&clip.video, &cached);
            at_once += reopened;
            assert_eq!(
                decoded, 0,
                "step {step}: every frame was kept, none decoded"
            );
            let (fresh, _, _) = track(
                &clip.video,
                &TrackJob {
                    keys,
                    ..job.clone()
                },
            );
            assert_eq!(text(&again.tracks), text(&fresh.tracks), "step {step}");
            assert_eq!(again.spans, fresh.spans, "step {step}");
            background = again.background;
            passes = again.passes;
            last = Some(again.tracks);
        }
        // The history's edits changed the tracks (so the comparisons above could fail).
        assert_ne!(text(&last.unwrap()), text(&first.tracks));
        // The re-tracks with a backward pass ran their two passes at once (each on a reader).
        assert!(at_once >= 6, "{at_once} second readers");
    }
}

/// A cache from other settings is not used: the run decodes its frames and gives a fresh
/// run's tracks.
#[test]
fn a_passes_cache_from_other_settings_is_not_used() {
    let dir = tempfile::tempdir().unwrap();
    let clip = render_small_clip(dir.path(), ProceduralMotion::Walk, 12, View::Side).unwrap();
    let marks = Marks::load(&clip.marks).unwrap();
    let params = TrackerParams {
        network: false,
        ..TrackerParams::default()
    };
    let job = TrackJob::from_marks(&marks, params, 2);
    let (first, decoded_first, _) = track(&clip.video, &job);
    assert!(decoded_first >= 12);
    let other = TrackJob {
        params: TrackerParams {
            limb_range_deg: params.limb_range_deg * 0.5,
            ..params
        },
        ..job.clone()
    };
    let (cached, decoded, _) = track(
        &clip.video,
        &TrackJob {
            previous_passes: first.passes.clone(),
            ..other.clone()
        },
    );
    let (fresh, _, _) = track(&clip.video, &other);
    assert!(decoded >= 12, "{decoded} frames decoded");
    assert_eq!(text(&cached.tracks), text(&fresh.tracks));
}
