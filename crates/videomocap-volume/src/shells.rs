//! Nonlinear spherical shells (paper §3, Fig. 3–4): concentric shells around the embedding's
//! origin, bounding-box clustering inside each shell, and links between overlapping clusters of
//! neighbouring shells, giving a tree of principal-curve points.

use nalgebra::Vector3;
use std::collections::HashMap;

/// Shell settings (the paper's values are the defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShellParams {
    /// Number of concentric shells (paper: 25).
    pub shells: usize,
    /// Clustering threshold as a fraction of the embedding's bounding-box diagonal (paper: 1/25).
    pub cluster_fraction: f64,
}

impl Default for ShellParams {
    fn default() -> Self {
        ShellParams {
            shells: 25,
            cluster_fraction: 1.0 / 25.0,
        }
    }
}

/// One cluster of one shell: a node of the principal-curve tree.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Indices of the embedded points in the cluster (merged nodes hold the union).
    pub members: Vec<usize>,
    /// Shell index (0 = innermost); a merged node keeps the innermost.
    pub shell: usize,
    /// Parent node, `None` for the root and for removed nodes.
    pub parent: Option<usize>,
    /// Child nodes.
    pub children: Vec<usize>,
    /// False once merged into another node or clipped.
    pub alive: bool,
}

/// The tree of shell clusters, rooted at the innermost shell's largest cluster.
#[derive(Debug, Clone)]
pub struct ShellTree {
    /// All nodes ever made (see [`Node::alive`]).
    pub nodes: Vec<Node>,
    /// The root node.
    pub root: usize,
    /// Width of one shell in the embedding.
    pub shell_width: f64,
    /// The clustering threshold used.
    pub threshold: f64,
    /// Embedded points that no cluster reachable from the root holds (ghosts, far noise).
    pub unreached: usize,
}

/// Small union–find over point indices.
struct Sets(Vec<u32>);

impl Sets {
    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] as usize != i {
            let p = self.0[i] as usize;
            self.0[i] = self.0[p];
            i = p;
        }
        i
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb)] = ra.min(rb) as u32;
        }
    }
}

/// Builds the shell tree of embedded points (centred at the origin): each point's shell,
/// the shells' clusters, the clusters as nodes linked across neighbouring shells, and the tree
/// grown from the root.
pub fn build(coords: &[Vector3<f64>], params: &ShellParams) -> ShellTree {
    let shells = params.shells.max(2);
    let radius: Vec<f64> = coords.iter().map(|c| c.norm()).collect();
    let r_max = radius.iter().copied().fold(0.0, f64::max).max(1e-12);
    let shell_of: Vec<usize> = radius
        .iter()
        .map(|r| ((r / r_max * shells as f64) as usize).min(shells - 1))
        .collect();
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for c in coords {
        lo = lo.inf(c);
        hi = hi.sup(c);
    }
    let threshold = ((hi - lo).norm() * params.cluster_fraction).max(1e-12);
    let grouping = Grouping::new(coords, &shell_of, threshold);
    let (mut sets, cross) = grouping.join(threshold);
    let (mut nodes, links) = grouping.nodes(&mut sets, cross);
    let (root, unreached) = grow_tree(&mut nodes, &links, coords.len());
    ShellTree {
        nodes,
        root,
        shell_width: r_max / shells as f64,
        threshold,
        unreached,
    }
}

/// The points of one shell inside one grid cell of side `threshold`: all within the threshold
/// of each other, with their bounding box.
struct Group {
    key: [i64; 3],
    shell: usize,
    lo: Vector3<f64>,
    hi: Vector3<f64>,
    members: Vec<usize>,
}

/// Bounding-box clustering (Cohen et al.'s boxes): the points grouped by shell and grid cell;
/// groups of the same shell in neighbouring cells join one cluster when their boxes are no
/// farther apart than the threshold (Chebyshev gap), and groups of neighbouring shells that
/// close link their clusters. Working on boxes instead of point pairs keeps this linear in the
/// number of points.
struct Grouping {
    groups: Vec<Group>,
    /// Each (cell, shell)'s group.
    group_of: HashMap<([i64; 3], usize), usize>,
}

impl Grouping {
    /// Groups the points by their shell (`shell_of`) and their cell of side `threshold`.
    fn new(coords: &[Vector3<f64>], shell_of: &[usize], threshold: f64) -> Grouping {
        let cell = |c: &Vector3<f64>| {
            [
                (c.x / threshold).floor() as i64,
                (c.y / threshold).floor() as i64,
                (c.z / threshold).floor() as i64,
            ]
        };
        let mut group_of: HashMap<([i64; 3], usize), usize> = HashMap::new();
        let mut groups: Vec<Group> = Vec::new();
        for (i, c) in coords.iter().enumerate() {
            let key = cell(c);
            let g = *group_of.entry((key, shell_of[i])).or_insert_with(|| {
                groups.push(Group {
                    key,
                    shell: shell_of[i],
                    lo: *c,
                    hi: *c,
                    members: Vec::new(),
                });
                groups.len() - 1
            });
            let gr = &mut groups[g];
            gr.lo = gr.lo.inf(c);
            gr.hi = gr.hi.sup(c);
            gr.members.push(i);
        }
        Grouping { groups, group_of }
    }

    /// Joins the groups of one shell within `threshold` of each other into clusters, and
    /// lists the pairs of groups of neighbouring shells that close.
    fn join(&self, threshold: f64) -> (Sets, Vec<(usize, usize)>) {
        let gap = |a: &Group, b: &Group| {
            (0..3)
                .map(|k| (b.lo[k] - a.hi[k]).max(a.lo[k] - b.hi[k]).max(0.0))
                .fold(0.0, f64::max)
        };
        let mut sets = Sets((0..self.groups.len() as u32).collect());
        let mut cross: Vec<(usize, usize)> = Vec::new();
        for (a, ga) in self.groups.iter().enumerate() {
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let key = [ga.key[0] + dx, ga.key[1] + dy, ga.key[2] + dz];
                        for shell in ga.shell.saturating_sub(1)..=ga.shell + 1 {
                            let Some(&b) = self.group_of.get(&(key, shell)) else {
                                continue;
                            };
                            if b <= a || gap(ga, &self.groups[b]) > threshold {
                                continue;
                            }
                            if shell == ga.shell {
                                sets.union(a, b);
                            } else {
                                cross.push((a, b));
                            }
                        }
                    }
                }
            }
        }
        (sets, cross)
    }

    /// The clusters as nodes (none alive yet), and each node's links to overlapping clusters
    /// of neighbouring shells (Fig. 4), from the groups' pairs `cross`.
    fn nodes(&self, sets: &mut Sets, cross: Vec<(usize, usize)>) -> (Vec<Node>, Vec<Vec<usize>>) {
        let mut node_of_root: HashMap<usize, usize> = HashMap::new();
        let mut nodes: Vec<Node> = Vec::new();
        let mut node_of_group = vec![0usize; self.groups.len()];
        for (g, group) in self.groups.iter().enumerate() {
            let r = sets.find(g);
            let id = *node_of_root.entry(r).or_insert_with(|| {
                nodes.push(Node {
                    members: Vec::new(),
                    shell: group.shell,
                    parent: None,
                    children: Vec::new(),
                    alive: false,
                });
                nodes.len() - 1
            });
            nodes[id].members.extend_from_slice(&group.members);
            node_of_group[g] = id;
        }
        let mut links: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
        for (a, b) in cross {
            let (na, nb) = (node_of_group[a], node_of_group[b]);
            if na != nb && !links[na].contains(&nb) {
                links[na].push(nb);
                links[nb].push(na);
            }
        }
        (nodes, links)
    }
}

/// The tree by breadth-first search over `links` from the root, the largest cluster of the
/// innermost non-empty shell (a cluster reached twice keeps its first parent): (the root, how
/// many of the `n` points no reached cluster holds).
fn grow_tree(nodes: &mut [Node], links: &[Vec<usize>], n: usize) -> (usize, usize) {
    let inner = nodes.iter().map(|c| c.shell).min().unwrap_or(0);
    let root = (0..nodes.len())
        .filter(|&k| nodes[k].shell == inner)
        .max_by_key(|&k| nodes[k].members.len())
        .unwrap_or(0);
    let mut unreached = n;
    if !nodes.is_empty() {
        nodes[root].alive = true;
        let mut queue = std::collections::VecDeque::from([root]);
        while let Some(k) = queue.pop_front() {
            unreached -= nodes[k].members.len();
            let mut next = links[k].clone();
            next.sort_unstable();
            for m in next {
                if !nodes[m].alive {
                    nodes[m].alive = true;
                    nodes[m].parent = Some(k);
                    nodes[k].children.push(m);
                    queue.push_back(m);
                }
            }
        }
    }
    (root, unreached)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A "da Vinci" star: five arms of points leaving the origin give a root with five chains.
    #[test]
    fn a_star_gives_five_chains_from_the_root() {
        let dirs = [
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 0.3, 0.0),
            Vector3::new(-1.0, 0.3, 0.0),
            Vector3::new(0.4, -1.0, 0.0),
            Vector3::new(-0.4, -1.0, 0.0),
        ];
        let mut pts = Vec::new();
        for d in dirs {
            let d = d.normalize();
            for k in 0..100 {
                pts.push(d * (k as f64 * 0.01));
            }
        }
        let t = build(&pts, &ShellParams::default());
        assert_eq!(t.unreached, 0);
        let leaves = t
            .nodes
            .iter()
            .filter(|n| n.alive && n.children.is_empty())
            .count();
        assert_eq!(leaves, 5);
        assert_eq!(t.nodes[t.root].shell, 0);
    }
}
