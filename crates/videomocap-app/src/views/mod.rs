//! The app's views: each draws part of the window from the state and returns the user's
//! [`Intent`](crate::intent::Intent)s; none changes the state itself.
//!
//! `menu` (the menu bar), `fitted` (sliders whose label fits the panel), `side_panel` (marking guide, parameters, weak tracking) with
//! `marking`, `tracker_settings` and `lift_settings`, `timeline` (scrubber and reliability
//! strips), `frame_view` (the frame, marking and corrections), `view3d` (the orbiting 3D view)
//! drawing what `scene` builds, `status_bar` (status line, job progress), `windows` (prompts,
//! the path field, shortcuts, the user guide) and `keys` (keyboard shortcuts).

pub mod fitted;
pub mod frame_view;
pub mod keys;
pub mod lift_settings;
pub mod marking;
pub mod menu;
pub mod scene;
pub mod side_panel;
pub mod status_bar;
pub mod timeline;
pub mod tracker_settings;
pub mod view3d;
pub mod windows;
