//! A row's temporary folder, `DIR/.partial-<id>-<host>-<pid>`, renamed to `DIR/<id>` when the
//! row is finished: a row's folder is complete or absent.
//!
//! A process that is killed (a Slurm time limit, `scancel`, a power cut) leaves its temporary
//! folders behind. Each holds an owner file (host, pid, id) that a live process rewrites every
//! [`HEARTBEAT`]; every batch run removes the temporary folders whose owner is dead: a process
//! of this host that no longer exists (named by the owner file, or by the folder's name when a
//! process was killed before it wrote the file), or, from any host (a cluster's nodes share the output
//! folder but not their process tables), an owner file older than [`STALE_AFTER`].

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, SystemTime};

/// The temporary folders' name prefix (hidden).
const PREFIX: &str = ".partial-";
/// The owner file in a temporary folder.
const OWNER: &str = ".owner.json";
/// How often a live process rewrites its owner files.
const HEARTBEAT: Duration = Duration::from_secs(30);
/// An owner file older than this belongs to a dead process: ten heartbeats, room for the
/// clocks of a cluster's nodes and its file server to disagree and for NFS attribute caching
/// (60 s at most by default).
const STALE_AFTER: Duration = Duration::from_secs(300);

/// Who writes a temporary folder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Owner {
    id: String,
    host: String,
    pid: u32,
}

/// This machine's name (`unknown` where the system does not say).
fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_owned())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// A row's temporary folder, owned by this process while it exists.
pub(super) struct Partial {
    /// The folder.
    pub path: PathBuf,
    owner: Owner,
}

impl Partial {
    /// Creates this process's temporary folder for row `id` in `out_dir`, with its owner file.
    pub(super) fn create(out_dir: &Path, id: &str) -> std::io::Result<Partial> {
        let owner = Owner {
            id: id.to_owned(),
            host: host_name(),
            pid: std::process::id(),
        };
        let path = out_dir.join(format!("{PREFIX}{id}-{}-{}", owner.host, owner.pid));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path)?;
        let partial = Partial { path, owner };
        partial.touch()?;
        Ok(partial)
    }

    /// Writes the owner file anew (its time is the heartbeat).
    fn touch(&self) -> std::io::Result<()> {
        let text = serde_json::to_string(&self.owner).map_err(std::io::Error::other)?;
        std::fs::write(self.path.join(OWNER), text)
    }

    /// Runs `work` while a thread rewrites the owner file every [`HEARTBEAT`].
    pub(super) fn with_heartbeat<T>(&self, work: impl FnOnce() -> T) -> T {
        let (stop, stopped) = mpsc::channel::<()>();
        std::thread::scope(|s| {
            s.spawn(move || {
                while let Err(mpsc::RecvTimeoutError::Timeout) = stopped.recv_timeout(HEARTBEAT) {
                    let _ = self.touch();
                }
            });
            let out = work();
            drop(stop);
            out
        })
    }

    /// Removes the owner file: the folder holds the row's results only, ready to be renamed.
    pub(super) fn seal(&self) -> std::io::Result<()> {
        std::fs::remove_file(self.path.join(OWNER))
    }

    /// Removes the folder (a failed row, or one that could not be renamed).
    pub(super) fn discard(&self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

/// Whether process `pid` of this host exists (`None` where the system cannot say).
fn process_exists(pid: u32) -> Option<bool> {
    Path::new("/proc/self")
        .exists()
        .then(|| Path::new(&format!("/proc/{pid}")).exists())
}

/// The process of this host (`here`) whose folder `dir` is, read from the folder's name
/// (`<prefix><id>-<host>-<pid>`): a folder without its owner file yet (killed between making
/// the folder and writing the file) or any more (sealed) still names its writer.
fn pid_in_name(dir: &Path, here: &str) -> Option<u32> {
    let name = dir.file_name()?.to_str()?;
    let (rest, pid) = name.rsplit_once('-')?;
    let pid: u32 = pid.parse().ok()?;
    rest.ends_with(&format!("-{here}")).then_some(pid)
}

/// Whether a temporary folder's writer is gone, from its owner file (or, without one, the
/// writer named by the folder's name, else the folder's own time).
fn is_dead(dir: &Path, here: &str, now: SystemTime) -> bool {
    let owner_path = dir.join(OWNER);
    let owner: Option<Owner> = std::fs::read_to_string(&owner_path)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    let local_pid = match &owner {
        Some(o) => (o.host == here).then_some(o.pid),
        None => pid_in_name(dir, here),
    };
    if let Some(pid) = local_pid
        && let Some(exists) = process_exists(pid)
    {
        return !exists;
    }
    let written = std::fs::metadata(if owner.is_some() {
        owner_path.as_path()
    } else {
        dir
    })
    .and_then(|m| m.modified())
    .ok();
    written
        .and_then(|t| now.duration_since(t).ok())
        .is_some_and(|age| age > STALE_AFTER)
}

/// Removes the temporary folders of dead processes from `out_dir`; returns how many.
pub(super) fn remove_dead(out_dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(out_dir) else {
        return 0;
    };
    let here = host_name();
    let now = SystemTime::now();
    entries
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with(PREFIX))
        .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
        .filter(|e| is_dead(&e.path(), &here, now))
        // Another process may be removing the same folder: whoever finishes, it is gone.
        .filter(|e| std::fs::remove_dir_all(e.path()).is_ok() || !e.path().exists())
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write_owner(dir: &Path, owner: &Owner) {
        std::fs::create_dir_all(dir).expect("dir");
        std::fs::write(dir.join(OWNER), serde_json::to_string(owner).expect("json"))
            .expect("owner");
    }

    /// The pid of a process of this host that has exited.
    fn exited_pid() -> u32 {
        let mut child = std::process::Command::new("true").spawn().expect("true");
        let pid = child.id();
        child.wait().expect("wait");
        pid
    }

    #[test]
    fn folders_of_dead_processes_go_and_those_of_live_ones_stay() {
        let out = tempfile::tempdir().expect("temp dir");
        let here = host_name();
        let dead_pid = exited_pid();
        let dead = out.path().join(format!(".partial-a-{here}-{dead_pid}"));
        write_owner(
            &dead,
            &Owner {
                id: "a".into(),
                host: here.clone(),
                pid: dead_pid,
            },
        );
        std::fs::write(dead.join("tracks2d.json"), "{}").expect("file");
        // This process: alive.
        let live = Partial::create(out.path(), "b").expect("create");
        // Another host's, written just now: it may be running there.
        let elsewhere = out.path().join(".partial-c-node7-42");
        write_owner(
            &elsewhere,
            &Owner {
                id: "c".into(),
                host: "node7".into(),
                pid: 42,
            },
        );
        // A finished row's folder is never touched.
        std::fs::create_dir_all(out.path().join("d")).expect("row");
        assert_eq!(remove_dead(out.path()), 1);
        assert!(!dead.exists());
        assert!(live.path.exists() && elsewhere.exists());
        assert!(out.path().join("d").exists());
        // Another host's owner file not rewritten for longer than STALE_AFTER: dead.
        let later = SystemTime::now() + STALE_AFTER + Duration::from_secs(1);
        assert!(is_dead(&elsewhere, &here, later));
        assert!(!is_dead(&live.path, &here, later), "a live local pid wins");
    }

    #[test]
    fn a_folder_killed_before_its_owner_file_names_its_dead_writer() {
        let out = tempfile::tempdir().expect("temp dir");
        let here = host_name();
        let dead_pid = exited_pid();
        // Made, then killed before the owner file was written (an id with dashes in it).
        let dead = out
            .path()
            .join(format!(".partial-take-2-{here}-{dead_pid}"));
        std::fs::create_dir_all(&dead).expect("dir");
        // This process's folder without its owner file (sealed): alive.
        let live = out
            .path()
            .join(format!(".partial-x-{here}-{}", std::process::id()));
        std::fs::create_dir_all(&live).expect("dir");
        // Another host's without an owner file, made just now: it may be running there.
        let elsewhere = out
            .path()
            .join(format!(".partial-y-other{here}-{dead_pid}"));
        std::fs::create_dir_all(&elsewhere).expect("dir");
        assert_eq!(remove_dead(out.path()), 1);
        assert!(!dead.exists());
        assert!(live.exists() && elsewhere.exists());
    }

    #[test]
    fn a_sealed_folder_holds_the_results_only() {
        let out = tempfile::tempdir().expect("temp dir");
        let p = Partial::create(out.path(), "row").expect("create");
        let n = p.with_heartbeat(|| 3);
        assert_eq!(n, 3);
        std::fs::write(p.path.join("status.json"), "{}").expect("file");
        p.seal().expect("seal");
        let names: Vec<String> = std::fs::read_dir(&p.path)
            .expect("dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, vec!["status.json".to_owned()]);
    }
}
