//! Atomic saving: user work is written to a temporary file beside the target, flushed to disk
//! and renamed over it, so a crash leaves either the old or the new file, never a torn one.

use super::FormatError;
use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically (temp file in the same directory, fsync, rename).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), FormatError> {
    let err = |source| FormatError::Write {
        path: path.to_owned(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(FormatError::Invalid {
            path: path.to_owned(),
            problem: format!(
                "cannot write: the folder {} does not exist (create it or choose another)",
                dir.display()
            ),
        });
    }
    // The temporary file's name means nothing to the user: the error keeps only its kind
    // ("permission denied"), named by the file being saved.
    let mut tmp = tempfile::Builder::new()
        .prefix(TEMP_PREFIX)
        .suffix(TEMP_SUFFIX)
        .tempfile_in(dir)
        .map_err(|e| err(std::io::Error::from(e.kind())))?;
    tmp.write_all(bytes).map_err(err)?;
    // The temporary file is private (0600); give the result the old file's permissions, or the
    // usual 0644 for a new file, so that saving never changes who can read the user's work.
    #[cfg(unix)]
    {
        let permissions = match std::fs::metadata(path) {
            Ok(meta) => meta.permissions(),
            Err(_) => default_permissions(),
        };
        tmp.as_file().set_permissions(permissions).map_err(err)?;
    }
    tmp.as_file().sync_all().map_err(err)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    remove_stale_temporaries(dir);
    Ok(())
}

/// Prefix and suffix of our temporary files.
const TEMP_PREFIX: &str = ".videomocap-";
const TEMP_SUFFIX: &str = ".tmp";

/// Age past which a temporary file of ours can only be left over from a killed save.
const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(600);

/// Removes temporary files a killed or crashed save left in `dir` (ours only, by name, and only
/// when older than [`STALE_AFTER`], so a save in progress elsewhere is never touched). Best
/// effort: errors are ignored.
fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if !(name.starts_with(TEMP_PREFIX) && name.ends_with(TEMP_SUFFIX)) {
            continue;
        }
        let stale = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age > STALE_AFTER);
        if stale {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

#[cfg(unix)]
fn default_permissions() -> std::fs::Permissions {
    use std::os::unix::fs::PermissionsExt;
    std::fs::Permissions::from_mode(0o644)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_the_file_and_leaves_no_temporary_behind() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.json");
        write_atomically(&path, b"old").unwrap();
        write_atomically(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn new_files_are_readable_and_old_permissions_are_kept() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("marks.json");
        write_atomically(&path, b"a").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&path), 0o644);
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
        write_atomically(&path, b"b").unwrap();
        assert_eq!(mode(&path), 0o600);
    }

    #[test]
    fn temporaries_left_by_a_killed_save_are_removed_by_the_next_save() {
        let dir = tempfile::tempdir().unwrap();
        let old = dir.path().join(".videomocap-abc123.tmp");
        let fresh = dir.path().join(".videomocap-def456.tmp");
        let other = dir.path().join(".other-abc.tmp");
        for p in [&old, &fresh, &other] {
            std::fs::write(p, b"partial").unwrap();
        }
        let hour_ago = std::time::SystemTime::now() - std::time::Duration::from_secs(3600);
        for p in [&old, &other] {
            std::fs::File::options()
                .write(true)
                .open(p)
                .unwrap()
                .set_modified(hour_ago)
                .unwrap();
        }
        write_atomically(&dir.path().join("p.json"), b"x").unwrap();
        assert!(!old.exists(), "a stale temporary of ours stays");
        assert!(fresh.exists(), "a save in progress was disturbed");
        assert!(other.exists(), "someone else's file was removed");
    }

    #[test]
    fn a_missing_directory_is_an_error_naming_the_file_and_the_folder_not_the_temporary() {
        let err = write_atomically(Path::new("/nonexistent-dir/x.json"), b"x").unwrap_err();
        let text = err.to_string();
        assert!(text.contains("/nonexistent-dir/x.json"), "{text}");
        assert!(
            text.contains("the folder /nonexistent-dir does not exist"),
            "{text}"
        );
        assert!(
            !text.contains(".tmp") && !text.contains("os error"),
            "{text}"
        );
    }
}
