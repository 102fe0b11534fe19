//! The clustering step: the algorithms that turn an action's anchor
//! features into anchor concepts ([`ClusterMethod`]) and the helpers they
//! share (cutting OPTICS orderings, cluster centres).

use std::collections::BTreeMap;

use linfa::traits::{Fit, Predict, Transformer};
use linfa::{DatasetBase, ParamGuard};
use linfa_clustering::{Dbscan, KMeans, Optics};
use linfa_hierarchical::{HierarchicalCluster, Method};
use linfa_kernel::{Kernel, KernelMethod};
use serde::{Deserialize, Serialize};

use super::learn::rng_for;
use super::ConceptParams;
use crate::error::{RefineError, Result};

/// Which clustering algorithm learns the anchor concepts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum ClusterMethod {
    /// K-means with L2 distance (paper default).
    KMeans {
        /// Number of concepts per action (fewer when an action has fewer anchors).
        n_clusters: usize,
        /// Restarts; the lowest inertia wins. Default 10.
        n_runs: usize,
        /// Iteration cap. Default 300.
        max_iterations: u64,
    },
    /// DBSCAN; noise anchors belong to no concept.
    Dbscan {
        /// Neighbours (including the point) needed for a core point.
        min_points: usize,
        /// Neighbourhood radius in feature units.
        tolerance: f64,
    },
    /// OPTICS ordering (linfa-clustering) up to radius `tolerance`, cut into
    /// clusters at radius `cut` ≤ `tolerance` (`optics_clusters`); noise
    /// anchors belong to no concept.
    Optics {
        /// Neighbours (including the point) needed for a core point.
        min_points: usize,
        /// Largest neighbourhood radius of the ordering (feature units).
        tolerance: f64,
        /// Radius at which clusters are cut from the ordering.
        cut: f64,
    },
    /// Agglomerative hierarchical clustering (linfa-hierarchical) into
    /// `n_clusters` concepts per action (fewer when an action has fewer
    /// anchors).
    Hierarchical {
        /// Number of concepts per action.
        n_clusters: usize,
        /// How the dissimilarity of merged clusters is updated.
        linkage: Linkage,
    },
}

/// Linkage of [`ClusterMethod::Hierarchical`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Linkage {
    /// Ward's minimum variance. Default.
    #[default]
    Ward,
    /// Mean pairwise dissimilarity (UPGMA).
    Average,
    /// Largest pairwise dissimilarity.
    Complete,
    /// Smallest pairwise dissimilarity.
    Single,
}

impl Linkage {
    /// Lower-case name: `ward`, `average`, `complete` or `single`.
    pub fn as_str(self) -> &'static str {
        match self {
            Linkage::Ward => "ward",
            Linkage::Average => "average",
            Linkage::Complete => "complete",
            Linkage::Single => "single",
        }
    }
}

impl ClusterMethod {
    /// Concepts per action of k-means and hierarchical clustering by
    /// default: 4.
    pub const DEFAULT_CLUSTERS: usize = 4;
    /// K-means restarts by default: 10.
    pub const DEFAULT_KMEANS_RUNS: usize = 10;
    /// K-means iteration cap by default: 300.
    pub const DEFAULT_KMEANS_MAX_ITERATIONS: u64 = 300;
    /// Neighbours (including the point) of a DBSCAN / OPTICS core point by
    /// default: 4.
    pub const DEFAULT_MIN_POINTS: usize = 4;
    /// DBSCAN neighbourhood radius, and the radius at which OPTICS clusters
    /// are cut, by default: 0.35 (scale-normalised feature units).
    pub const DEFAULT_TOLERANCE: f64 = 0.35;
    /// Largest neighbourhood radius of the OPTICS ordering by default: 1.0
    /// (scale-normalised feature units).
    pub const DEFAULT_OPTICS_RADIUS: f64 = 1.0;

    /// K-means into `n_clusters` concepts per action with the default
    /// restarts and iteration cap.
    pub fn kmeans(n_clusters: usize) -> Self {
        ClusterMethod::KMeans {
            n_clusters,
            n_runs: Self::DEFAULT_KMEANS_RUNS,
            max_iterations: Self::DEFAULT_KMEANS_MAX_ITERATIONS,
        }
    }

    /// DBSCAN with the default core size and radius.
    pub fn default_dbscan() -> Self {
        ClusterMethod::Dbscan {
            min_points: Self::DEFAULT_MIN_POINTS,
            tolerance: Self::DEFAULT_TOLERANCE,
        }
    }

    /// OPTICS with the default core size, ordering radius and cut.
    pub fn default_optics() -> Self {
        ClusterMethod::Optics {
            min_points: Self::DEFAULT_MIN_POINTS,
            tolerance: Self::DEFAULT_OPTICS_RADIUS,
            cut: Self::DEFAULT_TOLERANCE,
        }
    }

    /// Hierarchical clustering into the default number of concepts with the
    /// default linkage.
    pub fn default_hierarchical() -> Self {
        ClusterMethod::Hierarchical {
            n_clusters: Self::DEFAULT_CLUSTERS,
            linkage: Linkage::default(),
        }
    }

    /// Lower-case name: `kmeans`, `dbscan`, `optics` or `hierarchical`.
    pub fn name(&self) -> &'static str {
        match self {
            ClusterMethod::KMeans { .. } => "kmeans",
            ClusterMethod::Dbscan { .. } => "dbscan",
            ClusterMethod::Optics { .. } => "optics",
            ClusterMethod::Hierarchical { .. } => "hierarchical",
        }
    }

    /// Concepts per action at most (`None` for the density-based methods,
    /// whose count depends on the data).
    pub fn max_concepts(&self) -> Option<usize> {
        match self {
            ClusterMethod::KMeans { n_clusters, .. }
            | ClusterMethod::Hierarchical { n_clusters, .. } => Some(*n_clusters),
            ClusterMethod::Dbscan { .. } | ClusterMethod::Optics { .. } => None,
        }
    }
}

/// Clusters cut from an OPTICS ordering at radius `cut` (Ankerst et al.
/// 1999, ExtractDBSCAN-Clustering). `order` holds, in the ordering, each
/// point's index, core distance and reachability distance (`None`:
/// undefined within the ordering's radius). A point whose reachability
/// exceeds `cut` starts a new cluster when its core distance is within
/// `cut`, and is noise otherwise; every other point joins the current
/// cluster (noise before the first cluster). Returns one label per point
/// (`n` points), clusters numbered in the order they start.
pub fn optics_clusters(
    order: &[(usize, Option<f64>, Option<f64>)],
    n: usize,
    cut: f64,
) -> Vec<Option<usize>> {
    let mut labels = vec![None; n];
    let mut current: Option<usize> = None;
    let mut next = 0;
    for &(i, core, reach) in order {
        if i >= n {
            continue;
        }
        if reach.is_none_or(|r| r > cut) {
            if core.is_some_and(|c| c <= cut) {
                current = Some(next);
                next += 1;
                labels[i] = current;
            }
        } else {
            labels[i] = current;
        }
    }
    labels
}

/// Reachability of each point of an OPTICS ordering from the points before
/// it: `min over earlier core points q within tolerance of max(core(q),
/// d(q, p))`, `None` where no earlier core point is within `tolerance` (the
/// start of a new component). linfa-clustering's ordering gives each point
/// its reachability from the point that *expanded* it, which may come later
/// in the ordering, so a new component is not marked; this recomputes the
/// textbook value from the ordering and core distances.
fn reachability_in_order(
    x: ndarray016::ArrayView2<'_, f64>,
    order: &[(usize, Option<f64>)],
    tolerance: f64,
) -> Vec<Option<f64>> {
    let mut out = Vec::with_capacity(order.len());
    for (k, &(p, _)) in order.iter().enumerate() {
        let mut best: Option<f64> = None;
        for &(q, core) in &order[..k] {
            let Some(c) = core else { continue };
            let d = x
                .row(p)
                .iter()
                .zip(x.row(q).iter())
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            if d <= tolerance {
                let r = c.max(d);
                best = Some(best.map_or(r, |b: f64| b.min(r)));
            }
        }
        out.push(best);
    }
    out
}

/// Centres of the labelled clusters (`labels[i]` of row `i` of `x`; rows
/// without a label are left out) and the labels renumbered `0..k` in order
/// of each cluster's first row.
fn cluster_centres(
    x: ndarray016::ArrayView2<'_, f64>,
    labels: &[Option<usize>],
) -> (Vec<Vec<f64>>, Vec<Option<usize>>) {
    let dim = x.ncols();
    let mut renum: BTreeMap<usize, usize> = BTreeMap::new();
    let mut out = Vec::with_capacity(labels.len());
    for l in labels {
        out.push(l.map(|l| {
            let k = renum.len();
            *renum.entry(l).or_insert(k)
        }));
    }
    let k = renum.len();
    let mut sums = vec![vec![0.0; dim]; k];
    let mut counts = vec![0usize; k];
    for (row, l) in x.outer_iter().zip(&out) {
        if let Some(l) = l {
            counts[*l] += 1;
            for (s, v) in sums[*l].iter_mut().zip(row.iter()) {
                *s += v;
            }
        }
    }
    let cents = sums
        .into_iter()
        .zip(&counts)
        .map(|(s, &c)| s.into_iter().map(|v| v / c.max(1) as f64).collect())
        .collect();
    (cents, out)
}

/// Concept centres, and the concept of each anchor (`None`: noise of a
/// density-based method).
type Clustering = (Vec<Vec<f64>>, Vec<Option<usize>>);

/// Clusters the anchor features `x` (one row per anchor) of `action` with
/// `params.method`.
pub(super) fn cluster_anchors(
    action: u32,
    x: ndarray016::ArrayView2<'_, f64>,
    params: &ConceptParams,
) -> Result<Clustering> {
    let n = x.nrows();
    let cerr = |reason: String| RefineError::Clustering { action, reason };
    Ok(match &params.method {
        ClusterMethod::KMeans {
            n_clusters,
            n_runs,
            max_iterations,
        } => {
            let k = (*n_clusters).min(n);
            let ds = DatasetBase::from(x);
            let model = KMeans::params_with_rng(k, rng_for(params.seed, action, 1))
                .n_runs(*n_runs)
                .max_n_iterations(*max_iterations)
                .tolerance(1e-6)
                .fit(&ds)
                .map_err(|e| cerr(e.to_string()))?;
            let labels = model.predict(&x);
            (
                model.centroids().outer_iter().map(|r| r.to_vec()).collect(),
                labels.iter().map(|&l| Some(l)).collect(),
            )
        }
        ClusterMethod::Dbscan {
            min_points,
            tolerance,
        } => {
            let labels = Dbscan::params(*min_points)
                .tolerance(*tolerance)
                .check()
                .map_err(|e| cerr(e.to_string()))?
                .transform(&x);
            cluster_centres(x, &labels.to_vec())
        }
        ClusterMethod::Optics {
            min_points,
            tolerance,
            cut,
        } => {
            let analysis = Optics::params(*min_points)
                .tolerance(*tolerance)
                .transform(x)
                .map_err(|e| cerr(format!("OPTICS: {e}")))?;
            let cores: Vec<(usize, Option<f64>)> = analysis
                .iter()
                .map(|s| (s.index(), *s.core_distance()))
                .collect();
            let reach = reachability_in_order(x, &cores, *tolerance);
            let order: Vec<(usize, Option<f64>, Option<f64>)> = cores
                .iter()
                .zip(reach)
                .map(|(&(i, c), r)| (i, c, r))
                .collect();
            cluster_centres(x, &optics_clusters(&order, n, *cut))
        }
        ClusterMethod::Hierarchical {
            n_clusters,
            linkage,
        } => {
            // linfa-hierarchical works on a Gaussian kernel and merges on
            // −ln k = ‖a − b‖² / ε: squared Euclidean distances, scaled by
            // the largest one so that none is clamped.
            let mut max_d2: f64 = 0.0;
            for (i, a) in x.outer_iter().enumerate() {
                for b in x.outer_iter().skip(i + 1) {
                    let d2: f64 = a.iter().zip(b.iter()).map(|(p, q)| (p - q) * (p - q)).sum();
                    max_d2 = max_d2.max(d2);
                }
            }
            let kernel = Kernel::params()
                .method(KernelMethod::Gaussian(max_d2.max(1e-12)))
                .transform(x);
            let method = match linkage {
                Linkage::Ward => Method::Ward,
                Linkage::Average => Method::Average,
                Linkage::Complete => Method::Complete,
                Linkage::Single => Method::Single,
            };
            let out = HierarchicalCluster::default()
                .with_method(method)
                .num_clusters((*n_clusters).min(n))
                .transform(kernel)
                .map_err(|e| cerr(format!("hierarchical clustering: {e}")))?;
            let labels: Vec<Option<usize>> = out.targets().iter().map(|&l| Some(l)).collect();
            cluster_centres(x, &labels)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::super::test_data::{blobs, params};
    use super::*;
    use crate::concepts::learn_concepts;

    #[test]
    fn optics_cut_follows_the_reachability_plot() {
        // Ordering: a cluster (0, 1, 2), noise (3), a second cluster (4, 5).
        let order = vec![
            (0, Some(0.1), None),
            (1, Some(0.1), Some(0.2)),
            (2, Some(0.3), Some(0.2)),
            (3, None, None),
            (4, Some(0.2), Some(5.0)),
            (5, Some(0.2), Some(0.2)),
        ];
        let l = optics_clusters(&order, 6, 0.5);
        assert_eq!(l, vec![Some(0), Some(0), Some(0), None, Some(1), Some(1)]);
        // A smaller radius: point 2's core distance no longer counts, but
        // it is still reachable from 1.
        let l = optics_clusters(&order, 6, 0.25);
        assert_eq!(l, vec![Some(0), Some(0), Some(0), None, Some(1), Some(1)]);
        // Below every reachability each point with a small core starts its own cluster.
        let l = optics_clusters(&order, 6, 0.15);
        assert_eq!(l, vec![Some(0), Some(1), None, None, None, None]);
        // A point reachable after a noise point joins the last cluster.
        let order = vec![
            (0, Some(0.1), None),
            (1, None, Some(0.2)),
            (2, None, Some(0.6)),
            (3, Some(0.1), Some(0.2)),
        ];
        let l = optics_clusters(&order, 4, 0.5);
        assert_eq!(l, vec![Some(0), Some(0), None, Some(0)]);
    }

    #[test]
    fn every_clustering_option_finds_the_two_blobs() {
        let s = blobs(12);
        let methods = [
            ClusterMethod::KMeans {
                n_clusters: 3,
                n_runs: 5,
                max_iterations: 100,
            },
            ClusterMethod::Dbscan {
                min_points: 3,
                tolerance: 0.5,
            },
            ClusterMethod::Optics {
                min_points: 3,
                tolerance: 2.0,
                cut: 0.5,
            },
            ClusterMethod::Hierarchical {
                n_clusters: 3,
                linkage: Linkage::Average,
            },
            ClusterMethod::Hierarchical {
                n_clusters: 3,
                linkage: Linkage::Ward,
            },
        ];
        for m in methods {
            let p = params(m.clone());
            let c = learn_concepts(&s, &p).unwrap();
            // Deterministic per seed, labels included.
            assert_eq!(c, learn_concepts(&s, &p).unwrap(), "{m:?}");
            let ac = c.action(1).unwrap();
            // Points of a blob share a label and the blobs differ.
            let la: Vec<Option<usize>> = (0..12).map(|i| ac.labels[2 * i]).collect();
            let lb: Vec<Option<usize>> = (0..12).map(|i| ac.labels[2 * i + 1]).collect();
            assert!(
                la.iter().all(|l| l.is_some() && *l == la[0]),
                "{m:?}: {la:?}"
            );
            assert!(
                lb.iter().all(|l| l.is_some() && *l == lb[0]),
                "{m:?}: {lb:?}"
            );
            assert_ne!(la[0], lb[0], "{m:?}");
            // The blob centres are concepts.
            let near_a = ac.nearest(&[0.0, 0.01, 0.0]).unwrap();
            let near_b = ac.nearest(&[5.0, 5.0, 0.005]).unwrap();
            assert!(
                near_a.1 < 0.1 && near_b.1 < 0.1,
                "{m:?}: {near_a:?} {near_b:?}"
            );
            match m {
                // The density methods leave the outlier out.
                ClusterMethod::Dbscan { .. } | ClusterMethod::Optics { .. } => {
                    assert_eq!(ac.labels[24], None, "{m:?}");
                    assert_eq!(ac.centroids.len(), 2, "{m:?}");
                }
                // Three clusters: the outlier is its own.
                ClusterMethod::Hierarchical { .. } | ClusterMethod::KMeans { .. } => {
                    assert_eq!(ac.centroids.len(), 3, "{m:?}");
                    assert!(ac.labels[24].is_some_and(|l| Some(l) != la[0] && Some(l) != lb[0]));
                }
            }
        }
    }
}
