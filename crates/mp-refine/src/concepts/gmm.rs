//! The quality model: a serialisable Gaussian mixture ([`Gmm`]) whose
//! log-likelihood is an anchor's quality score.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::{RefineError, Result};

/// A Gaussian mixture with full covariances, serialisable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Gmm {
    /// Feature dimension.
    pub dim: usize,
    /// Mixing weights (sum 1).
    pub weights: Vec<f64>,
    /// Component means (`dim` each).
    pub means: Vec<Vec<f64>>,
    /// Component covariances, row-major `dim × dim` each.
    pub covariances: Vec<Vec<f64>>,
}

impl Gmm {
    /// Tolerance on the sum of the mixing weights: `|Σ w − 1| ≤ 1e-6`.
    pub const WEIGHT_SUM_TOLERANCE: f64 = 1e-6;

    /// Checks the mixture: `dim` ≥ 1; at least one component; as many
    /// weights, means and covariances; weights finite, non-negative and
    /// summing to 1 (within [`Gmm::WEIGHT_SUM_TOLERANCE`]); means of `dim`
    /// finite values; covariances of `dim × dim` finite values, symmetric
    /// and positive definite where the weight is positive. Errors name the
    /// field (`gmm.weights`, `gmm.means[c]`, `gmm.covariances[c]`, …).
    pub fn validate(&self) -> Result<()> {
        let d = self.dim;
        if d == 0 {
            return Err(RefineError::Shape("`gmm.dim` is 0".into()));
        }
        let k = self.weights.len();
        if k == 0 {
            return Err(RefineError::Shape("`gmm.weights` is empty".into()));
        }
        if self.means.len() != k || self.covariances.len() != k {
            return Err(RefineError::Shape(format!(
                "`gmm.weights` has {k} components, `gmm.means` {}, `gmm.covariances` {}",
                self.means.len(),
                self.covariances.len()
            )));
        }
        if let Some(c) = self.weights.iter().position(|w| !w.is_finite()) {
            return Err(RefineError::NonFinite(format!(
                "`gmm.weights[{c}]` is {}",
                self.weights[c]
            )));
        }
        if let Some(c) = self.weights.iter().position(|w| *w < 0.0) {
            return Err(RefineError::Shape(format!(
                "`gmm.weights[{c}]` is negative ({})",
                self.weights[c]
            )));
        }
        let sum: f64 = self.weights.iter().sum();
        if (sum - 1.0).abs() > Self::WEIGHT_SUM_TOLERANCE {
            return Err(RefineError::Shape(format!(
                "`gmm.weights` sum to {sum}, not 1"
            )));
        }
        for (c, mu) in self.means.iter().enumerate() {
            if mu.len() != d {
                return Err(RefineError::Shape(format!(
                    "`gmm.means[{c}]` has {} values, `gmm.dim` is {d}",
                    mu.len()
                )));
            }
            if mu.iter().any(|v| !v.is_finite()) {
                return Err(RefineError::NonFinite(format!(
                    "`gmm.means[{c}]` has a non-finite value"
                )));
            }
        }
        for (c, cov) in self.covariances.iter().enumerate() {
            if cov.len() != d * d {
                return Err(RefineError::Shape(format!(
                    "`gmm.covariances[{c}]` has {} values, {d} × {d} = {} expected",
                    cov.len(),
                    d * d
                )));
            }
            if cov.iter().any(|v| !v.is_finite()) {
                return Err(RefineError::NonFinite(format!(
                    "`gmm.covariances[{c}]` has a non-finite value"
                )));
            }
            for i in 0..d {
                for j in 0..i {
                    let (a, b) = (cov[i * d + j], cov[j * d + i]);
                    if (a - b).abs() > 1e-9 * (1.0 + a.abs().max(b.abs())) {
                        return Err(RefineError::Shape(format!(
                            "`gmm.covariances[{c}]` is not symmetric at ({i}, {j}): {a} ≠ {b}"
                        )));
                    }
                }
            }
            if self.weights[c] > 0.0 && DMatrix::from_row_slice(d, d, cov).cholesky().is_none() {
                return Err(RefineError::Shape(format!(
                    "`gmm.covariances[{c}]` is not positive definite"
                )));
            }
        }
        Ok(())
    }

    /// Log-likelihood `log Σ_c w_c N(x; μ_c, Σ_c)` of one feature.
    pub fn log_likelihood(&self, x: &[f64]) -> Result<f64> {
        if x.len() != self.dim {
            return Err(RefineError::Shape(format!(
                "GMM score: feature has {} values, the model {}",
                x.len(),
                self.dim
            )));
        }
        let d = self.dim;
        let mut terms = Vec::with_capacity(self.weights.len());
        for (c, ((w, mu), cov)) in self
            .weights
            .iter()
            .zip(&self.means)
            .zip(&self.covariances)
            .enumerate()
        {
            if *w <= 0.0 {
                continue;
            }
            if mu.len() != d || cov.len() != d * d {
                return Err(RefineError::Shape(format!(
                    "GMM score: component {c} has a mean of {} values and a covariance of {}, \
                     the model's dimension is {d}",
                    mu.len(),
                    cov.len()
                )));
            }
            let m = DMatrix::from_row_slice(d, d, cov);
            let ch = m.cholesky().ok_or_else(|| {
                RefineError::NonFinite("GMM score: covariance is not positive definite".into())
            })?;
            let diff = DVector::from_iterator(d, x.iter().zip(mu).map(|(a, b)| a - b));
            let sol = ch
                .l()
                .solve_lower_triangular(&diff)
                .ok_or_else(|| RefineError::NonFinite("GMM score: singular covariance".into()))?;
            let maha = sol.norm_squared();
            let logdet: f64 = 2.0 * ch.l().diagonal().iter().map(|v| v.ln()).sum::<f64>();
            terms.push(
                w.ln() - 0.5 * (d as f64 * (2.0 * std::f64::consts::PI).ln() + logdet + maha),
            );
        }
        let mx = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if !mx.is_finite() {
            return Ok(f64::NEG_INFINITY);
        }
        Ok(mx + terms.iter().map(|t| (t - mx).exp()).sum::<f64>().ln())
    }
}
