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
    pub(super) fn new(value: f64) -> Row {
        Row {
            value,
            entries: [(0, 0.0); MAX_ENTRIES],
            len: 0,
        }
    }

    /// Adds the partial derivative `d` with respect to unknown `col`.
    pub(super) fn with(mut self, col: usize, d: f64) -> Row {
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

/// The normal equations' matrix JᵀJ in compressed columns, its sparsity pattern (with every
/// diagonal entry) kept from one step to the next: the rows' derivatives touch the same
/// unknowns at every step, so after the first step each product is added in place and the
/// Cholesky factor's structure is reused.
struct NormalMatrix {
    /// JᵀJ (both triangles: the factorization wants a symmetric pattern).
    matrix: CscMatrix<f64>,
    /// Where each column's diagonal entry sits in the values.
    diagonal_at: Vec<usize>,
    /// The factor of the last damped matrix, for its structure.
    factor: Option<CscCholesky<f64>>,
}

impl NormalMatrix {
    /// JᵀJ and Jᵀr at `x` by way of coordinates (the first step, or when a row touched a pair
    /// of unknowns the pattern lacks).
    fn build(problem: &dyn Residuals, x: &DVector<f64>) -> (NormalMatrix, DVector<f64>) {
        let m = x.len();
        let mut jtj = CooMatrix::new(m, m);
        let mut jtr = DVector::<f64>::zeros(m);
        for i in 0..m {
            jtj.push(i, i, 0.0);
        }
        problem.rows(x, &mut |row| {
            let e = &row.entries[..row.len];
            for &(i, di) in e {
                jtr[i] += di * row.value;
                for &(k, dk) in e {
                    jtj.push(i, k, di * dk);
                }
            }
        });
        let matrix = CscMatrix::from(&jtj);
        // Every diagonal entry was pushed, so each column has one (an invariant of the build).
        let diagonal_at = (0..m)
            .map(|k| {
                let (offsets, rows) = (matrix.col_offsets(), matrix.row_indices());
                offsets[k] + rows[offsets[k]..offsets[k + 1]].partition_point(|&r| r < k)
            })
            .collect();
        let normal = NormalMatrix {
            matrix,
            diagonal_at,
            factor: None,
        };
        (normal, jtr)
    }

    /// JᵀJ and Jᵀr at `x` added into the kept pattern; false (the matrix then undefined) when a
    /// row touched a pair of unknowns outside it.
    fn refill(
        &mut self,
        problem: &dyn Residuals,
        x: &DVector<f64>,
        jtr: &mut DVector<f64>,
    ) -> bool {
        jtr.fill(0.0);
        let (offsets, rows, values) = self.matrix.csc_data_mut();
        values.fill(0.0);
        let mut inside = true;
        problem.rows(x, &mut |row| {
            let e = &row.entries[..row.len];
            for &(i, di) in e {
                jtr[i] += di * row.value;
                for &(k, dk) in e {
                    let column = &rows[offsets[k]..offsets[k + 1]];
                    match column.binary_search(&i) {
                        Ok(at) => values[offsets[k] + at] += di * dk,
                        Err(_) => inside = false,
                    }
                }
            }
        });
        inside
    }

    /// Solves (JᵀJ + λ·diag(JᵀJ)) step = Jᵀr; `None` when the damped matrix is not positive
    /// definite.
    fn solve_damped(&mut self, lambda: f64, jtr: &DVector<f64>) -> Option<DMatrix<f64>> {
        let mut damped = self.matrix.values().to_vec();
        for &at in &self.diagonal_at {
            damped[at] += lambda * self.matrix.values()[at].max(1e-9) + 1e-12;
        }
        match &mut self.factor {
            Some(factor) => factor.refactor(&damped).ok()?,
            None => {
                let matrix =
                    CscMatrix::try_from_pattern_and_values(self.matrix.pattern().clone(), damped)
                        .ok()?;
                self.factor = Some(CscCholesky::factor(&matrix).ok()?);
            }
        }
        self.factor.as_ref().map(|f| f.solve(jtr))
    }
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
    let cost_before = problem.cost(&x);
    let mut cost = cost_before;
    let mut lambda = 1e-3;
    let mut iterations = 0;
    let mut normal: Option<NormalMatrix> = None;
    let mut jtr = DVector::<f64>::zeros(x.len());
    while iterations < max_iterations {
        if !before_step(iterations) {
            return None;
        }
        iterations += 1;
        // Normal equations JᵀJ and Jᵀr, accumulated row by row.
        let refilled = normal
            .as_mut()
            .is_some_and(|n| n.refill(problem, &x, &mut jtr));
        let normal = match (refilled, &mut normal) {
            (true, Some(n)) => n,
            _ => {
                let (n, r) = NormalMatrix::build(problem, &x);
                jtr = r;
                normal.insert(n)
            }
        };
        let mut improved = false;
        while lambda < 1e8 {
            let Some(step) = normal.solve_damped(lambda, &jtr) else {
                // Not positive definite: the next try starts the factor afresh.
                normal.factor = None;
                lambda *= 10.0;
                continue;
            };
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

    /// The line, with a row tying its ends together only where the first point is above 1.
    struct Tied(Line);

    impl Residuals for Tied {
        fn rows(&self, x: &DVector<f64>, emit: &mut dyn FnMut(Row)) {
            self.0.rows(x, emit);
            let n = self.0.samples.len() - 1;
            if x[0] > 1.0 {
                emit(Row::new(x[0] - x[n]).with(0, 1.0).with(n, -1.0));
            }
        }
    }

    #[test]
    fn the_kept_pattern_is_refilled_in_place_and_rebuilt_when_a_row_leaves_it() {
        let samples: Vec<f64> = (0..10).map(|i| (i as f64).sin()).collect();
        let tied = Tied(Line { samples });
        let (low, high) = (DVector::zeros(10), DVector::from_element(10, 2.0));
        // Refilled at another point with the same pattern: exactly what a fresh build gives.
        let (mut kept, _) = NormalMatrix::build(&tied, &low);
        let mut jtr = DVector::zeros(10);
        let shifted = DVector::from_element(10, 0.5);
        assert!(kept.refill(&tied, &shifted, &mut jtr));
        let (fresh, fresh_jtr) = NormalMatrix::build(&tied, &shifted);
        assert_eq!(kept.matrix, fresh.matrix);
        assert_eq!(jtr, fresh_jtr);
        // Where the tie appears, its pair of ends is outside the pattern: refused.
        assert!(!kept.refill(&tied, &high, &mut jtr));
        // And the minimisation from there (the pattern changing as the first point crosses 1)
        // still lowers the cost.
        let m = minimise(&tied, high, 20, &mut |_| true).unwrap();
        assert!(
            m.cost_after < 0.2 * m.cost_before,
            "{} {}",
            m.cost_before,
            m.cost_after
        );
    }
}
