//! The state's file actions: open (video, image folder, project, point volumes, marks),
//! recovery of an autosaved session, save, and leaving (opening something else,
//! quitting) with "save changes?" first. Every save ends with a status line naming the file
//! written or saying why not; when no file dialog can be shown, the app's own path field asks
//! instead (for exports too: `export`).

use super::export_kind::ExportKind;
use super::file_dialogs::Picked;
use super::frame_loader::FrameLoader;
use super::jobs::Job;
use super::volume::VolumeSequence;
use super::{Running, State};
use std::path::{Path, PathBuf};
use videomocap_core::formats::Marks;
use videomocap_core::project::Project;

/// What can be opened from the File menu.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Choose {
    /// A video file.
    Video,
    /// A folder of images.
    ImageFolder,
    /// A folder of point volumes.
    PointVolumes,
    /// A project file.
    Project,
    /// A marks file, loaded into the project's keys.
    Marks,
}

impl Choose {
    fn title(self) -> &'static str {
        match self {
            Choose::Video => "Open video",
            Choose::ImageFolder => "Open image folder",
            Choose::PointVolumes => "Open point volumes",
            Choose::Project => "Open project",
            Choose::Marks => "Load marks",
        }
    }
}

/// Where the user is going once "save changes?" is answered.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Leave {
    /// Opening this file or folder.
    Open(PathBuf),
    /// Quitting the app.
    Quit,
}

/// The answers to "save changes?".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SaveAnswer {
    /// Save, then go on.
    Save,
    /// Go on without saving.
    Discard,
    /// Stay.
    Cancel,
}

/// What a path typed into the app's own path field is for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum PathPurpose {
    /// Opening something.
    Open(Choose),
    /// Saving the project, then going where the user was going.
    Save(Option<Leave>),
    /// Writing an export.
    Export(ExportKind),
}

/// The app's own path field: shown when no file dialog can be.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct PathRequest {
    /// What the path is for.
    pub purpose: PathPurpose,
    /// The window's title.
    pub title: String,
    /// The path as typed (the default name and folder to start with).
    pub text: String,
    /// Why the last path given did not work.
    pub error: Option<String>,
    /// The folder the path lies in, when it does not exist (the window offers to create it).
    pub missing_folder: Option<PathBuf>,
}

/// The status line when no dialog could be shown.
pub(super) const NO_DIALOG: &str = "No file dialog could be shown on this desktop (no XDG portal, zenity or \
     kdialog): type the path in the window instead";

impl State {
    /// Opens `path`, or asks "save changes?" first; quits, likewise. A path that cannot open
    /// (missing, a broken project, a folder with nothing to open) is refused first, with the
    /// session left as it was: nothing is asked and nothing is lost.
    pub(super) fn leave(&mut self, to: Leave) {
        if let Leave::Open(path) = &to {
            match openable(path) {
                Err(problem) => {
                    self.status = format!("Cannot open {}: {problem}", path.display());
                    self.forget(&path.clone());
                    return;
                }
                // Read once: opening takes it from here.
                Ok(project) => self.checked_project = project.map(|p| (path.clone(), p)),
            }
        }
        if self.dirty() {
            self.leaving = Some(to);
        } else {
            self.go(to);
        }
    }

    fn go(&mut self, to: Leave) {
        match to {
            Leave::Open(path) => self.open_now(&path),
            Leave::Quit => {
                // A deliberate quit leaves nothing to recover.
                if let Some(a) = &mut self.autosaver {
                    a.clear();
                }
                self.quitting = true;
            }
        }
    }

    /// Answers "save changes?": save (then go on), discard (go on) or cancel (stay).
    pub(super) fn answer_save(&mut self, answer: SaveAnswer) {
        let Some(to) = self.leaving.take() else {
            return;
        };
        match answer {
            SaveAnswer::Save => self.save_project(false, Some(to)),
            SaveAnswer::Discard => {
                self.dirty = false;
                self.go(to);
            }
            SaveAnswer::Cancel => self.status = "Cancelled: nothing closed".to_owned(),
        }
    }

    /// Asks for a file or folder to open (a dialog, or the path field).
    pub(super) fn choose(&mut self, what: Choose) {
        let picked = if self.no_native_dialogs {
            Picked::Unavailable
        } else {
            match what {
                Choose::Video => self.config.dialogs.open_file(what.title(), &[]),
                Choose::Project | Choose::Marks => {
                    self.config.dialogs.open_file(what.title(), &["json"])
                }
                Choose::ImageFolder | Choose::PointVolumes => {
                    self.config.dialogs.open_folder(what.title())
                }
            }
        };
        match picked {
            Picked::Path(p) => self.chosen(what, &p),
            Picked::Cancelled => {}
            Picked::Unavailable => {
                let folder = self.default_folder();
                self.ask_path(PathPurpose::Open(what), what.title(), folder);
            }
        }
    }

    fn chosen(&mut self, what: Choose, path: &Path) {
        match what {
            Choose::Marks => self.load_marks(path),
            _ => self.leave(Leave::Open(path.to_owned())),
        }
    }

    fn load_marks(&mut self, path: &Path) {
        match Marks::load(path) {
            Ok(m) => self.edit("load marks", |p| {
                for (j, q) in m.points.iter() {
                    p.keys.set(m.frame, j, *q);
                }
            }),
            Err(e) => self.status = format!("Cannot load marks: {e}"),
        }
    }

    /// The folder files are proposed in: the project's, else the video's.
    pub(super) fn default_folder(&self) -> PathBuf {
        self.project_path
            .as_deref()
            .or_else(|| self.project.as_ref().map(|p| p.video.as_path()))
            .and_then(Path::parent)
            .map(Path::to_owned)
            .or_else(|| std::env::current_dir().ok())
            .unwrap_or_default()
    }

    /// The video's name without its extension (names proposed for saves and exports).
    pub(super) fn video_stem(&self) -> String {
        self.project
            .as_ref()
            .and_then(|p| p.video.file_stem())
            .map_or_else(|| "motion".to_owned(), |s| s.to_string_lossy().into_owned())
    }

    pub(super) fn ask_path(&mut self, purpose: PathPurpose, title: &str, default: PathBuf) {
        self.no_native_dialogs = true;
        self.status = NO_DIALOG.to_owned();
        self.path_request = Some(PathRequest {
            purpose,
            title: title.to_owned(),
            text: default.display().to_string(),
            error: None,
            missing_folder: None,
        });
    }

    pub(super) fn path_edited(&mut self, text: String) {
        if let Some(r) = &mut self.path_request {
            r.text = text;
            r.error = None;
            r.missing_folder = None;
        }
    }

    /// The path field was confirmed or cancelled.
    pub(super) fn path_chosen(&mut self, path: Option<PathBuf>) {
        let Some(request) = self.path_request.take() else {
            return;
        };
        let Some(path) = path.filter(|p| !p.as_os_str().is_empty()) else {
            self.status = match request.purpose {
                PathPurpose::Open(_) => "Nothing opened".to_owned(),
                PathPurpose::Save(_) => "Not saved (cancelled)".to_owned(),
                PathPurpose::Export(_) => "Export cancelled: nothing written".to_owned(),
            };
            return;
        };
        // A file to write in a folder that does not exist: the window says so and offers to
        // create it (a desktop's save dialog can make a folder; the path field does it so).
        if !matches!(request.purpose, PathPurpose::Open(_))
            && let Some(folder) = missing_folder(&path)
        {
            self.status = format!(
                "Nothing written: the folder {} does not exist",
                folder.display()
            );
            self.path_request = Some(PathRequest {
                error: Some(format!(
                    "The folder {} does not exist: create it, or change the path.",
                    folder.display()
                )),
                missing_folder: Some(folder),
                text: path.display().to_string(),
                ..request
            });
            return;
        }
        let failed = match &request.purpose {
            PathPurpose::Open(what) => {
                if path.exists() {
                    self.chosen(*what, &path);
                    None
                } else {
                    Some(format!("{} does not exist", path.display()))
                }
            }
            PathPurpose::Save(then) => {
                self.save_project_to(&path);
                if self.dirty {
                    Some(self.status.clone())
                } else {
                    if let Some(to) = then.clone() {
                        self.go(to);
                    }
                    None
                }
            }
            PathPurpose::Export(kind) => self.export_to(*kind, &path).err(),
        };
        if let Some(error) = failed {
            // The window stays, saying why, so the user can change the path.
            self.path_request = Some(PathRequest {
                error: Some(error),
                missing_folder: None,
                text: path.display().to_string(),
                ..request
            });
        }
    }

    /// "Create the folder" in the path field: makes the missing folder, then writes as asked.
    pub(super) fn create_folder(&mut self) {
        let Some(r) = &mut self.path_request else {
            return;
        };
        let Some(folder) = r.missing_folder.take() else {
            return;
        };
        match std::fs::create_dir_all(&folder) {
            Ok(()) => {
                let path = PathBuf::from(r.text.trim());
                self.path_chosen(Some(path));
            }
            Err(e) => r.error = Some(format!("Cannot create {}: {e}", folder.display())),
        }
    }

    /// Saves the project to its file, or asks where (`ask`, or no file yet); then goes on to
    /// `then`.
    pub(super) fn save_project(&mut self, ask: bool, then: Option<Leave>) {
        if self.project.is_none() {
            self.status = "Nothing to save: open a video first".to_owned();
            return;
        }
        let picked = match (&self.project_path, ask) {
            (Some(p), false) => Picked::Path(p.clone()),
            _ if self.no_native_dialogs => Picked::Unavailable,
            _ => {
                let name = format!("{}.videomocap.json", self.video_stem());
                let folder = self.default_folder();
                self.config
                    .dialogs
                    .save_file("Save project", Some(&folder), &name)
            }
        };
        match picked {
            Picked::Path(path) => {
                self.save_project_to(&path);
                if !self.dirty
                    && let Some(to) = then
                {
                    self.go(to);
                }
            }
            Picked::Cancelled => self.status = "Not saved (cancelled)".to_owned(),
            Picked::Unavailable => {
                let default = self
                    .default_folder()
                    .join(format!("{}.videomocap.json", self.video_stem()));
                self.ask_path(PathPurpose::Save(then), "Save project", default);
            }
        }
    }

    /// Saves the project to `path` and clears the recovery file.
    pub(super) fn save_project_to(&mut self, path: &Path) {
        let Some(p) = &self.project else { return };
        match p.save(path) {
            Ok(()) => {
                self.project_path = Some(path.to_owned());
                // Recent brings back the project, not its bare video.
                let video = p.video.clone();
                self.forget(&video);
                self.remember(path);
                self.dirty = false;
                if let Some(a) = &mut self.autosaver {
                    a.clear();
                }
                self.status = format!("Saved {}", path.display());
            }
            Err(e) => self.status = format!("Not saved: {e}"),
        }
    }

    /// Accepts or declines the recovery offered at start.
    pub(super) fn answer_recovery(&mut self, recover: bool) {
        let Some(path) = self.recovery.take() else {
            return;
        };
        if recover {
            match Project::load(&path) {
                Ok(p) => {
                    self.open_video(&p.video.clone());
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

    /// Opens a video, image folder, project file or a folder of point volumes now.
    pub(super) fn open_now(&mut self, path: &Path) {
        if is_volume_dir(path) {
            self.dirty = false;
            self.open_volume(path);
            self.remember(path);
        } else if path.is_file() && path.extension().is_some_and(|e| e == "json") {
            let checked = self.checked_project.take().filter(|(p, _)| p == path);
            let loaded = match checked {
                Some((_, project)) => Ok(project),
                None => Project::load(path),
            };
            match loaded {
                Ok(p) => {
                    self.dirty = false;
                    let video = p.video.clone();
                    self.open_video(&video);
                    self.set_project(p);
                    self.project_path = Some(path.to_owned());
                    self.status = format!("Opened project {}", path.display());
                    // Recent brings back the project, not its bare video.
                    self.forget(&video);
                    self.remember(path);
                }
                Err(e) => {
                    self.status = format!("Cannot open project: {e}");
                    self.forget(path);
                }
            }
        } else {
            // Remembered once it opens (`remember_opened`).
            self.dirty = false;
            self.open_video(path);
        }
    }

    /// Volume mode: processes the point volumes of `dir` on a worker thread.
    fn open_volume(&mut self, dir: &Path) {
        self.close_current();
        self.volume = Some(VolumeSequence::new(dir.to_owned()));
        self.running = Some(Running {
            job: Job::volume(dir.to_owned(), 30.0, self.ctx.clone()),
            keys: Default::default(),
            overrides: Default::default(),
            settings: Default::default(),
        });
        self.status = format!("Processing point volumes in {}…", dir.display());
    }

    fn open_video(&mut self, path: &Path) {
        self.close_current();
        self.loader = Some(FrameLoader::open(
            path.to_owned(),
            self.ctx.clone(),
            self.config.proxy_dir.clone(),
        ));
        self.project = Some(Project::new(path.to_owned()));
        self.background = None;
        self.network_seen = None;
        self.passes_seen = None;
        self.results_changed();
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
        self.background = None;
        self.network_seen = None;
        self.passes_seen = None;
        self.project_path = None;
        self.project_beside = None;
        self.history.clear();
        self.results_changed();
        self.current = 0;
        self.shown = None;
        self.preview = false;
        self.texture = None;
        self.marking = None;
        self.subject_fit = None;
        self.flip_ghost = None;
        self.opened_count += 1;
    }
}

/// The folder `path` would be written in, when it does not exist.
fn missing_folder(path: &Path) -> Option<PathBuf> {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty() && !d.is_dir())
        .map(Path::to_owned)
}

/// Why `path` cannot be opened, in the user's words, checked before anything is closed (a
/// video's own format is checked as it opens); a project is read here, once.
fn openable(path: &Path) -> Result<Option<Project>, String> {
    if !path.exists() {
        return Err("there is no such file or folder".to_owned());
    }
    if path.is_file() && path.extension().is_some_and(|e| e == "json") {
        return Project::load(path)
            .map(Some)
            .map_err(|e| format!("it is not a project this app can read ({e})"));
    }
    if path.is_dir() && !is_volume_dir(path) && !has_images(path) {
        return Err(
            "the folder holds neither video frames (PNG or JPEG images) nor point volumes \
             (PLY files); choose a video file, an image folder or a project"
                .to_owned(),
        );
    }
    Ok(None)
}

/// Whether `path` is a folder of point clouds (and no images): volume mode.
fn is_volume_dir(path: &Path) -> bool {
    path.is_dir() && videomocap_volume::list_frames(path).is_ok() && !has_images(path)
}

/// Whether a folder holds PNG or JPEG images (video frames).
fn has_images(path: &Path) -> bool {
    std::fs::read_dir(path).is_ok_and(|entries| {
        entries.filter_map(Result::ok).any(|e| {
            let name = e.file_name().to_string_lossy().to_ascii_lowercase();
            name.ends_with(".png") || name.ends_with(".jpg") || name.ends_with(".jpeg")
        })
    })
}
