//! The marked person followed through a carved clip (issue 91, item 3): a second person, or a
//! fragment, can be the blob nearest a fixed point on some frames (a person walking away from
//! where they were marked, another walking in), so the carve keeps, on each frame, the blob
//! that continues the one it kept on the frame before.
//!
//! The clip starts from the frame whose blob comes nearest the marked point (that blob); from
//! there, forwards and backwards, each frame keeps the blob sharing the most voxels with the
//! neighbouring frame's kept blob, or, sharing none, the one whose centre is nearest its centre.

use super::voxel::VoxelGrid;
use nalgebra::{Point3, Vector3};
use std::collections::HashSet;

/// Per frame, which of its blobs (`frames[t]`: the 26-connected components of `grid`'s shape,
/// flat voxel indices) is the person marked at `person`; `None` for a frame without blobs.
pub(crate) fn follow(
    grid: &VoxelGrid,
    frames: &[Vec<Vec<usize>>],
    person: &Point3<f64>,
) -> Vec<Option<usize>> {
    let mut chosen = vec![None; frames.len()];
    let start = frames
        .iter()
        .enumerate()
        .filter_map(|(t, blobs)| {
            let k = grid.nearest_component(blobs, person)?;
            let d = blobs[k]
                .iter()
                .map(|&i| (grid.centre_of(i) - person).norm_squared())
                .fold(f64::INFINITY, f64::min);
            Some((t, k, d))
        })
        .min_by(|a, b| a.2.total_cmp(&b.2));
    let Some((s, k, _)) = start else {
        return chosen;
    };
    chosen[s] = Some(k);
    for order in [
        Box::new(s + 1..frames.len()) as Box<dyn Iterator<Item = usize>>,
        Box::new((0..s).rev()),
    ] {
        let mut last = &frames[s][k];
        for t in order {
            let Some(next) = continuing(grid, &frames[t], last) else {
                continue;
            };
            chosen[t] = Some(next);
            last = &frames[t][next];
        }
    }
    chosen
}

/// Which of `blobs` continues `last`: the most shared voxels, else the nearest centre.
fn continuing(grid: &VoxelGrid, blobs: &[Vec<usize>], last: &[usize]) -> Option<usize> {
    let before: HashSet<usize> = last.iter().copied().collect();
    let shared = |b: &Vec<usize>| b.iter().filter(|i| before.contains(i)).count();
    let best = blobs
        .iter()
        .enumerate()
        .map(|(k, b)| (k, shared(b)))
        .max_by_key(|&(k, n)| (n, std::cmp::Reverse(k)))?;
    if best.1 > 0 {
        return Some(best.0);
    }
    let centre = |b: &[usize]| {
        b.iter()
            .map(|&i| grid.centre_of(i).coords)
            .sum::<Vector3<f64>>()
            / b.len().max(1) as f64
    };
    let c = centre(last);
    blobs
        .iter()
        .enumerate()
        .min_by(|a, b| {
            (centre(a.1) - c)
                .norm_squared()
                .total_cmp(&(centre(b.1) - c).norm_squared())
        })
        .map(|(k, _)| k)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2-voxel-wide bar of `len` voxels along x from `x0` (y = z = 0), as flat indices.
    fn bar(g: &VoxelGrid, x0: usize, len: usize) -> Vec<usize> {
        (x0..x0 + len)
            .flat_map(|x| [g.index(x, 0, 0), g.index(x, 1, 0)])
            .collect()
    }

    #[test]
    fn the_person_walking_past_the_marked_point_is_followed_not_the_other_blob() {
        // The person walks +x one voxel a frame from x = 0; another person stands at x = 20;
        // the point marked is x = 14, which the other person is nearer on the first frames.
        let g = VoxelGrid::new(Point3::origin(), 0.1, [40, 2, 1]);
        let frames: Vec<Vec<Vec<usize>>> = (0..12)
            .map(|t| vec![bar(&g, t, 4), bar(&g, 20, 4)])
            .collect();
        let chosen = follow(&g, &frames, &Point3::new(1.3, 0.0, 0.0));
        assert!(chosen.iter().all(|&c| c == Some(0)), "{chosen:?}");
        // A frame with a fragment only near the point, and a frame without blobs.
        let mut frames = frames;
        frames[5] = vec![bar(&g, 13, 1), bar(&g, 5, 4), bar(&g, 20, 4)];
        frames[6] = Vec::new();
        let chosen = follow(&g, &frames, &Point3::new(0.5, 0.0, 0.0));
        assert_eq!(chosen[5], Some(1));
        assert_eq!(chosen[6], None);
        assert_eq!(chosen[7], Some(0));
    }
}
