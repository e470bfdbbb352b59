//! File dialogs behind a trait, so the app uses the desktop's (rfd) and tests answer with
//! prepared paths. A desktop may have no dialog at all (no XDG portal, zenity or kdialog): the
//! answer then says so, and the app offers its own path field instead of doing nothing.

#[cfg(test)]
use std::cell::RefCell;
#[cfg(test)]
use std::collections::VecDeque;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// What a file dialog gave.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Picked {
    /// The user chose this path.
    Path(PathBuf),
    /// The user closed the dialog without choosing.
    Cancelled,
    /// No dialog could be shown on this desktop.
    Unavailable,
}

/// Asks the user for files.
pub(crate) trait Dialogs {
    /// A file to open, filtered to `extensions` (empty = any).
    fn open_file(&self, title: &str, extensions: &[&str]) -> Picked;
    /// A folder to open (image sequences, point volumes).
    fn open_folder(&self, title: &str) -> Picked;
    /// Where to save, proposing `name` in `folder`.
    fn save_file(&self, title: &str, folder: Option<&std::path::Path>, name: &str) -> Picked;
}

/// The desktop's dialogs (XDG portal, or zenity).
pub(crate) struct RfdDialogs;

/// A dialog that returned nothing sooner than this was never shown: rfd returns at once when
/// the desktop has no portal and no zenity, and no one closes a shown dialog this fast.
const NOT_SHOWN: Duration = Duration::from_millis(150);

/// What rfd's answer means, given how long it took.
fn picked(answer: Option<PathBuf>, started: Instant) -> Picked {
    match answer {
        Some(p) => Picked::Path(p),
        None if started.elapsed() < NOT_SHOWN => Picked::Unavailable,
        None => Picked::Cancelled,
    }
}

impl Dialogs for RfdDialogs {
    fn open_file(&self, title: &str, extensions: &[&str]) -> Picked {
        let mut d = rfd::FileDialog::new().set_title(title);
        if !extensions.is_empty() {
            d = d.add_filter(title, extensions);
        }
        let started = Instant::now();
        picked(d.pick_file(), started)
    }

    fn open_folder(&self, title: &str) -> Picked {
        let started = Instant::now();
        picked(
            rfd::FileDialog::new().set_title(title).pick_folder(),
            started,
        )
    }

    fn save_file(&self, title: &str, folder: Option<&std::path::Path>, name: &str) -> Picked {
        let mut d = rfd::FileDialog::new().set_title(title).set_file_name(name);
        if let Some(f) = folder {
            d = d.set_directory(f);
        }
        if let Some(ext) = std::path::Path::new(name).extension() {
            let ext = ext.to_string_lossy();
            d = d.add_filter(ext.as_ref(), &[ext.as_ref()]);
        }
        let started = Instant::now();
        picked(d.save_file(), started)
    }
}

/// Answers every dialog with the next prepared path (tests; clones share the answers).
#[cfg(test)]
#[derive(Default, Clone)]
pub(crate) struct PreparedDialogs {
    /// Paths handed out in order; once empty, the user cancels.
    pub answers: std::rc::Rc<RefCell<VecDeque<PathBuf>>>,
    /// No dialog can be shown (a desktop without a portal or zenity).
    pub unavailable: std::rc::Rc<std::cell::Cell<bool>>,
}

#[cfg(test)]
impl PreparedDialogs {
    fn next(&self) -> Picked {
        if self.unavailable.get() {
            return Picked::Unavailable;
        }
        self.answers
            .borrow_mut()
            .pop_front()
            .map_or(Picked::Cancelled, Picked::Path)
    }
}

#[cfg(test)]
impl Dialogs for PreparedDialogs {
    fn open_file(&self, _: &str, _: &[&str]) -> Picked {
        self.next()
    }

    fn open_folder(&self, _: &str) -> Picked {
        self.next()
    }

    fn save_file(&self, _: &str, _: Option<&std::path::Path>, _: &str) -> Picked {
        self.next()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_returned_at_once_means_no_dialog_was_shown() {
        assert_eq!(picked(None, Instant::now()), Picked::Unavailable);
        let long_ago = Instant::now() - Duration::from_secs(2);
        assert_eq!(picked(None, long_ago), Picked::Cancelled);
        let p = PathBuf::from("/tmp/x.bvh");
        assert_eq!(picked(Some(p.clone()), Instant::now()), Picked::Path(p));
    }
}
