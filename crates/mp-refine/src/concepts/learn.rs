//! Learning ([`learn_concepts`]): anchor samples grouped by action,
//! clustered into concepts (the `cluster` step) and scored by a fitted
//! Gaussian mixture, whose low quantile becomes the flaw threshold.

use std::collections::BTreeMap;

use linfa::traits::Fit;
use linfa::DatasetBase;
use linfa_clustering::GaussianMixtureModel;
use rand_xoshiro06::rand_core::SeedableRng;
use rand_xoshiro06::Xoshiro256Plus;

use super::cluster::cluster_anchors;
use super::{ActionConcepts, AnchorSample, ConceptParams, Concepts, Gmm};
use crate::error::{RefineError, Result};

pub(super) fn rng_for(seed: u64, action: u32, salt: u64) -> Xoshiro256Plus {
    Xoshiro256Plus::seed_from_u64(
        seed ^ (u64::from(action)).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ salt,
    )
}

/// Learns concepts from anchor samples, action by action.
///
/// Errors: invalid parameters; no samples; features of different lengths or
/// non-finite; an action with fewer anchors than mixture components; a
/// failed clustering or mixture fit (named by action).
pub fn learn_concepts(samples: &[AnchorSample], params: &ConceptParams) -> Result<Concepts> {
    params.validate()?;
    let dim = samples
        .first()
        .map(|s| s.feature.len())
        .ok_or_else(|| RefineError::TooShort {
            what: "learn_concepts (anchor samples)".into(),
            needed: 1,
            got: 0,
        })?;
    if dim == 0 {
        return Err(RefineError::Shape("learn_concepts: empty features".into()));
    }
    let mut by_action: BTreeMap<u32, Vec<f64>> = BTreeMap::new();
    for (i, s) in samples.iter().enumerate() {
        if s.feature.len() != dim {
            return Err(RefineError::Shape(format!(
                "learn_concepts: sample {i} has {} values, sample 0 has {dim}",
                s.feature.len()
            )));
        }
        if s.feature.iter().any(|v| !v.is_finite()) {
            return Err(RefineError::NonFinite(format!(
                "learn_concepts: sample {i} has a non-finite value"
            )));
        }
        by_action.entry(s.action).or_default().extend(&s.feature);
    }
    let mut actions = BTreeMap::new();
    for (action, flat) in by_action {
        let n = flat.len() / dim;
        let x = ndarray016::ArrayView2::from_shape((n, dim), &flat)
            .map_err(|e| RefineError::Shape(e.to_string()))?;
        let ac = learn_action(action, x, dim, params)?;
        actions.insert(action, ac);
    }
    Ok(Concepts {
        dim,
        params: params.clone(),
        actions,
    })
}

fn learn_action(
    action: u32,
    x: ndarray016::ArrayView2<'_, f64>,
    dim: usize,
    params: &ConceptParams,
) -> Result<ActionConcepts> {
    let n = x.nrows();
    let cerr = |reason: String| RefineError::Clustering { action, reason };
    if n < params.gmm_components.max(2) {
        return Err(RefineError::TooShort {
            what: format!("concepts of action {action} (anchors)"),
            needed: params.gmm_components.max(2),
            got: n,
        });
    }
    let (centroids, labels) = cluster_anchors(action, x, params)?;
    let ds = DatasetBase::from(x);
    let gmm = GaussianMixtureModel::params_with_rng(
        params.gmm_components,
        rng_for(params.seed, action, 2),
    )
    .reg_covariance(params.gmm_reg_covariance)
    .n_runs(params.gmm_n_runs)
    .max_n_iterations(200)
    .fit(&ds)
    .map_err(|e| cerr(format!("Gaussian mixture: {e}")))?;
    let g = Gmm {
        dim,
        weights: gmm.weights().to_vec(),
        means: gmm.means().outer_iter().map(|r| r.to_vec()).collect(),
        covariances: gmm
            .covariances()
            .outer_iter()
            .map(|c| c.iter().copied().collect())
            .collect(),
    };
    let mut scores = x
        .outer_iter()
        .map(|r| g.log_likelihood(&r.to_vec()))
        .collect::<Result<Vec<_>>>()?;
    scores.sort_by(f64::total_cmp);
    let qi = ((scores.len() - 1) as f64 * params.score_quantile).floor() as usize;
    let score_threshold = scores.get(qi).copied().unwrap_or(f64::NEG_INFINITY);
    Ok(ActionConcepts {
        action,
        centroids,
        labels,
        gmm: g,
        score_threshold,
    })
}
