//! The skeleton curve (paper §3): the shell tree refined by `Adjust_Tree_Nodes` (small branches
//! merged or clipped down to five leaves, the root chain merged, the chest and pelvis chains
//! merged into single branch nodes), its five limbs named (§4: the shortest is the head, the two
//! nearest it the arms), and every node carried back to input space by a radial-basis weighted
//! average of its points.

use super::shells::ShellTree;
use nalgebra::{Point3, Vector3};

/// Refinement settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveParams {
    /// A branch this many nodes deep or fewer is "small" (noise, fingers, toes).
    pub small_branch_nodes: usize,
}

impl Default for CurveParams {
    fn default() -> Self {
        CurveParams {
            small_branch_nodes: 3,
        }
    }
}

/// What the skeleton curve of one frame is made of.
#[derive(Debug, Clone)]
pub struct SkeletonCurve {
    /// Curve points in input space, one per live node.
    pub points: Vec<Point3<f64>>,
    /// Parent of each curve point (`None` for the root).
    pub parents: Vec<Option<usize>>,
    /// Embedded-point indices held by each curve point.
    pub members: Vec<Vec<usize>>,
    /// The root (middle of the torso).
    pub root: usize,
    /// The five limbs: curve points from the first one after the branch node out to the leaf.
    pub head: Vec<usize>,
    /// The two arms (arm1, arm2 in the order found; labels are made consistent later). An
    /// empty chain is an arm the curve does not show: it lies against the trunk and its voxels
    /// joined the trunk's (the sequence places it from the neighbouring frames).
    pub arms: [Vec<usize>; 2],
    /// The two legs.
    pub legs: [Vec<usize>; 2],
    /// Branch node the head and arms leave from (chest), and the legs' (pelvis); either may be
    /// the root.
    pub chest: usize,
    /// See `chest`.
    pub pelvis: usize,
}

/// Why a frame has no usable skeleton curve.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CurveProblem {
    #[error(
        "the skeleton curve has {0} leaves after refinement; a body has 5 (head, 2 arms, 2 legs), and 3 or 4 when arms lie against the trunk"
    )]
    WrongLeafCount(usize),
}

/// Leaf counts a frame can be named from: five limbs, or the head and the legs with one or
/// both arms lying against the trunk (their voxels joined it, so the curve has no branch for
/// them).
const LEAF_COUNTS: std::ops::RangeInclusive<usize> = 3..=5;

impl SkeletonCurve {
    /// Arms the curve does not show (0, 1 or 2).
    pub fn arms_unseen(&self) -> usize {
        self.arms.iter().filter(|a| a.is_empty()).count()
    }
}

fn depth(t: &ShellTree, k: usize) -> usize {
    1 + t.nodes[k]
        .children
        .iter()
        .map(|&c| depth(t, c))
        .max()
        .unwrap_or(0)
}

fn leaves_below(t: &ShellTree, k: usize) -> usize {
    if t.nodes[k].children.is_empty() {
        1
    } else {
        t.nodes[k]
            .children
            .iter()
            .map(|&c| leaves_below(t, c))
            .sum()
    }
}

fn subtree(t: &ShellTree, k: usize, out: &mut Vec<usize>) {
    out.push(k);
    for &c in &t.nodes[k].children {
        subtree(t, c, out);
    }
}

/// Moves `from`'s points into `into` and hands its children to `into`.
fn merge_node(t: &mut ShellTree, from: usize, into: usize) {
    let members = std::mem::take(&mut t.nodes[from].members);
    t.nodes[into].members.extend(members);
    let children = std::mem::take(&mut t.nodes[from].children);
    for &c in &children {
        t.nodes[c].parent = Some(into);
    }
    if let Some(p) = t.nodes[from].parent.take() {
        t.nodes[p].children.retain(|&c| c != from);
    }
    t.nodes[into].children.extend(children);
    t.nodes[into].alive = true;
    t.nodes[from].alive = false;
}

/// Removes the subtree at `c`; its points go to its parent (they are still body points).
fn clip_subtree(t: &mut ShellTree, c: usize) {
    let Some(parent) = t.nodes[c].parent else {
        return;
    };
    let mut all = Vec::new();
    subtree(t, c, &mut all);
    for k in all {
        let members = std::mem::take(&mut t.nodes[k].members);
        t.nodes[parent].members.extend(members);
        t.nodes[k].alive = false;
        t.nodes[k].children.clear();
    }
    t.nodes[parent].children.retain(|&x| x != c);
    t.nodes[c].parent = None;
}

fn live_leaves(t: &ShellTree) -> usize {
    leaves_below(t, t.root)
}

/// `Adjust_Tree_Nodes`: prunes the tree in place.
pub fn adjust_tree_nodes(t: &mut ShellTree, params: &CurveParams) {
    let small = params.small_branch_nodes;
    // 1. Clip noise branches and merge the leaves of palms and feet: wherever a node branches,
    //    children whose subtrees are small are merged into one leaf when all of them are small,
    //    and clipped otherwise (smallest first). The paper applies this at nodes with more than
    //    two children; a limb tip that splits in two, or a one-shell bump on the trunk, is as
    //    common in voxel data, so we apply it at every branching node: always to one-node
    //    stubs, and to branches up to `small_branch_nodes` deep while more than five leaves
    //    remain (a head near the embedding's centre can be only three shells long).
    loop {
        let mut order = Vec::new();
        subtree(t, t.root, &mut order);
        let mut merged = false;
        for &n in order.iter().rev() {
            let kids = t.nodes[n].children.clone();
            let limit = if live_leaves(t) > 5 { small } else { 1 };
            if kids.len() >= 2 && kids.iter().all(|&c| depth(t, c) <= limit) {
                // Merge all children of n into one node (a leaf).
                let first = kids[0];
                for &c in &kids {
                    let mut all = Vec::new();
                    subtree(t, c, &mut all);
                    for k in all.into_iter().rev() {
                        if k != first {
                            merge_node(t, k, first);
                        }
                    }
                }
                t.nodes[first].children.clear();
                merged = true;
                break;
            }
        }
        if merged {
            continue;
        }
        // Clip the smallest branch that has a sibling.
        let limit = if live_leaves(t) > 5 { small } else { 1 };
        let candidate = order
            .iter()
            .filter(|&&n| t.nodes[n].children.len() >= 2)
            .flat_map(|&n| t.nodes[n].children.clone())
            .map(|c| (depth(t, c), t.nodes[c].members.len(), c))
            .filter(|(d, _, _)| *d <= limit)
            .min();
        match candidate {
            Some((_, _, c)) => clip_subtree(t, c),
            None => break,
        }
    }
    // 2. Merge root clusters until the first branch.
    while t.nodes[t.root].children.len() == 1 {
        let c = t.nodes[t.root].children[0];
        merge_node(t, c, t.root);
    }
    // 3. Merge the chest and pelvis: every descendant of the root that is an ancestor of two or
    //    more leaves joins its topmost such ancestor (the branch node under the root).
    for c in t.nodes[t.root].children.clone() {
        if leaves_below(t, c) < 2 {
            continue;
        }
        loop {
            let mut all = Vec::new();
            subtree(t, c, &mut all);
            let Some(k) = all.into_iter().find(|&k| k != c && leaves_below(t, k) >= 2) else {
                break;
            };
            merge_node(t, k, c);
        }
    }
}

/// Weighted average of the input positions of `members`, weights a Gaussian of the embedded
/// distance to the members' embedded centroid (σ = half a shell): the radial-basis interpolation
/// of curve points back to input space [Bishop 1995].
fn interpolate(
    members: &[usize],
    coords: &[Vector3<f64>],
    input: &[Point3<f64>],
    sigma: f64,
) -> Point3<f64> {
    if members.is_empty() {
        return Point3::origin();
    }
    let c = members.iter().map(|&i| coords[i]).sum::<Vector3<f64>>() / members.len() as f64;
    let (mut acc, mut wsum) = (Vector3::zeros(), 0.0);
    for &i in members {
        let w = (-(coords[i] - c).norm_squared() / (2.0 * sigma * sigma)).exp();
        acc += input[i].coords * w;
        wsum += w;
    }
    if wsum > 1e-12 {
        Point3::from(acc / wsum)
    } else {
        Point3::from(
            members
                .iter()
                .map(|&i| input[i].coords)
                .sum::<Vector3<f64>>()
                / members.len() as f64,
        )
    }
}

/// Where the head probably is when the curve could not be named (wrong leaf count): the tip
/// of the shortest limb of `tree` (refined by [`adjust_tree_nodes`]), measured in input space
/// through its nodes' centroids. The loop opening (`volume::handles`) starts from there.
pub fn head_tip_guess(tree: &ShellTree, input: &[Point3<f64>]) -> Option<Point3<f64>> {
    let centroid = |k: usize| -> Option<Point3<f64>> {
        let m = &tree.nodes[k].members;
        (!m.is_empty()).then(|| {
            Point3::from(m.iter().map(|&i| input[i].coords).sum::<Vector3<f64>>() / m.len() as f64)
        })
    };
    let mut order = Vec::new();
    subtree(tree, tree.root, &mut order);
    order
        .iter()
        .filter(|&&k| tree.nodes[k].children.is_empty() && k != tree.root)
        .filter_map(|&leaf| {
            let tip = centroid(leaf)?;
            let (mut cur, mut length) = (leaf, 0.0);
            while let Some(p) = tree.nodes[cur].parent {
                length += (centroid(p)? - centroid(cur)?).norm();
                if p == tree.root || leaves_below(tree, p) >= 2 {
                    break;
                }
                cur = p;
            }
            Some((length, tip))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, tip)| tip)
}

/// Names the five limbs, given as (curve points outwards, the point they leave from) with their
/// lengths along the curve: the indices of the head, the two arms and the two legs. Invariant:
/// exactly five limbs, each with at least one curve point (`skeleton_curve` checks the count).
///
/// §4: the shortest branch is the head and the two nearest it the arms. Beyond the paper, when
/// the limbs leave two branch nodes, geometry tells the chest from the pelvis: a limb's reach is
/// its length times the cosine between its leaf direction and the axis pointing away from the
/// other node; the pelvis is the node whose two farthest-reaching limbs reach farther (legs are
/// long and point away from the chest), and those two are the legs. The head is the chest limb
/// that best continues the pelvis→chest axis for its length (cosine − length / longest limb). A
/// third limb at the pelvis is an arm whose hand rests on the hip (it joins the hip there in
/// voxels). With one branch node, or a lone limb at a node: the head is the shortest of three
/// limbs leaving one node when there is such a node (a raised arm can be shorter than the legs
/// but a leg is not), else the shortest; the arms are the limbs leaving the head's node first,
/// then those nearest the head.
fn name_limbs(limbs: &[(Vec<usize>, usize)], length: &[f64], points: &[Point3<f64>]) -> Named {
    let mut nodes: Vec<usize> = limbs.iter().map(|l| l.1).collect();
    nodes.sort_unstable();
    nodes.dedup();
    if let [n0, n1] = nodes[..]
        && let Some(named) = name_at_two_nodes(limbs, length, points, (n0, n1))
    {
        return named;
    }
    name_by_shortest(limbs, length, points, &nodes)
}

/// The limbs of `limbs` attached at `node`.
fn limbs_at(limbs: &[(Vec<usize>, usize)], node: usize) -> Vec<usize> {
    (0..limbs.len()).filter(|&k| limbs[k].1 == node).collect()
}

/// Two branch nodes, each with two limbs or more: the pelvis is the node whose two
/// farthest-reaching limbs reach farther, the head the chest limb that best continues the
/// pelvis→chest axis for its length (see [`name_limbs`]); `None` when a node has fewer limbs
/// or the nodes coincide.
fn name_at_two_nodes(
    limbs: &[(Vec<usize>, usize)],
    length: &[f64],
    points: &[Point3<f64>],
    (n0, n1): (usize, usize),
) -> Option<Named> {
    let at = |node: usize| limbs_at(limbs, node);
    if at(n0).len() < 2 || at(n1).len() < 2 {
        return None;
    }
    let axis = (points[n0] - points[n1]).try_normalize(1e-9)?;
    let tip = |k: usize| points[*limbs[k].0.last().unwrap_or(&limbs[k].1)];
    // cos(k, away): limb k's leaf direction against `away`.
    let cos = |k: usize, away: &Vector3<f64>| {
        (tip(k) - points[limbs[k].1])
            .try_normalize(1e-9)
            .map_or(0.0, |d| d.dot(away))
    };
    // The limbs at `node` by reach away from the other node, farthest first.
    let by_reach = |node: usize, away: Vector3<f64>| {
        let mut g = at(node);
        g.sort_by(|&a, &b| (length[b] * cos(b, &away)).total_cmp(&(length[a] * cos(a, &away))));
        let reach: f64 = g.iter().take(2).map(|&k| length[k] * cos(k, &away)).sum();
        (g, reach)
    };
    let (g0, r0) = by_reach(n0, axis);
    let (g1, r1) = by_reach(n1, -axis);
    let (pelvis, chest, up) = if r0 >= r1 {
        (g0, at(n1), -axis)
    } else {
        (g1, at(n0), axis)
    };
    let longest = length.iter().copied().fold(f64::MIN_POSITIVE, f64::max);
    let continues = |k: usize| cos(k, &up) - length[k] / longest;
    let head = chest
        .iter()
        .copied()
        .max_by(|&a, &b| continues(a).total_cmp(&continues(b)))
        .unwrap_or(chest[0]);
    let mut arms = chest
        .iter()
        .chain(&pelvis[2..])
        .copied()
        .filter(|&k| k != head);
    Some(Named {
        head,
        arms: [arms.next(), arms.next()],
        legs: [pelvis[0], pelvis[1]],
    })
}

/// One branch node, or a lone limb at a node: the head is the shortest of three limbs leaving
/// one of the `nodes` when there is such a node, else the shortest; the arms are the limbs
/// leaving the head's node first, then those nearest the head; the last two the legs.
fn name_by_shortest(
    limbs: &[(Vec<usize>, usize)],
    length: &[f64],
    points: &[Point3<f64>],
    nodes: &[usize],
) -> Named {
    let shortest = |among: &[usize]| {
        among
            .iter()
            .copied()
            .min_by(|&a, &b| length[a].total_cmp(&length[b]))
            .unwrap_or(0)
    };
    let three = nodes
        .iter()
        .map(|&n| limbs_at(limbs, n))
        .find(|g| g.len() == 3);
    let all: Vec<usize> = (0..limbs.len()).collect();
    let head = shortest(three.as_deref().unwrap_or(&all));
    let head_start = points[limbs[head].0[0]];
    let head_attach = limbs[head].1;
    // Limbs leaving the head's branch node first, then by distance from the head.
    let rank = |k: usize| {
        (
            limbs[k].1 != head_attach,
            (points[limbs[k].0[0]] - head_start).norm(),
        )
    };
    let mut rest: Vec<usize> = all.into_iter().filter(|&k| k != head).collect();
    rest.sort_by(|&a, &b| {
        let (ra, rb) = (rank(a), rank(b));
        ra.0.cmp(&rb.0).then(ra.1.total_cmp(&rb.1))
    });
    // The last two are the legs; the ones before them (none, one or two) the arms seen.
    let n = rest.len();
    Named {
        head,
        arms: [
            rest.get(..n - 2).and_then(|a| a.first()).copied(),
            rest.get(..n - 2).and_then(|a| a.get(1)).copied(),
        ],
        legs: [rest[n - 2], rest[n - 1]],
    }
}

/// The limbs named by [`name_limbs`] (indices into its `limbs`); an arm is `None` when the curve
/// does not show it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Named {
    head: usize,
    arms: [Option<usize>; 2],
    legs: [usize; 2],
}

/// Names the limbs of `tree` (refined by [`adjust_tree_nodes`]). `coords` are the embedded
/// points, `input` their input positions (same indexing).
pub fn skeleton_curve(
    tree: &ShellTree,
    coords: &[Vector3<f64>],
    input: &[Point3<f64>],
) -> Result<SkeletonCurve, CurveProblem> {
    let leaves = live_leaves(tree);
    if !LEAF_COUNTS.contains(&leaves) {
        return Err(CurveProblem::WrongLeafCount(leaves));
    }
    // Live nodes → curve points.
    let mut order = Vec::new();
    subtree(tree, tree.root, &mut order);
    let mut index = vec![usize::MAX; tree.nodes.len()];
    for (i, &k) in order.iter().enumerate() {
        index[k] = i;
    }
    let sigma = tree.shell_width * 0.5;
    let points: Vec<Point3<f64>> = order
        .iter()
        .map(|&k| interpolate(&tree.nodes[k].members, coords, input, sigma))
        .collect();
    let parents: Vec<Option<usize>> = order
        .iter()
        .map(|&k| tree.nodes[k].parent.map(|p| index[p]))
        .collect();
    let members: Vec<Vec<usize>> = order
        .iter()
        .map(|&k| tree.nodes[k].members.clone())
        .collect();
    let mut limbs = leaf_limbs(tree, &order, &index);
    let length = |(chain, attach): &(Vec<usize>, usize)| {
        let mut prev = points[*attach];
        chain.iter().fold(0.0, |acc, &i| {
            let d = (points[i] - prev).norm();
            prev = points[i];
            acc + d
        })
    };
    // §4: the shortest branch is the head and the two nearest it the arms. Beyond the paper:
    // see `name_limbs`.
    if !LEAF_COUNTS.contains(&limbs.len()) {
        return Err(CurveProblem::WrongLeafCount(limbs.len()));
    }
    let lengths: Vec<f64> = limbs.iter().map(length).collect();
    let named = name_limbs(&limbs, &lengths, &points);
    let mut take = |k: usize| std::mem::take(&mut limbs[k]);
    let (head, leg1, leg2) = (take(named.head), take(named.legs[0]), take(named.legs[1]));
    let arms = named.arms.map(|a| a.map(|k| take(k).0).unwrap_or_default());
    Ok(SkeletonCurve {
        root: index[tree.root],
        chest: head.1,
        pelvis: leg1.1,
        head: head.0,
        arms,
        legs: [leg1.0, leg2.0],
        points,
        parents,
        members,
    })
}

/// The limbs of `tree`: from each leaf up to (not including) the first node with two or more
/// leaves below it (or the root), each as its chain outwards and its attachment (indices of
/// curve points: `index` maps tree nodes to them, `order` lists the live nodes).
fn leaf_limbs(tree: &ShellTree, order: &[usize], index: &[usize]) -> Vec<(Vec<usize>, usize)> {
    let mut limbs: Vec<(Vec<usize>, usize)> = Vec::new();
    for &k in order {
        if !tree.nodes[k].children.is_empty() {
            continue;
        }
        let mut chain = vec![index[k]];
        let mut cur = k;
        let attach = loop {
            match tree.nodes[cur].parent {
                Some(p) if p != tree.root && leaves_below(tree, p) < 2 => {
                    chain.push(index[p]);
                    cur = p;
                }
                Some(p) => break index[p],
                None => break index[cur],
            }
        };
        chain.reverse();
        limbs.push((chain, attach));
    }
    limbs
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names limbs given as (leaf, branch node) pairs; node 0 is the chest and node 1 the
    /// pelvis, at shoulder and hip height of a standing 1.75 m body.
    fn named(leaves: &[(f64, f64, usize)]) -> [usize; 5] {
        let mut points = vec![Point3::new(0.0, 1.3, 0.0), Point3::new(0.0, 0.9, 0.0)];
        let mut limbs = Vec::new();
        let mut lengths = Vec::new();
        for &(x, y, attach) in leaves {
            points.push(Point3::new(x, y, 0.0));
            limbs.push((vec![points.len() - 1], attach));
            lengths.push((points[points.len() - 1] - points[attach]).norm());
        }
        let n = name_limbs(&limbs, &lengths, &points);
        let none = usize::MAX;
        [
            n.head,
            n.arms[0].unwrap_or(none),
            n.arms[1].unwrap_or(none),
            n.legs[0],
            n.legs[1],
        ]
    }

    fn sorted(mut v: [usize; 2]) -> [usize; 2] {
        v.sort_unstable();
        v
    }

    #[test]
    fn a_hand_stub_at_the_hip_is_not_the_head() {
        // Head, a raised arm, two legs, and the other hand, which joins the hip in voxels: its
        // stub leaves the pelvis node and is the shortest limb (the paper's rule names it head).
        let n = named(&[
            (0.0, 1.65, 0),
            (-0.5, 1.7, 0),
            (0.12, 0.05, 1),
            (-0.12, 0.05, 1),
            (0.25, 0.8, 1),
        ]);
        assert_eq!(n[0], 0, "head");
        assert_eq!(sorted([n[1], n[2]]), [1, 4], "arms");
        assert_eq!(sorted([n[3], n[4]]), [2, 3], "legs");
    }

    #[test]
    fn arms_overhead_leave_the_head_and_legs_alone() {
        // Jumping jacks at the top: both arms up beside the head, legs apart.
        let n = named(&[
            (-0.3, 1.95, 0),
            (0.0, 1.65, 0),
            (0.3, 1.95, 0),
            (0.25, 0.05, 1),
            (-0.25, 0.05, 1),
        ]);
        assert_eq!(n[0], 1, "head");
        assert_eq!(sorted([n[1], n[2]]), [0, 2], "arms");
        assert_eq!(sorted([n[3], n[4]]), [3, 4], "legs");
    }
}
