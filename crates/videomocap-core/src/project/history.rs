//! Undo and redo over whole states (projects are small: keys, settings and shared results), each
//! step named by the edit that made it, so the app can say what undo and redo take back.

/// A state an edit started from, and the edit's name.
#[derive(Debug, Clone)]
struct Step<T> {
    state: T,
    what: String,
}

/// Past and undone states around the current one.
#[derive(Debug, Clone)]
pub struct History<T> {
    past: Vec<Step<T>>,
    future: Vec<Step<T>>,
    limit: usize,
}

impl<T: Clone> History<T> {
    /// An empty history keeping at most `limit` undo steps.
    pub fn new(limit: usize) -> History<T> {
        History {
            past: Vec::new(),
            future: Vec::new(),
            limit: limit.max(1),
        }
    }

    /// Records `before` as the state the edit `what` started from (clears redo).
    pub fn record(&mut self, before: T, what: impl Into<String>) {
        self.past.push(Step {
            state: before,
            what: what.into(),
        });
        if self.past.len() > self.limit {
            self.past.remove(0);
        }
        self.future.clear();
    }

    /// Steps back: returns the state to restore, given the current one, and the name of the
    /// edit undone.
    pub fn undo(&mut self, current: T) -> Option<(T, String)> {
        let previous = self.past.pop()?;
        self.future.push(Step {
            state: current,
            what: previous.what.clone(),
        });
        Some((previous.state, previous.what))
    }

    /// Steps forward again after an undo: the state and the name of the edit redone.
    pub fn redo(&mut self, current: T) -> Option<(T, String)> {
        let next = self.future.pop()?;
        self.past.push(Step {
            state: current,
            what: next.what.clone(),
        });
        Some((next.state, next.what))
    }

    /// Whether there is something to undo.
    pub fn can_undo(&self) -> bool {
        !self.past.is_empty()
    }

    /// Whether there is something to redo.
    pub fn can_redo(&self) -> bool {
        !self.future.is_empty()
    }

    /// The name of the edit undo would take back.
    pub fn undo_name(&self) -> Option<&str> {
        self.past.last().map(|s| s.what.as_str())
    }

    /// The name of the edit redo would bring back.
    pub fn redo_name(&self) -> Option<&str> {
        self.future.last().map(|s| s.what.as_str())
    }

    /// Forgets everything (a new project).
    pub fn clear(&mut self) {
        self.past.clear();
        self.future.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undo_and_redo_walk_the_edits() {
        let mut h = History::new(2);
        let mut state = 0;
        for next in 1..=3 {
            h.record(state, format!("set {next}"));
            state = next;
        }
        state = h.undo(state).unwrap().0;
        assert_eq!(state, 2);
        state = h.undo(state).unwrap().0;
        assert_eq!(state, 1);
        assert!(h.undo(state).is_none(), "only two steps kept");
        state = h.redo(state).unwrap().0;
        assert_eq!(state, 2);
        h.record(state, "set 9");
        state = 9;
        assert!(!h.can_redo(), "a new edit clears redo");
        assert_eq!(h.undo(state), Some((2, "set 9".to_owned())));
    }

    #[test]
    fn undo_and_redo_name_the_edit_they_take_back_and_bring_back() {
        let mut h = History::new(10);
        h.record(0, "mark the head");
        h.record(1, "move the left wrist");
        assert_eq!(h.undo_name(), Some("move the left wrist"));
        let (state, what) = h.undo(2).unwrap();
        assert_eq!((state, what.as_str()), (1, "move the left wrist"));
        assert_eq!(h.undo_name(), Some("mark the head"));
        assert_eq!(h.redo_name(), Some("move the left wrist"));
        let (state, what) = h.redo(state).unwrap();
        assert_eq!((state, what.as_str()), (2, "move the left wrist"));
        assert_eq!(h.redo_name(), None);
    }
}
