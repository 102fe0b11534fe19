//! Quality metrics of generated motion (paper 004, §4.1), computed on the
//! evaluator's features.
//!
//! * [`fid`]: Fréchet distance between the Gaussians fitted to two feature
//!   sets, `‖μ₁ − μ₂‖² + tr(Σ₁ + Σ₂ − 2 (Σ₁^½ Σ₂ Σ₁^½)^½)`; the matrix square
//!   roots come from symmetric eigendecompositions (nalgebra), negative
//!   eigenvalues of the (numerically) positive semi-definite matrices are
//!   clipped to 0. Covariances use the unbiased `n − 1` denominator.
//! * [`per_action_fid`]: FID between the samples of each action (A-FID).
//! * [`accuracy`]: share of samples whose arg-max logit is their label.
//! * [`diversity`]: mean distance between [`QualityParams::diversity_pairs`]
//!   (`S_d` = 200) random pairs of samples.
//! * [`multimodality`]: per action, mean distance between
//!   [`QualityParams::multimodality_pairs`] (`S_m` = 20) random pairs of that
//!   action's samples; averaged over actions.
//!
//! Random pairs are drawn with `ChaCha8Rng::seed_from_u64(seed)`.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};
use ndarray::ArrayView2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::refine::RefineResult as Result;
use mp_refine::RefineError;

/// Parameters of the random-pair metrics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QualityParams {
    /// Pairs of the diversity `S_d`. Default 200 (paper).
    pub diversity_pairs: usize,
    /// Pairs per action of the multimodality `S_m`. Default 20 (paper).
    pub multimodality_pairs: usize,
    /// Seed of the pair draws.
    pub seed: u64,
}

impl Default for QualityParams {
    fn default() -> Self {
        QualityParams {
            diversity_pairs: 200,
            multimodality_pairs: 20,
            seed: 0,
        }
    }
}

impl QualityParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        if self.diversity_pairs == 0 {
            return Err(RefineError::param("diversity_pairs", "must be ≥ 1"));
        }
        if self.multimodality_pairs == 0 {
            return Err(RefineError::param("multimodality_pairs", "must be ≥ 1"));
        }
        Ok(())
    }
}

/// Mean and covariance (`n − 1` denominator) of the rows of `x`.
pub fn mean_cov(x: ArrayView2<'_, f64>) -> Result<(DVector<f64>, DMatrix<f64>)> {
    let (n, d) = x.dim();
    if n < 2 {
        return Err(RefineError::TooShort {
            what: "feature statistics (samples)".into(),
            needed: 2,
            got: n,
        });
    }
    if d == 0 {
        return Err(RefineError::Shape("feature statistics: 0 features".into()));
    }
    if x.iter().any(|v| !v.is_finite()) {
        return Err(RefineError::NonFinite(
            "feature statistics: a feature is not finite".into(),
        ));
    }
    let mut mu = DVector::<f64>::zeros(d);
    for row in x.outer_iter() {
        for (m, v) in mu.iter_mut().zip(row.iter()) {
            *m += v;
        }
    }
    mu /= n as f64;
    let mut c = DMatrix::<f64>::zeros(d, d);
    let mut diff = DVector::<f64>::zeros(d);
    for row in x.outer_iter() {
        for (k, v) in row.iter().enumerate() {
            diff[k] = v - mu[k];
        }
        c.ger(1.0, &diff, &diff, 1.0);
    }
    c /= (n - 1) as f64;
    Ok((mu, c))
}

/// Square root of a symmetric positive semi-definite matrix (eigenvalues
/// below 0 are clipped to 0).
pub fn sqrtm_psd(m: &DMatrix<f64>) -> DMatrix<f64> {
    let sym = (m + m.transpose()) * 0.5;
    let e = sym.symmetric_eigen();
    let s = DMatrix::from_diagonal(&e.eigenvalues.map(|v| v.max(0.0).sqrt()));
    &e.eigenvectors * s * e.eigenvectors.transpose()
}

/// Fréchet distance between two Gaussians.
pub fn fid_from_stats(
    mu1: &DVector<f64>,
    cov1: &DMatrix<f64>,
    mu2: &DVector<f64>,
    cov2: &DMatrix<f64>,
) -> Result<f64> {
    let d = mu1.len();
    if mu2.len() != d || cov1.shape() != (d, d) || cov2.shape() != (d, d) {
        return Err(RefineError::Shape(format!(
            "FID: means of {} and {} values, covariances {:?} and {:?}",
            d,
            mu2.len(),
            cov1.shape(),
            cov2.shape()
        )));
    }
    let dm = (mu1 - mu2).norm_squared();
    let s1 = sqrtm_psd(cov1);
    let inner = &s1 * cov2 * &s1;
    let inner = (&inner + inner.transpose()) * 0.5;
    let tr_sqrt: f64 = inner
        .symmetric_eigenvalues()
        .iter()
        .map(|v| v.max(0.0).sqrt())
        .sum();
    let v = dm + cov1.trace() + cov2.trace() - 2.0 * tr_sqrt;
    if !v.is_finite() {
        return Err(RefineError::NonFinite("FID is not finite".into()));
    }
    // Rounding can make the distance of a set to itself slightly negative.
    Ok(v.max(0.0))
}

/// FID between two feature sets (rows are samples; ≥ 2 rows each, same
/// number of columns).
pub fn fid(a: ArrayView2<'_, f64>, b: ArrayView2<'_, f64>) -> Result<f64> {
    if a.ncols() != b.ncols() {
        return Err(RefineError::Shape(format!(
            "FID: {} features vs {}",
            a.ncols(),
            b.ncols()
        )));
    }
    let (m1, c1) = mean_cov(a)?;
    let (m2, c2) = mean_cov(b)?;
    fid_from_stats(&m1, &c1, &m2, &c2)
}

fn rows_of(x: ArrayView2<'_, f64>, labels: &[u32], action: u32) -> ndarray::Array2<f64> {
    let idx: Vec<usize> = labels
        .iter()
        .enumerate()
        .filter(|(_, &l)| l == action)
        .map(|(i, _)| i)
        .collect();
    x.select(ndarray::Axis(0), &idx)
}

fn check_labels(what: &str, x: ArrayView2<'_, f64>, labels: &[u32]) -> Result<()> {
    if x.nrows() != labels.len() {
        return Err(RefineError::Shape(format!(
            "{what}: {} samples but {} labels",
            x.nrows(),
            labels.len()
        )));
    }
    Ok(())
}

/// FID per action between `a` (labels `la`) and `b` (labels `lb`), for every
/// action with ≥ 2 samples on both sides.
pub fn per_action_fid(
    a: ArrayView2<'_, f64>,
    la: &[u32],
    b: ArrayView2<'_, f64>,
    lb: &[u32],
) -> Result<BTreeMap<u32, f64>> {
    check_labels("per-action FID (first set)", a, la)?;
    check_labels("per-action FID (second set)", b, lb)?;
    let mut actions: Vec<u32> = la.to_vec();
    actions.sort_unstable();
    actions.dedup();
    let mut out = BTreeMap::new();
    for act in actions {
        let xa = rows_of(a, la, act);
        let xb = rows_of(b, lb, act);
        if xa.nrows() >= 2 && xb.nrows() >= 2 {
            out.insert(act, fid(xa.view(), xb.view())?);
        }
    }
    Ok(out)
}

/// Share of rows of `logits` (`n × C`, class `c` ↦ label `c + 1`) whose
/// arg-max is the row's label (labels are 1-based action ids).
pub fn accuracy(logits: ArrayView2<'_, f64>, labels: &[u32]) -> Result<f64> {
    check_labels("accuracy", logits, labels)?;
    if labels.is_empty() {
        return Err(RefineError::TooShort {
            what: "accuracy (samples)".into(),
            needed: 1,
            got: 0,
        });
    }
    let ok = logits
        .outer_iter()
        .zip(labels)
        .filter(|(row, &l)| {
            let am = row
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map(|(i, _)| i);
            am.map(|i| i as u32 + 1) == Some(l)
        })
        .count();
    Ok(ok as f64 / labels.len() as f64)
}

fn dist(x: ArrayView2<'_, f64>, i: usize, j: usize) -> f64 {
    x.row(i)
        .iter()
        .zip(x.row(j).iter())
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt()
}

fn mean_pair_distance(x: ArrayView2<'_, f64>, pairs: usize, rng: &mut ChaCha8Rng) -> f64 {
    let n = x.nrows();
    let mut s = 0.0;
    for _ in 0..pairs {
        let i = rng.random_range(0..n);
        let mut j = rng.random_range(0..n - 1);
        if j >= i {
            j += 1;
        }
        s += dist(x, i, j);
    }
    s / pairs as f64
}

/// Diversity: mean L2 distance between `diversity_pairs` random pairs of
/// distinct samples (pairs drawn with replacement).
pub fn diversity(x: ArrayView2<'_, f64>, params: &QualityParams) -> Result<f64> {
    params.validate()?;
    if x.nrows() < 2 {
        return Err(RefineError::TooShort {
            what: "diversity (samples)".into(),
            needed: 2,
            got: x.nrows(),
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    Ok(mean_pair_distance(x, params.diversity_pairs, &mut rng))
}

/// Multimodality: per action with ≥ 2 samples, the mean L2 distance between
/// `multimodality_pairs` random pairs of its samples; the mean over actions.
pub fn multimodality(
    x: ArrayView2<'_, f64>,
    labels: &[u32],
    params: &QualityParams,
) -> Result<f64> {
    params.validate()?;
    check_labels("multimodality", x, labels)?;
    let mut actions: Vec<u32> = labels.to_vec();
    actions.sort_unstable();
    actions.dedup();
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed ^ 0x6d75_6c74);
    let mut vals = Vec::new();
    for act in actions {
        let xa = rows_of(x, labels, act);
        if xa.nrows() >= 2 {
            vals.push(mean_pair_distance(
                xa.view(),
                params.multimodality_pairs,
                &mut rng,
            ));
        }
    }
    if vals.is_empty() {
        return Err(RefineError::TooShort {
            what: "multimodality (samples of one action)".into(),
            needed: 2,
            got: 1,
        });
    }
    Ok(vals.iter().sum::<f64>() / vals.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;
    use rand_distr::{Distribution, Normal};

    fn gaussian(n: usize, mean: &[f64], std: &[f64], seed: u64) -> Array2<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let nd = Normal::new(0.0, 1.0).unwrap();
        Array2::from_shape_fn((n, mean.len()), |(_, k)| {
            mean[k] + std[k] * nd.sample(&mut rng)
        })
    }

    #[test]
    fn analytic_fid_of_two_gaussians() {
        // Diagonal covariances: FID = ‖Δμ‖² + Σ (σ₁ − σ₂)².
        let mu1 = DVector::from_vec(vec![0.0, 1.0, -2.0]);
        let mu2 = DVector::from_vec(vec![1.0, 1.0, 0.0]);
        let c1 = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 4.0, 9.0]));
        let c2 = DMatrix::from_diagonal(&DVector::from_vec(vec![4.0, 1.0, 9.0]));
        let f = fid_from_stats(&mu1, &c1, &mu2, &c2).unwrap();
        let expected = (1.0 + 0.0 + 4.0) + (1.0 + 1.0 + 0.0);
        assert!((f - expected).abs() < 1e-9, "{f} vs {expected}");
        // Σ₁ = I, Σ₂ full: FID = Σ_i (1 − √λ_i)² over the eigenvalues of Σ₂.
        let c2 = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]); // λ = 1, 3
        let z = DVector::zeros(2);
        let f = fid_from_stats(&z, &DMatrix::identity(2, 2), &z, &c2).unwrap();
        let expected = (1.0 - 3f64.sqrt()).powi(2);
        assert!((f - expected).abs() < 1e-9, "{f} vs {expected}");
        // Symmetric in its arguments.
        let g = fid_from_stats(&z, &c2, &z, &DMatrix::identity(2, 2)).unwrap();
        assert!((f - g).abs() < 1e-9);
    }

    #[test]
    fn fid_of_a_set_with_itself_is_zero_and_grows_with_a_shift() {
        let a = gaussian(500, &[0.0; 4], &[1.0, 0.5, 2.0, 1.0], 1);
        assert!(fid(a.view(), a.view()).unwrap() < 1e-9);
        let mut prev = 0.0;
        for shift in [0.5, 1.0, 2.0] {
            let b = a.mapv(|v| v + shift);
            let f = fid(a.view(), b.view()).unwrap();
            // Shifting every one of the 4 features by s adds 4 s² exactly.
            assert!((f - 4.0 * shift * shift).abs() < 1e-6, "{f}");
            assert!(f > prev);
            prev = f;
        }
        // Two samples of the same Gaussian: small; of different Gaussians: ≈ analytic.
        let b = gaussian(4000, &[0.0; 4], &[1.0, 0.5, 2.0, 1.0], 2);
        let c = gaussian(4000, &[1.0, 0.0, 0.0, 0.0], &[2.0, 0.5, 2.0, 1.0], 3);
        let same = fid(a.view(), b.view()).unwrap();
        let diff = fid(b.view(), c.view()).unwrap();
        assert!(same < 0.1, "{same}");
        assert!((diff - 2.0).abs() < 0.2, "{diff}");
    }

    #[test]
    fn fid_rejects_bad_input() {
        let a = Array2::<f64>::zeros((1, 3));
        let b = Array2::<f64>::zeros((5, 3));
        assert!(matches!(
            fid(a.view(), b.view()),
            Err(RefineError::TooShort { .. })
        ));
        let c = Array2::<f64>::zeros((5, 2));
        assert!(matches!(
            fid(b.view(), c.view()),
            Err(RefineError::Shape(_))
        ));
        let mut d = Array2::<f64>::zeros((5, 3));
        d[[2, 1]] = f64::NAN;
        assert!(matches!(
            fid(b.view(), d.view()),
            Err(RefineError::NonFinite(_))
        ));
    }

    #[test]
    fn accuracy_diversity_multimodality() {
        let logits =
            Array2::from_shape_vec((3, 3), vec![3.0, 1.0, 0.0, 0.0, 2.0, 1.0, 5.0, 0.0, 0.0])
                .unwrap();
        let acc = accuracy(logits.view(), &[1, 2, 3]).unwrap();
        assert!((acc - 2.0 / 3.0).abs() < 1e-12);
        // Points on two far-apart clusters: diversity ≈ half the pairs cross.
        let mut x = Array2::<f64>::zeros((40, 2));
        let mut labels = vec![1u32; 40];
        for i in 20..40 {
            x[[i, 0]] = 10.0;
            labels[i] = 2;
        }
        let p = QualityParams::default();
        let d = diversity(x.view(), &p).unwrap();
        assert!(d > 3.0 && d < 7.0, "{d}");
        assert_eq!(d, diversity(x.view(), &p).unwrap());
        // Within an action every sample is identical: multimodality 0.
        assert_eq!(multimodality(x.view(), &labels, &p).unwrap(), 0.0);
        let pa = per_action_fid(x.view(), &labels, x.view(), &labels).unwrap();
        assert_eq!(pa.len(), 2);
        assert!(pa.values().all(|v| *v < 1e-12));
        assert!(matches!(
            multimodality(x.view(), &labels[..3], &p),
            Err(RefineError::Shape(_))
        ));
    }
}
