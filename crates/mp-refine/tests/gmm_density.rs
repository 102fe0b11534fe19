//! The anchor quality score (`Gmm::log_likelihood`, a full-covariance
//! Gaussian mixture density written with a Cholesky factor and a
//! log-sum-exp) against statrs' `MultivariateNormal`, on random mixtures and
//! on the shipped concept models.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_refine::{Concepts, Gmm};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use statrs::distribution::{Continuous, MultivariateNormal};

/// `log Σ_c w_c N(x; μ_c, Σ_c)` from statrs' densities. statrs needs a
/// bit-exactly symmetric covariance, so `(Σ + Σᵀ) / 2` is passed.
fn reference(g: &Gmm, x: &[f64]) -> f64 {
    let d = g.dim;
    let terms: Vec<f64> = g
        .weights
        .iter()
        .zip(&g.means)
        .zip(&g.covariances)
        .filter(|((w, _), _)| **w > 0.0)
        .map(|((w, mu), cov)| {
            let c = DMatrix::from_row_slice(d, d, cov);
            let sym = (&c + c.transpose()) * 0.5;
            let mvn = MultivariateNormal::new_from_nalgebra(DVector::from_column_slice(mu), sym)
                .expect("positive definite covariance");
            w.ln() + mvn.ln_pdf(&DVector::from_column_slice(x))
        })
        .collect();
    let mx = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    mx + terms.iter().map(|t| (t - mx).exp()).sum::<f64>().ln()
}

fn random_spd(d: usize, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let a = DMatrix::from_fn(d, d, |_, _| rng.random_range(-1.0..1.0));
    let c = &a * a.transpose() + DMatrix::identity(d, d) * rng.random_range(1e-3..0.5);
    let mut out = vec![0.0; d * d];
    for i in 0..d {
        for j in 0..d {
            out[i * d + j] = c[(i.min(j), i.max(j))];
        }
    }
    out
}

#[test]
fn random_mixtures_match_statrs() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for case in 0..200 {
        let d = 1 + case % 8;
        let k = 1 + case % 3;
        let mut weights: Vec<f64> = (0..k).map(|_| rng.random_range(0.05..1.0)).collect();
        if k == 3 {
            weights[1] = 0.0; // a dropped component is skipped
        }
        let s: f64 = weights.iter().sum();
        weights.iter_mut().for_each(|w| *w /= s);
        let g = Gmm {
            dim: d,
            weights,
            means: (0..k)
                .map(|_| (0..d).map(|_| rng.random_range(-2.0..2.0)).collect())
                .collect(),
            covariances: (0..k).map(|_| random_spd(d, &mut rng)).collect(),
        };
        for _ in 0..5 {
            let x: Vec<f64> = (0..d).map(|_| rng.random_range(-4.0..4.0)).collect();
            let ours = g.log_likelihood(&x).unwrap();
            let theirs = reference(&g, &x);
            assert!(
                (ours - theirs).abs() <= 1e-9 * (1.0 + theirs.abs()),
                "case {case} (d = {d}, k = {k}): {ours} vs statrs {theirs}"
            );
        }
    }
}

#[test]
fn shipped_concept_models_match_statrs() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/refine/concepts.json"
    );
    let text = std::fs::read_to_string(path).expect("models/refine/concepts.json");
    let concepts = Concepts::from_json(&text).unwrap();
    assert!(!concepts.actions.is_empty());
    for (action, ac) in &concepts.actions {
        let g = &ac.gmm;
        // The fitted covariances are symmetric up to rounding.
        for cov in &g.covariances {
            let d = g.dim;
            let scale = cov.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..d {
                for j in 0..i {
                    assert!((cov[i * d + j] - cov[j * d + i]).abs() <= 1e-12 * scale);
                }
            }
        }
        let points = g.means.iter().chain(&ac.centroids);
        for x in points {
            let ours = g.log_likelihood(x).unwrap();
            let theirs = reference(g, x);
            assert!(
                (ours - theirs).abs() <= 1e-10 * (1.0 + theirs.abs()),
                "action {action}: {ours} vs statrs {theirs}"
            );
        }
        // The training threshold is a value of this score.
        assert!(ac.score_threshold.is_finite());
    }
}
