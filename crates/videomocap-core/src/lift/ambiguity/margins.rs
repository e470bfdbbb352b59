//! How sure each root choice is: the min-marginals of the clip-wide choice. For every frame and
//! candidate, the least total the whole sequence can reach with that frame held at that
//! candidate (the forward pass of [`super::viterbi`] met by the same pass run backwards), so a
//! bone's margin on a frame is what taking its other root there would cost the clip at best.

use super::Candidate;
use super::viterbi::{acceleration, first_pair, forward_step};

/// Per frame and candidate, the least total of the sequence with that frame at that candidate
/// (the same costs as [`super::viterbi`]: unaries, the first two frames' velocity, squared
/// accelerations).
pub(super) fn min_marginals(candidates: &[Vec<Candidate>]) -> Vec<Vec<f64>> {
    let n = candidates.len();
    if n < 2 {
        return candidates
            .iter()
            .map(|c| c.iter().map(|x| x.unary).collect())
            .collect();
    }
    let k = candidates[0].len();
    let pair = |a: usize, b: usize| a * k + b;
    // forward[t][a·k + b]: the best total of frames 0..=t with t−1 at a and t at b (t ≥ 1).
    let mut forward: Vec<Vec<f64>> = vec![Vec::new(); n];
    forward[1] = first_pair(candidates);
    for t in 2..n {
        forward[t] = forward_step(candidates, t, &forward[t - 1]).0;
    }
    // backward[t][a·k + b]: the best total of frames t+1.. given t−1 at a and t at b.
    let mut backward: Vec<Vec<f64>> = vec![vec![0.0; k * k]; n];
    for t in (1..n - 1).rev() {
        let mut here = vec![f64::INFINITY; k * k];
        for a in 0..k {
            for b in 0..k {
                for c in 0..k {
                    let cc = &candidates[t + 1][c];
                    let total = cc.unary
                        + acceleration(&candidates[t - 1][a], &candidates[t][b], cc)
                        + backward[t + 1][pair(b, c)];
                    here[pair(a, b)] = here[pair(a, b)].min(total);
                }
            }
        }
        backward[t] = here;
    }
    let mut out = vec![vec![f64::INFINITY; k]; n];
    for t in 1..n {
        for a in 0..k {
            for b in 0..k {
                let total = forward[t][pair(a, b)] + backward[t][pair(a, b)];
                out[t][b] = out[t][b].min(total);
                if t == 1 {
                    out[0][a] = out[0][a].min(total);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::viterbi::{VELOCITY_WEIGHT, test_candidate as cand, viterbi};
    use super::*;

    /// Brute force over every path: each frame's min-marginal is the best path through it, and
    /// the chosen path's candidates reach the optimum itself.
    #[test]
    fn min_marginals_are_the_best_path_through_each_candidate() {
        let frames: Vec<Vec<Candidate>> = [
            [(0.0, 0.1), (0.5, 0.0)],
            [(0.1, 0.0), (0.4, 0.2)],
            [(0.2, 0.3), (0.3, 0.0)],
            [(0.3, 0.0), (0.2, 0.1)],
            [(0.4, 0.2), (0.1, 0.0)],
        ]
        .iter()
        .map(|f| f.iter().map(|&(x, u)| cand(x, u)).collect())
        .collect();
        let n = frames.len();
        let cost = |path: &[usize]| -> f64 {
            let mut c: f64 = path
                .iter()
                .enumerate()
                .map(|(t, &s)| frames[t][s].unary)
                .sum();
            c += VELOCITY_WEIGHT
                * (frames[1][path[1]].absolute[0] - frames[0][path[0]].absolute[0]).norm_squared();
            for t in 2..n {
                c += acceleration(
                    &frames[t - 2][path[t - 2]],
                    &frames[t - 1][path[t - 1]],
                    &frames[t][path[t]],
                );
            }
            c
        };
        let paths: Vec<Vec<usize>> = (0..1usize << n)
            .map(|m| (0..n).map(|t| m >> t & 1).collect())
            .collect();
        let marginals = min_marginals(&frames);
        for (t, here) in marginals.iter().enumerate() {
            for (s, &m) in here.iter().enumerate() {
                let best = paths
                    .iter()
                    .filter(|p| p[t] == s)
                    .map(|p| cost(p))
                    .fold(f64::INFINITY, f64::min);
                assert!((m - best).abs() < 1e-12, "{t} {s}");
            }
        }
        let (path, total) = viterbi(&frames);
        for (t, &s) in path.iter().enumerate() {
            assert!((marginals[t][s] - total).abs() < 1e-12);
        }
    }
}
