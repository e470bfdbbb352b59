//! The app's state and its actions, in plain Rust (no drawing): the open video or point-volume
//! sequence, the project with its undo history, autosave and recovery, the running job, and
//! what is derived from the results (reliability strips, weak spans, the 3D world). The views
//! read it and return [`Intent`]s; [`State::apply`] carries them out.
//!
//! The actions live by subject: `files` (open, save, quit, the path field), `recent` (File ▸
//! Recent, the project offered beside a video), `export`, `edit`
//! (marks, corrections, settings, flips, undo), `work` (tracking and lifting jobs, decoded
//! frames arriving), `outdated` (results the settings changed under), `layout` (panel widths and
//! zoom kept across restarts), `read` (what the views read). The workers it owns: [`frame_loader`], [`jobs`], [`autosave`], and the
//! desktop's [`file_dialogs`].

pub(crate) mod autosave;
mod edit;
mod export;
mod export_kind;
pub(crate) mod file_dialogs;
mod files;
pub(crate) mod frame_loader;
pub(crate) mod jobs;
pub(crate) mod layout;
mod outdated;
mod read;
mod recent;
mod strips;
pub(crate) mod volume;
mod work;

pub(crate) use edit::FlipGhost;
pub(crate) use export_kind::ExportKind;
pub(crate) use files::{Choose, Leave, PathPurpose, PathRequest, SaveAnswer};
pub(crate) use outdated::Outdated;
pub(crate) use strips::Strips;

use crate::intent::Intent;
use crate::views::frame_view::PointState;
use autosave::Autosaver;
use file_dialogs::{Dialogs, RfdDialogs};
use frame_loader::FrameLoader;
use jobs::Job;
use nalgebra::Point2;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use videomocap_core::export::WorldSkeleton;
use videomocap_core::formats::{FrameIndex, FrameTracks, Skeleton3d};
use videomocap_core::lift::BoneDepth;
use videomocap_core::lift::SubjectFit;
use videomocap_core::project::{History, Project};
use videomocap_core::skeleton::{BONE_COUNT, Bone, JOINT_COUNT, PerJoint};
use videomocap_core::track::{KeyFrames, WeakSpan, weak_spans};
use videomocap_core::video::VideoInfo;
use volume::VolumeSequence;

/// How the app is set up (tests swap the dialogs and the autosave directory).
pub(crate) struct Config {
    /// File dialogs.
    pub dialogs: Box<dyn Dialogs>,
    /// Where the recovery file lives (`None`: no autosave).
    pub autosave_dir: Option<PathBuf>,
    /// Where seek proxies of long-GOP videos are kept (`None`: no proxies).
    pub proxy_dir: Option<PathBuf>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            dialogs: Box::new(RfdDialogs),
            autosave_dir: autosave::default_dir(),
            proxy_dir: dirs::cache_dir().map(|d| d.join("videomocap").join("proxies")),
        }
    }
}

/// A running job and the keys it started from (its result is dropped if they changed since).
struct Running {
    job: Job,
    keys: KeyFrames,
    overrides: videomocap_core::lift::DepthOverrides,
    /// The project's settings when the job started (what its result is made with).
    settings: videomocap_core::project::Settings,
}

/// What a lift chose per frame and bone, kept with the skeleton it produced (so that undo and
/// redo, which bring back an earlier skeleton, find its choices).
struct LiftChoices {
    skeleton: Arc<Skeleton3d>,
    bones: Vec<[BoneDepth; BONE_COUNT]>,
}

/// How much of the clip's tracks is weak, lost or filled in (the side panel's headline).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct WeakShare {
    /// Joint-frames in weak spans (a joint on a frame counts once).
    pub joint_frames: usize,
    /// All joint-frames of the tracked clip (16 per frame).
    pub total: usize,
}

impl WeakShare {
    /// The weak share of the clip, 0–1.
    pub(crate) fn share(self) -> f64 {
        self.joint_frames as f64 / self.total.max(1) as f64
    }
}

/// Everything the app knows and does, without a window.
pub(crate) struct State {
    ctx: egui::Context,
    config: Config,
    loader: Option<FrameLoader>,
    project: Option<Project>,
    project_path: Option<PathBuf>,
    history: History<Project>,
    autosaver: Option<Autosaver>,
    /// A recovery file found at start, waiting for the user's answer.
    recovery: Option<PathBuf>,
    current: usize,
    shown: Option<usize>,
    /// The texture holds the seek proxy's smaller picture of `shown`; the full frame follows.
    preview: bool,
    texture: Option<egui::TextureHandle>,
    /// Index into [`Joint::MARKING_ORDER`] of the joint the marking guide asks for.
    marking: Option<usize>,
    /// The user said the subject is seen from behind (the marking guide's diagram mirrored),
    /// until both shoulders or both hips are placed and say it themselves.
    from_behind: bool,
    move_limb: bool,
    running: Option<Running>,
    /// Frames tracked so far by the running job (drawn as they arrive, over the earlier
    /// tracks a re-track replaces).
    partial: BTreeMap<usize, FrameTracks>,
    /// The background the last tracking run of this video found (a re-track reuses it).
    background: Option<videomocap_core::track::KnownBackground>,
    /// What the pose network saw in the last tracking run of this video (a re-track runs it
    /// again only where a crop moved).
    network_seen: Option<videomocap_core::track::NetworkFrames>,
    /// What VBA's passes computed in the last tracking run of this video, and the frames they
    /// read (a re-track tracks again only from the first frame whose keys changed).
    passes_seen: Option<videomocap_core::track::PassesSeen>,
    /// Why the pose network could not be loaded, once a tracking job found it could not (shown
    /// in the status bar and the Tracker panel).
    network_problem: Option<String>,
    spans: Vec<WeakSpan>,
    strips: Option<Strips>,
    choices: Vec<LiftChoices>,
    /// What the last lift read of the subject from the tracks (shown under the height).
    subject_fit: Option<SubjectFit>,
    /// The pose before the last edit, when that edit was a flip.
    flip_ghost: Option<FlipGhost>,
    /// The settings the tracks and the 3D skeleton were made with.
    made_with: outdated::MadeWith,
    /// The project's 3D skeleton in the exports' world (what exports write), with the skeleton
    /// it was made from.
    world: Option<(WorldSkeleton, Arc<Skeleton3d>)>,
    /// The last 3D skeleton shown, kept on screen while a job makes the next one.
    last_world: Option<(WorldSkeleton, Arc<Skeleton3d>)>,
    playing: bool,
    play_time: f64,
    show_help: bool,
    show_guide: bool,
    recent: Vec<PathBuf>,
    status: String,
    /// Volume mode: a point-volume sequence instead of a video.
    volume: Option<VolumeSequence>,
    /// The project has edits not saved to its file (the autosave holds them).
    dirty: bool,
    /// Where the user is going once "save changes?" is answered.
    leaving: Option<Leave>,
    /// A saved project of the video just opened bare, offered to the user.
    project_beside: Option<PathBuf>,
    /// A project read while checking it could open, kept for the open (not read twice).
    checked_project: Option<(PathBuf, Project)>,
    /// The app's own path field, shown when no file dialog can be.
    path_request: Option<PathRequest>,
    /// A file dialog could not be shown once: use the path field from then on.
    no_native_dialogs: bool,
    /// The user chose to quit and nothing is left to ask: the window closes.
    quitting: bool,
    /// A settings slider is being dragged and its undo step is already recorded.
    settings_drag_recorded: bool,
    /// How many times something was opened (the views reset their zoom and orbit on a change).
    opened_count: u64,
}

impl State {
    /// The state at start, with the given dialogs and autosave directory; a recovery file left
    /// by an earlier session is offered.
    pub(crate) fn new(ctx: &egui::Context, config: Config) -> State {
        let autosaver = config.autosave_dir.as_deref().map(Autosaver::new);
        let recovery = autosaver
            .as_ref()
            .map(|a| a.path().to_owned())
            .filter(|p| p.is_file());
        let mut state = State {
            ctx: ctx.clone(),
            config,
            loader: None,
            project: None,
            project_path: None,
            history: History::new(200),
            autosaver,
            recovery,
            current: 0,
            shown: None,
            preview: false,
            texture: None,
            marking: None,
            from_behind: false,
            move_limb: false,
            running: None,
            partial: BTreeMap::new(),
            background: None,
            network_seen: None,
            passes_seen: None,
            network_problem: None,
            spans: Vec::new(),
            strips: None,
            choices: Vec::new(),
            subject_fit: None,
            flip_ghost: None,
            made_with: outdated::MadeWith::default(),
            world: None,
            last_world: None,
            playing: false,
            play_time: 0.0,
            show_help: false,
            show_guide: false,
            recent: Vec::new(),
            status: "Open a video with File > Open video (or drop one here)".to_owned(),
            volume: None,
            dirty: false,
            leaving: None,
            project_beside: None,
            checked_project: None,
            path_request: None,
            no_native_dialogs: false,
            quitting: false,
            settings_drag_recorded: false,
            opened_count: 0,
        };
        state.recent = state.load_recent();
        state
    }

    /// Carries out what a view asked for.
    pub(crate) fn apply(&mut self, intent: Intent) {
        match intent {
            Intent::Open(path) => self.leave(Leave::Open(path)),
            Intent::Choose(what) => self.choose(what),
            Intent::Save => self.save_project(false, None),
            Intent::SaveAs => self.save_project(true, None),
            Intent::Export(kind) => self.export(kind),
            Intent::Quit => self.leave(Leave::Quit),
            Intent::AnswerSave(answer) => self.answer_save(answer),
            Intent::AnswerRecovery(recover) => self.answer_recovery(recover),
            Intent::DismissProjectBeside => self.project_beside = None,
            Intent::PathEdited(text) => self.path_edited(text),
            Intent::PathChosen(path) => self.path_chosen(path),
            Intent::CreateFolder => self.create_folder(),
            Intent::Undo => self.undo(),
            Intent::Redo => self.redo(),
            Intent::StartMarking => self.start_marking(),
            Intent::SkipJoint => self.skip_joint(),
            Intent::StopMarking => self.marking = None,
            Intent::SeenFromBehind(on) => self.from_behind = on,
            Intent::MoveLimb(on) => self.move_limb = on,
            Intent::Click(pos) => self.click(pos),
            Intent::Moved(joint, pos) => self.moved(joint, pos),
            Intent::Track => self.start_tracking(None),
            Intent::Lift => self.start_lift(),
            Intent::Cancel => self.cancel_job(),
            Intent::Flip(bone) => self.flip(bone),
            Intent::GoTo(frame) => self.go_to(frame),
            Intent::Step(by) => self.go_to(self.current.saturating_add_signed(by)),
            Intent::TogglePlay => self.playing = !self.playing,
            Intent::Settings { settings, dragging } => self.edit_settings(*settings, dragging),
            Intent::SettingsReleased => self.settings_drag_recorded = false,
            Intent::VolumeLayers(layers) => {
                if let Some(v) = &mut self.volume {
                    v.layers = layers;
                }
            }
            Intent::Help(show) => self.show_help = show,
            Intent::Guide(show) => self.show_guide = show,
            Intent::Escape => {
                self.marking = None;
                self.show_help = false;
                self.show_guide = false;
            }
        }
    }
    /// The recovery file's path (when autosave is on).
    #[cfg(test)]
    pub(crate) fn autosave_path(&self) -> Option<PathBuf> {
        self.autosaver.as_ref().map(|a| a.path().to_owned())
    }

    /// Waits until autosaves are written (tests).
    #[cfg(test)]
    pub(crate) fn flush_autosave(&mut self) {
        if let Some(a) = &mut self.autosaver {
            a.flush();
        }
    }

    /// As a tracking job does when the pose network cannot load (tests of the Tracker panel).
    #[cfg(test)]
    pub(crate) fn report_network_problem_for_test(&mut self, why: String) {
        self.network_problem = Some(why);
    }

    /// Gives the project's 3D skeleton the lift's depth choices `bones` (tests of the 3D view).
    #[cfg(test)]
    pub(crate) fn set_depth_choices_for_test(&mut self, bones: Vec<[BoneDepth; BONE_COUNT]>) {
        if let Some(skeleton) = self.project.as_ref().and_then(|p| p.skeleton.clone()) {
            self.choices.push(LiftChoices { skeleton, bones });
        }
    }

    /// Puts a project in place without a video (tests of the panels).
    #[cfg(test)]
    pub(crate) fn set_project_for_test(&mut self, p: Project) {
        self.set_project(p);
    }

    // ----- derived results -----

    fn set_project(&mut self, p: Project) {
        self.made_with = outdated::MadeWith::of(&p);
        self.project = Some(p);
        self.background = None;
        self.network_seen = None;
        self.passes_seen = None;
        self.subject_fit = None;
        self.history.clear();
        self.results_changed();
    }

    /// Recomputes what is derived from the results (strips, spans, the 3D world).
    fn results_changed(&mut self) {
        self.partial.clear();
        if let Some(w) = self.world.take() {
            self.last_world = Some(w);
        }
        let Some(p) = &self.project else {
            self.strips = None;
            self.spans.clear();
            self.last_world = None;
            return;
        };
        let weak = p.settings.tracker.weak_reliability;
        self.strips = p.tracks.as_ref().map(|t| Strips::new(t, &p.keys, weak));
        // From the tracks, so a reopened project or an undone re-track shows its own spans.
        self.spans = p.tracks.as_ref().map_or_else(Vec::new, |t| {
            weak_spans(&t.frames, weak, &|f, j| p.keys.is_key(f, j))
        });
        self.world = p
            .skeleton
            .as_ref()
            .and_then(|s| WorldSkeleton::new(s, None).ok().map(|w| (w, Arc::clone(s))));
    }

    /// Per frame by play time: advances the current frame while playing (the caller repaints).
    pub(crate) fn play(&mut self, dt_s: f64) {
        if !self.playing {
            return;
        }
        let fps = self.fps();
        self.play_time += dt_s;
        let steps = (self.play_time * fps).floor();
        if steps >= 1.0 {
            self.play_time -= steps / fps;
            let next = self.current + steps as usize;
            if next >= self.frame_count() {
                self.playing = false;
            }
            self.go_to(next);
        }
    }

    fn go_to(&mut self, index: usize) {
        let n = self.frame_count();
        if n == 0 {
            return;
        }
        let index = index.min(n - 1);
        if index != self.current {
            self.current = index;
            if let Some(l) = &self.loader {
                l.request(index);
            }
        }
    }
}
