//! Sparse nonlinear least squares by Levenberg–Marquardt, shared by the key triangle's path
//! ([`super::key_path`]) and the global refinement ([`super::refine`]): both are long chains of
//! frames coupled only to their neighbours, so the normal equations are sparse and are factored
//! with `nalgebra-sparse`'s Cholesky.

use nalgebra::{DMatrix, DVector};
use nalgebra_sparse::factorization::CscCholesky;
use nalgebra_sparse::{CooMatrix, CscMatrix};

/// The time between frames at `fps`, seconds (1/30 s when the rate is unknown): both problems'
/// acceleration terms are second differences over frames.
pub(crate) fn frame_interval_s(fps: f64) -> f64 {
    if fps.is_finite() && fps > 0.0 {
        1.0 / fps
    } else {
        1.0 / 30.0
    }
}

/// Most nonzero partial derivatives in one residual row (the refinement's scale row has one per
/// length: 15 bones and the shoulder width).
pub(crate) const MAX_ENTRIES: usize = 16;

/// One residual row: its value and its nonzero partial derivatives.
pub(crate) struct Row {
    pub value: f64,
    pub entries: [(usize, f64); MAX_ENTRIES],
    pub len: usize,
}

impl Row {
    /// A row with no derivatives yet.
    pub fn new(value: f64) -> Row {
        Row {
            value,
            entries: [(0, 0.0); MAX_ENTRIES],
            len: 0,
        }
    }

    /// Adds the partial derivative `d` with respect to unknown `col`.
    pub fn with(mut self, col: usize, d: f64) -> Row {
        self.entries[self.len] = (col, d);
        self.len += 1;
        self
    }
}

/// A least-squares problem: every residual row at a point.
pub(crate) trait Residuals {
    /// Calls `emit` for every residual row at `x`.
    fn rows(&self, x: &DVector<f64>, emit: &mut dyn FnMut(Row));

    /// The sum of squared residuals at `x`.
    fn cost(&self, x: &DVector<f64>) -> f64 {
        let mut c = 0.0;
        self.rows(x, &mut |r| c += r.value * r.value);
        c
    }
}

/// Where a minimisation ended.
pub(crate) struct Minimum {
    /// The unknowns.
    pub x: DVector<f64>,
    /// Iterations run.
    pub iterations: usize,
    /// The cost at the start.
    pub cost_before: f64,
    /// The cost at `x`.
    pub cost_after: f64,
}

/// Levenberg–Marquardt from `x`, at most `max_iterations` steps, stopping when a step gains
/// less than a millionth of the cost. `before_step(i)` runs before step `i` and stops the
/// minimisation (`None`) when it returns false (a cancel).
pub(crate) fn minimise(
    problem: &dyn Residuals,
    mut x: DVector<f64>,
    max_iterations: usize,
    before_step: &mut dyn FnMut(usize) -> bool,
) -> Option<Minimum> {
    let m = x.len();
    let cost_before = problem.cost(&x);
    let mut cost = cost_before;
    let mut lambda = 1e-3;
    let mut iterations = 0;
    while iterations < max_iterations {
        if !before_step(iterations) {
            return None;
        }
        iterations += 1;
        // Normal equations JᵀJ and Jᵀr, accumulated row by row.
        let mut jtj = CooMatrix::new(m, m);
        let mut jtr = DVector::<f64>::zeros(m);
        problem.rows(&x, &mut |row| {
            let e = &row.entries[..row.len];
            for &(i, di) in e {
                jtr[i] += di * row.value;
                for &(k, dk) in e {
                    jtj.push(i, k, di * dk);
                }
            }
        });
        let jtj = CscMatrix::from(&jtj);
        let diagonal: Vec<f64> = (0..m)
            .map(|i| jtj.get_entry(i, i).map_or(0.0, |e| e.into_value()))
            .collect();
        let mut improved = false;
        while lambda < 1e8 {
            let mut damped = CooMatrix::new(m, m);
            for (i, k, v) in jtj.triplet_iter() {
                damped.push(i, k, *v);
            }
            for (i, d) in diagonal.iter().enumerate() {
                damped.push(i, i, lambda * d.max(1e-9) + 1e-12);
            }
            let Ok(chol) = CscCholesky::factor(&CscMatrix::from(&damped)) else {
                lambda *= 10.0;
                continue;
            };
            let step: DMatrix<f64> = chol.solve(&jtr);
            let candidate = &x - step.column(0);
            let c = problem.cost(&candidate);
            if c.is_finite() && c < cost {
                let gain = (cost - c) / cost.max(1e-300);
                x = candidate;
                cost = c;
                lambda = (lambda / 4.0).max(1e-9);
                improved = gain > 1e-6;
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    Some(Minimum {
        x,
        iterations,
        cost_before,
        cost_after: cost,
    })
}

/// Test support: asserts that every row's analytic partial derivatives at `x` match central
/// finite differences.
#[cfg(test)]
pub(crate) fn assert_rows_match_finite_differences(problem: &dyn Residuals, x: &DVector<f64>) {
    let collect = |x: &DVector<f64>| {
        let mut rows = Vec::new();
        problem.rows(x, &mut |r| rows.push(r));
        rows
    };
    let base = collect(x);
    let mut dense = DMatrix::<f64>::zeros(base.len(), x.len());
    for (r, row) in base.iter().enumerate() {
        for &(c, d) in &row.entries[..row.len] {
            dense[(r, c)] += d;
        }
    }
    for c in 0..x.len() {
        let h = 1e-6;
        let mut xp = x.clone();
        xp[c] += h;
        let mut xm = x.clone();
        xm[c] -= h;
        let (rp, rm) = (collect(&xp), collect(&xm));
        for r in 0..base.len() {
            let numeric = (rp[r].value - rm[r].value) / (2.0 * h);
            let analytic = dense[(r, c)];
            assert!(
                (numeric - analytic).abs() <= 1e-4 * (1.0 + numeric.abs()),
                "row {r} column {c}: analytic {analytic}, numeric {numeric}"
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The points of a line through noisy samples, with a smoothness term between neighbours.
    struct Line {
        samples: Vec<f64>,
    }

    impl Residuals for Line {
        fn rows(&self, x: &DVector<f64>, emit: &mut dyn FnMut(Row)) {
            for (i, s) in self.samples.iter().enumerate() {
                emit(Row::new(x[i] - s).with(i, 1.0));
            }
            for i in 1..self.samples.len() - 1 {
                emit(
                    Row::new(10.0 * (x[i - 1] - 2.0 * x[i] + x[i + 1]))
                        .with(i - 1, 10.0)
                        .with(i, -20.0)
                        .with(i + 1, 10.0),
                );
            }
        }
    }

    #[test]
    fn a_linear_problem_is_solved_and_a_cancel_stops_it() {
        let samples: Vec<f64> = (0..20)
            .map(|i| 0.5 * i as f64 + if i % 2 == 0 { 0.3 } else { -0.3 })
            .collect();
        let line = Line { samples };
        let start = DVector::zeros(20);
        let m = minimise(&line, start.clone(), 20, &mut |_| true).unwrap();
        assert!(m.cost_after < 0.05 * m.cost_before, "{}", m.cost_after);
        // The smoothness term straightens the zigzag: every point within 0.1 of the line.
        for i in 0..20 {
            assert!((m.x[i] - 0.5 * i as f64).abs() < 0.1, "{i}: {}", m.x[i]);
        }
        assert!(minimise(&line, start, 20, &mut |i| i < 1).is_none());
    }
}
