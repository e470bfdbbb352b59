//! Handles in the neighbourhood graph (beyond the paper). A hand resting on the hip, or two
//! hands clasped over the head, joins a limb to the body at both ends: geodesics then short-cut
//! through the contact, Isomap folds the limb into the trunk and the shells lose it (the
//! paper's §5 leaves volumes with cycles to future work).
//!
//! Swept outwards from the head, the level sets of the geodesic distance on a tree-shaped body
//! only ever split. A level-set component fed by two branches that parted several bands earlier
//! is a loop closing; its points are split by the branch their shortest path came through, and
//! the graph edges between the two sides are removed. Seen from the head, a limb's two routes
//! meet where it touches the body, not where it is attached, so the loop opens at the contact.
//! Every shortest-path edge is kept, so the graph stays connected and the geodesic distances
//! from the head do not change.

use super::isomap::{Graph, Neighbours, dijkstra};
use nalgebra::Point3;
use std::collections::BinaryHeap;

/// Bands (each as wide as the longest graph edge) a loop must span at least, from where its two
/// sides part to where they meet, to be opened; shorter ones are the voxel grid's staircase.
const MIN_LOOP_BANDS: u32 = 2;

/// The same as a share of the farthest geodesic distance from the head (about the stature), so
/// that fine voxels (many narrow bands) do not open the staircase of their own surface.
const MIN_LOOP_SHARE: f32 = 0.08;

/// One branch of the sweep: a run of level-set components between a split and the next.
struct Branch {
    parent: Option<usize>,
    /// Band in which the branch began.
    born: u32,
}

/// Whether branch `b` is `a` or descends from it.
fn descends(branches: &[Branch], mut b: usize, a: usize) -> bool {
    loop {
        if b == a {
            return true;
        }
        match branches[b].parent {
            Some(p) => b = p,
            None => return false,
        }
    }
}

/// The band where the lineages of branches `a` and `b` parted.
fn parted_at(branches: &[Branch], a: usize, b: usize) -> u32 {
    let mut x = a;
    loop {
        if descends(branches, b, x) {
            // `x` is the common ancestor; they parted where its children began.
            let mut child_born = u32::MAX;
            for mut y in [a, b] {
                while let Some(p) = branches[y].parent {
                    if p == x {
                        child_born = child_born.min(branches[y].born);
                        break;
                    }
                    y = p;
                }
            }
            return if child_born == u32::MAX {
                branches[x].born
            } else {
                child_born
            };
        }
        match branches[x].parent {
            Some(p) => x = p,
            None => return 0,
        }
    }
}

/// Opens the loops of `g` seen from `source`: the graph without the edges that close them, and
/// how many edges (counted once) were removed; `None` when there is no loop.
pub(super) fn cut_handles(g: &Graph, source: usize) -> Option<(Graph, usize)> {
    let bands = Bands::new(g, source);
    let mut sweep = Sweep::new(g.len());
    for (k, nodes) in bands.by_level.iter().enumerate() {
        let k = k as u32;
        let comps = sweep.components(g, &bands, nodes, k);
        let pieces = sweep.pieces(&bands, comps, k);
        sweep.grow_branches(&pieces, k);
    }
    let Sweep {
        branches,
        branch,
        mut merges,
        ..
    } = sweep;
    if merges.is_empty() {
        return None;
    }
    merges.sort_unstable();
    merges.dedup();
    let cut = |i: usize, j: usize| {
        let (a, b) = (branch[i], branch[j]);
        a != b
            && a != usize::MAX
            && b != usize::MAX
            && merges.iter().any(|&(x, y)| {
                (descends(&branches, a, x) && descends(&branches, b, y))
                    || (descends(&branches, a, y) && descends(&branches, b, x))
            })
    };
    let opened = g.without(cut);
    let removed = (g.targets_len() - opened.targets_len()) / 2;
    (removed > 0).then_some((opened, removed))
}

/// The geodesic distances from the source cut into bands as wide as the graph's longest edge.
struct Bands {
    /// Each point's distance from the source.
    dist: Vec<f32>,
    /// Each point's predecessor on its shortest path (`u32::MAX` for none).
    parent: Vec<u32>,
    /// Each point's band (`u32::MAX` where unreached).
    level: Vec<u32>,
    /// The reached points of each band, in order of distance.
    by_level: Vec<Vec<usize>>,
    /// Bands a loop must span to be opened ([`MIN_LOOP_BANDS`], [`MIN_LOOP_SHARE`]).
    min_loop: u32,
}

impl Bands {
    /// Runs Dijkstra from `source` and bands its distances.
    fn new(g: &Graph, source: usize) -> Bands {
        let n = g.len();
        let mut dist = vec![0f32; n];
        let mut parent = vec![u32::MAX; n];
        dijkstra(
            g,
            source,
            &mut dist,
            &mut BinaryHeap::new(),
            Some(&mut parent),
        );
        let band = g.longest_edge().max(f32::MIN_POSITIVE);
        let level: Vec<u32> = dist
            .iter()
            .map(|d| {
                if d.is_finite() {
                    (d / band) as u32
                } else {
                    u32::MAX
                }
            })
            .collect();
        let mut order: Vec<usize> = (0..n).filter(|&i| level[i] != u32::MAX).collect();
        order.sort_by(|&a, &b| dist[a].total_cmp(&dist[b]));
        let top = order.last().map_or(0, |&i| level[i]) as usize;
        let far = order.last().map_or(0.0, |&i| dist[i]);
        let min_loop = MIN_LOOP_BANDS.max((MIN_LOOP_SHARE * far / band).ceil() as u32);
        let mut by_level: Vec<Vec<usize>> = vec![Vec::new(); top + 1];
        for &i in &order {
            by_level[level[i] as usize].push(i);
        }
        Bands {
            dist,
            parent,
            level,
            by_level,
            min_loop,
        }
    }
}

/// The sweep outwards band by band: its branches, each point's branch and the branch its
/// shortest path arrived through, and the pairs of branches whose loops closed.
struct Sweep {
    branches: Vec<Branch>,
    branch: Vec<usize>,
    /// The branch each point's shortest path arrived through (its lowest-band ancestor's).
    incoming: Vec<usize>,
    component: Vec<usize>,
    merges: Vec<(usize, usize)>,
    stack: Vec<usize>,
}

impl Sweep {
    /// A sweep over `n` points, one branch at the source.
    fn new(n: usize) -> Sweep {
        Sweep {
            branches: vec![Branch {
                parent: None,
                born: 0,
            }],
            branch: vec![usize::MAX; n],
            incoming: vec![usize::MAX; n],
            component: vec![usize::MAX; n],
            merges: Vec::new(),
            stack: Vec::new(),
        }
    }

    /// The components of band `k` (its `nodes`, joined by edges between them), each in order
    /// of distance.
    fn components(&mut self, g: &Graph, bands: &Bands, nodes: &[usize], k: u32) -> Vec<Vec<usize>> {
        let mut comps: Vec<Vec<usize>> = Vec::new();
        for &s in nodes {
            if self.component[s] != usize::MAX {
                continue;
            }
            let id = comps.len();
            self.component[s] = id;
            let mut members = vec![s];
            self.stack.push(s);
            while let Some(i) = self.stack.pop() {
                for (j, _) in g.neighbours(i) {
                    if bands.level[j] == k && self.component[j] == usize::MAX {
                        self.component[j] = id;
                        members.push(j);
                        self.stack.push(j);
                    }
                }
            }
            members.sort_by(|&a, &b| bands.dist[a].total_cmp(&bands.dist[b]));
            comps.push(members);
        }
        comps
    }

    /// Band `k`'s pieces: a component, or the parts of a closing loop, each with the branch
    /// that feeds it; a closing loop's feeding branches are recorded as merged.
    fn pieces(
        &mut self,
        bands: &Bands,
        comps: Vec<Vec<usize>>,
        k: u32,
    ) -> Vec<(usize, Vec<usize>)> {
        let mut pieces: Vec<(usize, Vec<usize>)> = Vec::new();
        for members in comps {
            for &v in &members {
                let p = bands.parent[v];
                self.incoming[v] = if p == u32::MAX {
                    0
                } else if bands.level[p as usize] < k {
                    self.branch[p as usize]
                } else {
                    self.incoming[p as usize]
                };
            }
            let mut feeds: Vec<usize> = members.iter().map(|&v| self.incoming[v]).collect();
            feeds.sort_unstable();
            feeds.dedup();
            let closing = feeds.len() >= 2
                && feeds.iter().skip(1).any(|&b| {
                    k.saturating_sub(parted_at(&self.branches, feeds[0], b)) >= bands.min_loop
                });
            if closing {
                for (a, &fa) in feeds.iter().enumerate() {
                    for &fb in &feeds[a + 1..] {
                        self.merges.push((fa, fb));
                    }
                    pieces.push((
                        fa,
                        members
                            .iter()
                            .copied()
                            .filter(|&v| self.incoming[v] == fa)
                            .collect(),
                    ));
                }
            } else {
                // A short loop (the grid's staircase): the piece goes on as its first feeder.
                pieces.push((feeds[0], members));
            }
        }
        pieces
    }

    /// A branch feeding one piece of band `k` goes on; feeding several, it splits.
    fn grow_branches(&mut self, pieces: &[(usize, Vec<usize>)], k: u32) {
        for (b, members) in pieces {
            let fed = pieces.iter().filter(|(c, _)| c == b).count();
            let id = if fed == 1 {
                *b
            } else {
                self.branches.push(Branch {
                    parent: Some(*b),
                    born: k,
                });
                self.branches.len() - 1
            };
            for &v in members {
                self.branch[v] = id;
            }
        }
    }
}

impl Neighbours {
    /// Opens the graph's loops as seen from the kept point nearest `head`; returns how many
    /// edges were removed (0: no loop).
    pub fn open_handles(&mut self, head: Point3<f64>) -> usize {
        let Some((opened, cut)) = self
            .nearest(head)
            .and_then(|s| cut_handles(self.graph(), s))
        else {
            return 0;
        };
        self.set_opened(opened, cut);
        cut
    }
}

#[cfg(test)]
mod tests {
    use super::super::isomap::{IsomapParams, Neighbourhood, Neighbours, embed_graph};
    use nalgebra::{Point3, Vector3};

    /// A tube of 3 × 3 points per step along `path`.
    fn tube(path: &[Point3<f64>], step: f64) -> Vec<Point3<f64>> {
        let mut pts = Vec::new();
        for c in path {
            for dx in [-1.0, 0.0, 1.0] {
                for dz in [-1.0, 0.0, 1.0] {
                    pts.push(c + Vector3::new(dx, 0.0, dz) * step);
                }
            }
        }
        pts
    }

    fn params(step: f64) -> IsomapParams {
        IsomapParams {
            neighbourhood: Neighbourhood::Radius(step * 1.8),
            landmarks: 10,
        }
    }

    /// A 1 m trunk with a 0.9 m arm leaving its top, hanging down beside it and turning in so
    /// that its hand rests on the trunk's lower end: seen from the top, the loop is opened where
    /// the arm meets the hand, and the arm's lower end is then a whole arm and trunk away from
    /// the trunk's end (geodesically) instead of a hand's width.
    #[test]
    fn a_limb_resting_on_the_body_is_cut_free_where_it_touches() {
        let step = 0.03;
        let mut path = Vec::new();
        let steps = |a: f64| (a / step).round() as usize;
        for i in 0..=steps(1.0) {
            path.push(Point3::new(0.0, 1.0 - i as f64 * step, 0.0)); // trunk, top down
        }
        let trunk_end = path.len() - 1;
        for i in 1..=steps(0.15) {
            path.push(Point3::new(i as f64 * step, 1.0, 0.0)); // shoulder, outwards
        }
        for i in 1..=steps(0.9) {
            path.push(Point3::new(0.15, 1.0 - i as f64 * step, 0.0)); // arm, down
        }
        let arm_end = path.len() - 1;
        for i in 1..steps(0.15) {
            path.push(Point3::new(0.15 - i as f64 * step, 0.1, 0.0)); // hand, inwards
        }
        let pts = tube(&path, step);
        let p = params(step);
        let mut nb = Neighbours::new(&pts, &p).unwrap();
        let before = embed_graph(&nb, &p).unwrap();
        // The tube's centre points are index 9·k + 4.
        let (a, b) = (9 * trunk_end + 4, 9 * arm_end + 4);
        let gap = |e: &super::super::isomap::Embedding| (e.coords[a] - e.coords[b]).norm();
        assert!(gap(&before) < 0.3, "closed loop: {}", gap(&before));
        let cut = nb.open_handles(Point3::new(0.0, 1.0, 0.0));
        assert!(cut > 0);
        let after = embed_graph(&nb, &p).unwrap();
        assert_eq!(after.cut_edges, cut);
        assert!(gap(&after) > 0.6, "opened loop: {}", gap(&after));
    }

    /// A tree (an L-shaped tube with a side branch) has no loop: nothing is cut.
    #[test]
    fn a_tree_is_left_alone() {
        let step = 0.03;
        let mut path: Vec<Point3<f64>> = (0..30)
            .map(|i| Point3::new(0.0, -(i as f64) * step, 0.0))
            .collect();
        path.extend((1..20).map(|i| Point3::new(i as f64 * step, -0.87, 0.0)));
        path.extend((1..15).map(|i| Point3::new(-(i as f64) * step, -0.3, 0.0)));
        let pts = tube(&path, step);
        let mut nb = Neighbours::new(&pts, &params(step)).unwrap();
        assert_eq!(nb.open_handles(Point3::new(0.0, 0.0, 0.0)), 0);
    }
}
