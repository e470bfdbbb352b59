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

/// A Gaussian mixture over `dims`-vectors, with what its density needs precomputed per
/// component and packed in one slice (no allocation when it is evaluated): the normalising
/// constant's log, the mean, and the inverse of the covariance's Cholesky factor.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Gmm {
    pub(crate) dims: usize,
    pub(crate) components: Vec<Component>,
    /// Per component [`Gmm::stride`] numbers: ln weight − ½ d ln 2π − Σ ln Lᵢᵢ (the log of the
    /// weight over the normalising constant, the log-determinant taken from the factor's
    /// diagonal), the mean (`dims`), then `L⁻¹` (lower triangular, row by row, `dims (dims + 1)
    /// / 2`), so that (x − μ)ᵀ Σ⁻¹ (x − μ) = |L⁻¹ (x − μ)|².
    packed: Vec<f64>,
}

/// How far (nats) below the best term so far a component's term may be left out of the
/// log-sum-exp: e^−37 ≈ 8.5·10⁻¹⁷ is under half the spacing of doubles at the running sum (at
/// least 1), so adding it would leave the sum's bits unchanged.
const NEGLIGIBLE: f64 = 37.0;

/// The most dimensions a mixture may have (the pose prior's largest group has 9).
pub(super) const MAX_DIMS: usize = 16;

impl Gmm {
    /// A mixture from its components; `Err` names what is wrong (dimensions, weights, a factor
    /// that is not positive definite, a number that is not finite).
    pub(crate) fn new(dims: usize, components: Vec<Component>) -> Result<Gmm, String> {
        if components.is_empty() {
            return Err("a mixture without components".to_owned());
        }
        if dims == 0 || dims > MAX_DIMS {
            return Err(format!("{dims} dimensions (1 to {MAX_DIMS})"));
        }
        let mut packed = Vec::with_capacity(components.len() * stride(dims));
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
            let inverse = lower_inverse(&c.cov_chol, dims);
            if inverse.iter().any(|v| !v.is_finite()) {
                return Err(format!("component {k}: covariance not invertible"));
            }
            total += c.weight;
            packed.push(
                c.weight.ln() - 0.5 * dims as f64 * (2.0 * std::f64::consts::PI).ln() - log_det,
            );
            packed.extend_from_slice(&c.mean);
            for i in 0..dims {
                packed.extend_from_slice(&inverse[i * dims..i * dims + i + 1]);
            }
        }
        if (total - 1.0).abs() > 1e-3 {
            return Err(format!("weights sum to {total}, not 1"));
        }
        Ok(Gmm {
            dims,
            components,
            packed,
        })
    }

    /// The log density at `x` (`x.len() == dims`): the components' terms ln(weight · N(x; μ,
    /// Σ)) summed in order by a running log-sum-exp. A component is left off as soon as its
    /// Mahalanobis sum, accumulated row by row of `L⁻¹ (x − μ)` (it only grows), puts its term
    /// more than [`NEGLIGIBLE`] below the best so far: added, it would not have changed the
    /// running sum's bits (so the result is the same as the full sum's, to the bit; checked in
    /// a test against [`Gmm::log_density_full`]).
    pub(crate) fn log_density(&self, x: &[f64]) -> f64 {
        let dims = self.dims;
        let mut total = LogSumExp::default();
        let mut d = [0.0f64; MAX_DIMS];
        'components: for c in self.packed.chunks_exact(stride(dims)) {
            let (mean, inverse) = c[1..].split_at(dims);
            for i in 0..dims {
                d[i] = x[i] - mean[i];
            }
            // The term may fall below `best − NEGLIGIBLE` once 0.5 · maha exceeds this.
            let cut = 2.0 * (c[0] - total.best + NEGLIGIBLE);
            let mut maha = 0.0;
            let mut row = 0;
            for i in 0..dims {
                let y: f64 = inverse[row..row + i + 1]
                    .iter()
                    .zip(&d[..=i])
                    .map(|(a, b)| a * b)
                    .sum();
                maha += y * y;
                row += i + 1;
                if maha > cut {
                    continue 'components;
                }
            }
            total.add(c[0] - 0.5 * maha);
        }
        total.value()
    }

    /// Each component's log term at `x`: ln(weight · N(x; μ, Σ)), in order (for the fit's E
    /// step and the reference sum).
    pub(super) fn terms<'a>(&'a self, x: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
        let dims = self.dims;
        self.packed.chunks_exact(stride(dims)).map(move |c| {
            let (mean, inverse) = c[1..].split_at(dims);
            let mut d = [0.0f64; MAX_DIMS];
            for i in 0..dims {
                d[i] = x[i] - mean[i];
            }
            let mut sum = 0.0;
            let mut row = 0;
            for i in 0..dims {
                let y: f64 = inverse[row..row + i + 1]
                    .iter()
                    .zip(&d[..=i])
                    .map(|(a, b)| a * b)
                    .sum();
                sum += y * y;
                row += i + 1;
            }
            c[0] - 0.5 * sum
        })
    }

    /// [`Gmm::log_density`] with every component summed (the slow reference).
    #[cfg(test)]
    pub(crate) fn log_density_full(&self, x: &[f64]) -> f64 {
        let mut total = LogSumExp::default();
        for t in self.terms(x) {
            total.add(t);
        }
        total.value()
    }

    /// The highest log density over the components' means (about the mixture's mode).
    pub(crate) fn peak(&self) -> f64 {
        self.components
            .iter()
            .map(|c| self.log_density(&c.mean))
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// How many numbers one component takes in [`Gmm::packed`].
fn stride(dims: usize) -> usize {
    1 + dims + dims * (dims + 1) / 2
}

/// The inverse of a lower triangular `dims × dims` matrix with a positive diagonal (row-major;
/// lower triangular too), by forward substitution column by column.
fn lower_inverse(l: &[f64], dims: usize) -> Vec<f64> {
    let mut inv = vec![0.0; dims * dims];
    for col in 0..dims {
        for i in col..dims {
            let mut v = if i == col { 1.0 } else { 0.0 };
            for j in col..i {
                v -= l[i * dims + j] * inv[j * dims + col];
            }
            inv[i * dims + col] = v / l[i * dims + i];
        }
    }
    inv
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
/// directions of unit vectors and of mirrored pairs lie on lower-dimensional sets). `Err` where
/// `dims` is beyond [`MAX_DIMS`].
pub(crate) fn fit(
    data: &[Vec<f64>],
    dims: usize,
    k: usize,
    iterations: usize,
    floor: f64,
) -> Result<Gmm, String> {
    let n = data.len();
    let means = kmeans_pp_seeds(data, k, &mut Lcg(0x9e37_79b9_7f4a_7c15));
    let spread = data.iter().map(|x| dist(x, &means[0])).sum::<f64>() / (n * dims) as f64;
    let mut components: Vec<Component> = means
        .into_iter()
        .map(|mean| Component {
            weight: 1.0 / k as f64,
            mean,
            cov_chol: scaled_identity(dims, spread.max(floor).sqrt()),
        })
        .collect();
    let mut resp = vec![0.0; n * k];
    for _ in 0..iterations {
        let Ok(gmm) = Gmm::new(dims, components.clone()) else {
            break;
        };
        e_step(&gmm, data, &mut resp);
        for (j, c) in components.iter_mut().enumerate() {
            m_step(c, data, &resp, j, k, floor);
        }
        let total: f64 = components.iter().map(|c| c.weight).sum();
        components.iter_mut().for_each(|c| c.weight /= total);
    }
    components.retain(|c| c.weight > 1e-9);
    let total: f64 = components.iter().map(|c| c.weight).sum();
    components.iter_mut().for_each(|c| c.weight /= total);
    Gmm::new(dims, components).or_else(|_| {
        let standard = Component {
            weight: 1.0,
            mean: vec![0.0; dims],
            cov_chol: scaled_identity(dims, 1.0),
        };
        Gmm::new(dims, vec![standard])
    })
}

/// The fixed linear congruential sequence the seeds are drawn by, uniform in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Squared distance.
fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>()
}

/// A `dims` × `dims` matrix (row-major) with `s` on its diagonal.
fn scaled_identity(dims: usize, s: f64) -> Vec<f64> {
    (0..dims * dims)
        .map(|i| if i % (dims + 1) == 0 { s } else { 0.0 })
        .collect()
}

/// `k` k-means++ seeds: the first drawn uniformly, each next with probability proportional to
/// its squared distance from the nearest seed so far.
fn kmeans_pp_seeds(data: &[Vec<f64>], k: usize, rng: &mut Lcg) -> Vec<Vec<f64>> {
    let n = data.len();
    let mut means: Vec<Vec<f64>> = vec![data[(rng.next() * n as f64) as usize % n].clone()];
    let mut nearest: Vec<f64> = data.iter().map(|x| dist(x, &means[0])).collect();
    while means.len() < k {
        let total: f64 = nearest.iter().sum();
        let mut pick = rng.next() * total;
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
    means
}

/// Expectation: each point's responsibilities (`resp[i * k + j]`, `k` the mixture's size).
fn e_step(gmm: &Gmm, data: &[Vec<f64>], resp: &mut [f64]) {
    let k = resp.len() / data.len().max(1);
    for (i, x) in data.iter().enumerate() {
        let logs: Vec<f64> = gmm.terms(x).collect();
        let best = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let sum: f64 = logs.iter().map(|l| (l - best).exp()).sum();
        for (j, l) in logs.iter().enumerate() {
            resp[i * k + j] = (l - best).exp() / sum;
        }
    }
}

/// Maximisation for component `j` of `k`: its weight, mean and covariance (plus `floor` on the
/// diagonal) from the responsibilities; left as it was when it holds no weight or its
/// covariance has no Cholesky factor.
fn m_step(c: &mut Component, data: &[Vec<f64>], resp: &[f64], j: usize, k: usize, floor: f64) {
    let (n, dims) = (data.len(), c.mean.len());
    let weight: f64 = (0..n).map(|i| resp[i * k + j]).sum();
    if weight < 1e-6 {
        return;
    }
    let mut mean = vec![0.0; dims];
    for (i, x) in data.iter().enumerate() {
        for (m, v) in mean.iter_mut().zip(x) {
            *m += resp[i * k + j] * v;
        }
    }
    mean.iter_mut().for_each(|m| *m /= weight);
    let mut cov = scaled_identity(dims, floor);
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

/// A running log-sum-exp: ln Σ exp(tᵢ) over the terms added, kept as the largest term and the
/// sum of the others' exp relative to it (no overflow, and the same bits whatever adds it).
#[derive(Debug, Clone, Copy)]
struct LogSumExp {
    best: f64,
    sum: f64,
}

impl Default for LogSumExp {
    fn default() -> Self {
        LogSumExp {
            best: f64::NEG_INFINITY,
            sum: 0.0,
        }
    }
}

impl LogSumExp {
    #[inline]
    fn add(&mut self, t: f64) {
        if t > self.best {
            self.sum = self.sum * (self.best - t).exp() + 1.0;
            self.best = t;
        } else {
            self.sum += (t - self.best).exp();
        }
    }

    fn value(self) -> f64 {
        if self.best.is_finite() {
            self.best + self.sum.ln()
        } else {
            self.best
        }
    }
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
        let g = fit(&data, 2, 2, 30, 1e-4).unwrap();
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
