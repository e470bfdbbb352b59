//! Volume mode's state: the point-volume sequence, the pipeline's result once its job has
//! finished, and which layers the 3D view draws (`views::scene` draws them).

use std::path::PathBuf;
use std::sync::Arc;
use videomocap_core::export::WorldSkeleton;
use videomocap_volume::Processed;

/// What volume mode holds.
pub(crate) struct VolumeSequence {
    /// The sequence directory.
    pub dir: PathBuf,
    /// The pipeline's output, once the job has finished.
    pub processed: Option<Arc<Processed>>,
    /// The skeleton in the Y-up world (also the map for points, curve and bodies).
    pub world: Option<WorldSkeleton>,
    /// What the 3D view draws.
    pub layers: Layers,
    /// Why the pipeline failed on this sequence, in the user's words (the 3D view says it).
    pub failed: Option<String>,
}

/// The layers volume mode can draw (the skeleton always shows).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Layers {
    /// The points, coloured by body.
    pub points: bool,
    /// The skeleton curve.
    pub curve: bool,
    /// The fitted head sphere, torso and limb cylinders.
    pub bodies: bool,
}

impl Default for Layers {
    fn default() -> Self {
        Layers {
            points: true,
            curve: true,
            bodies: true,
        }
    }
}

impl VolumeSequence {
    /// A sequence about to be processed.
    pub(crate) fn new(dir: PathBuf) -> VolumeSequence {
        VolumeSequence {
            dir,
            processed: None,
            world: None,
            layers: Layers::default(),
            failed: None,
        }
    }

    /// Number of frames (0 until processed).
    pub(crate) fn frame_count(&self) -> usize {
        self.processed.as_ref().map_or(0, |p| p.files.len())
    }

    /// Takes the pipeline's result.
    pub(crate) fn set(&mut self, processed: Processed) {
        self.world = WorldSkeleton::new(&processed.assembled.skeleton, None).ok();
        self.processed = Some(Arc::new(processed));
        self.failed = None;
    }

    /// Records why the pipeline failed on this sequence.
    pub(crate) fn fail(&mut self, error: &str) {
        // The pipeline's error starts with the folder, which the sentence names already.
        let prefix = format!("{}: ", self.dir.display());
        let error = error.strip_prefix(&prefix).unwrap_or(error);
        let error = error.trim_end_matches(['.', ' ']);
        self.failed = Some(format!(
            "The point volumes in {} could not be turned into a skeleton: {error}. Check that \
             each file is a complete PLY, XYZ or voxel file, or open another folder.",
            self.dir.display()
        ));
    }
}
