//! Voxel occupancy grids: the output of carving and one of the input kinds (`.voxels.json`),
//! with the largest 26-connected component (the paper's clean-up, §5).

use super::VolumeError;
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;
use videomocap_core::formats::{
    FORMAT_VERSION, check_header, parse_json, read_text, write_atomically,
};

/// The `format` tag of voxel grid files.
pub const VOXELS_FORMAT: &str = "videomocap.voxels";

/// What [`VoxelGrid::keep_component`] kept and dropped.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Kept {
    /// Voxels of the component kept.
    pub voxels: usize,
    /// Voxels of the other components.
    pub dropped_voxels: usize,
    /// How many other components there were.
    pub dropped_components: usize,
}

/// A regular grid of cubic voxels, occupied or not.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelGrid {
    /// Centre of voxel (0, 0, 0), metres.
    pub origin: Point3<f64>,
    /// Edge length of a voxel, metres.
    pub voxel_m: f64,
    /// Number of voxels along x, y, z.
    pub dims: [usize; 3],
    /// Occupancy, index `x + dims[0]·(y + dims[1]·z)`.
    pub occupied: Vec<bool>,
}

#[derive(Serialize, Deserialize)]
struct VoxelFile {
    #[serde(default)]
    format: Option<String>,
    #[serde(default)]
    version: Option<u32>,
    origin_m: [f64; 3],
    voxel_m: f64,
    dims: [usize; 3],
    /// Flat indices of the occupied voxels.
    occupied: Vec<usize>,
}

/// Largest grid accepted from a file (voxels), so that a typo cannot ask for terabytes.
const MAX_VOXELS: usize = 1 << 28;

impl VoxelGrid {
    /// An empty grid.
    pub fn new(origin: Point3<f64>, voxel_m: f64, dims: [usize; 3]) -> VoxelGrid {
        VoxelGrid {
            origin,
            voxel_m,
            dims,
            occupied: vec![false; dims[0] * dims[1] * dims[2]],
        }
    }

    /// Flat index of voxel (x, y, z).
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// Centre of voxel (x, y, z), metres.
    pub fn centre(&self, x: usize, y: usize, z: usize) -> Point3<f64> {
        self.origin + Vector3::new(x as f64, y as f64, z as f64) * self.voxel_m
    }

    /// Centres of the occupied voxels.
    pub fn centres(&self) -> Vec<Point3<f64>> {
        let [nx, ny, _] = self.dims;
        self.occupied
            .iter()
            .enumerate()
            .filter(|(_, o)| **o)
            .map(|(i, _)| self.centre(i % nx, (i / nx) % ny, i / (nx * ny)))
            .collect()
    }

    /// Number of occupied voxels.
    pub fn count(&self) -> usize {
        self.occupied.iter().filter(|o| **o).count()
    }

    /// Keeps one 26-connected component of occupied voxels: the one holding the occupied voxel
    /// nearest `near` (the person the user points at), or the largest when `near` is `None`;
    /// says what it dropped.
    pub fn keep_component(&mut self, near: Option<Point3<f64>>) -> Kept {
        let components = self.components();
        let chosen = match near {
            Some(p) => self.nearest_component(&components, &p),
            None => components
                .iter()
                .enumerate()
                .max_by_key(|(_, c)| c.len())
                .map(|(k, _)| k),
        };
        self.keep_only(&components, chosen)
    }

    /// The 26-connected components of the occupied voxels (flat indices), in the order of
    /// their first voxel.
    pub(crate) fn components(&self) -> Vec<Vec<usize>> {
        let [nx, ny, nz] = self.dims;
        let mut seen = vec![false; self.occupied.len()];
        let mut out = Vec::new();
        let mut stack = Vec::new();
        for start in 0..self.occupied.len() {
            if !self.occupied[start] || seen[start] {
                continue;
            }
            let mut component = Vec::new();
            seen[start] = true;
            stack.push(start);
            while let Some(i) = stack.pop() {
                component.push(i);
                let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
                for c in z.saturating_sub(1)..(z + 2).min(nz) {
                    for b in y.saturating_sub(1)..(y + 2).min(ny) {
                        for a in x.saturating_sub(1)..(x + 2).min(nx) {
                            let j = self.index(a, b, c);
                            if self.occupied[j] && !seen[j] {
                                seen[j] = true;
                                stack.push(j);
                            }
                        }
                    }
                }
            }
            out.push(component);
        }
        out
    }

    /// Centre of the voxel of flat index `i`.
    pub(crate) fn centre_of(&self, i: usize) -> Point3<f64> {
        let [nx, ny, _] = self.dims;
        self.centre(i % nx, (i / nx) % ny, i / (nx * ny))
    }

    /// Which of `components` holds the voxel nearest `p` (the first such voxel in grid order).
    pub(crate) fn nearest_component(
        &self,
        components: &[Vec<usize>],
        p: &Point3<f64>,
    ) -> Option<usize> {
        components
            .iter()
            .enumerate()
            .flat_map(|(k, c)| c.iter().map(move |&i| (i, k)))
            .map(|(i, k)| (i, k, (self.centre_of(i) - p).norm_squared()))
            .min_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)))
            .map(|(_, k, _)| k)
    }

    /// Leaves only component `chosen` of `components` occupied (none when `None`); says what
    /// was dropped.
    pub(crate) fn keep_only(&mut self, components: &[Vec<usize>], chosen: Option<usize>) -> Kept {
        let Some(best) = chosen.filter(|&k| k < components.len()) else {
            return Kept::default();
        };
        let mut dropped_voxels = 0;
        for (k, c) in components.iter().enumerate() {
            if k != best {
                dropped_voxels += c.len();
                for &i in c {
                    self.occupied[i] = false;
                }
            }
        }
        Kept {
            voxels: components[best].len(),
            dropped_voxels,
            dropped_components: components.len().saturating_sub(1),
        }
    }

    /// Reads and checks a `.voxels.json` file.
    pub fn load(path: &Path) -> Result<VoxelGrid, VolumeError> {
        VoxelGrid::parse(&read_text(path)?, path)
    }

    /// Parses and checks `.voxels.json` text; `path` names the file in errors.
    pub fn parse(text: &str, path: &Path) -> Result<VoxelGrid, VolumeError> {
        let raw: VoxelFile = parse_json(text, path)?;
        check_header(path, VOXELS_FORMAT, raw.format.as_deref(), raw.version)?;
        let invalid = |problem: String| VolumeError::Invalid {
            path: path.to_owned(),
            problem,
        };
        if !(raw.voxel_m.is_finite() && raw.voxel_m > 0.0) {
            return Err(invalid(format!(
                "voxel_m must be positive (got {})",
                raw.voxel_m
            )));
        }
        if !raw.origin_m.iter().all(|c| c.is_finite()) {
            return Err(invalid("origin_m must be finite".into()));
        }
        let total = raw
            .dims
            .iter()
            .try_fold(1usize, |acc, d| acc.checked_mul(*d))
            .filter(|t| *t > 0 && *t <= MAX_VOXELS)
            .ok_or_else(|| {
                invalid(format!(
                    "dims {:?} must be positive and hold at most {MAX_VOXELS} voxels",
                    raw.dims
                ))
            })?;
        let mut grid = VoxelGrid::new(Point3::from(raw.origin_m), raw.voxel_m, raw.dims);
        for &i in &raw.occupied {
            if i >= total {
                return Err(invalid(format!(
                    "occupied index {i} is outside the {total}-voxel grid"
                )));
            }
            grid.occupied[i] = true;
        }
        Ok(grid)
    }

    /// Writes the grid as `.voxels.json` atomically.
    pub fn save(&self, path: &Path) -> Result<(), VolumeError> {
        let file = VoxelFile {
            format: Some(VOXELS_FORMAT.to_owned()),
            version: Some(FORMAT_VERSION),
            origin_m: self.origin.coords.into(),
            voxel_m: self.voxel_m,
            dims: self.dims,
            occupied: (0..self.occupied.len())
                .filter(|&i| self.occupied[i])
                .collect(),
        };
        let text = serde_json::to_string(&file).map_err(|e| VolumeError::Invalid {
            path: path.to_owned(),
            problem: e.to_string(),
        })?;
        Ok(write_atomically(path, text.as_bytes())?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn largest_component_keeps_the_big_blob_and_diagonal_neighbours() {
        let mut g = VoxelGrid::new(Point3::origin(), 0.1, [6, 6, 6]);
        for (x, y, z) in [(0, 0, 0), (1, 1, 1), (2, 2, 2), (5, 5, 5)] {
            let i = g.index(x, y, z);
            g.occupied[i] = true;
        }
        assert_eq!(g.keep_component(None).dropped_voxels, 1);
        assert_eq!(g.count(), 3);
    }

    /// The person pointed at is kept even when another blob is larger, and the rest is counted.
    #[test]
    fn the_blob_nearest_the_point_is_kept_and_the_rest_reported() {
        let mut g = VoxelGrid::new(Point3::origin(), 0.1, [8, 3, 3]);
        for (x, y, z) in [
            (0, 0, 0),
            (1, 0, 0),
            (5, 0, 0),
            (6, 0, 0),
            (7, 0, 0),
            (7, 2, 2),
        ] {
            let i = g.index(x, y, z);
            g.occupied[i] = true;
        }
        let near = g.centre(0, 0, 0);
        let kept = g.keep_component(Some(near));
        assert_eq!(
            kept,
            Kept {
                voxels: 2,
                dropped_voxels: 4,
                dropped_components: 2
            }
        );
        assert!(g.occupied[g.index(1, 0, 0)] && !g.occupied[g.index(6, 0, 0)]);
    }

    #[test]
    fn grid_files_round_trip_and_bad_ones_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let mut g = VoxelGrid::new(Point3::new(0.0, 1.0, 2.0), 0.05, [3, 4, 5]);
        g.occupied[7] = true;
        g.occupied[59] = true;
        let p = dir.path().join("f.voxels.json");
        g.save(&p).unwrap();
        assert_eq!(VoxelGrid::load(&p).unwrap(), g);
        assert_eq!(g.centres()[0], Point3::new(0.05, 1.1, 2.0));
        std::fs::write(
            &p,
            r#"{"origin_m":[0,0,0],"voxel_m":0.05,"dims":[2,2,2],"occupied":[8]}"#,
        )
        .unwrap();
        let e = VoxelGrid::load(&p).unwrap_err().to_string();
        assert!(e.contains("f.voxels.json") && e.contains("outside"), "{e}");
        std::fs::write(
            &p,
            r#"{"origin_m":[0,0,0],"voxel_m":0.05,"dims":[100000,100000,100000],"occupied":[]}"#,
        )
        .unwrap();
        assert!(
            VoxelGrid::load(&p)
                .unwrap_err()
                .to_string()
                .contains("dims")
        );
    }
}
