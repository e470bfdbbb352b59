//! The points a frame's fit takes: the largest connected blob of the cloud (scattered ghost or
//! noise voxels and a second, smaller blob left out, as the curve's Isomap graph keeps its
//! largest component), its surface, evenly thinned.

use nalgebra::Point3;
use std::collections::HashMap;

/// One frame's points as the fit takes them: surface points thinned, and the point spacing.
#[derive(Debug, Clone, Default)]
pub struct FitPoints {
    /// Surface points of the largest connected blob, evenly thinned.
    pub points: Vec<Point3<f64>>,
    /// The cloud's point spacing (voxel size), metres.
    pub spacing_m: f64,
}

/// The surface points of `cloud`'s largest connected blob (spacing `spacing_m`), at most
/// `max_points` of them. Points are put on the lattice of that spacing; two cells are connected
/// when they touch (26 neighbours), and a point is on the surface when one of the six face
/// neighbours is empty (every point of a cloud that is not a voxel lattice is).
pub fn fit_points(cloud: &[Point3<f64>], spacing_m: f64, max_points: usize) -> FitPoints {
    let finite: Vec<Point3<f64>> = cloud
        .iter()
        .filter(|p| p.coords.iter().all(|c| c.is_finite()))
        .copied()
        .collect();
    let surface = if spacing_m > 0.0 && spacing_m.is_finite() && !finite.is_empty() {
        let cells: Vec<[i64; 3]> = finite
            .iter()
            .map(|p| [p.x, p.y, p.z].map(|c| (c / spacing_m).round() as i64))
            .collect();
        let lattice = Lattice::new(&cells);
        let blob = lattice.largest_blob();
        finite
            .iter()
            .zip(&cells)
            .filter(|(_, c)| lattice.slot(**c).is_some_and(|s| blob[s]))
            .filter(|(_, c)| {
                FACES.iter().any(|d| {
                    lattice
                        .slot([c[0] + d[0], c[1] + d[1], c[2] + d[2]])
                        .is_none()
                })
            })
            .map(|(p, _)| *p)
            .collect()
    } else {
        finite
    };
    let step = surface.len().div_ceil(max_points.max(1)).max(1);
    FitPoints {
        points: surface.into_iter().step_by(step).collect(),
        spacing_m,
    }
}

/// The six face neighbours of a cell.
const FACES: [[i64; 3]; 6] = [
    [1, 0, 0],
    [-1, 0, 0],
    [0, 1, 0],
    [0, -1, 0],
    [0, 0, 1],
    [0, 0, -1],
];

/// The occupied lattice cells, each numbered (its slot): a dense box when it is small enough
/// (the usual case, and much faster than hashing), else a hash map.
struct Lattice {
    /// The occupied cells, by slot.
    occupied: Vec<[i64; 3]>,
    map: Slots,
}

enum Slots {
    Dense {
        lo: [i64; 3],
        dims: [i64; 3],
        slot: Vec<u32>,
    },
    Sparse(HashMap<[i64; 3], u32>),
}

/// The dense box's largest size, cells (a 64 MB box of slots at most; a cloud spread wider is
/// hashed).
const DENSE_CELLS: i64 = 1 << 24;

/// An empty cell in the dense box.
const EMPTY: u32 = u32::MAX;

impl Lattice {
    fn new(cells: &[[i64; 3]]) -> Lattice {
        let mut lo = [i64::MAX; 3];
        let mut hi = [i64::MIN; 3];
        for c in cells {
            for k in 0..3 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        let dims = [0, 1, 2].map(|k| hi[k].saturating_sub(lo[k]).saturating_add(1));
        let size = dims
            .iter()
            .try_fold(1i64, |a, &d| a.checked_mul(d))
            .unwrap_or(i64::MAX);
        let mut lattice = Lattice {
            occupied: Vec::new(),
            map: if size > DENSE_CELLS {
                Slots::Sparse(HashMap::with_capacity(cells.len()))
            } else {
                Slots::Dense {
                    lo,
                    dims,
                    slot: vec![EMPTY; size as usize],
                }
            },
        };
        for &c in cells {
            lattice.insert(c);
        }
        lattice
    }

    fn insert(&mut self, c: [i64; 3]) {
        let next = self.occupied.len() as u32;
        let fresh = match &mut self.map {
            Slots::Dense { lo, dims, slot } => match dense_index(*lo, *dims, c) {
                Some(i) if slot[i] == EMPTY => {
                    slot[i] = next;
                    true
                }
                _ => false,
            },
            Slots::Sparse(map) => match map.entry(c) {
                std::collections::hash_map::Entry::Vacant(e) => {
                    e.insert(next);
                    true
                }
                std::collections::hash_map::Entry::Occupied(_) => false,
            },
        };
        if fresh {
            self.occupied.push(c);
        }
    }

    /// The slot of cell `c`, when it is occupied.
    fn slot(&self, c: [i64; 3]) -> Option<usize> {
        match &self.map {
            Slots::Dense { lo, dims, slot } => dense_index(*lo, *dims, c)
                .map(|i| slot[i])
                .filter(|&s| s != EMPTY)
                .map(|s| s as usize),
            Slots::Sparse(map) => map.get(&c).map(|&s| s as usize),
        }
    }

    /// Per slot, whether its cell belongs to the largest blob of touching cells (the first
    /// found on a tie).
    fn largest_blob(&self) -> Vec<bool> {
        let n = self.occupied.len();
        let mut blob_of = vec![u32::MAX; n];
        let mut sizes: Vec<usize> = Vec::new();
        let mut stack = Vec::new();
        for s in 0..n {
            if blob_of[s] != u32::MAX {
                continue;
            }
            let id = sizes.len() as u32;
            blob_of[s] = id;
            stack.push(s);
            let mut size = 0;
            while let Some(i) = stack.pop() {
                size += 1;
                let c = self.occupied[i];
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            if let Some(j) = self.slot([c[0] + dx, c[1] + dy, c[2] + dz])
                                && blob_of[j] == u32::MAX
                            {
                                blob_of[j] = id;
                                stack.push(j);
                            }
                        }
                    }
                }
            }
            sizes.push(size);
        }
        let best = (0..sizes.len())
            .max_by(|&a, &b| sizes[a].cmp(&sizes[b]).then(b.cmp(&a)))
            .map_or(u32::MAX, |b| b as u32);
        blob_of.iter().map(|&b| b == best).collect()
    }
}

fn dense_index(lo: [i64; 3], dims: [i64; 3], c: [i64; 3]) -> Option<usize> {
    let r = [0, 1, 2].map(|k| c[k] - lo[k]);
    if (0..3).any(|k| r[k] < 0 || r[k] >= dims[k]) {
        return None;
    }
    Some(((r[2] * dims[1] + r[1]) * dims[0] + r[0]) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(at: [i64; 3], side: i64, s: f64) -> Vec<Point3<f64>> {
        let mut out = Vec::new();
        for x in 0..side {
            for y in 0..side {
                for z in 0..side {
                    out.push(Point3::new(
                        (at[0] + x) as f64 * s,
                        (at[1] + y) as f64 * s,
                        (at[2] + z) as f64 * s,
                    ));
                }
            }
        }
        out
    }

    #[test]
    fn scattered_voxels_and_a_smaller_blob_are_left_out() {
        let s = 0.04;
        let mut cloud = cube([0, 0, 0], 5, s);
        cloud.extend(cube([20, 0, 0], 3, s));
        cloud.push(Point3::new(-10.0 * s, 30.0 * s, 3.0 * s));
        cloud.push(Point3::new(40.0 * s, -7.0 * s, 9.0 * s));
        let fit = fit_points(&cloud, s, 10_000);
        // The 5³ cube's surface: 125 − 27 inner voxels; nothing from the rest.
        assert_eq!(fit.points.len(), 125 - 27);
        assert!(fit.points.iter().all(|p| p.x < 5.0 * s && p.y >= 0.0));
    }

    #[test]
    fn a_diagonal_touch_joins_two_blobs_and_a_spread_cloud_is_hashed() {
        let s = 0.05;
        let mut cloud = cube([0, 0, 0], 3, s);
        cloud.extend(cube([3, 3, 3], 3, s));
        assert_eq!(fit_points(&cloud, s, 10_000).points.len(), 2 * 26);
        // A cloud too spread for the dense box gives the same answer through the hash map.
        let mut far = cloud.clone();
        far.push(Point3::new(1.0e5, 1.0e5, 1.0e5));
        assert_eq!(fit_points(&far, s, 10_000).points.len(), 2 * 26);
    }
}
