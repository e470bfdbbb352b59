//! The window's layout as the user left it, kept across restarts beside the recent list and the
//! autosave (`layout.json`): the side panel's and the 3D view's widths, the timeline's strips
//! folded or not, and per video the
//! frame view's zoom and the image point at its centre (marking a portrait clip at one screen
//! pixel per three video pixels needs the zoom, and it was forgotten on every start). A file
//! that is missing or unreadable gives the defaults; losing it is harmless.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// How many videos' zooms are kept (as many as File ▸ Recent lists).
const VIDEOS_KEPT: usize = 8;

/// The 3D view's width when the user has not chosen one, points: narrower than the 380 it
/// was, so a landscape clip gets the width (on a 1440-point window with the side panel at 280,
/// 860 points for the video instead of 820).
pub(crate) const DEFAULT_VIEW3D_PX: f32 = 300.0;

/// The side panel's width when the user has not chosen one, points: the widest setting's
/// label ("hands outside the body", 134 points) fits beside its number box and a short bar.
pub(crate) const DEFAULT_SIDE_PX: f32 = 280.0;

/// The frame view's zoom on one video.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct FrameZoom {
    /// 1: the frame fits the view.
    pub zoom: f32,
    /// The image point at the view's centre, pixels (`None`: the image's centre).
    pub centre: Option<[f32; 2]>,
}

/// One video's zoom.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct VideoZoom {
    video: PathBuf,
    #[serde(flatten)]
    zoom: FrameZoom,
}

/// The layout kept across restarts.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub(crate) struct Layout {
    /// The side panel's width, points.
    #[serde(default)]
    pub side_px: Option<f32>,
    /// The 3D view's width, points.
    #[serde(default)]
    pub view3d_px: Option<f32>,
    /// The timeline's strips: one per joint (`true`) or folded into one (`false`), as the user
    /// last chose (`None`: folded only where they would take height from the video).
    #[serde(default)]
    pub each_joint: Option<bool>,
    /// The frame view's zoom per video, the latest first.
    #[serde(default)]
    zooms: Vec<VideoZoom>,
}

impl Layout {
    /// The file in the app's state folder.
    fn path(dir: &Path) -> PathBuf {
        dir.join("layout.json")
    }

    /// The layout kept in `dir` (the defaults when there is none or it cannot be read).
    pub(crate) fn load(dir: Option<&Path>) -> Layout {
        dir.map(Layout::path)
            .and_then(|p| std::fs::read_to_string(p).ok())
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default()
    }

    /// Writes the layout into `dir` (atomically; a failure only loses the layout).
    pub(crate) fn save(&self, dir: Option<&Path>) {
        let Some(dir) = dir else { return };
        let _ = std::fs::create_dir_all(dir);
        if let Ok(text) = serde_json::to_string_pretty(self) {
            let _ = videomocap_core::formats::write_atomically(&Layout::path(dir), text.as_bytes());
        }
    }

    /// The zoom last used on `video`.
    pub(crate) fn zoom_of(&self, video: &Path) -> Option<FrameZoom> {
        self.zooms.iter().find(|z| z.video == video).map(|z| z.zoom)
    }

    /// Keeps `zoom` for `video`; `true` when it changed.
    pub(crate) fn set_zoom(&mut self, video: &Path, zoom: FrameZoom) -> bool {
        if self.zoom_of(video) == Some(zoom) {
            return false;
        }
        self.zooms.retain(|z| z.video != video);
        self.zooms.insert(
            0,
            VideoZoom {
                video: video.to_owned(),
                zoom,
            },
        );
        self.zooms.truncate(VIDEOS_KEPT);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_layout_is_read_back_as_written_and_a_bad_file_gives_the_defaults() {
        let dir = tempfile::tempdir().unwrap();
        let mut layout = Layout {
            side_px: Some(280.0),
            view3d_px: Some(260.0),
            ..Layout::default()
        };
        let zoom = FrameZoom {
            zoom: 2.5,
            centre: Some([540.0, 300.0]),
        };
        assert!(layout.set_zoom(Path::new("/v/a.mp4"), zoom));
        assert!(!layout.set_zoom(Path::new("/v/a.mp4"), zoom));
        layout.save(Some(dir.path()));
        let back = Layout::load(Some(dir.path()));
        assert_eq!(back, layout);
        assert_eq!(back.zoom_of(Path::new("/v/a.mp4")), Some(zoom));
        assert_eq!(back.zoom_of(Path::new("/v/b.mp4")), None);
        std::fs::write(dir.path().join("layout.json"), "{ not json").unwrap();
        assert_eq!(Layout::load(Some(dir.path())), Layout::default());
    }
}
