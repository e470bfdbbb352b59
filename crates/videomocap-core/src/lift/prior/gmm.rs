//! A Gaussian mixture with full covariances: its density (through each component's Cholesky
//! factor) and its fit by expectation–maximisation from k-means++ seeds.

use serde::{Deserialize, Serialize};

/// One component: weight, mean and the lower Cholesky factor of its covariance (row-major,
/// `dims × dims`, upper part zero).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Component {
    /// Mixing weight (the components' sum to 1).
    pub weight: f64,
    /// Mean.
    pub mean: Vec<f64>,
    /// Lower Cholesky factor `L` of the covariance `L Lᵀ`, row-major.
    pub cov_chol: Vec<f64>,
}

/// A Gaussian mixture over `dims`-vectors, with each component's normalising constant (log)
/// precomputed.
#[derive(Debug, Clone, PartialEq)]
pub struct Gmm {
    pub(crate) dims: usize,
    pub(crate) components: Vec<Component>,
    /// Per component: ln weight − ½ d ln 2π − Σ ln Lᵢᵢ.
    log_norm: Vec<f64>,
}

impl Gmm {
    /// A mixture from its components; `Err` names what is wrong (dimensions, weights, a factor
    /// that is not positive definite, a number that is not finite).
    pub fn new(dims: usize, components: Vec<Component>) -> Result<Gmm, String> {
        if components.is_empty() {
            return Err("a mixture without components".to_owned());
        }
        let mut log_norm = Vec::with_capacity(components.len());
        let mut total = 0.0;
        for (k, c) in components.iter().enumerate() {
            if c.mean.len() != dims || c.cov_chol.len() != dims * dims {
                return Err(format!("component {k}: not {dims} dimensions"));
            }
            if !(c.weight.is_finite() && c.weight > 0.0) {
                return Err(format!(
                    "component {k}: weight {} is not positive",
                    c.weight
                ));
            }
            if c.mean.iter().chain(&c.cov_chol).any(|v| !v.is_finite()) {
                return Err(format!("component {k}: a number that is not finite"));
            }
            let mut log_det = 0.0;
            for i in 0..dims {
                let d = c.cov_chol[i * dims + i];
                if d <= 0.0 {
                    return Err(format!("component {k}: covariance not positive definite"));
                }
                log_det += d.ln();
            }
            total += c.weight;
            log_norm.push(
                c.weight.ln() - 0.5 * dims as f64 * (2.0 * std::f64::consts::PI).ln() - log_det,
            );
        }
        if (total - 1.0).abs() > 1e-3 {
            return Err(format!("weights sum to {total}, not 1"));
        }
        Ok(Gmm {
            dims,
            components,
            log_norm,
        })
    }

    /// The log density at `x` (`x.len() == dims`).
    pub fn log_density(&self, x: &[f64]) -> f64 {
        let mut best = f64::NEG_INFINITY;
        let mut terms = [0.0f64; 64];
        let k = self.components.len().min(terms.len());
        for (i, (c, norm)) in self
            .components
            .iter()
            .zip(&self.log_norm)
            .take(k)
            .enumerate()
        {
            let t = norm - 0.5 * mahalanobis_sq(&c.cov_chol, &c.mean, x, self.dims);
            terms[i] = t;
            best = best.max(t);
        }
        if !best.is_finite() {
            return best;
        }
        best + terms[..k]
            .iter()
            .map(|t| (t - best).exp())
            .sum::<f64>()
            .ln()
    }

    /// The highest log density over the components' means (about the mixture's mode).
    pub fn peak(&self) -> f64 {
        self.components
            .iter()
            .map(|c| self.log_density(&c.mean))
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// (x − μ)ᵀ Σ⁻¹ (x − μ) with Σ = L Lᵀ: forward substitution for L y = x − μ, then |y|².
fn mahalanobis_sq(chol: &[f64], mean: &[f64], x: &[f64], dims: usize) -> f64 {
    let mut y = [0.0f64; 16];
    let mut sum = 0.0;
    for i in 0..dims {
        let mut v = x[i] - mean[i];
        for j in 0..i {
            v -= chol[i * dims + j] * y[j];
        }
        y[i] = v / chol[i * dims + i];
        sum += y[i] * y[i];
    }
    sum
}

/// The lower Cholesky factor of a symmetric `dims × dims` matrix (row-major); `None` if it is
/// not positive definite.
fn cholesky(a: &[f64], dims: usize) -> Option<Vec<f64>> {
    let mut l = vec![0.0; dims * dims];
    for i in 0..dims {
        for j in 0..=i {
            let mut s = a[i * dims + j];
            for k in 0..j {
                s -= l[i * dims + k] * l[j * dims + k];
            }
            if i == j {
                if s <= 0.0 {
                    return None;
                }
                l[i * dims + i] = s.sqrt();
            } else {
                l[i * dims + j] = s / l[j * dims + j];
            }
        }
    }
    Some(l)
}

/// Fits a `k`-component mixture to `data` (each `dims` long) by expectation–maximisation,
/// `iterations` rounds from k-means++ seeds drawn by a fixed linear congruential sequence (so
/// the same data give the same file). `floor` is added to every covariance's diagonal (the
/// directions of unit vectors and of mirrored pairs lie on lower-dimensional sets).
pub fn fit(data: &[Vec<f64>], dims: usize, k: usize, iterations: usize, floor: f64) -> Gmm {
    let n = data.len();
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let dist = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
    // k-means++ seeds.
    let mut means: Vec<Vec<f64>> = vec![data[(next() * n as f64) as usize % n].clone()];
    let mut nearest: Vec<f64> = data.iter().map(|x| dist(x, &means[0])).collect();
    while means.len() < k {
        let total: f64 = nearest.iter().sum();
        let mut pick = next() * total;
        let mut chosen = n - 1;
        for (i, d) in nearest.iter().enumerate() {
            pick -= d;
            if pick <= 0.0 {
                chosen = i;
                break;
            }
        }
        means.push(data[chosen].clone());
        for (d, x) in nearest.iter_mut().zip(data) {
            *d = d.min(dist(x, &data[chosen]));
        }
    }
    let spread = data.iter().map(|x| dist(x, &means[0])).sum::<f64>() / (n * dims) as f64;
    let identity = |s: f64| -> Vec<f64> {
        (0..dims * dims)
            .map(|i| if i % (dims + 1) == 0 { s } else { 0.0 })
            .collect()
    };
    let mut components: Vec<Component> = means
        .into_iter()
        .map(|mean| Component {
            weight: 1.0 / k as f64,
            mean,
            cov_chol: identity(spread.max(floor).sqrt()),
        })
        .collect();
    let mut resp = vec![0.0; n * k];
    for _ in 0..iterations {
        let Ok(gmm) = Gmm::new(dims, components.clone()) else {
            break;
        };
        // E step.
        for (i, x) in data.iter().enumerate() {
            let logs: Vec<f64> = components
                .iter()
                .zip(&gmm.log_norm)
                .map(|(c, norm)| norm - 0.5 * mahalanobis_sq(&c.cov_chol, &c.mean, x, dims))
                .collect();
            let best = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let sum: f64 = logs.iter().map(|l| (l - best).exp()).sum();
            for (j, l) in logs.iter().enumerate() {
                resp[i * k + j] = (l - best).exp() / sum;
            }
        }
        // M step.
        for (j, c) in components.iter_mut().enumerate() {
            let weight: f64 = (0..n).map(|i| resp[i * k + j]).sum();
            if weight < 1e-6 {
                continue;
            }
            let mut mean = vec![0.0; dims];
            for (i, x) in data.iter().enumerate() {
                for (m, v) in mean.iter_mut().zip(x) {
                    *m += resp[i * k + j] * v;
                }
            }
            mean.iter_mut().for_each(|m| *m /= weight);
            let mut cov = identity(floor);
            for (i, x) in data.iter().enumerate() {
                let r = resp[i * k + j] / weight;
                for a in 0..dims {
                    for b in 0..=a {
                        cov[a * dims + b] += r * (x[a] - mean[a]) * (x[b] - mean[b]);
                    }
                }
            }
            for a in 0..dims {
                for b in 0..a {
                    cov[b * dims + a] = cov[a * dims + b];
                }
            }
            if let Some(l) = cholesky(&cov, dims) {
                c.weight = weight / n as f64;
                c.mean = mean;
                c.cov_chol = l;
            }
        }
        let total: f64 = components.iter().map(|c| c.weight).sum();
        components.iter_mut().for_each(|c| c.weight /= total);
    }
    components.retain(|c| c.weight > 1e-9);
    let total: f64 = components.iter().map(|c| c.weight).sum();
    components.iter_mut().for_each(|c| c.weight /= total);
    Gmm::new(dims, components).unwrap_or_else(|_| Gmm {
        dims,
        components: vec![Component {
            weight: 1.0,
            mean: vec![0.0; dims],
            cov_chol: identity(1.0),
        }],
        log_norm: vec![-0.5 * dims as f64 * (2.0 * std::f64::consts::PI).ln()],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One standard normal component: the log density is the textbook one.
    #[test]
    fn a_single_standard_normal_has_the_textbook_density() {
        let g = Gmm::new(
            2,
            vec![Component {
                weight: 1.0,
                mean: vec![0.0, 0.0],
                cov_chol: vec![1.0, 0.0, 0.0, 1.0],
            }],
        )
        .unwrap();
        let want = -(2.0 * std::f64::consts::PI).ln() - 0.5 * (1.0 + 4.0);
        assert!((g.log_density(&[1.0, 2.0]) - want).abs() < 1e-12);
    }

    /// Two clusters far apart: the fit finds both means and gives points between them a lower
    /// density than points at either.
    #[test]
    fn the_fit_finds_two_separate_clusters() {
        let mut data = Vec::new();
        for i in 0..200 {
            let e = (i as f64 * 0.37).sin() * 0.1;
            data.push(vec![-2.0 + e, 1.0 - e]);
            data.push(vec![3.0 - e, -1.0 + e]);
        }
        let g = fit(&data, 2, 2, 30, 1e-4);
        let mut means: Vec<f64> = g.components.iter().map(|c| c.mean[0]).collect();
        means.sort_by(f64::total_cmp);
        assert!((means[0] + 2.0).abs() < 0.05 && (means[1] - 3.0).abs() < 0.05);
        assert!(g.log_density(&[0.5, 0.0]) < g.log_density(&[-2.0, 1.0]) - 10.0);
    }

    /// What a file may hold wrongly is refused with the reason.
    #[test]
    fn a_component_that_is_not_positive_definite_is_refused() {
        let bad = Component {
            weight: 1.0,
            mean: vec![0.0],
            cov_chol: vec![0.0],
        };
        assert!(
            Gmm::new(1, vec![bad])
                .unwrap_err()
                .contains("positive definite")
        );
    }
}
