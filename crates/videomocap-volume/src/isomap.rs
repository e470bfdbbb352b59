//! Isomap (Tenenbaum, de Silva, Langford 2000) as the paper uses it (§3): a neighbourhood graph
//! (ε-radius as in the paper, or k nearest; `kiddo` k-d tree), geodesic distances by Dijkstra on
//! the largest connected component, and landmark MDS (de Silva & Tenenbaum 2003, the remedy the
//! paper names in §5) into three dimensions, centred at the mean.
//!
//! Landmark MDS needs Dijkstra from M landmarks only (M·N distances instead of N²), which is what
//! makes 10,000+ points per frame fast: with M = 12 one frame of 10k points costs 12 Dijkstra runs.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{DMatrix, Point3, SymmetricEigen, Vector3};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::num::NonZero;

/// How each point's neighbours are chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Neighbourhood {
    /// Every point within this distance, metres (the paper's ε).
    Radius(f64),
    /// The k nearest points, made symmetric.
    Nearest(usize),
}

/// Isomap settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IsomapParams {
    /// The neighbourhood graph.
    pub neighbourhood: Neighbourhood,
    /// Number of landmarks for landmark MDS (at least 4 for a 3-D embedding).
    pub landmarks: usize,
}

/// The embedding of one frame's points.
#[derive(Debug, Clone)]
pub struct Embedding {
    /// Indices (into the input) of the points embedded: the largest connected component.
    pub kept: Vec<usize>,
    /// Embedded coordinates of `kept`, centred at their mean.
    pub coords: Vec<Vector3<f64>>,
    /// Graph degree of each kept point (interior voxels have a full neighbourhood; fewer
    /// neighbours means the point lies on the surface).
    pub degree: Vec<u32>,
    /// Graph edges removed to open loops ([`Neighbours::open_handles`]); 0 when none were
    /// looked for or found.
    pub cut_edges: usize,
}

/// Why a frame could not be embedded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IsomapProblem {
    #[error("only {0} points are connected; at least {1} are needed")]
    TooFewPoints(usize, usize),
    #[error("the geodesic distances do not span three dimensions")]
    Degenerate,
}

/// Adjacency in compressed rows: neighbours of `i` are `targets[starts[i]..starts[i + 1]]`.
pub(super) struct Graph {
    starts: Vec<u32>,
    targets: Vec<u32>,
    weights: Vec<f32>,
}

impl Graph {
    /// Number of nodes.
    pub(super) fn len(&self) -> usize {
        self.starts.len() - 1
    }

    /// Number of directed edges (each undirected edge counts twice).
    pub(super) fn targets_len(&self) -> usize {
        self.targets.len()
    }

    /// The longest edge.
    pub(super) fn longest_edge(&self) -> f32 {
        self.weights.iter().copied().fold(0.0, f32::max)
    }

    /// The same graph without the edges `cut` says to remove (asked once per direction).
    pub(super) fn without(&self, cut: impl Fn(usize, usize) -> bool) -> Graph {
        let mut g = Graph {
            starts: Vec::with_capacity(self.starts.len()),
            targets: Vec::with_capacity(self.targets.len()),
            weights: Vec::with_capacity(self.weights.len()),
        };
        g.starts.push(0);
        for i in 0..self.len() {
            for (j, w) in self.neighbours(i) {
                if !cut(i, j) {
                    g.targets.push(j as u32);
                    g.weights.push(w);
                }
            }
            g.starts.push(g.targets.len() as u32);
        }
        g
    }

    pub(super) fn neighbours(&self, i: usize) -> impl Iterator<Item = (usize, f32)> + '_ {
        let (a, b) = (self.starts[i] as usize, self.starts[i + 1] as usize);
        self.targets[a..b]
            .iter()
            .zip(&self.weights[a..b])
            .map(|(t, w)| (*t as usize, *w))
    }

    fn degree(&self, i: usize) -> u32 {
        self.starts[i + 1] - self.starts[i]
    }
}

fn build_graph(points: &[Point3<f64>], hood: Neighbourhood) -> Graph {
    let coords: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&coords);
    let mut lists: Vec<Vec<(u32, f32)>> = vec![Vec::new(); points.len()];
    for (i, q) in coords.iter().enumerate() {
        let found = match hood {
            Neighbourhood::Radius(r) => tree.within_unsorted::<SquaredEuclidean>(q, r * r),
            Neighbourhood::Nearest(k) => tree.nearest_n::<SquaredEuclidean>(
                q,
                NonZero::new(k + 1).unwrap_or(NonZero::<usize>::MIN),
            ),
        };
        for n in found {
            let j = n.item as usize;
            if j != i {
                let w = n.distance.sqrt() as f32;
                lists[i].push((j as u32, w));
                if matches!(hood, Neighbourhood::Nearest(_)) {
                    lists[j].push((i as u32, w));
                }
            }
        }
    }
    let mut starts = Vec::with_capacity(points.len() + 1);
    let (mut targets, mut weights) = (Vec::new(), Vec::new());
    starts.push(0u32);
    for mut l in lists {
        l.sort_unstable_by_key(|(j, _)| *j);
        l.dedup_by_key(|(j, _)| *j);
        for (j, w) in l {
            targets.push(j);
            weights.push(w);
        }
        starts.push(targets.len() as u32);
    }
    Graph {
        starts,
        targets,
        weights,
    }
}

/// The nodes of the largest connected component, in increasing order.
fn largest_component(g: &Graph, n: usize) -> Vec<usize> {
    let mut label = vec![u32::MAX; n];
    let mut best: Vec<usize> = Vec::new();
    let mut stack = Vec::new();
    for s in 0..n {
        if label[s] != u32::MAX {
            continue;
        }
        let mut members = vec![s];
        label[s] = s as u32;
        stack.push(s);
        while let Some(i) = stack.pop() {
            for (j, _) in g.neighbours(i) {
                if label[j] == u32::MAX {
                    label[j] = s as u32;
                    members.push(j);
                    stack.push(j);
                }
            }
        }
        if members.len() > best.len() {
            best = members;
        }
    }
    best.sort_unstable();
    best
}

/// Geodesic distances from `source` to every node (Dijkstra with a binary heap; f32 keys are
/// compared by their bits, which orders non-negative floats correctly), and each node's
/// predecessor on its shortest path when `parents` is given (`u32::MAX` for the source).
pub(super) fn dijkstra(
    g: &Graph,
    source: usize,
    dist: &mut [f32],
    heap: &mut BinaryHeap<Reverse<(u32, u32)>>,
    mut parents: Option<&mut [u32]>,
) {
    dist.fill(f32::INFINITY);
    heap.clear();
    if let Some(p) = parents.as_deref_mut() {
        p.fill(u32::MAX);
    }
    dist[source] = 0.0;
    heap.push(Reverse((0f32.to_bits(), source as u32)));
    while let Some(Reverse((d_bits, i))) = heap.pop() {
        let d = f32::from_bits(d_bits);
        let i = i as usize;
        if d > dist[i] {
            continue;
        }
        for (j, w) in g.neighbours(i) {
            let nd = d + w;
            if nd < dist[j] {
                dist[j] = nd;
                if let Some(p) = parents.as_deref_mut() {
                    p[j] = i as u32;
                }
                heap.push(Reverse((nd.to_bits(), j as u32)));
            }
        }
    }
}

/// The neighbourhood graph of a frame's largest connected component, ready to embed.
pub struct Neighbours {
    /// Indices (into the input) of the points kept.
    kept: Vec<usize>,
    /// Their positions.
    points: Vec<Point3<f64>>,
    graph: Graph,
    /// Edges removed by [`Neighbours::open_handles`].
    cut_edges: usize,
}

impl Neighbours {
    /// Builds the graph of `points` and keeps its largest connected component.
    pub fn new(points: &[Point3<f64>], params: &IsomapParams) -> Result<Self, IsomapProblem> {
        let min_points = params.landmarks.max(4) + 1;
        if points.len() < min_points {
            return Err(IsomapProblem::TooFewPoints(points.len(), min_points));
        }
        let full = build_graph(points, params.neighbourhood);
        let kept = largest_component(&full, points.len());
        if kept.len() < min_points {
            return Err(IsomapProblem::TooFewPoints(kept.len(), min_points));
        }
        let sub: Vec<Point3<f64>> = kept.iter().map(|&i| points[i]).collect();
        let graph = if kept.len() == points.len() {
            full
        } else {
            build_graph(&sub, params.neighbourhood)
        };
        Ok(Neighbours {
            kept,
            points: sub,
            graph,
            cut_edges: 0,
        })
    }

    /// Positions of the points kept, in the embedding's order.
    pub fn points(&self) -> &[Point3<f64>] {
        &self.points
    }

    /// The kept point nearest `head`.
    pub(crate) fn nearest(&self, head: Point3<f64>) -> Option<usize> {
        (0..self.points.len()).min_by(|&a, &b| {
            (self.points[a] - head)
                .norm_squared()
                .total_cmp(&(self.points[b] - head).norm_squared())
        })
    }

    /// The neighbourhood graph.
    pub(crate) fn graph(&self) -> &Graph {
        &self.graph
    }

    /// Puts `opened` in place of the graph, `cut` edges fewer (`volume::handles`).
    pub(crate) fn set_opened(&mut self, opened: Graph, cut: usize) {
        self.graph = opened;
        self.cut_edges += cut;
    }
}

/// Embeds `points` in three dimensions.
pub fn embed(points: &[Point3<f64>], params: &IsomapParams) -> Result<Embedding, IsomapProblem> {
    embed_graph(&Neighbours::new(points, params)?, params)
}

/// Embeds a built neighbourhood graph in three dimensions: landmarks, classical MDS on them,
/// then every point placed from its distances to the landmarks (landmark Isomap).
pub fn embed_graph(nb: &Neighbours, params: &IsomapParams) -> Result<Embedding, IsomapProblem> {
    let g = &nb.graph;
    let n = nb.points.len();
    let (chosen, rows) = landmarks(g, n, params.landmarks.max(4));
    let mds = LandmarkMds::new(&chosen, &rows)?;
    let mut coords: Vec<Vector3<f64>> = (0..n).map(|a| mds.place(&rows, a)).collect();
    let mean = coords.iter().sum::<Vector3<f64>>() / n as f64;
    for c in &mut coords {
        *c -= mean;
    }
    let degree = (0..n).map(|i| g.degree(i)).collect();
    Ok(Embedding {
        kept: nb.kept.clone(),
        coords,
        degree,
        cut_edges: nb.cut_edges,
    })
}

/// Up to `count` landmarks by max-min: each new landmark is the point farthest (geodesically)
/// from those chosen so far, started from the point farthest from point 0. Returns the
/// landmarks and each one's geodesic distances to every one of the `n` points.
fn landmarks(g: &Graph, n: usize, count: usize) -> (Vec<usize>, Vec<Vec<f32>>) {
    let mut heap = BinaryHeap::new();
    let mut scratch = vec![0f32; n];
    dijkstra(g, 0, &mut scratch, &mut heap, None);
    let farthest = |d: &[f32]| {
        d.iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(i, _)| i)
    };
    let mut chosen = vec![farthest(&scratch)];
    let mut rows: Vec<Vec<f32>> = Vec::with_capacity(count);
    let mut nearest = vec![f32::INFINITY; n];
    while rows.len() < count {
        let Some(&l) = chosen.last() else { break };
        let mut row = vec![0f32; n];
        dijkstra(g, l, &mut row, &mut heap, None);
        for (m, d) in nearest.iter_mut().zip(&row) {
            *m = m.min(*d);
        }
        rows.push(row);
        if rows.len() < count {
            chosen.push(farthest(&nearest));
        }
    }
    (chosen, rows)
}

/// Classical MDS on the landmarks: the mean of each landmark's squared distances, and the
/// pseudo-inverse rows of the top three eigenvectors.
struct LandmarkMds {
    col_mean: Vec<f64>,
    pinv: Vec<Vec<f64>>,
}

impl LandmarkMds {
    /// MDS on the landmarks' squared geodesic distances: B = −½ J Δ J. Pseudo-inverse rows
    /// L#_k = v_kᵀ / √λ_k; a direction without spread (λ ≈ 0: a flat or thin volume) gets
    /// coordinate 0.
    fn new(chosen: &[usize], rows: &[Vec<f32>]) -> Result<LandmarkMds, IsomapProblem> {
        let m = rows.len();
        let delta = DMatrix::from_fn(m, m, |a, b| {
            let d = 0.5 * (f64::from(rows[a][chosen[b]]) + f64::from(rows[b][chosen[a]]));
            d * d
        });
        let col_mean: Vec<f64> = (0..m).map(|j| delta.column(j).mean()).collect();
        let all_mean = col_mean.iter().sum::<f64>() / m as f64;
        let b = DMatrix::from_fn(m, m, |i, j| {
            -0.5 * (delta[(i, j)] - col_mean[i] - col_mean[j] + all_mean)
        });
        let eig = SymmetricEigen::new(b);
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|a, b| eig.eigenvalues[*b].total_cmp(&eig.eigenvalues[*a]));
        let top = &order[..3];
        if eig.eigenvalues[top[0]] <= 1e-12 {
            return Err(IsomapProblem::Degenerate);
        }
        let pinv = top
            .iter()
            .map(|&k| {
                let l = eig.eigenvalues[k];
                let s = if l > 1e-12 { 1.0 / l.sqrt() } else { 0.0 };
                eig.eigenvectors.column(k).iter().map(|v| v * s).collect()
            })
            .collect();
        Ok(LandmarkMds { col_mean, pinv })
    }

    /// Point `a` from its distances to the landmarks (`rows`): y = −½ L# (δ − δ_μ).
    fn place(&self, rows: &[Vec<f32>], a: usize) -> Vector3<f64> {
        let mut y = Vector3::zeros();
        for (j, row) in rows.iter().enumerate() {
            let d = f64::from(row[a]);
            let centred = d * d - self.col_mean[j];
            for k in 0..3 {
                y[k] += self.pinv[k][j] * centred;
            }
        }
        -0.5 * y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points along a bent tube: Isomap straightens it, so embedded distances between the ends
    /// equal the geodesic length, not the (much shorter) straight-line distance.
    #[test]
    fn a_folded_tube_is_unfolded() {
        let step = 0.02;
        let mut pts = Vec::new();
        let arc = |s: f64| -> Point3<f64> {
            // A U shape: down 0.5 m, across 0.2 m, up 0.5 m.
            if s < 0.5 {
                Point3::new(0.0, -s, 0.0)
            } else if s < 0.7 {
                Point3::new(s - 0.5, -0.5, 0.0)
            } else {
                Point3::new(0.2, s - 1.2, 0.0)
            }
        };
        let mut s = 0.0;
        while s <= 1.2 + 1e-9 {
            let c = arc(s);
            for dx in [-1.0, 0.0, 1.0] {
                for dz in [-1.0, 0.0, 1.0] {
                    pts.push(c + Vector3::new(dx, 0.0, dz) * step * 0.5);
                }
            }
            s += step;
        }
        let params = IsomapParams {
            neighbourhood: Neighbourhood::Radius(step * 1.8),
            landmarks: 10,
        };
        let e = embed(&pts, &params).unwrap();
        assert_eq!(e.kept.len(), pts.len());
        let first = e.coords[0];
        let last = e.coords[e.coords.len() - 1];
        let straight = (pts[0] - pts[pts.len() - 1]).norm();
        let embedded = (first - last).norm();
        assert!(straight < 0.25, "{straight}");
        assert!(
            (embedded - 1.2).abs() < 0.1,
            "embedded end-to-end {embedded}"
        );
        let mean = e.coords.iter().sum::<Vector3<f64>>() / e.coords.len() as f64;
        assert!(mean.norm() < 1e-9);
    }

    #[test]
    fn the_largest_component_is_kept_and_tiny_inputs_refused() {
        let mut pts: Vec<Point3<f64>> = (0..50)
            .map(|i| Point3::new(i as f64 * 0.01, 0.0, (i % 3) as f64 * 0.01))
            .collect();
        pts.push(Point3::new(5.0, 5.0, 5.0));
        let params = IsomapParams {
            neighbourhood: Neighbourhood::Radius(0.025),
            landmarks: 6,
        };
        let e = embed(&pts, &params).unwrap();
        assert_eq!(e.kept.len(), 50);
        assert!(!e.kept.contains(&50));
        assert_eq!(
            embed(&pts[..3], &params).unwrap_err(),
            IsomapProblem::TooFewPoints(3, 7)
        );
    }
}
