//! Autosave: after every change the project is written, atomically, to one recovery file by a
//! worker thread (only the newest state is written when changes come quickly). The file stays
//! until the user saves or discards, so a crash or kill leaves it for the next start to offer.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Sender, channel};
use std::thread::JoinHandle;
use videomocap_core::project::Project;

/// Name of the recovery file in the autosave directory.
pub(crate) const AUTOSAVE_FILE: &str = "autosave.videomocap.json";

/// The default autosave directory: `$XDG_STATE_HOME/videomocap` (or the platform's equivalent).
pub(crate) fn default_dir() -> Option<PathBuf> {
    dirs::state_dir()
        .or_else(dirs::data_local_dir)
        .map(|d| d.join("videomocap"))
}

/// Writes projects to the recovery file off the UI thread.
pub(crate) struct Autosaver {
    path: PathBuf,
    tx: Option<Sender<Project>>,
    worker: Option<JoinHandle<()>>,
}

impl Autosaver {
    /// An autosaver writing `dir/autosave.videomocap.json`.
    pub(crate) fn new(dir: &Path) -> Autosaver {
        let path = dir.join(AUTOSAVE_FILE);
        let (tx, rx) = channel::<Project>();
        let target = path.clone();
        let dir = dir.to_owned();
        let worker = std::thread::Builder::new()
            .name("autosave".into())
            .spawn(move || {
                while let Ok(mut p) = rx.recv() {
                    while let Ok(newer) = rx.try_recv() {
                        p = newer;
                    }
                    let _ = std::fs::create_dir_all(&dir);
                    if let Err(e) = p.save(&target) {
                        eprintln!("autosave failed: {e}");
                    }
                }
            })
            .ok();
        Autosaver {
            path,
            tx: Some(tx),
            worker,
        }
    }

    /// The recovery file.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Queues a save of `project`.
    pub(crate) fn save(&self, project: &Project) {
        if let Some(tx) = &self.tx {
            let _ = tx.send(project.clone());
        }
    }

    /// Waits until every queued save is on disk (tests, and before deleting the file).
    pub(crate) fn flush(&mut self) {
        self.tx = None;
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
        let fresh = Autosaver::new(self.path.parent().unwrap_or(Path::new(".")));
        *self = fresh;
    }

    /// Removes the recovery file (after an explicit save or a discard).
    pub(crate) fn clear(&mut self) {
        self.flush();
        let _ = std::fs::remove_file(&self.path);
    }
}

impl Drop for Autosaver {
    fn drop(&mut self) {
        self.tx = None;
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}
