//! A small damped Gauss–Newton (Levenberg–Marquardt) solver for the fixed-size systems of the
//! calibration (eq. 9, six unknowns) and the key-joint depths (eqs. 10–11, three unknowns).
//!
//! The paper solves eq. 9 with Newton's method and eqs. 10–11 with "the grads method"; damping
//! keeps both from diverging when the start is far, and the normal equations let the same code
//! serve over-determined systems. Left to nalgebra's dense Cholesky: no crate offers a
//! fixed-size, allocation-free LM for closures over nalgebra types.

use nalgebra::{SMatrix, SVector};

/// Result of a solve.
#[derive(Debug, Clone, Copy)]
pub(super) struct Solved<S> {
    /// The best state found.
    pub state: S,
    /// Residual vector norm at that state.
    pub residual_norm: f64,
}

/// Minimises `|r(s)|²` from `start`. `eval` gives residuals and their Jacobian with respect to
/// the step parameters; `step` applies a step.
pub(super) fn levenberg_marquardt<S: Clone, const R: usize, const P: usize>(
    start: S,
    eval: impl Fn(&S) -> (SVector<f64, R>, SMatrix<f64, R, P>),
    step: impl Fn(&S, &SVector<f64, P>) -> S,
    max_iterations: usize,
) -> Solved<S> {
    let mut state = start;
    let (mut r, mut j) = eval(&state);
    let mut cost = r.norm_squared();
    let mut lambda = 1e-4;
    let mut iterations = 0;
    while iterations < max_iterations && cost.is_finite() {
        iterations += 1;
        let h = j.transpose() * j;
        let g = j.transpose() * r;
        let mut accepted = false;
        while lambda < 1e12 {
            let mut a = h;
            for k in 0..P {
                a[(k, k)] += lambda * h[(k, k)].max(1e-12);
            }
            let Some(chol) = a.cholesky() else {
                lambda *= 10.0;
                continue;
            };
            let delta = -chol.solve(&g);
            let candidate = step(&state, &delta);
            let (r2, j2) = eval(&candidate);
            let c2 = r2.norm_squared();
            if c2.is_finite() && c2 < cost {
                let small = delta.norm() < 1e-12 || cost - c2 < 1e-15 * cost.max(1e-300);
                state = candidate;
                r = r2;
                j = j2;
                cost = c2;
                lambda = (lambda / 4.0).max(1e-9);
                accepted = !small;
                break;
            }
            lambda *= 4.0;
        }
        if !accepted || cost < 1e-24 {
            break;
        }
    }
    Solved {
        state,
        residual_norm: cost.sqrt(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    #[test]
    fn solves_a_small_nonlinear_system() {
        // x² + y² = 4, x − y = 0 → (√2, √2) from (1, 0.5).
        let s = levenberg_marquardt(
            Vector2::new(1.0, 0.5),
            |p: &Vector2<f64>| {
                (
                    Vector2::new(p.x * p.x + p.y * p.y - 4.0, p.x - p.y),
                    Matrix2::new(2.0 * p.x, 2.0 * p.y, 1.0, -1.0),
                )
            },
            |p, d| p + d,
            50,
        );
        assert!(s.residual_norm < 1e-10);
        assert!((s.state.x - 2f64.sqrt()).abs() < 1e-9);
    }
}
