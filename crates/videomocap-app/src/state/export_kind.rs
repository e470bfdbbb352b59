//! What the Export menu can write: each kind's menu entry and the file name it proposes.

/// Things the export menu can write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ExportKind {
    /// The motion as BVH (CMU bone names).
    Bvh,
    /// The motion as BVH with Mixamo's bone names, for retargeting onto Mixamo characters.
    BvhMixamo,
    /// The 2D tracks (tracks2d.json).
    TracksJson,
    /// The 3D skeleton (skeleton3d.json).
    SkeletonJson,
    /// The 2D tracks as CSV.
    TracksCsv,
    /// The 3D joints as CSV.
    JointsCsv,
    /// OpenSim markers.
    Trc,
    /// The marks (marks.json).
    Marks,
}

impl ExportKind {
    /// Every export, in menu order.
    pub(crate) const ALL: [ExportKind; 8] = [
        ExportKind::Bvh,
        ExportKind::BvhMixamo,
        ExportKind::TracksJson,
        ExportKind::SkeletonJson,
        ExportKind::TracksCsv,
        ExportKind::JointsCsv,
        ExportKind::Trc,
        ExportKind::Marks,
    ];

    /// The menu entry.
    pub(crate) fn label(self) -> &'static str {
        match self {
            ExportKind::Bvh => "BVH (Blender, motion builders)…",
            ExportKind::BvhMixamo => "BVH, Mixamo bone names (retargeting)…",
            ExportKind::TracksJson => "2D tracks (tracks2d.json)…",
            ExportKind::SkeletonJson => "3D skeleton (skeleton3d.json)…",
            ExportKind::TracksCsv => "2D tracks CSV…",
            ExportKind::JointsCsv => "3D joints CSV…",
            ExportKind::Trc => "OpenSim markers (.trc)…",
            ExportKind::Marks => "Marks (marks.json)…",
        }
    }

    /// The file name proposed, after the video's name.
    pub(super) fn file_name(self, stem: &str) -> String {
        let suffix = match self {
            ExportKind::Bvh => ".bvh",
            ExportKind::BvhMixamo => ".mixamo.bvh",
            ExportKind::TracksJson => ".tracks2d.json",
            ExportKind::SkeletonJson => ".skeleton3d.json",
            ExportKind::TracksCsv => ".tracks2d.csv",
            ExportKind::JointsCsv => ".joints3d.csv",
            ExportKind::Trc => ".trc",
            ExportKind::Marks => ".marks.json",
        };
        format!("{stem}{suffix}")
    }
}
