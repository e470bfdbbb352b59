//! File dialogs behind a trait, so the app uses rfd and tests answer with prepared paths.

#[cfg(test)]
use std::cell::RefCell;
#[cfg(test)]
use std::collections::VecDeque;
use std::path::PathBuf;

/// Asks the user for files.
pub trait Dialogs {
    /// A file to open, filtered to `extensions` (empty = any).
    fn open_file(&self, title: &str, extensions: &[&str]) -> Option<PathBuf>;
    /// A folder to open (image sequences).
    fn open_folder(&self, title: &str) -> Option<PathBuf>;
    /// Where to save, proposing `name`.
    fn save_file(&self, title: &str, name: &str, extension: &str) -> Option<PathBuf>;
}

/// The desktop's dialogs (XDG portal, or zenity; `None` when neither is there).
pub struct RfdDialogs;

impl Dialogs for RfdDialogs {
    fn open_file(&self, title: &str, extensions: &[&str]) -> Option<PathBuf> {
        let mut d = rfd::FileDialog::new().set_title(title);
        if !extensions.is_empty() {
            d = d.add_filter(title, extensions);
        }
        d.pick_file()
    }

    fn open_folder(&self, title: &str) -> Option<PathBuf> {
        rfd::FileDialog::new().set_title(title).pick_folder()
    }

    fn save_file(&self, title: &str, name: &str, extension: &str) -> Option<PathBuf> {
        rfd::FileDialog::new()
            .set_title(title)
            .set_file_name(name)
            .add_filter(extension, &[extension])
            .save_file()
    }
}

/// Answers every dialog with the next prepared path (tests; clones share the answers).
#[cfg(test)]
#[derive(Default, Clone)]
pub struct PreparedDialogs {
    /// Paths handed out in order; `None` once empty (the user cancelled).
    pub answers: std::rc::Rc<RefCell<VecDeque<PathBuf>>>,
}

#[cfg(test)]
impl Dialogs for PreparedDialogs {
    fn open_file(&self, _: &str, _: &[&str]) -> Option<PathBuf> {
        self.answers.borrow_mut().pop_front()
    }

    fn open_folder(&self, _: &str) -> Option<PathBuf> {
        self.answers.borrow_mut().pop_front()
    }

    fn save_file(&self, _: &str, _: &str, _: &str) -> Option<PathBuf> {
        self.answers.borrow_mut().pop_front()
    }
}
