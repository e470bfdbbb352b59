//! The state's exports: what the Export menu can write, where (a dialog, or the path field when
//! none can be shown), and the status line naming the file written or why nothing was.

use super::export_kind::ExportKind;
use super::file_dialogs::Picked;
use super::{PathPurpose, State};
use std::path::Path;
use videomocap_core::export;

impl State {
    /// Asks where to write an export, then writes it.
    pub(super) fn export(&mut self, kind: ExportKind) {
        let name = kind.file_name(&self.video_stem());
        let folder = self.default_folder();
        let picked = if self.no_native_dialogs {
            Picked::Unavailable
        } else {
            self.config
                .dialogs
                .save_file("Export", Some(&folder), &name)
        };
        match picked {
            Picked::Path(path) => {
                let _ = self.export_to(kind, &path);
            }
            Picked::Cancelled => self.status = "Export cancelled: nothing written".to_owned(),
            Picked::Unavailable => {
                let title = format!("Export {}", kind.label().trim_end_matches('…'));
                self.ask_path(PathPurpose::Export(kind), &title, folder.join(name));
            }
        }
    }

    /// Writes one export to `path`; the status line names the file or the reason.
    pub(super) fn export_to(&mut self, kind: ExportKind, path: &Path) -> Result<(), String> {
        let result = self.write_export(kind, path).map_err(|e| e.to_string());
        let shown = path.display().to_string();
        self.status = match &result {
            Ok(()) => format!("Wrote {shown}"),
            // The path once: most reasons name it already.
            Err(e) if e.contains(&shown) => format!("Nothing written: {e}"),
            Err(e) => format!("Nothing written to {shown}: {e}"),
        };
        result
    }

    fn write_export(&self, kind: ExportKind, path: &Path) -> anyhow::Result<()> {
        let p = self
            .project
            .as_ref()
            .ok_or_else(|| anyhow::anyhow!("no video open"))?;
        let need_tracks = || {
            p.tracks
                .as_deref()
                .ok_or_else(|| anyhow::anyhow!("nothing tracked yet (Track > Track and lift)"))
        };
        let need_world = || {
            self.world
                .as_ref()
                .map(|(w, _)| w)
                .ok_or_else(|| anyhow::anyhow!("no 3D skeleton yet (Track > Track and lift)"))
        };
        match kind {
            ExportKind::Bvh | ExportKind::BvhMixamo => {
                let names = if kind == ExportKind::Bvh {
                    export::RigNames::Cmu
                } else {
                    export::RigNames::Mixamo
                };
                let b = export::bvh(need_world()?, names)?;
                export::save_text(path, &b.text)?;
            }
            ExportKind::TracksJson => need_tracks()?.save(path)?,
            ExportKind::SkeletonJson => p
                .skeleton
                .as_deref()
                .ok_or_else(|| anyhow::anyhow!("no 3D skeleton yet (Track > Track and lift)"))?
                .save(path)?,
            ExportKind::TracksCsv => {
                export::save_text(path, &export::tracks_csv(need_tracks()?))?;
            }
            ExportKind::JointsCsv => {
                export::save_text(path, &export::skeleton_csv(need_world()?))?;
            }
            ExportKind::Trc => {
                let name = path
                    .file_name()
                    .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
                export::save_text(path, &export::trc(need_world()?, &name))?;
            }
            ExportKind::Marks => p
                .marks()
                .ok_or_else(|| anyhow::anyhow!("not all 16 joints are marked on one frame"))?
                .save(path)?,
        }
        Ok(())
    }
}
