//! The state's background work: tracking and lifting jobs started, their progress and results
//! taken in (a result for keys or flips changed since is dropped), and decoded frames arriving
//! from the frame loader.

use super::frame_loader::{LoaderEvent, ProxyStatus};
use super::jobs::{Job, JobEvent};
use super::{LiftChoices, Running, State};
use std::sync::Arc;
use videomocap_core::formats::Marks;
use videomocap_core::lift::LiftOutput;
use videomocap_core::lift::SubjectFit;
use videomocap_core::lift::default_focal;
use videomocap_core::track::{KeyFrames, TrackJob, TrackOutput};
use videomocap_core::video::VideoInfo;

/// How many lifts' depth choices are kept for flips after undo and redo.
const CHOICES_KEPT: usize = 16;

impl State {
    /// Tracks the whole video from the keys (`from = None`), or again after a correction on frame
    /// `from` (the same: tracking is a function of the video, the keys and the settings).
    pub(super) fn start_tracking(&mut self, from: Option<usize>) {
        if self.running.is_some() && from.is_none() {
            return;
        }
        let Some(p) = &self.project else { return };
        if p.marks().is_none() {
            self.status = "Mark all 16 joints on one frame first (Edit > Mark joints)".to_owned();
            return;
        }
        if let Some(r) = &self.running {
            r.job.cancel();
        }
        let job = TrackJob {
            keys: p.keys.clone(),
            params: p.settings.tracker,
            threads: 2,
            background: self.background.clone(),
            // The network is loaded on the job's thread (see `Job::track`).
            network: None,
            previous_network: self.network_seen.clone(),
            previous_passes: self.passes_seen.clone(),
        };
        self.running = Some(Running {
            job: Job::track(p.video.clone(), job, self.ctx.clone()),
            keys: p.keys.clone(),
            overrides: p.overrides.clone(),
            settings: p.settings,
        });
        self.partial.clear();
    }

    /// Lifts the tracks to 3D on a worker thread.
    pub(super) fn start_lift(&mut self) {
        let (Some(p), Some(info)) = (&self.project, self.video_info()) else {
            return;
        };
        let Some(tracks) = p.tracks.clone() else {
            self.status = "Nothing tracked yet: Track > Track and lift (T)".to_owned();
            return;
        };
        let focal = p
            .settings
            .focal_px
            .unwrap_or_else(|| default_focal(info.width, info.height));
        self.running = Some(Running {
            job: Job::lift(
                tracks,
                focal,
                p.settings.height_m,
                p.settings.lengths.known(),
                p.settings.lift,
                p.overrides.clone(),
                self.ctx.clone(),
            ),
            keys: p.keys.clone(),
            overrides: p.overrides.clone(),
            settings: p.settings,
        });
    }

    /// Cancels the running job.
    pub(super) fn cancel_job(&mut self) {
        if let Some(r) = &self.running {
            r.job.cancel();
        }
    }

    /// Takes in decoded frames and job events (once per drawn frame).
    pub(crate) fn receive(&mut self) {
        if let Some(l) = &self.loader {
            l.pause_background(self.running.is_some());
        }
        let events = self
            .loader
            .as_mut()
            .map(super::frame_loader::FrameLoader::poll)
            .unwrap_or_default();
        for event in events {
            self.loaded(event);
        }
        let events = self
            .running
            .as_mut()
            .map(|r| r.job.poll())
            .unwrap_or_default();
        for event in events {
            match event {
                JobEvent::Progress { frame: Some(f), .. } => {
                    self.partial.insert(f.index.get(), f);
                }
                JobEvent::Progress { .. } => {}
                JobEvent::NetworkUnavailable(why) => {
                    self.network_problem = Some(why);
                }
                JobEvent::Tracked(result) => self.tracked(result),
                JobEvent::Lifted(result) => self.lifted(result),
                JobEvent::Volume(result) => {
                    self.running = None;
                    match (result, &mut self.volume) {
                        (Ok(p), Some(v)) => {
                            self.status = format!(
                                "{}   {} frames, {} with a five-limb skeleton curve, {} with a pose, {} warnings",
                                v.dir.display(),
                                p.files.len(),
                                p.five_limb_frames(),
                                p.posed_frames(),
                                p.assembled.warnings.len()
                            );
                            v.set(*p);
                        }
                        (Err(e), Some(v)) => {
                            v.fail(&e);
                            self.status = v.failed.clone().unwrap_or_default();
                        }
                        (Err(e), None) => self.status = format!("Cannot process the volumes: {e}"),
                        (Ok(_), None) => {}
                    }
                }
            }
        }
    }

    fn loaded(&mut self, event: LoaderEvent) {
        match event {
            LoaderEvent::Opened(Ok(info)) => {
                self.status = format!(
                    "{}   {}×{}   {:.2} fps   {} frames",
                    info.path.file_name().unwrap_or_default().to_string_lossy(),
                    info.width,
                    info.height,
                    info.fps,
                    info.frame_count
                );
                self.after_open(&info);
                self.remember_opened(&info.path);
                if let Some(l) = &self.loader {
                    l.request(self.current);
                }
            }
            LoaderEvent::Opened(Err(e)) => {
                self.status = format!("Cannot open: {e}");
                if let Some(video) = self.project.as_ref().map(|p| p.video.clone()) {
                    self.forget(&video);
                }
                self.loader = None;
                self.project = None;
            }
            LoaderEvent::Frame(Ok(frame)) => {
                self.show_frame(&frame);
                self.preview = false;
            }
            // A preview only stands in for the current frame until the full one comes.
            LoaderEvent::Preview(frame)
                if frame.index == self.current
                    && (self.shown != Some(frame.index) || self.preview) =>
            {
                self.show_frame(&frame);
                self.preview = true;
            }
            LoaderEvent::Preview(_) => {}
            LoaderEvent::Proxy(ProxyStatus::Failed(e)) => {
                self.status = format!("Fast seeking is off: {e}");
            }
            LoaderEvent::Proxy(_) => {}
            LoaderEvent::Frame(Err(e)) => self.status = format!("{e}"),
        }
    }

    /// Puts a decoded frame (full or preview) on screen.
    fn show_frame(&mut self, frame: &videomocap_core::video::Frame) {
        let size = [frame.image.width() as usize, frame.image.height() as usize];
        let image = egui::ColorImage::from_rgb(size, frame.image.as_raw());
        self.texture = Some(
            self.ctx
                .load_texture("frame", image, egui::TextureOptions::LINEAR),
        );
        self.shown = Some(frame.index);
    }

    /// A video opened: marks.json beside it is loaded when the project has no keys yet.
    fn after_open(&mut self, info: &VideoInfo) {
        let Some(p) = &self.project else { return };
        if !p.keys.frames.is_empty() {
            return;
        }
        let beside = info
            .path
            .parent()
            .map(|d| d.join("marks.json"))
            .filter(|m| m.is_file())
            .and_then(|m| Marks::load(&m).ok())
            .filter(|m| {
                m.check_in_frame(&info.path, info.width, info.height)
                    .is_ok()
            });
        if let Some(m) = beside {
            self.current = m.frame.get().min(info.frame_count.saturating_sub(1));
            if let Some(p) = &mut self.project {
                p.keys = KeyFrames::from_marks(&m);
            }
            self.status.push_str("   (marks.json loaded)");
        }
    }

    fn tracked(&mut self, result: Result<TrackOutput, String>) {
        let Some(r) = self.running.take() else { return };
        match result {
            Ok(out) => {
                let current = self.project.as_ref().map(|p| &p.keys);
                if current != Some(&r.keys) {
                    self.status = "Tracking finished for an older edit; result dropped".to_owned();
                    return;
                }
                if let Some(p) = &mut self.project {
                    p.tracks = Some(Arc::new(out.tracks));
                    p.skeleton = None;
                }
                self.background = out.background;
                self.network_seen = out.network;
                self.passes_seen = out.passes;
                self.tracks_made_with(r.settings.tracker);
                self.dirty = true;
                self.autosave();
                self.results_changed();
                self.status = format!("Tracked {} frames", self.frame_count());
                if let Some(why) = &self.network_problem {
                    self.status +=
                        &format!(" with VBA alone (the pose network could not load: {why})");
                }
                if let Some(w) = self.weak_share() {
                    self.status += &format!(
                        "; {} weak joint-frames ({:.1} % of the clip)",
                        w.joint_frames,
                        w.share() * 100.0
                    );
                }
                if !out.damaged.is_empty() {
                    self.status += &format!(
                        "; {} damaged frame(s) could not be decoded and count as lost (first: {})",
                        out.damaged.len(),
                        out.damaged[0]
                    );
                }
                self.start_lift();
            }
            Err(e) => {
                self.partial.clear();
                self.status = format!("Tracking stopped: {e}");
            }
        }
    }

    fn lifted(&mut self, result: Result<(LiftOutput, Option<SubjectFit>), String>) {
        let Some(r) = self.running.take() else { return };
        match result {
            Ok((out, fit)) => {
                let same = self
                    .project
                    .as_ref()
                    .is_some_and(|p| p.keys == r.keys && p.overrides == r.overrides);
                if !same {
                    self.status = "Lift finished for an older edit; result dropped".to_owned();
                    return;
                }
                self.subject_fit = fit;
                let skeleton = Arc::new(out.skeleton);
                let flagged = skeleton.frames.iter().filter(|f| f.flagged()).count();
                self.choices.push(LiftChoices {
                    skeleton: skeleton.clone(),
                    bones: out.bones,
                });
                if self.choices.len() > CHOICES_KEPT {
                    self.choices.remove(0);
                }
                if let Some(p) = &mut self.project {
                    p.skeleton = Some(skeleton);
                }
                self.skeleton_made_with(r.settings);
                self.dirty = true;
                self.autosave();
                self.results_changed();
                let done = std::mem::take(&mut self.status);
                self.status = format!("{done}; lifted to 3D ({flagged} frames flagged)");
            }
            Err(e) => self.status = format!("Lift stopped: {e}"),
        }
    }
}
