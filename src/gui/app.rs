//! The main window: menus, the frame view with marking and correction, the timeline with
//! reliability strips, the 3D viewport, parameters, background jobs with progress, export,
//! projects with undo, autosave and recovery.

use super::autosave::Autosaver;
use super::dialogs::{Dialogs, RfdDialogs};
use super::frame_loader::{FrameLoader, LoaderEvent, ProxyStatus};
use super::frame_view::{FrameView, Overlay, PointState, ViewEvent};
use super::jobs::{Job, JobEvent};
use super::timeline::{self, Strips};
use super::view3d::{Orbit, Scene};
use super::volume_view::VolumeView;
use nalgebra::{Point2, Point3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use videomocap::export::{self, WorldSkeleton};
use videomocap::formats::{FrameTracks, Marks, Skeleton3d};
use videomocap::lift::Root;
use videomocap::lift::focal::default_focal;
use videomocap::project::{History, Project};
use videomocap::skeleton::{BONE_COUNT, Bone, Joint, PerJoint};
use videomocap::track::{TrackJob, TrackerParams, WeakSpan, weak_spans};
use videomocap::video::VideoInfo;

/// How the app is set up (tests swap the dialogs and the autosave directory).
pub struct Config {
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
            autosave_dir: super::autosave::default_dir(),
            proxy_dir: dirs::cache_dir().map(|d| d.join("videomocap").join("proxies")),
        }
    }
}

/// Things the export menu can write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportKind {
    Bvh,
    TracksJson,
    SkeletonJson,
    TracksCsv,
    JointsCsv,
    Trc,
    Marks,
}

impl ExportKind {
    const ALL: [ExportKind; 7] = [
        ExportKind::Bvh,
        ExportKind::TracksJson,
        ExportKind::SkeletonJson,
        ExportKind::TracksCsv,
        ExportKind::JointsCsv,
        ExportKind::Trc,
        ExportKind::Marks,
    ];

    fn label(self) -> &'static str {
        match self {
            ExportKind::Bvh => "BVH (Blender, motion builders)…",
            ExportKind::TracksJson => "2D tracks (tracks2d.json)…",
            ExportKind::SkeletonJson => "3D skeleton (skeleton3d.json)…",
            ExportKind::TracksCsv => "2D tracks CSV…",
            ExportKind::JointsCsv => "3D joints CSV…",
            ExportKind::Trc => "OpenSim markers (.trc)…",
            ExportKind::Marks => "Marks (marks.json)…",
        }
    }

    fn file(self) -> (&'static str, &'static str) {
        match self {
            ExportKind::Bvh => ("motion.bvh", "bvh"),
            ExportKind::TracksJson => ("tracks2d.json", "json"),
            ExportKind::SkeletonJson => ("skeleton3d.json", "json"),
            ExportKind::TracksCsv => ("tracks2d.csv", "csv"),
            ExportKind::JointsCsv => ("joints3d.csv", "csv"),
            ExportKind::Trc => ("motion.trc", "trc"),
            ExportKind::Marks => ("marks.json", "json"),
        }
    }
}

/// A running job and the keys it started from (its result is dropped if they changed since).
struct Running {
    job: Job,
    keys: videomocap::track::KeyFrames,
    overrides: videomocap::lift::DepthOverrides,
}

/// The desktop app.
pub struct App {
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
    view: FrameView,
    orbit: Orbit,
    /// Index into [`Joint::ALL`] of the joint the marking guide asks for.
    marking: Option<usize>,
    move_limb: bool,
    running: Option<Running>,
    /// Frames tracked so far by the running job (drawn as they arrive).
    partial: BTreeMap<usize, FrameTracks>,
    spans: Vec<WeakSpan>,
    strips: Option<Strips>,
    /// Depth-root choices of recent lifts, keyed by the skeleton they produced (so that undo
    /// and redo, which bring back an earlier skeleton, find its choices).
    choices: Vec<(Arc<Skeleton3d>, Vec<[Root; BONE_COUNT]>)>,
    /// What the last lift read of the subject from the tracks (shown under the height).
    subject_fit: Option<videomocap::lift::subject_fit::SubjectFit>,
    world: Option<WorldSkeleton>,
    playing: bool,
    play_time: f64,
    space_dragged: bool,
    show_help: bool,
    recent: Vec<PathBuf>,
    status: String,
    /// Volume mode: a point-volume sequence instead of a video.
    volume: Option<VolumeView>,
    /// The project has edits not saved to its file (the autosave holds them).
    dirty: bool,
    /// A path to open once the user has answered "save changes?".
    pending_open: Option<PathBuf>,
    /// A settings slider is being dragged and its undo step is already recorded.
    settings_drag_recorded: bool,
}

impl App {
    /// A window with the desktop's dialogs and autosave, opening `path` (a video, an image
    /// folder or a project) if given.
    pub fn new(ctx: &egui::Context, path: Option<PathBuf>) -> App {
        App::with_config(ctx, path, Config::default())
    }

    /// A window with the given dialogs and autosave directory.
    pub fn with_config(ctx: &egui::Context, path: Option<PathBuf>, config: Config) -> App {
        let autosaver = config.autosave_dir.as_deref().map(Autosaver::new);
        let recovery = autosaver
            .as_ref()
            .map(|a| a.path().to_owned())
            .filter(|p| p.is_file());
        let mut app = App {
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
            view: FrameView::default(),
            orbit: Orbit::default(),
            marking: None,
            move_limb: false,
            running: None,
            partial: BTreeMap::new(),
            spans: Vec::new(),
            strips: None,
            choices: Vec::new(),
            world: None,
            playing: false,
            play_time: 0.0,
            space_dragged: false,
            show_help: false,
            recent: Vec::new(),
            status: "Open a video with File > Open video (or drop one here)".to_owned(),
            subject_fit: None,
            volume: None,
            dirty: false,
            pending_open: None,
            settings_drag_recorded: false,
        };
        app.recent = app.load_recent();
        if let Some(p) = path {
            app.open_path(ctx, &p);
        }
        app
    }

    // ----- what tests and the menus use -----

    /// The project being edited.
    #[cfg(test)]
    pub fn project(&self) -> Option<&Project> {
        self.project.as_ref()
    }

    /// Metadata of the open video.
    pub fn video_info(&self) -> Option<&VideoInfo> {
        self.loader.as_ref().and_then(FrameLoader::info)
    }

    /// Number of frames of the open video or volume sequence (0 when none).
    pub fn frame_count(&self) -> usize {
        match &self.volume {
            Some(v) => v.frame_count(),
            None => self.video_info().map_or(0, |i| i.frame_count),
        }
    }

    /// Volume mode's state, when a point-volume sequence is open.
    #[cfg(test)]
    pub fn volume(&self) -> Option<&VolumeView> {
        self.volume.as_ref()
    }

    /// What the 3D viewport shows now.
    #[cfg(test)]
    pub fn current_scene(&self) -> Scene {
        self.scene()
    }

    /// The frame the user is on.
    #[cfg(test)]
    pub fn current_frame(&self) -> usize {
        self.current
    }

    /// The status line.
    #[cfg(test)]
    pub fn status(&self) -> &str {
        &self.status
    }

    /// The frame index the shown texture holds.
    #[cfg(test)]
    pub fn shown(&self) -> Option<usize> {
        self.shown
    }

    /// Whether a tracking or lifting job runs.
    pub fn busy(&self) -> bool {
        self.running.is_some()
    }

    /// The joint the marking guide asks for, if marking.
    pub fn asking(&self) -> Option<Joint> {
        self.marking.map(|k| Joint::ALL[k])
    }

    /// The frame view's mapping (tests click through it).
    #[cfg(test)]
    pub fn frame_view(&self) -> &FrameView {
        &self.view
    }

    /// The 3D view's orbit.
    #[cfg(test)]
    pub fn orbit(&self) -> Orbit {
        self.orbit
    }

    /// Whether a recovery prompt is showing.
    #[cfg(test)]
    pub fn offers_recovery(&self) -> bool {
        self.recovery.is_some()
    }

    /// The recovery file's path (when autosave is on).
    #[cfg(test)]
    pub fn autosave_path(&self) -> Option<PathBuf> {
        self.autosaver.as_ref().map(|a| a.path().to_owned())
    }

    /// Waits until autosaves are written (tests).
    #[cfg(test)]
    pub fn flush_autosave(&mut self) {
        if let Some(a) = &mut self.autosaver {
            a.flush();
        }
    }

    /// Opens a video, image folder, project file or a folder of point volumes; first asks to
    /// save unsaved changes.
    pub fn open_path(&mut self, ctx: &egui::Context, path: &Path) {
        if self.dirty && self.project.is_some() {
            self.pending_open = Some(path.to_owned());
            return;
        }
        self.open_now(ctx, path);
    }

    /// Whether the "save changes?" question is showing.
    #[cfg(test)]
    pub fn asks_to_save(&self) -> bool {
        self.pending_open.is_some()
    }

    /// Answers "save changes?": save (then open), discard (open) or cancel (stay).
    pub fn answer_save(&mut self, ctx: &egui::Context, answer: SaveAnswer) {
        let Some(path) = self.pending_open.take() else {
            return;
        };
        match answer {
            SaveAnswer::Save => {
                self.save_project(false);
                if self.dirty {
                    return; // not saved (dialog cancelled or write failed): stay
                }
            }
            SaveAnswer::Discard => self.dirty = false,
            SaveAnswer::Cancel => return,
        }
        self.open_now(ctx, &path);
    }

    fn open_now(&mut self, ctx: &egui::Context, path: &Path) {
        self.dirty = false;
        if is_volume_dir(path) {
            self.open_volume(ctx, path);
        } else if path.is_file() && path.extension().is_some_and(|e| e == "json") {
            match Project::load(path) {
                Ok(p) => {
                    self.open_video(ctx, &p.video.clone());
                    self.set_project(p);
                    self.project_path = Some(path.to_owned());
                    self.status = format!("Opened project {}", path.display());
                }
                Err(e) => self.status = format!("Cannot open project: {e}"),
            }
        } else {
            self.open_video(ctx, path);
        }
        self.recent.retain(|p| p != path);
        self.recent.insert(0, path.to_owned());
        self.recent.truncate(8);
        self.save_recent();
    }

    fn recent_path(&self) -> Option<PathBuf> {
        self.config
            .autosave_dir
            .as_ref()
            .map(|d| d.join("recent.json"))
    }

    /// The recent-files list kept beside the autosave (missing or unreadable: empty).
    fn load_recent(&self) -> Vec<PathBuf> {
        self.recent_path()
            .and_then(|p| std::fs::read_to_string(p).ok())
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default()
    }

    fn save_recent(&self) {
        let Some(path) = self.recent_path() else {
            return;
        };
        if let Some(dir) = path.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        if let Ok(text) = serde_json::to_string_pretty(&self.recent) {
            // Losing the recent list is harmless; the write is still atomic.
            let _ = videomocap::formats::write_atomically(&path, text.as_bytes());
        }
    }

    /// The recent files (newest first).
    #[cfg(test)]
    pub fn recent(&self) -> &[PathBuf] {
        &self.recent
    }

    /// Volume mode: processes the point volumes of `dir` on a worker thread.
    fn open_volume(&mut self, ctx: &egui::Context, dir: &Path) {
        self.close_current();
        self.volume = Some(VolumeView::new(dir.to_owned()));
        self.orbit = Orbit::default();
        self.running = Some(Running {
            job: Job::volume(dir.to_owned(), 30.0, ctx.clone()),
            keys: Default::default(),
            overrides: Default::default(),
        });
        self.status = format!("Processing point volumes in {}…", dir.display());
    }

    fn open_video(&mut self, ctx: &egui::Context, path: &Path) {
        self.close_current();
        self.loader = Some(FrameLoader::open(
            path.to_owned(),
            ctx.clone(),
            self.config.proxy_dir.clone(),
        ));
        self.project = Some(Project::new(path.to_owned()));
        self.results_changed();
        self.view.fit();
        self.status = format!("Opening {}…", path.display());
    }

    /// Stops any job and forgets the open video, project or volume sequence.
    fn close_current(&mut self) {
        if let Some(r) = self.running.take() {
            r.job.cancel();
        }
        self.loader = None;
        self.volume = None;
        self.project = None;
        self.project_path = None;
        self.history.clear();
        self.results_changed();
        self.current = 0;
        self.shown = None;
        self.preview = false;
        self.texture = None;
        self.marking = None;
        self.subject_fit = None;
    }

    fn set_project(&mut self, p: Project) {
        self.project = Some(p);
        self.subject_fit = None;
        self.history.clear();
        self.results_changed();
    }

    /// Recomputes what is derived from the results (strips, the 3D world).
    fn results_changed(&mut self) {
        self.partial.clear();
        let Some(p) = &self.project else {
            self.strips = None;
            self.world = None;
            return;
        };
        let weak = p.settings.tracker.weak_reliability;
        self.strips = p.tracks.as_ref().map(|t| Strips::new(t, &p.keys, weak));
        // From the tracks, so a reopened project or an undone re-track shows its own spans.
        self.spans = p.tracks.as_ref().map_or_else(Vec::new, |t| {
            weak_spans(&t.frames, weak, &|i, j| p.keys.is_key(t.frames[i].index, j))
        });
        self.world = p
            .skeleton
            .as_ref()
            .and_then(|s| WorldSkeleton::new(s, None).ok());
    }

    /// Applies an edit to the project, with undo and autosave.
    fn edit(&mut self, f: impl FnOnce(&mut Project)) {
        let Some(p) = &mut self.project else { return };
        self.history.record(p.clone());
        f(p);
        self.dirty = true;
        self.autosave();
        self.results_changed();
    }

    /// A settings change from the side panel: a slider drag is one undo step, not one per
    /// repaint.
    fn edit_settings(&mut self, settings: videomocap::project::Settings, dragging: bool) {
        if dragging && self.settings_drag_recorded {
            if let Some(p) = &mut self.project {
                p.settings = settings;
                self.dirty = true;
                self.autosave();
            }
        } else {
            self.edit(|p| p.settings = settings);
        }
        self.settings_drag_recorded = dragging;
    }

    fn autosave(&self) {
        if let (Some(a), Some(p)) = (&self.autosaver, &self.project) {
            a.save(p);
        }
    }

    /// Undoes the last edit.
    pub fn undo(&mut self) {
        self.step_history(History::undo, "Undone");
    }

    /// Redoes an undone edit.
    pub fn redo(&mut self) {
        self.step_history(History::redo, "Redone");
    }

    /// Swaps the project for the one `step` brings back from the history, if any.
    fn step_history(
        &mut self,
        step: fn(&mut History<Project>, Project) -> Option<Project>,
        done: &str,
    ) {
        if let Some(p) = self.project.take() {
            self.project = Some(match step(&mut self.history, p.clone()) {
                Some(other) => {
                    self.status = done.to_owned();
                    other
                }
                None => p,
            });
            self.dirty = true;
            self.autosave();
            self.results_changed();
        }
    }

    /// Starts the marking guide on the current frame (asks for each joint in turn).
    pub fn start_marking(&mut self) {
        if self.project.is_some() {
            self.marking = Some(0);
            self.status = "Marking: click each joint in turn (Esc to stop)".to_owned();
        }
    }

    /// Places (or moves) a joint on the current frame by hand; with "move the limb below" on,
    /// the joints below it on its limb move by the same amount.
    pub fn place(&mut self, joint: Joint, pos: Point2<f64>) {
        let frame = self.current;
        let shown = self.points(frame);
        let move_limb = self.move_limb;
        // Hand-placed joints stay on the image (marks and key frames must be on it to be saved
        // and read back); a click beside the image lands on its edge.
        let size = self.video_info().map(|i| (i.width, i.height));
        let onto_image = move |q: Point2<f64>| match size {
            Some((w, h)) => Point2::new(
                q.x.clamp(-0.5, f64::from(w) - 0.5),
                q.y.clamp(-0.5, f64::from(h) - 0.5),
            ),
            None => q,
        };
        self.edit(|p| {
            let old = shown[joint].map(|(q, _)| q);
            p.keys.set(frame, joint, onto_image(pos));
            if move_limb && let Some(old) = old {
                let delta = pos - old;
                for j in descendants(joint) {
                    if let Some((q, _)) = shown[j] {
                        p.keys.set(frame, j, onto_image(q + delta));
                    }
                }
            }
        });
    }

    fn click(&mut self, pos: Point2<f64>) {
        let Some(k) = self.marking else { return };
        self.place(Joint::ALL[k], pos);
        if k + 1 < Joint::ALL.len() {
            self.marking = Some(k + 1);
        } else {
            self.marking = None;
            self.status =
                "All 16 joints marked: Track (T) follows them through the video".to_owned();
        }
    }

    fn moved(&mut self, joint: Joint, pos: Point2<f64>) {
        self.place(joint, pos);
        let has_tracks = self.project.as_ref().is_some_and(|p| p.tracks.is_some());
        if has_tracks && self.marking.is_none() {
            self.status = format!(
                "{} corrected on frame {}: re-tracking from there",
                joint.name(),
                self.current
            );
            self.start_tracking(Some(self.current));
        }
    }

    /// Tracks the whole video from the marks (`from = None`), or re-tracks from a corrected frame.
    pub fn start_tracking(&mut self, from: Option<usize>) {
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
            from: from.filter(|_| p.tracks.is_some()),
            previous: p.tracks.as_deref().cloned(),
        };
        let ctx = self.ctx.clone();
        self.running = Some(Running {
            job: Job::track(p.video.clone(), job, ctx),
            keys: p.keys.clone(),
            overrides: p.overrides.clone(),
        });
        self.partial.clear();
    }

    fn start_lift(&mut self) {
        let (Some(p), Some(info)) = (&self.project, self.video_info()) else {
            return;
        };
        let Some(tracks) = p.tracks.clone() else {
            return;
        };
        let focal = p
            .settings
            .focal_px
            .unwrap_or_else(|| default_focal(info.width, info.height));
        let ctx = self.ctx.clone();
        self.running = Some(Running {
            job: Job::lift(
                tracks,
                focal,
                p.settings.height_m,
                p.settings.lengths.known(),
                p.settings.lift,
                p.overrides.clone(),
                ctx,
            ),
            keys: p.keys.clone(),
            overrides: p.overrides.clone(),
        });
    }

    /// Cancels the running job.
    pub fn cancel_job(&mut self) {
        if let Some(r) = &self.running {
            r.job.cancel();
        }
    }

    /// Flips the depth choice of `bone` on the current frame and lifts again.
    pub fn flip(&mut self, bone: Bone) {
        let Some(k) = self
            .project
            .as_ref()
            .and_then(|p| p.tracks.as_ref())
            .and_then(|t| {
                t.frames
                    .binary_search_by_key(&self.current, |f| f.index)
                    .ok()
            })
        else {
            return;
        };
        let skeleton = self.project.as_ref().and_then(|p| p.skeleton.clone());
        let known = skeleton.and_then(|s| {
            self.choices
                .iter()
                .find(|(k, _)| Arc::ptr_eq(k, &s))
                .map(|(_, c)| c)
        });
        let Some(current) = known.and_then(|c| c.get(k)).map(|c| c[bone.index()]) else {
            self.status =
                "This 3D result's depth choices are not known (it was loaded from a file): lift again (T), then flip"
                    .to_owned();
            return;
        };
        let frame = self.current;
        self.edit(|p| {
            p.overrides.insert((frame, bone), current.flipped());
        });
        self.status = format!("{} flipped on frame {frame}: lifting again", bone.key());
        self.start_lift();
    }

    /// Writes one export to `path`.
    pub fn export_to(&mut self, kind: ExportKind, path: &Path) {
        self.status = match self.write_export(kind, path) {
            Ok(()) => format!("Wrote {}", path.display()),
            Err(e) => format!("Export failed: {e}"),
        };
    }

    fn write_export(&self, kind: ExportKind, path: &Path) -> anyhow::Result<()> {
        let p = self
            .project
            .as_ref()
            .ok_or_else(|| anyhow::anyhow!("no video open"))?;
        let need_tracks = || {
            p.tracks
                .as_deref()
                .ok_or_else(|| anyhow::anyhow!("nothing tracked yet"))
        };
        let need_world = || {
            self.world
                .as_ref()
                .ok_or_else(|| anyhow::anyhow!("no 3D skeleton yet"))
        };
        match kind {
            ExportKind::Bvh => {
                let b = export::bvh(need_world()?)?;
                export::save_text(path, &b.text)?;
            }
            ExportKind::TracksJson => need_tracks()?.save(path)?,
            ExportKind::SkeletonJson => p
                .skeleton
                .as_deref()
                .ok_or_else(|| anyhow::anyhow!("no 3D skeleton yet"))?
                .save(path)?,
            ExportKind::TracksCsv => {
                export::save_text(path, &export::tracks_csv(need_tracks()?))?;
            }
            ExportKind::JointsCsv => {
                export::save_text(path, &export::skeleton_csv(need_world()?))?;
            }
            ExportKind::Trc => {
                let name = path
                    .file_name()
                    .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
                export::save_text(path, &export::trc(need_world()?, &name))?;
            }
            ExportKind::Marks => p
                .marks()
                .ok_or_else(|| anyhow::anyhow!("not all 16 joints are marked on one frame"))?
                .save(path)?,
        }
        Ok(())
    }

    fn export_dialog(&mut self, kind: ExportKind) {
        let (name, ext) = kind.file();
        if let Some(path) = self.config.dialogs.save_file("Export", name, ext) {
            self.export_to(kind, &path);
        }
    }

    /// Saves the project to `path` and clears the recovery file.
    pub fn save_project_to(&mut self, path: &Path) {
        let Some(p) = &self.project else { return };
        match p.save(path) {
            Ok(()) => {
                self.project_path = Some(path.to_owned());
                self.dirty = false;
                if let Some(a) = &mut self.autosaver {
                    a.clear();
                }
                self.status = format!("Saved {}", path.display());
            }
            Err(e) => self.status = format!("Cannot save: {e}"),
        }
    }

    fn save_project(&mut self, ask: bool) {
        let path = match (&self.project_path, ask) {
            (Some(p), false) => Some(p.clone()),
            _ => self
                .config
                .dialogs
                .save_file("Save project", "project.videomocap.json", "json"),
        };
        if let Some(path) = path {
            self.save_project_to(&path);
        }
    }

    /// Accepts or declines the recovery offered at start.
    pub fn answer_recovery(&mut self, ctx: &egui::Context, recover: bool) {
        let Some(path) = self.recovery.take() else {
            return;
        };
        if recover {
            match Project::load(&path) {
                Ok(p) => {
                    self.open_video(ctx, &p.video.clone());
                    self.set_project(p);
                    self.dirty = true;
                    self.autosave();
                    self.status = "Recovered the unsaved session".to_owned();
                }
                Err(e) => self.status = format!("Cannot recover: {e}"),
            }
        } else if let Some(a) = &mut self.autosaver {
            a.clear();
        }
    }

    // ----- per-frame work -----

    /// What to draw for a frame: keys win, then final tracks, then tracks arriving.
    fn points(&self, frame: usize) -> PerJoint<Option<(Point2<f64>, PointState)>> {
        let Some(p) = &self.project else {
            return PerJoint::from_fn(|_| None);
        };
        let weak = p.settings.tracker.weak_reliability;
        let tracked = p
            .tracks
            .as_ref()
            .and_then(|t| {
                t.frames
                    .binary_search_by_key(&frame, |f| f.index)
                    .ok()
                    .map(|k| &t.frames[k])
            })
            .or_else(|| self.partial.get(&frame));
        let keys = p.keys.frames.get(&frame);
        PerJoint::from_fn(|j| {
            if let Some(k) = keys.and_then(|k| k[j]) {
                return Some((k, PointState::Key));
            }
            let t = tracked?.points[j];
            Some((t.pos, PointState::of(&t, weak)))
        })
    }

    /// Puts a decoded frame (full or preview) on screen.
    fn show_frame(&mut self, ctx: &egui::Context, frame: &videomocap::video::Frame) {
        let size = [frame.image.width() as usize, frame.image.height() as usize];
        let image = egui::ColorImage::from_rgb(size, frame.image.as_raw());
        self.texture = Some(ctx.load_texture("frame", image, egui::TextureOptions::LINEAR));
        self.shown = Some(frame.index);
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

    fn receive(&mut self, ctx: &egui::Context) {
        let events = self
            .loader
            .as_mut()
            .map(FrameLoader::poll)
            .unwrap_or_default();
        for event in events {
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
                    if let Some(l) = &self.loader {
                        l.request(self.current);
                    }
                }
                LoaderEvent::Opened(Err(e)) => {
                    self.status = format!("Cannot open: {e}");
                    self.loader = None;
                    self.project = None;
                }
                LoaderEvent::Frame(Ok(frame)) => {
                    self.show_frame(ctx, &frame);
                    self.preview = false;
                }
                // A preview only stands in for the current frame until the full one comes.
                LoaderEvent::Preview(frame)
                    if frame.index == self.current
                        && (self.shown != Some(frame.index) || self.preview) =>
                {
                    self.show_frame(ctx, &frame);
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
        let events = self
            .running
            .as_mut()
            .map(|r| r.job.poll())
            .unwrap_or_default();
        for event in events {
            match event {
                JobEvent::Progress { frame: Some(f), .. } => {
                    self.partial.insert(f.index, f);
                }
                JobEvent::Progress { .. } => {}
                JobEvent::Tracked(result) => self.tracked(result),
                JobEvent::Lifted(result) => self.lifted(result),
                JobEvent::Volume(result) => {
                    self.running = None;
                    match (result, &mut self.volume) {
                        (Ok(p), Some(v)) => {
                            let ok = p.results.iter().filter(|r| r.is_ok()).count();
                            self.status = format!(
                                "{}   {} frames, {} with a five-limb skeleton curve, {} warnings",
                                v.dir.display(),
                                p.files.len(),
                                ok,
                                p.assembled.warnings.len()
                            );
                            v.set(p);
                        }
                        (Err(e), _) => self.status = format!("Cannot process the volumes: {e}"),
                        (Ok(_), None) => {}
                    }
                }
            }
        }
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
            self.current = m.frame.min(info.frame_count.saturating_sub(1));
            if let Some(p) = &mut self.project {
                p.keys = videomocap::track::KeyFrames::from_marks(&m);
            }
            self.status.push_str("   (marks.json loaded)");
        }
    }

    fn tracked(&mut self, result: Result<videomocap::track::TrackOutput, String>) {
        let Some(r) = self.running.take() else { return };
        match result {
            Ok(out) => {
                let current = self.project.as_ref().map(|p| &p.keys);
                if current != Some(&r.keys) {
                    self.status = "Tracking finished for an older edit; result dropped".to_owned();
                    return;
                }
                let tracks = Arc::new(out.tracks);
                if let Some(p) = &mut self.project {
                    p.tracks = Some(tracks);
                    p.skeleton = None;
                }
                self.dirty = true;
                self.autosave();
                self.results_changed();
                self.status = format!(
                    "Tracked {} frames; {} weak spans",
                    self.frame_count(),
                    self.spans.len()
                );
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

    fn lifted(
        &mut self,
        result: Result<
            (
                videomocap::lift::LiftOutput,
                videomocap::lift::subject_fit::SubjectFit,
            ),
            String,
        >,
    ) {
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
                self.subject_fit = Some(fit);
                let skeleton = Arc::new(out.skeleton);
                self.choices.push((skeleton.clone(), out.choices));
                if self.choices.len() > 16 {
                    self.choices.remove(0);
                }
                if let Some(p) = &mut self.project {
                    p.skeleton = Some(skeleton);
                }
                self.dirty = true;
                self.autosave();
                self.results_changed();
                let done = std::mem::take(&mut self.status);
                self.status = format!("{done}; lifted to 3D");
            }
            Err(e) => self.status = format!("Lift stopped: {e}"),
        }
    }

    fn handle_keys(&mut self, ctx: &egui::Context) {
        let typing = ctx.egui_wants_keyboard_input();
        if typing {
            return;
        }
        let cmd = egui::Modifiers::COMMAND;
        let (undo, redo, save) = ctx.input_mut(|i| {
            let redo = i.consume_key(cmd | egui::Modifiers::SHIFT, egui::Key::Z);
            let undo = i.consume_key(cmd, egui::Key::Z);
            let save = i.consume_key(cmd, egui::Key::S);
            (undo, redo, save)
        });
        if redo {
            self.redo();
        } else if undo {
            self.undo();
        }
        if save {
            self.save_project(false);
        }
        let (left, right, home, end, shift, f1, esc, m, t, space_up) = ctx.input(|i| {
            (
                i.key_pressed(egui::Key::ArrowLeft),
                i.key_pressed(egui::Key::ArrowRight),
                i.key_pressed(egui::Key::Home),
                i.key_pressed(egui::Key::End),
                i.modifiers.shift,
                i.key_pressed(egui::Key::F1),
                i.key_pressed(egui::Key::Escape),
                i.key_pressed(egui::Key::M),
                i.key_pressed(egui::Key::T),
                i.key_released(egui::Key::Space),
            )
        });
        let step = if shift { 10 } else { 1 };
        if left {
            self.go_to(self.current.saturating_sub(step));
        }
        if right {
            self.go_to(self.current + step);
        }
        if home {
            self.go_to(0);
        }
        if end {
            self.go_to(self.frame_count().saturating_sub(1));
        }
        if f1 {
            self.show_help = !self.show_help;
        }
        if esc {
            self.marking = None;
            self.show_help = false;
        }
        if m {
            self.start_marking();
        }
        if t && !self.busy() {
            self.start_tracking(None);
        }
        // Space: a tap plays or pauses; held, it pans the frame view while dragging.
        if ctx.input(|i| i.key_down(egui::Key::Space) && i.pointer.is_decidedly_dragging()) {
            self.space_dragged = true;
        }
        if space_up {
            if !self.space_dragged {
                self.playing = !self.playing;
            }
            self.space_dragged = false;
        }
    }

    fn play(&mut self, ctx: &egui::Context) {
        if !self.playing {
            return;
        }
        let fps = match &self.volume {
            Some(v) => v.world.as_ref().map_or(30.0, |w| w.fps),
            None => self.video_info().map_or(30.0, |i| i.fps),
        };
        self.play_time += f64::from(ctx.input(|i| i.stable_dt));
        let steps = (self.play_time * fps).floor();
        if steps >= 1.0 {
            self.play_time -= steps / fps;
            let next = self.current + steps as usize;
            if next >= self.frame_count() {
                self.playing = false;
            }
            self.go_to(next);
        }
        ctx.request_repaint();
    }

    // ----- panels -----

    fn menu(&mut self, ui: &mut egui::Ui, ctx: &egui::Context) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("Open video…").clicked() {
                    ui.close();
                    if let Some(p) = self.config.dialogs.open_file("Open video", &[]) {
                        self.open_path(ctx, &p);
                    }
                }
                if ui.button("Open image folder…").clicked() {
                    ui.close();
                    if let Some(p) = self.config.dialogs.open_folder("Open image folder") {
                        self.open_path(ctx, &p);
                    }
                }
                if ui.button("Open point volumes…").clicked() {
                    ui.close();
                    if let Some(p) = self.config.dialogs.open_folder("Open point volumes") {
                        self.open_path(ctx, &p);
                    }
                }
                if ui.button("Open project…").clicked() {
                    ui.close();
                    if let Some(p) = self.config.dialogs.open_file("Open project", &["json"]) {
                        self.open_path(ctx, &p);
                    }
                }
                ui.menu_button("Recent", |ui| {
                    for p in self.recent.clone() {
                        if ui.button(p.display().to_string()).clicked() {
                            ui.close();
                            self.open_path(ctx, &p);
                        }
                    }
                });
                ui.separator();
                if ui.button("Save project (Ctrl+S)").clicked() {
                    ui.close();
                    self.save_project(false);
                }
                if ui.button("Save project as…").clicked() {
                    ui.close();
                    self.save_project(true);
                }
                if ui.button("Load marks…").clicked() {
                    ui.close();
                    if let Some(path) = self.config.dialogs.open_file("Load marks", &["json"]) {
                        match Marks::load(&path) {
                            Ok(m) => self.edit(|p| {
                                for (j, q) in m.points.iter() {
                                    p.keys.set(m.frame, j, *q);
                                }
                            }),
                            Err(e) => self.status = format!("Cannot load marks: {e}"),
                        }
                    }
                }
            });
            ui.menu_button("Edit", |ui| {
                if ui
                    .add_enabled(self.history.can_undo(), egui::Button::new("Undo (Ctrl+Z)"))
                    .clicked()
                {
                    ui.close();
                    self.undo();
                }
                if ui
                    .add_enabled(
                        self.history.can_redo(),
                        egui::Button::new("Redo (Ctrl+Shift+Z)"),
                    )
                    .clicked()
                {
                    ui.close();
                    self.redo();
                }
                if ui.button("Mark joints (M)").clicked() {
                    ui.close();
                    self.start_marking();
                }
                ui.checkbox(
                    &mut self.move_limb,
                    "Dragging a joint moves the limb below it",
                );
            });
            ui.menu_button("Track", |ui| {
                if ui
                    .add_enabled(!self.busy(), egui::Button::new("Track and lift (T)"))
                    .clicked()
                {
                    ui.close();
                    self.start_tracking(None);
                }
                if ui
                    .add_enabled(!self.busy(), egui::Button::new("Lift to 3D again"))
                    .clicked()
                {
                    ui.close();
                    self.start_lift();
                }
            });
            ui.menu_button("Export", |ui| {
                for kind in ExportKind::ALL {
                    if ui.button(kind.label()).clicked() {
                        ui.close();
                        self.export_dialog(kind);
                    }
                }
            });
            ui.menu_button("Help", |ui| {
                if ui.button("Shortcuts (F1)").clicked() {
                    ui.close();
                    self.show_help = true;
                }
            });
        });
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        if let Some(v) = &mut self.volume {
            ui.heading("Point volumes");
            ui.checkbox(&mut v.show_points, "points (coloured by body)");
            ui.checkbox(&mut v.show_curve, "skeleton curve");
            ui.checkbox(&mut v.show_bodies, "head sphere, torso and limb cylinders");
            if let Some(p) = &v.processed {
                ui.label(format!("left/right from: {:?}", p.assembled.sides_from));
                if let Some(Err(e)) = p.results.get(self.current) {
                    ui.colored_label(egui::Color32::from_rgb(240, 160, 60), e.to_string());
                }
                ui.separator();
                ui.heading("Warnings");
                egui::ScrollArea::vertical()
                    .max_height(300.0)
                    .show(ui, |ui| {
                        if p.assembled.warnings.is_empty() {
                            ui.label("none");
                        }
                        for w in &p.assembled.warnings {
                            ui.label(w);
                        }
                    });
            }
            return;
        }
        if let Some(k) = self.marking {
            ui.heading("Marking");
            let j = Joint::ALL[k];
            ui.label(format!("{} of 16: {}", k + 1, j.name()));
            ui.label(egui::RichText::new(j.definition()).italics());
            body_diagram(ui, j);
            ui.horizontal(|ui| {
                if ui.button("Skip").clicked() {
                    self.marking = (k + 1 < Joint::ALL.len()).then_some(k + 1);
                }
                if ui.button("Done (Esc)").clicked() {
                    self.marking = None;
                }
            });
            ui.separator();
        }
        ui.heading("Parameters");
        if let Some(before) = self.project.as_ref().map(|p| p.settings) {
            let mut settings = before;
            let info = self.video_info().cloned();
            let default_f = info
                .as_ref()
                .map_or(1000.0, |i| default_focal(i.width, i.height));
            let mut given = settings.focal_px.is_some();
            let mut f = settings.focal_px.unwrap_or(default_f);
            ui.checkbox(&mut given, "Focal length known")
                .on_hover_text("Off: 60° across the image's longer side (a typical phone or webcam). On: give the focal length in pixels (from calibration, or focal mm × image width px / sensor width mm).");
            ui.add_enabled(
                given,
                egui::DragValue::new(&mut f)
                    .range(50.0..=20000.0)
                    .suffix(" px"),
            )
            .on_hover_text(format!("Focal length in pixels; default {default_f:.0} px"));
            settings.focal_px = given.then_some(f);
            ui.add(egui::Slider::new(&mut settings.height_m, 1.0..=2.3).text("subject height (m)"))
                .on_hover_text("The subject's stature (default 1.70 m): every length is read from the video and this fixes their overall scale, so the 3D skeleton's size and depth follow it. Lengths you know (below) set the scale instead.");
            if let Some(fit) = &self.subject_fit {
                ui.label(egui::RichText::new(fit.to_string()).small().weak());
            }
            let read = |name: &str| {
                self.subject_fit
                    .as_ref()
                    .and_then(|f| f.parts.iter().find(|p| p.name == name))
                    .map(|p| p.metres)
            };
            ui.collapsing("Lengths you know", |ui| {
                ui.label(egui::RichText::new("Measured on the person (joint centre to joint centre), each kept as given and setting the scale of the rest instead of the height.").small().weak());
                egui::Grid::new("known lengths").num_columns(2).show(ui, |ui| {
                    for (name, value) in settings.lengths.fields_mut() {
                        let mut known = value.is_some();
                        ui.checkbox(&mut known, name);
                        // Ticked, a part starts at what the last lift read.
                        let mut v = value.or_else(|| read(name)).unwrap_or(0.3);
                        if known {
                            ui.add(egui::DragValue::new(&mut v).range(0.05..=1.0).speed(0.005).suffix(" m"));
                        } else {
                            ui.label(egui::RichText::new(read(name).map_or_else(|| "not read yet".to_owned(), |m| format!("read {m:.3} m"))).weak());
                        }
                        *value = known.then_some(v);
                        ui.end_row();
                    }
                });
            });
            ui.collapsing("Tracker", |ui| {
                let t = &mut settings.tracker;
                let d = TrackerParams::default();
                ui.add(egui::Slider::new(&mut t.weak_reliability, 0.0..=1.0).text("weak below"))
                    .on_hover_text(format!("Reliability under which a joint counts as weak (orange) and may be interpolated; default {}", d.weak_reliability));
                ui.add(egui::Slider::new(&mut t.max_gap_s, 0.0..=2.0).text("interpolate up to (s)"))
                    .on_hover_text(format!("Longest weak run filled by interpolation between reliable frames; default {} s", d.max_gap_s));
                ui.add(egui::Slider::new(&mut t.smooth_s, 0.0..=0.1).fixed_decimals(3).text("smooth tracks (s)"))
                    .on_hover_text(format!("The finished tracks are smoothed over time by a window this wide (standard deviation), each frame counting as much as it is reliable, so a weak frame between sound ones moves most; your own marks stay put. For 2D work: the lift smooths by the jitter it finds and gets less on smoothed tracks (0 = off); default {} s", d.smooth_s));
                ui.add(egui::Slider::new(&mut t.twin_merge_s, 0.0..=1.0).text("twins merged after (s)"))
                    .on_hover_text(format!("Left and right elbows, wrists, knees or ankles tracked onto one spot this long: the one that followed the other is made weak (0 = off); default {} s", d.twin_merge_s));
                ui.add(egui::Slider::new(&mut t.twin_guard_torso, 0.0..=0.5).text("legs second look (torso)"))
                    .on_hover_text(format!("Legs whose knees or ankles are tracked this close (fraction of the torso) are each searched again away from the other, and one moves where it matches as well (0 = off); default {}", d.twin_guard_torso));
                ui.add(egui::Slider::new(&mut t.working_stature_px, 100.0..=800.0).text("working size (px)"))
                    .on_hover_text(format!("Frames are shrunk so the person is about this tall while tracking (faster, smoother); default {} px", d.working_stature_px));
                ui.add(egui::Slider::new(&mut t.limb_range_deg, 5.0..=90.0).text("limb search (°)"))
                    .on_hover_text(format!("How far a limb may turn between frames in the search; default {}°", d.limb_range_deg));
                ui.add(egui::Slider::new(&mut t.short_penalty, 0.0..=20.0).text("keep limbs long"))
                    .on_hover_text(format!("How strongly a limb is pulled back to its full length when it looks shorter (legs crossing); lower it for limbs pointing at the camera, such as a seated person's thighs seen from the front; default {}", d.short_penalty));
                ui.add(egui::Slider::new(&mut t.upper_arm_short_penalty, 0.0..=60.0).text("keep upper arms long"))
                    .on_hover_text(format!("The same pull for the upper arms, stronger: a bare or plain-sleeved upper arm looks alike along its length and otherwise shrinks towards the shoulder; lower it for an arm pointing at the camera; default {}", d.upper_arm_short_penalty));
                ui.add(egui::Slider::new(&mut t.forearm_short_penalty, 0.0..=40.0).text("keep forearms long"))
                    .on_hover_text(format!("The same pull for the forearms: raise it (12) when a forearm crossing the body, or a sleeve of its colour, shrinks towards the elbow and the wrist falls short; check the 3D view after; default {}", d.forearm_short_penalty));
                ui.checkbox(&mut t.hip_patch, "hold the hips when the back bends")
                    .on_hover_text(format!("A patch around the hips holds the pelvis when the spine bends (a bow, a reach), and the trunk is re-hung from the neck to it; default {}", if d.hip_patch { "on" } else { "off" }));
                ui.checkbox(&mut t.chain_refine, "refine each limb as one chain")
                    .on_hover_text(format!("After each limb's two segments are found, the elbow or knee and the wrist or ankle are nudged together so both segments fit; default {}", if d.chain_refine { "on" } else { "off" }));
                // The spring is part of the chain refinement: greyed out without it.
                ui.add_enabled(t.chain_refine, egui::Slider::new(&mut t.shoulder_spring, 0.0..=0.5).text("shoulder spring"))
                    .on_hover_text(format!("Cost per square pixel that a shoulder pays for leaving the place the rigid trunk gives it, so it can rise with a raised arm (part of the chain refinement); higher holds it closer; 0 holds it on the trunk; default {}", d.shoulder_spring));
                ui.checkbox(&mut t.arm_rescue, "look again for lost arms")
                    .on_hover_text(format!("When a forearm is lost, the whole arm is looked for again as one piece, so a sleeve the colour of the shirt no longer holds the arm on the body; default {}", if d.arm_rescue { "on" } else { "off" }));
                ui.add(egui::Slider::new(&mut t.arm_foreground, 0.0..=1.0).text("arms stand out from the background"))
                    .on_hover_text(format!("With a camera that stands still, the background is the median of 25 frames, and an arm's blocks must stand out from it where they did on the marked frame, so a forearm no longer settles on a wall of its colour; ignored when the camera moves (0 = off); default {}", d.arm_foreground));
                ui.add(egui::Slider::new(&mut t.head_min_share, 0.0..=1.0).text("shortest head"))
                    .on_hover_text(format!("The head's length may not fall below this share of its marked length (less when the whole body has shrunk), so a head turning away keeps the neck in its place (0 = no floor); default {}", d.head_min_share));
                ui.checkbox(&mut t.gait_completion, "complete hidden limbs from the gait")
                    .on_hover_text(format!("In a walk or run seen from the side, the far arm's and leg's joints that are weak, or far from where the near limb was half a stride earlier and later, are put there (pink) for you to check; default {}", if d.gait_completion { "on" } else { "off" }));
                if ui.button("Defaults").clicked() {
                    *t = d;
                }
            });
            ui.collapsing("Lift", |ui| {
                super::lift_settings::lift_settings_ui(ui, &mut settings.lift)
            });
            let dragging = ui.ctx().dragged_id().is_some();
            if settings != before {
                self.edit_settings(settings, dragging);
            } else if !dragging {
                self.settings_drag_recorded = false;
            }
        }
        ui.separator();
        ui.heading("Weak spans");
        egui::ScrollArea::vertical()
            .max_height(220.0)
            .show(ui, |ui| {
                if self.spans.is_empty() {
                    ui.label("none");
                }
                let mut jump = None;
                for s in &self.spans {
                    let text = format!(
                        "{} {}–{} ({}, {:.2})",
                        s.joint, s.start, s.end, s.kind, s.min_reliability
                    );
                    if ui.link(text).clicked() {
                        jump = Some(s.start);
                    }
                }
                if let Some(f) = jump {
                    self.go_to(f);
                }
            });
    }

    /// The right end of the status bar: the seek proxy's progress, and whether the frame shown
    /// is its preview.
    fn seek_status(&self, ui: &mut egui::Ui) {
        let Some(loader) = &self.loader else {
            return;
        };
        let gap = loader.info().map_or(0, |i| i.keyframe_interval);
        match loader.proxy() {
            Some(ProxyStatus::Building(done, total)) => {
                let f = *done as f32 / (*total).max(1) as f32;
                let paused = if self.running.is_some() {
                    " (paused while tracking)"
                } else {
                    ""
                };
                ui.add(
                    egui::ProgressBar::new(f)
                        .desired_width(140.0)
                        .text(format!("fast seeking {:.0} %{paused}", f * 100.0)),
                )
                .on_hover_text(format!(
                    "Keyframes in this video are up to {gap} frames apart, so a seek decodes up \
                     to {gap} frames. A small copy with a keyframe every {} frames is being made \
                     once (kept in the cache folder) to show any frame at once; the full frame \
                     follows. Tracking always reads the video itself.",
                    videomocap::video::proxy::PROXY_GOP
                ));
            }
            Some(ProxyStatus::Ready) => {
                let text = if self.preview {
                    "preview (full frame decoding)"
                } else {
                    "fast seeking"
                };
                ui.weak(text).on_hover_text(format!(
                    "Keyframes in this video are up to {gap} frames apart: a seek first shows \
                     the frame from a small copy, then the full frame."
                ));
            }
            _ => {}
        }
    }

    fn progress_panel(&mut self, ui: &mut egui::Ui) {
        let Some(r) = &self.running else { return };
        let (share, per_s, left) = r.job.rate();
        let mut cancel = false;
        ui.horizontal(|ui| {
            ui.label(format!("{} ({})", r.job.what, r.job.stage));
            let text = match left {
                Some(s) => format!(
                    "{}/{} · {per_s:.1}/s · {s:.0} s left",
                    r.job.done, r.job.total
                ),
                None => format!("{}/{}", r.job.done, r.job.total),
            };
            ui.add(
                egui::ProgressBar::new(share)
                    .desired_width((ui.available_width() - 90.0).max(100.0))
                    .text(text),
            );
            cancel = ui.button("Cancel").clicked();
        });
        if cancel {
            self.cancel_job();
        }
    }

    fn scene(&self) -> Scene {
        if let Some(v) = &self.volume {
            return v.scene(self.current);
        }
        let Some(world) = &self.world else {
            return Scene {
                joints: None,
                camera: None,
                flippable: Vec::new(),
                cloud: Vec::new(),
                segments: Vec::new(),
            };
        };
        let joints = world
            .indices
            .binary_search(&self.current)
            .ok()
            .map(|k| world.frames[k]);
        let camera = self
            .project
            .as_ref()
            .and_then(|p| p.skeleton.as_ref())
            .map(|s| {
                let cam = &s.camera;
                let corner = |x: f64, y: f64| {
                    let depth = 0.5;
                    world.world.to_world(&Point3::new(
                        (x - cam.cx) / cam.focal_px * depth,
                        (y - cam.cy) / cam.focal_px * depth,
                        depth,
                    ))
                };
                let (w, h) = (f64::from(cam.width), f64::from(cam.height));
                (
                    world.world.to_world(&Point3::origin()),
                    [
                        corner(0.0, 0.0),
                        corner(w, 0.0),
                        corner(w, h),
                        corner(0.0, h),
                    ],
                )
            });
        let key = videomocap::lift::calibrate::KEY_JOINTS;
        Scene {
            joints,
            camera,
            flippable: Bone::ALL
                .into_iter()
                .filter(|b| !(key.contains(&b.parent) && key.contains(&b.child)))
                .collect(),
            cloud: Vec::new(),
            segments: Vec::new(),
        }
    }

    fn dialogs(&mut self, ctx: &egui::Context) {
        if self.recovery.is_some() {
            let mut answer = None;
            egui::Window::new("Recover unsaved work?")
                .collapsible(false)
                .resizable(false)
                .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
                .show(ctx, |ui| {
                    ui.label("videomocap did not close cleanly last time. Recover the autosaved session?");
                    ui.horizontal(|ui| {
                        if ui.button("Recover").clicked() {
                            answer = Some(true);
                        }
                        if ui.button("Discard").clicked() {
                            answer = Some(false);
                        }
                    });
                });
            if let Some(a) = answer {
                self.answer_recovery(ctx, a);
            }
        }
        if self.pending_open.is_some() {
            let mut answer = None;
            egui::Window::new("Save changes?")
                .collapsible(false)
                .resizable(false)
                .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
                .show(ctx, |ui| {
                    ui.label(
                        "The current project has changes that are not saved to a project file.",
                    );
                    ui.horizontal(|ui| {
                        if ui.button("Save").clicked() {
                            answer = Some(SaveAnswer::Save);
                        }
                        if ui.button("Don't save").clicked() {
                            answer = Some(SaveAnswer::Discard);
                        }
                        if ui.button("Cancel").clicked() {
                            answer = Some(SaveAnswer::Cancel);
                        }
                    });
                });
            if let Some(a) = answer {
                self.answer_save(ctx, a);
            }
        }
        if self.show_help {
            egui::Window::new("Shortcuts")
                .open(&mut self.show_help)
                .show(ctx, |ui| {
                    egui::Grid::new("keys").show(ui, |ui| {
                        for (k, what) in SHORTCUTS {
                            ui.label(egui::RichText::new(*k).strong());
                            ui.label(*what);
                            ui.end_row();
                        }
                    });
                });
        }
    }
}

/// The answers to "save changes?".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SaveAnswer {
    Save,
    Discard,
    Cancel,
}

const SHORTCUTS: &[(&str, &str)] = &[
    ("Left / Right", "previous / next frame"),
    ("Shift + Left / Right", "ten frames back / forward"),
    ("Home / End", "first / last frame"),
    ("Space", "play / pause (hold and drag: pan)"),
    ("Wheel", "zoom at the cursor (frame and 3D view)"),
    ("Middle drag", "pan"),
    ("M", "mark the 16 joints on this frame"),
    ("Esc", "stop marking, close this window"),
    ("Drag a joint", "correct it: key frame, re-track from here"),
    ("T", "track and lift"),
    ("Ctrl+Z / Ctrl+Shift+Z", "undo / redo"),
    ("Ctrl+S", "save the project"),
    ("Click a limb (3D)", "flip its depth on this frame"),
    ("F1", "this help"),
];

/// Joints below `joint` on its limb (the bone tree's descendants).
/// Whether `path` is a folder of point clouds (and no images): volume mode.
fn is_volume_dir(path: &Path) -> bool {
    path.is_dir()
        && videomocap::volume::list_frames(path).is_ok()
        && !std::fs::read_dir(path).is_ok_and(|entries| {
            entries.filter_map(Result::ok).any(|e| {
                let name = e.file_name().to_string_lossy().to_ascii_lowercase();
                name.ends_with(".png") || name.ends_with(".jpg") || name.ends_with(".jpeg")
            })
        })
}

fn descendants(joint: Joint) -> Vec<Joint> {
    let mut out = Vec::new();
    let mut frontier = vec![joint];
    while let Some(j) = frontier.pop() {
        for b in Bone::ALL {
            if b.parent == j {
                out.push(b.child);
                frontier.push(b.child);
            }
        }
    }
    out
}

/// A small front view of the body with `asking` highlighted.
fn body_diagram(ui: &mut egui::Ui, asking: Joint) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(120.0, 170.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    // Front view: the subject's left on the image's right.
    let at = |j: Joint| -> egui::Pos2 {
        let (x, y) = match j {
            Joint::HeadTop => (0.0, 0.0),
            Joint::Neck => (0.0, 0.16),
            Joint::Chest => (0.0, 0.27),
            Joint::Pelvis => (0.0, 0.48),
            Joint::LeftShoulder => (0.2, 0.19),
            Joint::LeftElbow => (0.26, 0.35),
            Joint::LeftWrist => (0.3, 0.5),
            Joint::RightShoulder => (-0.2, 0.19),
            Joint::RightElbow => (-0.26, 0.35),
            Joint::RightWrist => (-0.3, 0.5),
            Joint::LeftHip => (0.1, 0.48),
            Joint::LeftKnee => (0.11, 0.72),
            Joint::LeftAnkle => (0.12, 0.95),
            Joint::RightHip => (-0.1, 0.48),
            Joint::RightKnee => (-0.11, 0.72),
            Joint::RightAnkle => (-0.12, 0.95),
        };
        egui::pos2(rect.center().x + x * 160.0, rect.top() + 5.0 + y * 160.0)
    };
    for b in Bone::ALL {
        painter.line_segment(
            [at(b.parent), at(b.child)],
            egui::Stroke::new(2.0, egui::Color32::GRAY),
        );
    }
    for j in Joint::ALL {
        let (r, c) = if j == asking {
            (6.0, egui::Color32::YELLOW)
        } else {
            (3.0, egui::Color32::LIGHT_GRAY)
        };
        painter.circle_filled(at(j), r, c);
    }
}

impl eframe::App for App {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        // Files dropped on the window open like File ▸ Open.
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_owned())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        if let Some(p) = dropped.first() {
            self.open_path(&ctx, p);
        }
        self.receive(&ctx);
        if let Some(l) = &self.loader {
            l.pause_background(self.running.is_some());
        }
        self.handle_keys(&ctx);
        self.play(&ctx);
        egui::Panel::top("menu").show(ui, |ui| self.menu(ui, &ctx));
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.label(&self.status);
                ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                    self.seek_status(ui);
                });
            });
        });
        if self.running.is_some() {
            egui::Panel::bottom("progress").show(ui, |ui| self.progress_panel(ui));
        }
        let n = self.frame_count();
        if n > 0 {
            let fps = self.video_info().map_or(30.0, |i| i.fps);
            let mut jump = None;
            egui::Panel::bottom("timeline").show(ui, |ui| {
                ui.horizontal(|ui| {
                    let label = if self.playing { "Pause" } else { "Play" };
                    if ui
                        .button(label)
                        .on_hover_text("play / pause (Space)")
                        .clicked()
                    {
                        self.playing = !self.playing;
                    }
                    ui.vertical(|ui| {
                        let no_keys = videomocap::track::KeyFrames::default();
                        let keys = self.project.as_ref().map_or(&no_keys, |p| &p.keys);
                        jump = timeline::show(ui, self.current, n, fps, self.strips.as_ref(), keys);
                    });
                });
            });
            if let Some(f) = jump {
                self.go_to(f);
            }
        }
        egui::Panel::left("side")
            .resizable(true)
            .default_size(240.0)
            .show(ui, |ui| self.side_panel(ui));
        let scene = self.scene();
        if self.volume.is_some() {
            // Volume mode: the 3D viewport fills the window.
            egui::CentralPanel::default().show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.label("3D (point volumes)");
                    if ui.button("Reset view").clicked() {
                        self.orbit = Orbit::default();
                    }
                });
                self.orbit.show(ui, &scene);
            });
            self.dialogs(&ctx);
            return;
        }
        let mut flip = None;
        egui::Panel::right("3d")
            .resizable(true)
            .default_size(380.0)
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.label("3D");
                    if ui.button("Reset view").clicked() {
                        self.orbit = Orbit::default();
                    }
                    ui.checkbox(&mut self.orbit.follow, "Follow")
                        .on_hover_text("Keep the view on the subject as they move across the floor (panning turns it off)");
                });
                flip = self.orbit.show(ui, &scene);
            });
        if let Some(b) = flip {
            self.flip(b);
        }
        let overlay = Overlay {
            points: self.points(self.current),
            asking: self.asking(),
        };
        let mut event = None;
        let image_size = self
            .video_info()
            .map(|i| egui::vec2(i.width as f32, i.height as f32));
        egui::CentralPanel::default().show(ui, |ui| match &self.texture {
            Some(texture) => {
                let size = image_size.unwrap_or_else(|| texture.size_vec2());
                event = self.view.show(ui, texture, size, &overlay);
            }
            None => {
                ui.centered_and_justified(|ui| ui.label(&self.status));
            }
        });
        match event {
            Some(ViewEvent::Click(p)) => self.click(p),
            Some(ViewEvent::Moved(j, p)) => self.moved(j, p),
            None => {}
        }
        self.dialogs(&ctx);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gui::dialogs::PreparedDialogs;
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable;

    fn wait(h: &mut Harness<'_, App>, what: &str, done: impl Fn(&App) -> bool) {
        for _ in 0..6000 {
            h.step();
            if done(h.state()) {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        panic!(
            "timed out waiting for {what}; status: {}",
            h.state().status()
        );
    }

    fn click(h: &mut Harness<'_, App>, pos: egui::Pos2) {
        h.hover_at(pos);
        h.step();
        h.drag_at(pos);
        h.step();
        h.drop_at(pos);
        h.step();
        h.step();
    }

    fn drag(h: &mut Harness<'_, App>, from: egui::Pos2, to: egui::Pos2) {
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

    fn screen(h: &Harness<'_, App>, p: Point2<f64>) -> egui::Pos2 {
        h.state()
            .frame_view()
            .transform()
            .expect("frame drawn")
            .to_screen(p)
    }

    fn harness(
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

    /// A video with far-apart keyframes gets a seek proxy in the cache folder, the status bar
    /// says so, and seeks end on the full frame (the preview only stands in meanwhile).
    #[test]
    fn a_long_gop_video_gets_fast_seeking_and_seeks_end_on_the_full_frame() {
        let dir = tempfile::tempdir().unwrap();
        let clip = dir.path().join("long.mp4");
        super::super::frame_loader::tests::long_gop_clip(&clip, 120);
        let dialogs = PreparedDialogs::default();
        let state = dir.path().join("state");
        let mut h = harness(Some(clip), &dialogs, &state);
        wait(&mut h, "the proxy", |a| {
            a.loader.as_ref().and_then(FrameLoader::proxy) == Some(&ProxyStatus::Ready)
        });
        h.step();
        h.get_by_label("fast seeking");
        assert_eq!(std::fs::read_dir(state.join("proxies")).unwrap().count(), 1);
        wait(&mut h, "frame 0", |a| a.shown() == Some(0) && !a.preview);
        let fitted = h.state().frame_view().transform().expect("frame drawn");
        h.key_press(egui::Key::End);
        wait(&mut h, "the last frame, full size", |a| {
            a.shown() == Some(119) && !a.preview
        });
        let texture = h.state().texture.as_ref().map(|t| t.size());
        assert_eq!(texture, Some([320, 240]));
        // The picture stays where it was: previews are drawn over the frame's own size.
        let after = h.state().frame_view().transform().expect("frame drawn");
        assert_eq!(
            fitted.to_screen(Point2::new(10.0, 10.0)),
            after.to_screen(Point2::new(10.0, 10.0))
        );
    }

    #[test]
    fn arrow_keys_step_through_frames_and_stop_at_the_ends() {
        let dir = tempfile::tempdir().unwrap();
        for i in 0..12 {
            image::RgbImage::from_pixel(8, 6, image::Rgb([i * 20, 0, 0]))
                .save(dir.path().join(format!("f{i}.png")))
                .unwrap();
        }
        let dialogs = PreparedDialogs::default();
        let mut h = harness(
            Some(dir.path().to_owned()),
            &dialogs,
            &dir.path().join("state"),
        );
        wait(&mut h, "the folder to open", |a| a.frame_count() == 12);
        h.key_press(egui::Key::ArrowRight);
        h.step();
        assert_eq!(h.state().current_frame(), 1);
        h.key_press_modifiers(egui::Modifiers::SHIFT, egui::Key::ArrowRight);
        h.step();
        assert_eq!(h.state().current_frame(), 11);
        h.key_press(egui::Key::Home);
        h.step();
        assert_eq!(h.state().current_frame(), 0);
    }

    /// Volume mode: File ▸ Open point volumes processes a folder of PLY frames off the UI
    /// thread, then the 3D viewport shows the frame's points, skeleton curve, bodies and
    /// skeleton; arrow keys step through the frames.
    #[test]
    fn volume_mode_opens_a_point_volume_folder_and_steps_through_it() {
        let dir = tempfile::tempdir().unwrap();
        let vols = dir.path().join("vols");
        let motion = videomocap::synth::procedural(
            videomocap::synth::ProceduralMotion::March,
            &videomocap::skeleton::SubjectModel::default(),
            6,
            10.0,
        );
        videomocap::synth::write_volume_sequence(
            &motion,
            &vols,
            &videomocap::synth::VoxelParams::default(),
            |_, _| {},
        )
        .unwrap();
        let dialogs = PreparedDialogs::default();
        dialogs.answers.borrow_mut().push_back(vols.clone());
        let mut h = harness(None, &dialogs, &dir.path().join("state"));
        h.step();
        h.get_by_label("File").click();
        h.run_steps(3);
        h.get_by_label("Open point volumes…").click();
        h.run_steps(3);
        assert!(h.state().volume().is_some(), "{}", h.state().status());
        wait(&mut h, "the volumes to be processed", |a| {
            a.frame_count() == 6
        });
        assert!(!h.state().busy());
        assert!(
            h.state().status().contains("6 with a five-limb"),
            "{}",
            h.state().status()
        );
        let scene = h.state().current_scene();
        assert!(scene.joints.is_some());
        assert!(scene.cloud.len() > 500, "{} points", scene.cloud.len());
        assert!(scene.segments.len() > 50, "curve and bodies drawn");
        h.key_press(egui::Key::ArrowRight);
        h.step();
        assert_eq!(h.state().current_frame(), 1);
        // Hiding the points leaves the curve and the skeleton.
        h.get_by_label("points (coloured by body)").click();
        h.step();
        let scene = h.state().current_scene();
        assert!(scene.cloud.is_empty() && scene.joints.is_some());
    }

    /// The whole session a user has: open a clip, mark 16 joints by clicking, drag one, undo,
    /// track and lift, scrub, orbit the 3D view, export a BVH, and after the app dies, recover
    /// the work from the autosave.
    #[test]
    fn mark_drag_undo_track_scrub_orbit_export_and_recover() {
        let dir = tempfile::tempdir().unwrap();
        let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_videos/synth_walk_oblique");
        let video = dir.path().join("clip.mp4");
        std::fs::copy(sample.join("video.mp4"), &video).unwrap();
        let truth = Marks::load(&sample.join("marks.json")).unwrap();
        let state = dir.path().join("state");
        let dialogs = PreparedDialogs::default();
        let mut h = harness(Some(video.clone()), &dialogs, &state);
        wait(&mut h, "the clip to open", |a| {
            a.frame_count() == 60 && a.shown() == Some(0)
        });
        assert!(
            h.state().project().unwrap().keys.frames.is_empty(),
            "no marks beside the copy"
        );

        // Mark: the guide asks for each joint in turn; click where it is.
        h.key_press(egui::Key::M);
        h.step();
        for j in Joint::ALL {
            assert_eq!(h.state().asking(), Some(j));
            let pos = screen(&h, truth.points[j]);
            click(&mut h, pos);
        }
        assert_eq!(h.state().asking(), None, "the guide ends after 16 joints");
        let marks = h.state().project().unwrap().marks().expect("all 16 marked");
        for j in Joint::ALL {
            assert!((marks.points[j] - truth.points[j]).norm() < 0.5, "{j:?}");
        }

        // Drag the left wrist 30 screen points right, then undo.
        let wrist = truth.points[Joint::LeftWrist];
        let from = screen(&h, wrist);
        drag(&mut h, from, from + egui::vec2(30.0, 0.0));
        let moved = h.state().project().unwrap().keys.frames[&0][Joint::LeftWrist].unwrap();
        assert!(
            moved.x - wrist.x > 5.0,
            "dragged to {moved:?} from {wrist:?}"
        );
        h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
        h.step();
        let back = h.state().project().unwrap().keys.frames[&0][Joint::LeftWrist].unwrap();
        assert!(
            (back - marks.points[Joint::LeftWrist]).norm() < 1e-9,
            "undo puts it back"
        );

        // Track (and lift) in the background.
        h.key_press(egui::Key::T);
        h.step();
        assert!(h.state().busy());
        wait(&mut h, "tracking and lifting", |a| {
            !a.busy() && a.project().is_some_and(|p| p.skeleton.is_some())
        });
        assert_eq!(
            h.state()
                .project()
                .unwrap()
                .tracks
                .as_ref()
                .unwrap()
                .frames
                .len(),
            60
        );
        // The Parameters panel says what lengths the lift used and where each came from.
        h.step();
        assert!(
            h.query_by_label_contains("body lengths: trunk").is_some()
                || h.query_by_label_contains("body: the proportions table")
                    .is_some(),
            "no lengths line under the height"
        );

        // Scrub.
        for _ in 0..3 {
            h.key_press(egui::Key::ArrowRight);
            h.step();
        }
        assert_eq!(h.state().current_frame(), 3);
        wait(&mut h, "frame 3", |a| a.shown() == Some(3));

        // Correct a joint on frame 3 by dragging it: frame 3 becomes a key frame for it and
        // tracking re-runs from there, keeping the correction.
        let wrist = h.state().points(3)[Joint::LeftWrist].unwrap().0;
        let before = h.state().project().unwrap().tracks.as_ref().unwrap().frames[3].points;
        let moved_to = wrist + nalgebra::Vector2::new(6.0, -4.0);
        let (from, to) = (screen(&h, wrist), screen(&h, moved_to));
        drag(&mut h, from, to);
        assert!(h.state().busy(), "re-tracking: {}", h.state().status());
        wait(&mut h, "re-tracking and lifting", |a| {
            !a.busy() && a.project().is_some_and(|p| p.skeleton.is_some())
        });
        let p = h.state().project().unwrap();
        let key = p.keys.frames[&3][Joint::LeftWrist].unwrap();
        assert!((key - moved_to).norm() < 1.5, "key {key} vs {moved_to}");
        let tracked = &p.tracks.as_ref().unwrap().frames[3].points[Joint::LeftWrist];
        assert!((tracked.pos - key).norm() < 1e-9, "the track keeps the key");
        // The joints not dragged stay where they were on frame 3 (the re-track starts from
        // what the user saw there, not from the marks of frame 0).
        let after = &p.tracks.as_ref().unwrap().frames[3].points;
        let marked = p.marks().unwrap().points;
        let mut kept = 0;
        for j in Joint::ALL.into_iter().filter(|&j| j != Joint::LeftWrist) {
            if before[j].confidence >= p.settings.tracker.weak_reliability {
                assert!((after[j].pos - before[j].pos).norm() < 1e-6, "{}", j.name());
                kept += usize::from((before[j].pos - marked[j]).norm() > 1.0);
            }
        }
        assert!(
            kept >= 3,
            "too few joints moved since frame 0 to tell ({kept})"
        );

        // Flip a limb's depth on this frame: an override is recorded and the lift re-runs;
        // after undoing it, the earlier result's choices are still known and it flips again.
        let flips_before = h.state().project().unwrap().overrides.len();
        h.state_mut().flip(Bone::ALL[4]);
        assert_eq!(
            h.state().project().unwrap().overrides.len(),
            flips_before + 1
        );
        wait(&mut h, "the lift after a flip", |a| !a.busy());
        h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
        h.step();
        assert_eq!(h.state().project().unwrap().overrides.len(), flips_before);
        h.state_mut().flip(Bone::ALL[7]);
        assert!(
            !h.state().status().contains("not known"),
            "{}",
            h.state().status()
        );
        wait(&mut h, "the lift after the second flip", |a| !a.busy());

        // Orbit the 3D view by dragging in it (the right-hand panel).
        let before = h.state().orbit();
        drag(&mut h, egui::pos2(1200.0, 400.0), egui::pos2(1260.0, 420.0));
        assert!(
            (h.state().orbit().yaw - before.yaw).abs() > 0.1,
            "the view turned"
        );

        // Export a BVH through the menu (the dialog answers with a path).
        let bvh = dir.path().join("out.bvh");
        dialogs.answers.borrow_mut().push_back(bvh.clone());
        h.get_by_label("Export").click();
        h.run_steps(3);
        h.get_by_label(ExportKind::Bvh.label()).click();
        h.run_steps(3);
        assert!(
            h.state().status().contains("Wrote"),
            "{}",
            h.state().status()
        );
        let read = videomocap::bvh::Bvh::load(&bvh).unwrap();
        assert_eq!(read.frame_count(), 60);

        // The app dies without saving: the autosave holds the work, and the next start offers it.
        h.state_mut().flush_autosave();
        let autosave = h.state().autosave_path().unwrap();
        assert!(autosave.is_file());
        let expected = h.state().project().unwrap().clone();
        drop(h);
        let mut h = harness(None, &dialogs, &state);
        h.step();
        assert!(h.state().offers_recovery());
        h.get_by_label("Recover").click();
        h.run_steps(2);
        wait(&mut h, "the recovered clip", |a| a.frame_count() == 60);
        let p = h.state().project().unwrap();
        assert_eq!(p.keys, expected.keys);
        assert_eq!(p.tracks, expected.tracks);
        assert!(p.skeleton.is_some());
        // Recent files survive the restart.
        assert_eq!(h.state().recent().first(), Some(&video));

        // The recovered work is not in a project file: opening another video asks first.
        let other = dir.path().join("other");
        std::fs::create_dir(&other).unwrap();
        image::RgbImage::new(8, 6)
            .save(other.join("f0.png"))
            .unwrap();
        let ctx = h.ctx.clone();
        h.state_mut().open_path(&ctx, &other);
        h.run_steps(3);
        assert!(h.state().asks_to_save());
        h.get_by_label("Cancel").click();
        h.run_steps(2);
        assert!(!h.state().asks_to_save());
        assert_eq!(
            h.state().project().unwrap().video,
            video,
            "cancel keeps the work"
        );
        let saved = dir.path().join("saved.videomocap.json");
        dialogs.answers.borrow_mut().push_back(saved.clone());
        h.state_mut().open_path(&ctx, &other);
        h.run_steps(3);
        h.get_by_label("Save").click();
        h.run_steps(2);
        assert!(
            saved.is_file(),
            "saved before opening: {}",
            h.state().status()
        );
        assert_eq!(Project::load(&saved).unwrap().keys, expected.keys);
        wait(&mut h, "the other folder", |a| a.frame_count() == 1);
    }

    /// The app on a fresh project (no video) in `dir`, one frame drawn.
    fn with_project(dir: &Path) -> Harness<'static, App> {
        let mut h = harness(None, &PreparedDialogs::default(), &dir.join("state"));
        h.state_mut().project = Some(Project::new(dir.join("v.mp4")));
        h.run();
        h
    }

    /// The app on a fresh project in `dir` with the Parameters panel's Tracker section open.
    fn with_tracker_panel(dir: &Path) -> Harness<'static, App> {
        let mut h = with_project(dir);
        h.get_by_label("Tracker").click();
        h.run();
        h
    }

    /// The pull of short limbs back to full length, and the upper arms' and the forearms' own,
    /// are each set from the Parameters panel on its own (the others stay), and each is an
    /// undoable project setting.
    #[test]
    fn the_short_limb_pulls_are_set_in_the_tracker_settings() {
        type Get = fn(&TrackerParams) -> f32;
        let pulls: [(&str, Get); 3] = [
            ("keep limbs long", |t| t.short_penalty),
            ("keep upper arms long", |t| t.upper_arm_short_penalty),
            ("keep forearms long", |t| t.forearm_short_penalty),
        ];
        let dir = tempfile::tempdir().unwrap();
        let mut h = with_tracker_panel(dir.path());
        let now = |h: &Harness<'static, App>| {
            let t = h.state().project().unwrap().settings.tracker;
            pulls.map(|(_, get)| get(&t))
        };
        let defaults = pulls.map(|(_, get)| get(&TrackerParams::default()));
        assert_eq!(now(&h), defaults);
        for (k, (label, _)) in pulls.iter().enumerate() {
            h.get_by_role_and_label(egui::accesskit::Role::Slider, label)
                .set_value_accesskit(2.0);
            h.run();
            let mut want = defaults;
            want[k] = 2.0;
            assert_eq!(now(&h), want, "{label} set on its own");
            h.state_mut().undo();
            assert_eq!(now(&h), defaults, "{label} undone");
        }
    }

    /// The tracks' smoothing window (off by default) is set from the Parameters panel, an
    /// undoable project setting.
    #[test]
    fn the_track_smoothing_is_an_undoable_tracker_setting() {
        let dir = tempfile::tempdir().unwrap();
        let mut h = with_tracker_panel(dir.path());
        let now =
            |h: &Harness<'static, App>| h.state().project().unwrap().settings.tracker.smooth_s;
        assert_eq!(now(&h), TrackerParams::default().smooth_s);
        h.get_by_role_and_label(egui::accesskit::Role::Slider, "smooth tracks (s)")
            .set_value_accesskit(0.02);
        h.run();
        assert_eq!(now(&h), 0.02);
        h.state_mut().undo();
        assert_eq!(now(&h), TrackerParams::default().smooth_s);
    }

    /// The arms' foreground weight and the head's shortest share are set from the Parameters
    /// panel, each on its own and undoable.
    #[test]
    fn the_background_and_head_floor_are_undoable_tracker_settings() {
        let dir = tempfile::tempdir().unwrap();
        let mut h = with_tracker_panel(dir.path());
        let now = |h: &Harness<'static, App>| {
            let t = h.state().project().unwrap().settings.tracker;
            (t.arm_foreground, t.head_min_share)
        };
        let d = TrackerParams::default();
        assert_eq!(now(&h), (d.arm_foreground, d.head_min_share));
        h.get_by_role_and_label(
            egui::accesskit::Role::Slider,
            "arms stand out from the background",
        )
        .set_value_accesskit(0.0);
        h.run();
        assert_eq!(now(&h), (0.0, d.head_min_share), "the weight on its own");
        h.get_by_role_and_label(egui::accesskit::Role::Slider, "shortest head")
            .set_value_accesskit(0.5);
        h.run();
        assert_eq!(now(&h), (0.0, 0.5));
        h.state_mut().undo();
        h.state_mut().undo();
        assert_eq!(now(&h), (d.arm_foreground, d.head_min_share), "both undone");
    }

    /// The tracker's switches (gait completion, the hip patch, the arms' second look) can each
    /// be turned off from the Parameters panel, and each is an undoable project setting.
    #[test]
    fn each_tracker_switch_is_an_undoable_setting() {
        type Get = fn(&TrackerParams) -> bool;
        let switches: [(&str, Get); 3] = [
            ("complete hidden limbs from the gait", |t| t.gait_completion),
            ("hold the hips when the back bends", |t| t.hip_patch),
            ("look again for lost arms", |t| t.arm_rescue),
        ];
        for (label, get) in switches {
            let dir = tempfile::tempdir().unwrap();
            let mut h = with_tracker_panel(dir.path());
            let on =
                |h: &Harness<'static, App>| get(&h.state().project().unwrap().settings.tracker);
            assert!(on(&h), "{label} starts on");
            h.get_by_label(label).click();
            h.run();
            assert!(!on(&h), "{label} turned off");
            h.state_mut().undo();
            assert!(on(&h), "{label} back on after undo");
        }
    }

    /// The lift's global refinement can be turned off from the Parameters panel: an undoable
    /// project setting, which the next lift uses.
    #[test]
    fn the_global_refinement_is_switched_in_the_lift_settings() {
        let dir = tempfile::tempdir().unwrap();
        let mut h = with_project(dir.path());
        let refine = |h: &Harness<'_, App>| h.state().project().unwrap().settings.lift.refine;
        assert!(refine(&h));
        h.get_by_label("Lift").click();
        h.run();
        h.get_by_label("global refinement").click();
        h.run();
        assert!(!refine(&h));
        h.state_mut().undo();
        assert!(refine(&h));
    }

    /// A fixed smoothing width replaces the adaptive smoothing: its checkbox is greyed out
    /// while one is set.
    #[test]
    fn the_adaptive_smoothing_is_greyed_out_under_a_fixed_width() {
        use egui_kittest::kittest::NodeT;
        let dir = tempfile::tempdir().unwrap();
        let mut h = with_project(dir.path());
        h.get_by_label("Lift").click();
        h.run();
        let disabled = |h: &Harness<'_, App>| {
            h.get_by_label("smooth each joint by its own noise")
                .accesskit_node()
                .is_disabled()
        };
        assert!(!disabled(&h));
        if let Some(p) = &mut h.state_mut().project {
            p.settings.lift.smoothing_s = 0.1;
        }
        h.run();
        assert!(disabled(&h));
    }

    /// The shoulder spring is part of the chain refinement: its slider is greyed out while the
    /// chain refinement is off.
    #[test]
    fn the_shoulder_spring_is_greyed_out_without_the_chain_refinement() {
        use egui_kittest::kittest::NodeT;
        let dir = tempfile::tempdir().unwrap();
        let mut h = with_tracker_panel(dir.path());
        let disabled = |h: &Harness<'_, App>| {
            h.get_by_role_and_label(egui::accesskit::Role::Slider, "shoulder spring")
                .accesskit_node()
                .is_disabled()
        };
        assert!(!disabled(&h));
        h.get_by_label("refine each limb as one chain").click();
        h.run();
        assert!(!h.state().project().unwrap().settings.tracker.chain_refine);
        assert!(disabled(&h));
    }

    /// A length ticked as known in the Parameters panel goes into the project's settings (and
    /// from there to the lift), and unticked leaves it again.
    #[test]
    fn a_known_length_is_ticked_into_the_project() {
        let dir = tempfile::tempdir().unwrap();
        let mut h = with_project(dir.path());
        h.get_by_label("Lengths you know").click();
        h.run();
        assert_eq!(h.state().project().unwrap().settings.lengths.thigh, None);
        h.get_by_label("thigh").click();
        h.run();
        let thigh = h.state().project().unwrap().settings.lengths.thigh;
        assert!(thigh.is_some_and(|t| t > 0.0), "{thigh:?}");
        let known = h.state().project().unwrap().settings.lengths.known();
        assert_eq!(known.bones.len(), 2);
        h.get_by_label("thigh").click();
        h.run();
        assert_eq!(h.state().project().unwrap().settings.lengths.thigh, None);
    }

    /// A slider drag changes the settings many times but is one undo step.
    #[test]
    fn a_settings_drag_is_one_undo_step() {
        let dir = tempfile::tempdir().unwrap();
        let dialogs = PreparedDialogs::default();
        let mut h = harness(None, &dialogs, &dir.path().join("state"));
        h.state_mut().project = Some(Project::new(dir.path().join("v.mp4")));
        let mut s = h.state().project().unwrap().settings;
        for k in 0..5 {
            s.height_m = 1.6 + 0.01 * f64::from(k);
            h.state_mut().edit_settings(s, true);
        }
        s.height_m = 1.9;
        h.state_mut().edit_settings(s, false);
        h.state_mut().undo();
        assert!((h.state().project().unwrap().settings.height_m - 1.64).abs() < 1e-9);
        h.state_mut().undo();
        assert!((h.state().project().unwrap().settings.height_m - 1.70).abs() < 1e-9);
    }
}
