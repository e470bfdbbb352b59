//! Results that no longer match the settings: tracks made with other tracker settings (the
//! pose network switched on or off, …), a 3D skeleton made with another height, focal length,
//! known lengths or lift settings. The side panel offers to track or lift again under the
//! section changed, and the status line says so at the change; nothing re-runs by itself
//! (tracking a long clip takes minutes, and the user may change more first).

use super::State;
use videomocap_core::project::{Project, Settings};
use videomocap_core::track::TrackerParams;

/// The settings the project's results were made with (`None`: no result, or not known).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct MadeWith {
    tracks: Option<TrackerParams>,
    skeleton: Option<Settings>,
}

impl MadeWith {
    /// A project opened from a file: its results taken as made with its own settings.
    pub(super) fn of(p: &Project) -> MadeWith {
        MadeWith {
            tracks: p.tracks.is_some().then_some(p.settings.tracker),
            skeleton: p.skeleton.is_some().then_some(p.settings),
        }
    }
}

/// A result that no longer matches the settings, with what changed in words.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Outdated {
    /// The tracks: Track again.
    Tracks(String),
    /// The 3D skeleton: Lift again.
    Skeleton(String),
}

impl State {
    /// New tracks made with `tracker` (the 3D skeleton made from the old ones is gone).
    pub(super) fn tracks_made_with(&mut self, tracker: TrackerParams) {
        self.made_with = MadeWith {
            tracks: Some(tracker),
            skeleton: None,
        };
    }

    /// A new 3D skeleton made with `settings`.
    pub(super) fn skeleton_made_with(&mut self, settings: Settings) {
        self.made_with.skeleton = Some(settings);
    }

    /// The results the settings changed under since they were made: the tracks, then the 3D
    /// skeleton (not while a job makes new ones).
    pub(crate) fn outdated(&self) -> Vec<Outdated> {
        let Some(p) = self.project.as_ref().filter(|_| !self.busy()) else {
            return Vec::new();
        };
        let mut out = Vec::new();
        if let Some(before) = self.made_with.tracks.filter(|_| p.tracks.is_some())
            && before != p.settings.tracker
        {
            out.push(Outdated::Tracks(tracker_change(
                &before,
                &p.settings.tracker,
            )));
        }
        if let Some(before) = self.made_with.skeleton.filter(|_| p.skeleton.is_some())
            && let Some(what) = lift_change(&before, &p.settings)
        {
            out.push(Outdated::Skeleton(what));
        }
        out
    }

    /// After a settings change: the status line says which result it leaves out of date and
    /// how to bring it up to date.
    pub(super) fn say_outdated(&mut self) {
        if let Some(o) = self.outdated().first() {
            self.status = match o {
                Outdated::Tracks(what) => format!("{what}: Track again (T) to apply it"),
                Outdated::Skeleton(what) => {
                    format!("{what}: Lift again (Parameters, or Track > Lift to 3D again)")
                }
            };
        }
    }
}

fn on_off(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

/// What changed in the tracker settings, in words.
fn tracker_change(before: &TrackerParams, now: &TrackerParams) -> String {
    if before.network != now.network {
        format!(
            "These tracks were made with the pose network {}; it is {} now",
            on_off(before.network),
            on_off(now.network)
        )
    } else {
        "The tracker settings changed since these tracks were made".to_owned()
    }
}

/// What changed in the settings the lift reads, in words (`None`: nothing it reads).
fn lift_change(before: &Settings, now: &Settings) -> Option<String> {
    let what = if before.height_m != now.height_m {
        "The subject height"
    } else if before.focal_px != now.focal_px {
        "The focal length"
    } else if before.lengths != now.lengths {
        "The lengths you know"
    } else if before.lift != now.lift {
        "The lift settings"
    } else {
        return None;
    };
    Some(format!("{what} changed since this 3D was made"))
}
