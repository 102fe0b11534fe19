//! Fitting the counter's confidence model (`mp_abstract::ConfidenceModel`)
//! on synthetic cases of known count: a logistic regression (linfa) of
//! "the case repeats (N ≥ 2) and the count is within ±1 of N" on the
//! features each count carries (`mp_abstract::CountFeatures::inputs`).

use anyhow::{anyhow, Context};
use linfa::prelude::*;
use linfa_logistic::LogisticRegression;
use mp_abstract::{ConfidenceModel, CountFeatures};
use ndarray016::{Array1, Array2};

/// A count's features and whether it was right in the sense the
/// confidence stands for.
pub struct Example {
    pub features: CountFeatures,
    pub right: bool,
}

impl Example {
    /// `truth` repetitions, `count` counted.
    pub fn new(features: CountFeatures, truth: usize, count: usize) -> Self {
        Example {
            features,
            right: truth >= 2 && (count as i64 - truth as i64).abs() <= 1,
        }
    }
}

/// L2 penalty of the fit: small, only to keep the weights finite when a
/// feature separates the classes.
const ALPHA: f64 = 1e-3;

/// Fits the model on `examples`. The frame-signal weight is left at 0
/// when no example was counted from frames (it cannot be estimated).
pub fn fit(examples: &[Example]) -> anyhow::Result<ConfidenceModel> {
    let rows: Vec<[f64; 7]> = examples.iter().map(|e| e.features.inputs()).collect();
    // Columns that never vary (the frames flag on keypoint cases) are left
    // out of the fit and given weight 0; so is the periodicity (column 0):
    // fitted freely its weight comes out negative (it is confounded with the
    // cycle mismatch, 5-fold log loss 0.412 with it, 0.421 without), and a
    // more periodic motion must never be less certain.
    let used: Vec<usize> = (1..7)
        .filter(|&k| {
            let first = rows.first().map(|r| r[k]).unwrap_or(0.0);
            rows.iter().any(|r| r[k] != first)
        })
        .collect();
    let x = Array2::from_shape_fn((rows.len(), used.len()), |(i, k)| rows[i][used[k]]);
    let y: Array1<bool> = examples.iter().map(|e| e.right).collect();
    if !y.iter().any(|&v| v) || y.iter().all(|&v| v) {
        return Err(anyhow!(
            "fitting the confidence needs both right and wrong counts among the {} cases",
            examples.len()
        ));
    }
    let fitted = LogisticRegression::default()
        .alpha(ALPHA)
        .max_iterations(1000)
        .with_intercept(true)
        .fit(&Dataset::new(x, y))
        .context("fitting the confidence model")?;
    // linfa models the probability of its "positive" class, the more
    // frequent one: when that is `wrong`, the signs are turned round.
    let sign = if fitted.labels().pos.class { 1.0 } else { -1.0 };
    let mut weights = [0.0; 7];
    for (k, &col) in used.iter().enumerate() {
        weights[col] = sign * fitted.params()[k];
    }
    let model = ConfidenceModel {
        bias: sign * fitted.intercept(),
        weights,
    };
    model.validate()?;
    Ok(model)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ex(periodicity: f64, mismatch: f64, right: bool) -> Example {
        Example {
            features: CountFeatures {
                periodicity,
                cycles: 6.0,
                coverage: 0.8,
                cycle_mismatch: mismatch,
                ..CountFeatures::default()
            },
            right,
        }
    }

    #[test]
    fn the_fit_learns_that_regular_motion_is_counted_right() {
        // Right counts where the motion returns to itself, wrong where not,
        // with some overlap.
        let mut v = Vec::new();
        for i in 0..200 {
            let m = i as f64 / 100.0; // 0 .. 2
            let right = m < 0.8 || (i % 7 == 0 && m < 1.2);
            v.push(ex(0.5, m, right));
        }
        let model = fit(&v).unwrap();
        assert!(model.weights[3] < -1.0, "{model:?}");
        assert_eq!(model.weights[4], 0.0, "no frame-signal examples");
        assert_eq!(model.weights[0], 0.0, "periodicity is not fitted");
        let good = model.confidence(&ex(0.5, 0.2, true).features);
        let bad = model.confidence(&ex(0.5, 1.8, false).features);
        assert!(good > 0.9 && bad < 0.1, "{good} {bad}");
    }

    #[test]
    fn the_fit_refuses_a_single_class() {
        let v: Vec<Example> = (0..10).map(|i| ex(0.5, i as f64 / 10.0, true)).collect();
        assert!(fit(&v).is_err());
    }
}
