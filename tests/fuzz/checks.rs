//! What every fuzz target checks, shared by the fuzz targets (`fuzz_targets/`) and the cargo
//! test that replays the seeds and every crash found so far (`tests/fuzz_regressions.rs`).
//! Parsing must never panic; what parses must survive a write and re-read unchanged (JSON
//! formats) or keep the promises of its type (BVH frames, finite points).

use std::path::Path;
use videomocap_core::bvh::Bvh;
use videomocap_core::formats::{Marks, Skeleton3d, Tracks2d};
use videomocap_core::project::Project;
use videomocap_volume::cloud::{CloudKind, parse_cloud};

/// The fuzz targets, by name (also the folder names under `seeds/` and `regressions/`).
#[allow(dead_code)]
pub(crate) const TARGETS: [&str; 8] = [
    "marks",
    "tracks2d",
    "skeleton3d",
    "project",
    "bvh",
    "ply",
    "xyz",
    "voxels",
];

/// Feeds `data` to the parser of `target`; panics when an invariant breaks. Returns whether
/// the input parsed.
pub(crate) fn check(target: &str, data: &[u8]) -> bool {
    let path = Path::new("fuzz-input");
    let cloud = |kind| match parse_cloud(kind, data, path) {
        Ok(points) => {
            assert!(
                points
                    .iter()
                    .all(|p| p.coords.iter().all(|c| c.is_finite()))
            );
            true
        }
        Err(_) => false,
    };
    match target {
        "ply" => return cloud(CloudKind::Ply),
        "xyz" => return cloud(CloudKind::Xyz),
        "voxels" => return cloud(CloudKind::Voxels),
        _ => {}
    }
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    match target {
        "marks" => Marks::parse(text, path).is_ok_and(|m| {
            assert_eq!(m, Marks::parse(&m.to_json(), path).expect("re-read"));
            true
        }),
        "tracks2d" => Tracks2d::parse(text, path).is_ok_and(|t| {
            let written = t.to_json_value().to_string();
            assert_eq!(t, Tracks2d::parse(&written, path).expect("re-read"));
            true
        }),
        "skeleton3d" => Skeleton3d::parse(text, path).is_ok_and(|s| {
            let written = s.to_json_value().to_string();
            assert_eq!(s, Skeleton3d::parse(&written, path).expect("re-read"));
            true
        }),
        "project" => Project::parse(text, path).is_ok_and(|p| {
            assert_eq!(p, Project::parse(&p.to_json(), path).expect("re-read"));
            true
        }),
        "bvh" => Bvh::parse(text, path).is_ok_and(|b| {
            assert!(b.frame_count() > 0);
            let last = b.frame_count() - 1;
            assert_eq!(b.frame(last).len(), b.frame(0).len());
            // Forward kinematics of a parsed file never panics.
            let _ = b.positions(last);
            true
        }),
        other => panic!("unknown fuzz target {other}"),
    }
}
