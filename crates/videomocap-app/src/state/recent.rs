//! File ▸ Recent: the last eight things that opened, kept beside the autosave
//! (`recent.json`), a saved project in place of its video (opening the project or saving one
//! takes the bare video out; opening the video alone moves its listed project first); and the
//! saved project offered when a video opens alone beside one.

use super::State;
use std::path::{Path, PathBuf};

/// How many entries File ▸ Recent keeps.
const RECENT_KEPT: usize = 8;

impl State {
    /// Puts `path` first in File ▸ Recent.
    pub(super) fn remember(&mut self, path: &Path) {
        self.recent.retain(|p| p != path);
        self.recent.insert(0, path.to_owned());
        self.recent.truncate(RECENT_KEPT);
        self.save_recent();
    }

    /// Takes `path` out of File ▸ Recent (it did not open).
    pub(super) fn forget(&mut self, path: &Path) {
        let before = self.recent.len();
        self.recent.retain(|p| p != path);
        if self.recent.len() != before {
            self.save_recent();
        }
    }

    /// A video that opened: remembered in Recent unless a project holds it (the project is
    /// what the user opened, and what Recent should bring back), and a project saved beside it
    /// offered.
    pub(super) fn remember_opened(&mut self, video: &Path) {
        if self.project_path.is_none() {
            // A saved project of this video in Recent stands for it there (moved first).
            let listed = self
                .recent
                .iter()
                .find(|p| is_project_file(p) && video_of(p).is_some_and(|v| same_file(&v, video)))
                .cloned();
            self.remember(listed.as_deref().unwrap_or(video));
            // Work recovered or begun on this video is newer than any saved project: none is
            // offered over it.
            self.project_beside = project_beside(video).filter(|_| !self.dirty);
            if let Some(p) = &self.project_beside {
                self.status = format!("A saved project for this video: {}", p.display());
            }
        }
    }

    fn recent_path(&self) -> Option<PathBuf> {
        self.config
            .autosave_dir
            .as_ref()
            .map(|d| d.join("recent.json"))
    }

    /// The recent-files list kept beside the autosave (missing or unreadable: empty).
    pub(super) fn load_recent(&self) -> Vec<PathBuf> {
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
            let _ = videomocap_core::formats::write_atomically(&path, text.as_bytes());
        }
    }
}

/// Whether `path` names a project file (`*.json`, not a folder).
fn is_project_file(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "json")
}

/// Whether two paths are the same file (the same path when either cannot be resolved).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// A project file in `video`'s folder (`*.videomocap.json`) whose video is `video`, the newest
/// first.
fn project_beside(video: &Path) -> Option<PathBuf> {
    let folder = video.parent()?;
    let same = |p: &Path| same_file(p, video);
    let mut found: Vec<(std::time::SystemTime, PathBuf)> = std::fs::read_dir(folder)
        .ok()?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.to_string_lossy().ends_with(".videomocap.json"))
        .filter(|p| video_of(p).is_some_and(|v| same(&v)))
        .map(|p| {
            let modified = std::fs::metadata(&p)
                .and_then(|m| m.modified())
                .unwrap_or(std::time::UNIX_EPOCH);
            (modified, p)
        })
        .collect();
    found.sort();
    found.pop().map(|(_, p)| p)
}

/// The video a project file is for, reading that field alone (the folder may hold several
/// large projects, and this runs as a video opens).
fn video_of(project: &Path) -> Option<PathBuf> {
    #[derive(serde::Deserialize)]
    struct VideoOnly {
        video: PathBuf,
    }
    let file = std::fs::File::open(project).ok()?;
    serde_json::from_reader::<_, VideoOnly>(std::io::BufReader::new(file))
        .ok()
        .map(|v| v.video)
}
