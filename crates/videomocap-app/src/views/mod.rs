//! The app's views: each draws part of the window from the state and returns the user's
//! [`Intent`](crate::intent::Intent)s; none changes the state itself.
//!
//! `menu` (the menu bar), `fitted` (sliders whose label fits the panel), `side_panel` (marking guide, parameters, weak tracking) with
//! `marking`, `tracker_settings` and `lift_settings`, `timeline` (scrubber and reliability
//! strips), `frame_view` (the frame, marking and corrections), `view3d` (the orbiting 3D view)
//! drawing what `scene` builds, `status_bar` (status line, job progress), `windows` (prompts,
//! the path field, shortcuts, the user guide) and `keys` (keyboard shortcuts).

pub(crate) mod fitted;
pub(crate) mod frame_view;
pub(crate) mod keys;
pub(crate) mod lift_settings;
pub(crate) mod marking;
pub(crate) mod menu;
pub(crate) mod scene;
pub(crate) mod side_panel;
pub(crate) mod status_bar;
pub(crate) mod timeline;
pub(crate) mod tracker_settings;
pub(crate) mod view3d;
pub(crate) mod windows;
