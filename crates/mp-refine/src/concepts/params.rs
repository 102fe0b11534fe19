//! Parameters of concept learning ([`ConceptParams`]) and their checks.

use serde::{Deserialize, Serialize};

use super::ClusterMethod;
use crate::error::{RefineError, Result};

/// Parameters of concept learning.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConceptParams {
    /// Clustering algorithm. Default k-means with 4 concepts per action.
    pub method: ClusterMethod,
    /// Root joint for root-relative features; `None` uses the skeleton's
    /// root, or the mean of the joints when the skeleton has none.
    pub root_joint: Option<usize>,
    /// Divide each root-relative pose by its RMS joint distance to the root.
    /// Default true.
    pub scale_normalise: bool,
    /// Mixture components of the quality model. Default 2 (paper).
    pub gmm_components: usize,
    /// Added to the mixture's covariance diagonals (feature units²). Default 1e-3.
    pub gmm_reg_covariance: f64,
    /// EM restarts. Default 3.
    pub gmm_n_runs: u64,
    /// Quantile of the training anchors' scores used as the flaw threshold. Default 0.05.
    pub score_quantile: f64,
    /// Seed of the clustering and mixture initialisations.
    pub seed: u64,
}

impl Default for ConceptParams {
    fn default() -> Self {
        ConceptParams {
            method: ClusterMethod::kmeans(ClusterMethod::DEFAULT_CLUSTERS),
            root_joint: None,
            scale_normalise: true,
            gmm_components: 2,
            gmm_reg_covariance: 1e-3,
            gmm_n_runs: 3,
            score_quantile: 0.05,
            seed: 0,
        }
    }
}

impl ConceptParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        match &self.method {
            ClusterMethod::KMeans {
                n_clusters,
                n_runs,
                max_iterations,
            } => {
                if *n_clusters == 0 {
                    return Err(RefineError::param("n_clusters", "must be ≥ 1"));
                }
                if *n_runs == 0 {
                    return Err(RefineError::param("n_runs", "must be ≥ 1"));
                }
                if *max_iterations == 0 {
                    return Err(RefineError::param("max_iterations", "must be ≥ 1"));
                }
            }
            ClusterMethod::Dbscan {
                min_points,
                tolerance,
            } => check_density(*min_points, *tolerance)?,
            ClusterMethod::Optics {
                min_points,
                tolerance,
                cut,
            } => {
                check_density(*min_points, *tolerance)?;
                if !(cut.is_finite() && *cut > 0.0 && cut <= tolerance) {
                    return Err(RefineError::param(
                        "cut",
                        format!("must be in (0, tolerance = {tolerance}], got {cut}"),
                    ));
                }
            }
            ClusterMethod::Hierarchical { n_clusters, .. } => {
                if *n_clusters == 0 {
                    return Err(RefineError::param("n_clusters", "must be ≥ 1"));
                }
            }
        }
        if self.gmm_components == 0 {
            return Err(RefineError::param("gmm_components", "must be ≥ 1"));
        }
        if !(self.gmm_reg_covariance.is_finite() && self.gmm_reg_covariance > 0.0) {
            return Err(RefineError::param(
                "gmm_reg_covariance",
                format!("must be finite and > 0, got {}", self.gmm_reg_covariance),
            ));
        }
        if self.gmm_n_runs == 0 {
            return Err(RefineError::param("gmm_n_runs", "must be ≥ 1"));
        }
        if !(0.0..=1.0).contains(&self.score_quantile) {
            return Err(RefineError::param(
                "score_quantile",
                format!("must be in [0, 1], got {}", self.score_quantile),
            ));
        }
        Ok(())
    }
}

/// Checks the core size and radius of a density-based clustering.
fn check_density(min_points: usize, tolerance: f64) -> Result<()> {
    if min_points < 2 {
        return Err(RefineError::param("min_points", "must be ≥ 2"));
    }
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(RefineError::param(
            "tolerance",
            format!("must be finite and > 0, got {tolerance}"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::test_data::params;
    use super::*;
    use crate::concepts::Linkage;

    #[test]
    fn bad_clustering_parameters_are_named() {
        for (m, name) in [
            (
                ClusterMethod::Optics {
                    min_points: 3,
                    tolerance: 1.0,
                    cut: 2.0,
                },
                "cut",
            ),
            (
                ClusterMethod::Optics {
                    min_points: 1,
                    tolerance: 1.0,
                    cut: 0.5,
                },
                "min_points",
            ),
            (
                ClusterMethod::Hierarchical {
                    n_clusters: 0,
                    linkage: Linkage::Ward,
                },
                "n_clusters",
            ),
        ] {
            match params(m).validate() {
                Err(RefineError::InvalidParam { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{name}: {other:?}"),
            }
        }
    }
}
