//! Heavy work off the UI thread: tracking and lifting run on worker threads, report progress
//! through a channel (with each newly tracked frame, so results draw as they arrive), and stop
//! when their cancel flag is set.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, channel};
use std::time::Instant;
use videomocap_core::formats::{FrameTracks, Tracks2d};
use videomocap_core::lift::{CameraChoice, SubjectChoice, reconstruct};
use videomocap_core::lift::{DepthOverrides, LiftOutput, LiftParams, SubjectFit};
use videomocap_core::network::PoseNetwork;
use videomocap_core::track::{TrackJob, TrackOutput, track_video};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_volume::{Processed, VolumeParams, process_directory};

/// What a job sends back.
pub(crate) enum JobEvent {
    /// Steps done of a total, and a frame just tracked.
    Progress {
        done: usize,
        total: usize,
        stage: String,
        frame: Option<FrameTracks>,
    },
    /// Tracking finished.
    Tracked(Result<TrackOutput, String>),
    /// Lifting finished.
    Lifted(Result<(LiftOutput, Option<SubjectFit>), String>),
    /// A point-volume sequence was processed (boxed: far larger than the other events).
    Volume(Result<Box<Processed>, String>),
    /// The pose network could not be loaded (why): tracking goes on with VBA alone.
    NetworkUnavailable(String),
}

/// A running job.
pub(crate) struct Job {
    /// "Tracking" or "Lifting".
    pub what: &'static str,
    events: Receiver<JobEvent>,
    cancel: Arc<AtomicBool>,
    /// When the current stage started and the steps done then (the stage's own steps give the
    /// rate: stages differ in speed).
    started: (Instant, usize),
    /// Progress so far.
    pub done: usize,
    /// Steps in all.
    pub total: usize,
    /// What is being done now.
    pub stage: String,
}

impl Job {
    /// Tracks `video` on a worker thread.
    pub(crate) fn track(video: PathBuf, mut job: TrackJob, ctx: egui::Context) -> Job {
        let (tx, rx) = channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let flag = cancel.clone();
        std::thread::spawn(move || {
            if job.params.network && job.network.is_none() {
                // The product's one loader, shared with the command line and the benchmarks.
                match PoseNetwork::shared(job.threads) {
                    Ok(n) => job.network = Some(n),
                    Err(e) => {
                        let _ = tx.send(JobEvent::NetworkUnavailable(e.to_string()));
                    }
                }
            }
            let result = Video::open(&video, &OpenOptions::default())
                .map_err(|e| e.to_string())
                .and_then(|mut v| {
                    let progress_tx = tx.clone();
                    let repaint = ctx.clone();
                    let mut progress = move |p: &videomocap_core::track::TrackProgress| {
                        let _ = progress_tx.send(JobEvent::Progress {
                            done: p.done,
                            total: p.total,
                            stage: "tracking".to_owned(),
                            frame: p.frame.clone(),
                        });
                        repaint.request_repaint();
                    };
                    track_video(&mut v, &job, &mut progress, &flag).map_err(|e| e.to_string())
                });
            let _ = tx.send(JobEvent::Tracked(result));
            ctx.request_repaint();
        });
        Job::new("Tracking", rx, cancel)
    }

    /// Lifts `tracks` to 3D on a worker thread with the project's lift settings `params` and
    /// the lengths the user knows.
    pub(crate) fn lift(
        tracks: Arc<Tracks2d>,
        focal_px: f64,
        height_m: f64,
        known: videomocap_core::formats::KnownLengths,
        params: LiftParams,
        overrides: DepthOverrides,
        ctx: egui::Context,
    ) -> Job {
        let (tx, rx) = channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let flag = cancel.clone();
        std::thread::spawn(move || {
            let progress_tx = tx.clone();
            let repaint = ctx.clone();
            let mut progress = move |p: &videomocap_core::lift::LiftProgress| {
                let _ = progress_tx.send(JobEvent::Progress {
                    done: p.done,
                    total: p.total,
                    stage: p.stage.to_string(),
                    frame: None,
                });
                repaint.request_repaint();
            };
            let subject = SubjectChoice::Height { height_m, known };
            let result = reconstruct(
                &tracks,
                CameraChoice::FocalPx(focal_px),
                &subject,
                &params,
                overrides,
                &mut progress,
                &flag,
            )
            .map(|done| (done.output, done.fit))
            .map_err(|e| e.to_string());
            let _ = tx.send(JobEvent::Lifted(result));
            ctx.request_repaint();
        });
        Job::new("Lifting", rx, cancel)
    }

    /// Runs the point-volume pipeline on `dir` on a worker thread (frames in parallel).
    pub(crate) fn volume(dir: PathBuf, fps: f64, ctx: egui::Context) -> Job {
        let (tx, rx) = channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let flag = cancel.clone();
        std::thread::spawn(move || {
            let progress_tx = tx.clone();
            let repaint = ctx.clone();
            let progress = move |done: usize, total: usize| {
                let _ = progress_tx.send(JobEvent::Progress {
                    done,
                    total,
                    stage: "volumes".to_owned(),
                    frame: None,
                });
                repaint.request_repaint();
            };
            let result = process_directory(&dir, &VolumeParams::default(), fps, &progress, &flag)
                .map(Box::new)
                .map_err(|e| e.to_string());
            let _ = tx.send(JobEvent::Volume(result));
            ctx.request_repaint();
        });
        Job::new("Volumes", rx, cancel)
    }

    fn new(what: &'static str, events: Receiver<JobEvent>, cancel: Arc<AtomicBool>) -> Job {
        Job {
            what,
            events,
            cancel,
            started: (Instant::now(), 0),
            done: 0,
            total: 0,
            stage: String::new(),
        }
    }

    /// Asks the job to stop (it answers with a "cancelled" error).
    pub(crate) fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// Events since the last call (progress is folded into `done`/`total`).
    pub(crate) fn poll(&mut self) -> Vec<JobEvent> {
        let mut out = Vec::new();
        while let Ok(e) = self.events.try_recv() {
            if let JobEvent::Progress {
                done, total, stage, ..
            } = &e
            {
                if *stage != self.stage || *done < self.done {
                    self.started = (
                        Instant::now(),
                        if *done < self.done { 0 } else { self.done },
                    );
                }
                self.done = *done;
                self.total = *total;
                self.stage.clone_from(stage);
            }
            out.push(e);
        }
        out
    }

    /// The progress bar's text: what, the stage, the share done, and once the stage has run
    /// a second and done a step, the time left in it. A share and not a step count: a track's
    /// steps are its passes over the frames (and the network's), not the clip's frames.
    pub(crate) fn progress_text(&self) -> String {
        let (share, _, left) = self.rate();
        let mut text = self.what.to_owned();
        // The stage in brackets when it says more than the job's name ("Tracking (tracking)").
        if !self.stage.is_empty() && !self.stage.eq_ignore_ascii_case(self.what) {
            text += &format!(" ({})", self.stage);
        }
        if self.total > 0 {
            text += &format!(" {:.0} %", 100.0 * share);
        }
        if let Some(s) = left.filter(|_| self.started.0.elapsed().as_secs_f64() >= 1.0) {
            text += &format!(" · {s:.0} s left");
        }
        text
    }

    /// Share done, steps per second and seconds left, in the current stage.
    pub(crate) fn rate(&self) -> (f32, f64, Option<f64>) {
        let share = if self.total == 0 {
            0.0
        } else {
            self.done as f32 / self.total as f32
        };
        let (since, from) = self.started;
        let secs = since.elapsed().as_secs_f64().max(1e-3);
        let per_s = self.done.saturating_sub(from) as f64 / secs;
        let left = (per_s > 0.0).then(|| (self.total.saturating_sub(self.done)) as f64 / per_s);
        (share, per_s, left)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job() -> (Job, std::sync::mpsc::Sender<JobEvent>) {
        let (tx, rx) = channel();
        (
            Job::new("Lifting", rx, Arc::new(AtomicBool::new(false))),
            tx,
        )
    }

    fn progress(done: usize, total: usize, stage: &str) -> JobEvent {
        JobEvent::Progress {
            done,
            total,
            stage: stage.to_owned(),
            frame: None,
        }
    }

    /// The bar shows a share, not the steps (a track's steps are its passes, not the clip's
    /// frames: "72/101" on a 100-frame clip), and the time left is the current stage's.
    #[test]
    fn progress_reads_as_a_share_and_the_rate_restarts_with_each_stage() {
        let (mut j, tx) = job();
        tx.send(progress(72, 101, "")).unwrap();
        j.poll();
        let text = j.progress_text();
        assert!(text.contains("71 %") && !text.contains("72/101"), "{text}");
        // A new stage (its own steps) restarts the clock and the count the rate is taken from.
        j.started = (Instant::now() - std::time::Duration::from_secs(10), 0);
        tx.send(progress(1, 20, "global refinement")).unwrap();
        j.poll();
        assert_eq!(j.started.1, 0);
        assert!(j.started.0.elapsed().as_secs_f64() < 5.0);
        assert!(j.progress_text().contains("(global refinement) 5 %"));
        // A stage named as the job is not said twice.
        tx.send(progress(2, 20, &j.what.to_lowercase())).unwrap();
        j.poll();
        assert!(!j.progress_text().contains('('), "{}", j.progress_text());
        tx.send(progress(1, 20, "global refinement")).unwrap();
        j.poll();
        j.started = (Instant::now(), 0);
        // Within one stage the clock runs on.
        j.started.0 -= std::time::Duration::from_secs(4);
        tx.send(progress(11, 20, "global refinement")).unwrap();
        j.poll();
        let (_, per_s, left) = j.rate();
        assert!((2.0..3.0).contains(&per_s), "{per_s}");
        let left = left.unwrap();
        assert!((3.0..4.5).contains(&left), "{left}");
    }
}
