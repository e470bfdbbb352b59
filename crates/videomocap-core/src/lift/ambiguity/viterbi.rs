//! The clip-wide choice of each group's candidates: Viterbi over pairs of consecutive choices,
//! least unary cost plus squared 3D acceleration of the joints.

use super::Candidate;

/// Squared second difference of the candidates' camera-space positions at three frames.
///
/// A hand or a knee carries its own momentum: it moves smoothly in space, not only relative to
/// the shoulder or hip it hangs from (which the key triangle's and the spine's choices move).
/// It was measured relative to the group's root joint before; `bench lift` (refined; before →
/// after) from exact 2D with true lengths 11.0 → 10.9 mm, wrong roots 868 → 828 bone-frames
/// (4.4 → 4.2 %; dance_oblique 151 → 132, jumping_jacks_frontal 42 → 26), on the reference's
/// key triangle 3.9 → 3.2 %; 2 px noise 46.7 → 46.0 (from the height 61.3 → 60.9); from the
/// tracker 83.0 → 82.0 (from the height 89.1 → 88.7); the real sample unchanged but from its
/// exact 2D and the height, 97.2 → 98.8. Half relative and half absolute gave 826 wrong roots;
/// absolute scaled by 0.5 / 0.7 / 1.4 / 2 against the priors, 887 / 900 / 899 / 966.
///
/// It is per frame, not per second: scaled to physical units by (fps/30)^k for k = 1 / 2 / 4
/// the suite's wrong roots went 722 → 786 / 852 / 1034 (walk_toward_frontal at 60 frames/s
/// 63 → 138–140), for k = −0.5 / −1 to 755 / 768. Weighed ×10 / ×100 / ×1000 where the
/// group's first bone has its two roots under 5 mm apart: 770 / 845 / 909.
pub(super) fn acceleration(a: &Candidate, b: &Candidate, c: &Candidate) -> f64 {
    (0..2)
        .map(|k| {
            (c.absolute[k].coords - b.absolute[k].coords * 2.0 + a.absolute[k].coords)
                .norm_squared()
        })
        .sum()
}

/// Weight of the squared velocity between the first two frames (only matters for two-frame
/// clips, where there is no acceleration).
pub(super) const VELOCITY_WEIGHT: f64 = 0.01;

/// The best totals of the first two frames, `[a·k + b]` with frame 0 at `a` and frame 1 at `b`
/// (their unaries and the velocity between them). Needs two frames or more.
pub(super) fn first_pair(candidates: &[Vec<Candidate>]) -> Vec<f64> {
    let k = candidates[0].len();
    let mut cost = vec![f64::INFINITY; k * k];
    for a in 0..k {
        for b in 0..k {
            let (ca, cb) = (&candidates[0][a], &candidates[1][b]);
            let v: f64 = (0..2)
                .map(|i| (cb.absolute[i] - ca.absolute[i]).norm_squared())
                .sum();
            cost[a * k + b] = ca.unary + cb.unary + VELOCITY_WEIGHT * v;
        }
    }
    cost
}

/// One step of the second-order Viterbi: from the best totals `cost[a·k + b]` of frames
/// `t − 2`, `t − 1`, those of frames `t − 1`, `t` (`[b·k + c]`), with the `a` each came from.
pub(super) fn forward_step(
    candidates: &[Vec<Candidate>],
    t: usize,
    cost: &[f64],
) -> (Vec<f64>, Vec<usize>) {
    let k = candidates[t].len();
    let mut next = vec![f64::INFINITY; k * k];
    let mut from = vec![0usize; k * k];
    for b in 0..k {
        for c in 0..k {
            let cc = &candidates[t][c];
            for a in 0..k {
                let prev = cost[a * k + b];
                if !prev.is_finite() {
                    continue;
                }
                let total = prev
                    + cc.unary
                    + acceleration(&candidates[t - 2][a], &candidates[t - 1][b], cc);
                if total < next[b * k + c] {
                    next[b * k + c] = total;
                    from[b * k + c] = a;
                }
            }
        }
    }
    (next, from)
}

/// The sequence of candidate indices minimising priors plus squared accelerations.
pub(super) fn viterbi(candidates: &[Vec<Candidate>]) -> (Vec<usize>, f64) {
    let n = candidates.len();
    let best_single = |t: usize| {
        (0..candidates[t].len())
            .min_by(|&a, &b| candidates[t][a].unary.total_cmp(&candidates[t][b].unary))
            .unwrap_or(0)
    };
    if n < 2 {
        let path: Vec<usize> = (0..n).map(best_single).collect();
        let cost = path
            .iter()
            .enumerate()
            .map(|(t, &c)| candidates[t][c].unary)
            .sum();
        return (path, cost);
    }
    let k = candidates[0].len();
    // cost[a * k + b]: best total with frame t−1 at a and frame t at b.
    let mut cost = first_pair(candidates);
    let mut back: Vec<Vec<usize>> = Vec::with_capacity(n);
    for t in 2..n {
        let (next, from) = forward_step(candidates, t, &cost);
        cost = next;
        back.push(from);
    }
    let end = (0..k * k)
        .min_by(|&x, &y| cost[x].total_cmp(&cost[y]))
        .unwrap_or(0);
    let mut path = vec![0usize; n];
    path[n - 2] = end / k;
    path[n - 1] = end % k;
    for t in (2..n).rev() {
        path[t - 2] = back[t - 2][path[t - 1] * k + path[t]];
    }
    (path, cost[end])
}

/// A candidate whose first child sits at `x` on a line, for the Viterbi tests.
#[cfg(test)]
pub(super) fn test_candidate(x: f64, unary: f64) -> Candidate {
    Candidate {
        absolute: [
            nalgebra::Point3::new(x, 0.0, 0.0),
            nalgebra::Point3::origin(),
        ],
        too_long: [false; 2],
        unary,
        steer: 0.0,
        nats: 0.0,
    }
}
