//! What the views read from the [`State`]: the open project and video, the frame shown, the
//! job, the strips and weak spans, the 3D world, the points to draw. Read only; the actions are
//! in the sibling files.

use super::*;

impl State {
    /// The folder the app keeps its state in between sessions (recovery file, recent list,
    /// layout); `None`: nothing is kept.
    pub(crate) fn state_dir(&self) -> Option<&Path> {
        self.config.autosave_dir.as_deref()
    }

    /// The project being edited.
    pub(crate) fn project(&self) -> Option<&Project> {
        self.project.as_ref()
    }

    /// Metadata of the open video.
    pub(crate) fn video_info(&self) -> Option<&VideoInfo> {
        self.loader.as_ref().and_then(FrameLoader::info)
    }

    /// The frame loader of the open video (the status bar shows its seek proxy).
    pub(crate) fn loader(&self) -> Option<&FrameLoader> {
        self.loader.as_ref()
    }

    /// Number of frames of the open video or volume sequence (0 when none).
    pub(crate) fn frame_count(&self) -> usize {
        match &self.volume {
            Some(v) => v.frame_count(),
            None => self.video_info().map_or(0, |i| i.frame_count),
        }
    }

    /// Frames per second of what is open (30 until known).
    pub(crate) fn fps(&self) -> f64 {
        match &self.volume {
            Some(v) => v.world.as_ref().map_or(30.0, |w| w.fps),
            None => self.video_info().map_or(30.0, |i| i.fps),
        }
    }

    /// Volume mode's state, when a point-volume sequence is open.
    pub(crate) fn volume(&self) -> Option<&VolumeSequence> {
        self.volume.as_ref()
    }

    /// The frame the user is on.
    pub(crate) fn current_frame(&self) -> usize {
        self.current
    }

    /// The status line.
    pub(crate) fn status(&self) -> &str {
        &self.status
    }

    /// The frame index the shown texture holds.
    #[cfg(test)]
    pub(crate) fn shown(&self) -> Option<usize> {
        self.shown
    }

    /// Whether the texture is the seek proxy's preview of the current frame.
    pub(crate) fn preview(&self) -> bool {
        self.preview
    }

    /// The picture of the current frame.
    pub(crate) fn texture(&self) -> Option<&egui::TextureHandle> {
        self.texture.as_ref()
    }

    /// Whether a tracking, lifting or volume job runs.
    pub(crate) fn busy(&self) -> bool {
        self.running.is_some()
    }

    /// The running job (the progress bar reads it).
    pub(crate) fn job(&self) -> Option<&Job> {
        self.running.as_ref().map(|r| &r.job)
    }

    /// Whether dragging a joint moves the limb below it.
    pub(crate) fn move_limb(&self) -> bool {
        self.move_limb
    }

    /// The edit undo would take back, if any.
    pub(crate) fn undo_name(&self) -> Option<&str> {
        self.history.undo_name()
    }

    /// The edit redo would bring back, if any.
    pub(crate) fn redo_name(&self) -> Option<&str> {
        self.history.redo_name()
    }

    /// The recent files (newest first).
    pub(crate) fn recent(&self) -> &[PathBuf] {
        &self.recent
    }

    /// Whether playback runs.
    pub(crate) fn playing(&self) -> bool {
        self.playing
    }

    /// Whether the shortcuts window shows.
    pub(crate) fn show_help(&self) -> bool {
        self.show_help
    }

    /// Whether the user guide window shows.
    pub(crate) fn show_guide(&self) -> bool {
        self.show_guide
    }

    /// The reliability strips of the tracks.
    pub(crate) fn strips(&self) -> Option<&Strips> {
        self.strips.as_ref()
    }

    /// The tracks' weak spans (fragments the user can jump to).
    pub(crate) fn spans(&self) -> &[WeakSpan] {
        &self.spans
    }

    /// How much of the tracks is weak: joint-frames in weak spans and all joint-frames.
    pub(crate) fn weak_share(&self) -> Option<WeakShare> {
        let tracks = self.project.as_ref()?.tracks.as_ref()?;
        Some(WeakShare {
            joint_frames: self.spans.iter().map(|s| s.frames()).sum(),
            total: tracks.frames.len() * JOINT_COUNT,
        })
    }

    /// What the last lift read of the subject.
    pub(crate) fn subject_fit(&self) -> Option<&SubjectFit> {
        self.subject_fit.as_ref()
    }

    /// The 3D skeleton to show: the project's, or while a job makes the next one, the last.
    pub(crate) fn shown_world(&self) -> Option<(&WorldSkeleton, &Skeleton3d)> {
        match &self.world {
            Some((w, s)) => Some((w, s.as_ref())),
            None if self.busy() => self.last_world.as_ref().map(|(w, s)| (w, s.as_ref())),
            None => None,
        }
    }

    /// The bones whose depth choice the lift of the shown skeleton was unsure of on `frame`
    /// ([`BoneDepth::unsure`]: the other root explained the clip almost as well), worth a look
    /// and perhaps a flip. Empty when the lift's choices are not known (a loaded result).
    pub(crate) fn unsure_bones(&self, frame: usize) -> Vec<Bone> {
        let Some((_, skeleton)) = self.shown_world() else {
            return Vec::new();
        };
        let Some(k) = skeleton
            .frames
            .binary_search_by_key(&FrameIndex(frame), |f| f.index)
            .ok()
        else {
            return Vec::new();
        };
        self.choices
            .iter()
            .find(|c| std::ptr::eq(c.skeleton.as_ref(), skeleton))
            .and_then(|c| c.bones.get(k))
            .map_or_else(Vec::new, |bones| {
                Bone::ALL
                    .into_iter()
                    .filter(|b| bones[b.index()].unsure())
                    .collect()
            })
    }

    /// Whether the 3D skeleton shown is the last one, kept while a job makes the next.
    pub(crate) fn world_is_stale(&self) -> bool {
        self.world.is_none() && self.busy() && self.last_world.is_some()
    }

    /// Whether a recovery prompt is showing.
    pub(crate) fn offers_recovery(&self) -> bool {
        self.recovery.is_some()
    }

    /// A saved project of the video that was just opened without it, to offer.
    pub(crate) fn project_beside(&self) -> Option<&Path> {
        self.project_beside.as_deref()
    }

    /// Where the user is going once "save changes?" is answered (the prompt shows meanwhile).
    pub(crate) fn leaving(&self) -> Option<&Leave> {
        self.leaving.as_ref()
    }

    /// The app's own path field, when it shows.
    pub(crate) fn path_request(&self) -> Option<&PathRequest> {
        self.path_request.as_ref()
    }

    /// How many times something was opened (a change: the views fit the new frame).
    pub(crate) fn opened(&self) -> u64 {
        self.opened_count
    }

    /// Whether the user chose to quit and nothing is left to ask.
    pub(crate) fn quitting(&self) -> bool {
        self.quitting
    }

    /// Whether the project has changes not saved to a project file.
    pub(crate) fn dirty(&self) -> bool {
        self.dirty && self.project.is_some()
    }

    /// What to draw for a frame: keys win, then tracks arriving (a running job's, newer than the
    /// tracks it replaces), then the final tracks.
    pub(crate) fn points(&self, frame: usize) -> PerJoint<Option<(Point2<f64>, PointState)>> {
        let Some(p) = &self.project else {
            return PerJoint::from_fn(|_| None);
        };
        let weak = p.settings.tracker.weak_reliability;
        let tracked = self.partial.get(&frame).or_else(|| {
            p.tracks.as_ref().and_then(|t| {
                t.frames
                    .binary_search_by_key(&FrameIndex(frame), |f| f.index)
                    .ok()
                    .map(|k| &t.frames[k])
            })
        });
        let keys = p.keys.frames.get(&FrameIndex(frame));
        PerJoint::from_fn(|j| {
            if let Some(k) = keys.and_then(|k| k[j]) {
                return Some((k, PointState::Key));
            }
            let t = tracked?.points[j];
            Some((t.pos, PointState::of(&t, weak)))
        })
    }

    /// Why the pose network could not be loaded, when a tracking run found so.
    pub(crate) fn network_problem(&self) -> Option<&str> {
        self.network_problem.as_deref()
    }
}
