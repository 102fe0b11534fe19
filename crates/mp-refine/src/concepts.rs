//! Anchor concepts (paper 004, §3.1.2) and the anchor quality score (§3.2.1).
//!
//! Anchor poses are turned into features ([`anchor_feature`]: root-relative,
//! optionally divided by the pose's RMS joint distance to the root) and
//! clustered action by action. Each cluster centre is an *anchor concept*.
//! K-means (L2, seeded) is the default, as in the paper; the paper's
//! ablation alternatives are options: DBSCAN and OPTICS (linfa-clustering;
//! OPTICS clusters are cut from linfa's reachability ordering at a radius,
//! Ankerst et al.'s ExtractDBSCAN) and agglomerative hierarchical clustering
//! (linfa-hierarchical, on squared Euclidean distances).
//!
//! A Gaussian mixture (2 components by default, full covariances, fitted by
//! EM in linfa-clustering) over the anchor features of each action gives the
//! quality score: the log-likelihood of a feature. The lowest
//! [`ConceptParams::score_quantile`] of the training anchors' scores is
//! stored as the threshold below which an anchor counts as flawed.
//!
//! linfa 0.8 is built on ndarray 0.16 and rand 0.8: features are passed as
//! `ndarray016` views and the clustering generators are
//! `Xoshiro256Plus::seed_from_u64(seed)` from `rand_xoshiro` 0.6.

use std::collections::BTreeMap;

use linfa::traits::{Fit, Predict, Transformer};
use linfa::{DatasetBase, ParamGuard};
use linfa_clustering::{Dbscan, GaussianMixtureModel, KMeans, Optics};
use linfa_hierarchical::{HierarchicalCluster, Method};
use linfa_kernel::{Kernel, KernelMethod};
use mp_geom::Track;
use nalgebra::{DMatrix, DVector};
use ndarray::ArrayView2;
use rand_xoshiro06::rand_core::SeedableRng;
use rand_xoshiro06::Xoshiro256Plus;
use serde::{Deserialize, Serialize};

use crate::error::{RefineError, Result};
use crate::segment::{segment_track, SegmentParams};

/// Which clustering algorithm learns the anchor concepts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// clusters at radius `cut` ≤ `tolerance` ([`optics_clusters`]); noise
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

/// The feature of one pose (`J × D`): root-relative coordinates, flattened
/// joint-major, optionally divided by the RMS joint distance to the root.
///
/// `root = None` uses the mean of the joints as the root.
pub fn anchor_feature(
    pose: ArrayView2<'_, f64>,
    root: Option<usize>,
    scale_normalise: bool,
) -> Result<Vec<f64>> {
    let (j, d) = pose.dim();
    if j == 0 || d == 0 {
        return Err(RefineError::Shape("anchor_feature: empty pose".into()));
    }
    let origin: Vec<f64> = match root {
        Some(r) => {
            if r >= j {
                return Err(RefineError::param(
                    "root_joint",
                    format!("joint {r} is outside 0..{j}"),
                ));
            }
            pose.row(r).to_vec()
        }
        None => (0..d)
            .map(|k| pose.column(k).mean().unwrap_or(0.0))
            .collect(),
    };
    let mut f = Vec::with_capacity(j * d);
    for row in pose.outer_iter() {
        for (v, o) in row.iter().zip(&origin) {
            f.push(v - o);
        }
    }
    if f.iter().any(|v| !v.is_finite()) {
        return Err(RefineError::NonFinite(
            "anchor_feature: pose has a non-finite coordinate".into(),
        ));
    }
    if scale_normalise {
        let rms = feature_rms(&f, j);
        if rms > 0.0 {
            f.iter_mut().for_each(|v| *v /= rms);
        }
    }
    Ok(f)
}

/// RMS joint distance to the root of a root-relative feature of `joints`
/// joints: the scale [`anchor_feature`] divides by.
pub fn feature_rms(feature: &[f64], joints: usize) -> f64 {
    (feature.iter().map(|v| v * v).sum::<f64>() / joints.max(1) as f64).sqrt()
}

/// One anchor pose of an action, as a feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AnchorSample {
    /// Action label.
    pub action: u32,
    /// Feature ([`anchor_feature`]).
    pub feature: Vec<f64>,
}

/// The root joint that `params` selects for `track`.
pub fn root_of(track: &Track, params: &ConceptParams) -> Option<usize> {
    params.root_joint.or(track.skeleton().root)
}

/// Segments `track` and returns the features of its anchors (first and last
/// frame included) labelled `action`.
pub fn collect_anchors(
    track: &Track,
    action: u32,
    seg: &SegmentParams,
    params: &ConceptParams,
) -> Result<Vec<AnchorSample>> {
    let s = segment_track(track, seg)?;
    let root = root_of(track, params);
    s.anchors
        .iter()
        .map(|&a| {
            let pose = track.positions().index_axis_move(ndarray::Axis(0), a);
            Ok(AnchorSample {
                action,
                feature: anchor_feature(pose, root, params.scale_normalise)?,
            })
        })
        .collect()
}

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

/// Concepts of one action.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ActionConcepts {
    /// Action label.
    pub action: u32,
    /// Anchor concepts (cluster centres), one feature each.
    pub centroids: Vec<Vec<f64>>,
    /// Cluster of each training anchor (`None` = DBSCAN noise).
    pub labels: Vec<Option<usize>>,
    /// Quality model over the action's anchor features.
    pub gmm: Gmm,
    /// Anchors scoring below this log-likelihood are flawed.
    pub score_threshold: f64,
}

impl ActionConcepts {
    /// Index of and L2 distance to the nearest concept.
    pub fn nearest(&self, feature: &[f64]) -> Option<(usize, f64)> {
        self.centroids
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let d2: f64 = c.iter().zip(feature).map(|(a, b)| (a - b) * (a - b)).sum();
                (i, d2.sqrt())
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// Anchor concepts of every action, serialisable to JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Concepts {
    /// Feature dimension (`J · D`).
    pub dim: usize,
    /// Parameters they were learned with.
    pub params: ConceptParams,
    /// Per action.
    pub actions: BTreeMap<u32, ActionConcepts>,
}

impl Concepts {
    /// The concepts of `action`.
    pub fn action(&self, action: u32) -> Result<&ActionConcepts> {
        self.actions
            .get(&action)
            .ok_or(RefineError::UnknownAction(action))
    }
    /// Quality score (GMM log-likelihood) of a feature under `action`'s model.
    pub fn score(&self, action: u32, feature: &[f64]) -> Result<f64> {
        self.action(action)?.gmm.log_likelihood(feature)
    }
    /// Pretty JSON.
    pub fn to_json(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(self)?)
    }
    /// Parses JSON written by [`Concepts::to_json`] and checks it with
    /// [`Concepts::validate`].
    pub fn from_json(text: &str) -> Result<Self> {
        let c: Concepts = serde_json::from_str(text)?;
        c.validate()?;
        Ok(c)
    }

    /// Checks that the concepts are consistent: a feature dimension ≥ 1;
    /// valid learning parameters; per action, a key equal to its `action`,
    /// at most the method's number of concepts, concept features of `dim`
    /// finite values, labels that name existing concepts, a finite
    /// threshold and a valid quality model ([`Gmm::validate`] with the same
    /// dimension).
    ///
    /// Errors name the action and the field: [`RefineError::Shape`] for
    /// wrong lengths or counts, [`RefineError::NonFinite`] for NaN or
    /// infinite values, [`RefineError::InvalidParam`] for bad parameters.
    pub fn validate(&self) -> Result<()> {
        if self.dim == 0 {
            return Err(RefineError::Shape("concepts: `dim` is 0".into()));
        }
        self.params.validate()?;
        for (&key, ac) in &self.actions {
            let at = |field: &str| format!("concepts: action {key}: `{field}`");
            if ac.action != key {
                return Err(RefineError::Shape(format!(
                    "{} is {}, the key is {key}",
                    at("action"),
                    ac.action
                )));
            }
            if let Some(max) = self.params.method.max_concepts() {
                if ac.centroids.len() > max {
                    return Err(RefineError::Shape(format!(
                        "{} holds {} concepts, the {} method at most {max}",
                        at("centroids"),
                        ac.centroids.len(),
                        self.params.method.name()
                    )));
                }
            }
            for (i, c) in ac.centroids.iter().enumerate() {
                if c.len() != self.dim {
                    return Err(RefineError::Shape(format!(
                        "{}[{i}] has {} values, `dim` is {}",
                        at("centroids"),
                        c.len(),
                        self.dim
                    )));
                }
                if c.iter().any(|v| !v.is_finite()) {
                    return Err(RefineError::NonFinite(format!(
                        "{}[{i}] has a non-finite value",
                        at("centroids")
                    )));
                }
            }
            for (i, l) in ac.labels.iter().enumerate() {
                if let Some(l) = l {
                    if *l >= ac.centroids.len() {
                        return Err(RefineError::Shape(format!(
                            "{}[{i}] is {l}, there are {} concepts",
                            at("labels"),
                            ac.centroids.len()
                        )));
                    }
                }
            }
            if !ac.score_threshold.is_finite() {
                return Err(RefineError::NonFinite(format!(
                    "{} is {}",
                    at("score_threshold"),
                    ac.score_threshold
                )));
            }
            if ac.gmm.dim != self.dim {
                return Err(RefineError::Shape(format!(
                    "{} is {}, `dim` is {}",
                    at("gmm.dim"),
                    ac.gmm.dim,
                    self.dim
                )));
            }
            ac.gmm.validate().map_err(|e| match e {
                RefineError::Shape(m) => RefineError::Shape(format!("concepts: action {key}: {m}")),
                RefineError::NonFinite(m) => {
                    RefineError::NonFinite(format!("concepts: action {key}: {m}"))
                }
                other => other,
            })?;
        }
        Ok(())
    }
}

fn rng_for(seed: u64, action: u32, salt: u64) -> Xoshiro256Plus {
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
    let (centroids, labels): (Vec<Vec<f64>>, Vec<Option<usize>>) = match &params.method {
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
    };
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Two tight blobs of `n` points each in 3D, far apart, and one far
    /// outlier.
    fn blobs(n: usize) -> Vec<AnchorSample> {
        let mut out = Vec::new();
        for i in 0..n {
            let e = (i as f64 * 0.37).sin() * 0.05;
            out.push(AnchorSample {
                action: 1,
                feature: vec![e, 0.02 * i as f64 / n as f64, -e],
            });
            out.push(AnchorSample {
                action: 1,
                feature: vec![5.0 + e, 5.0 - e, 0.01 * i as f64 / n as f64],
            });
        }
        out.push(AnchorSample {
            action: 1,
            feature: vec![-20.0, 20.0, 20.0],
        });
        out
    }

    fn params(method: ClusterMethod) -> ConceptParams {
        ConceptParams {
            method,
            gmm_components: 1,
            ..ConceptParams::default()
        }
    }

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

    /// Concepts learned from the blobs, as JSON.
    fn concepts_json() -> serde_json::Value {
        let c = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3))).unwrap();
        serde_json::from_str(&c.to_json().unwrap()).unwrap()
    }

    /// The error of `from_json` on `v` changed by `edit`.
    fn load_error(edit: impl FnOnce(&mut serde_json::Value)) -> RefineError {
        let mut v = concepts_json();
        edit(&mut v);
        Concepts::from_json(&v.to_string()).expect_err("an invalid file loads")
    }

    #[test]
    fn concepts_round_trip_through_validation() {
        let v = concepts_json();
        let c = Concepts::from_json(&v.to_string()).unwrap();
        assert_eq!(c.dim, 3);
        c.validate().unwrap();
    }

    #[test]
    fn concepts_with_wrong_shapes_or_values_are_refused_by_field() {
        type Edit = Box<dyn Fn(&mut serde_json::Value)>;
        let cases: Vec<(Edit, &str, &str)> = vec![
            (
                Box::new(|v| v["actions"]["1"]["centroids"][0] = serde_json::json!([1.0, 2.0])),
                "shape",
                "`centroids`[0] has 2 values",
            ),
            (
                Box::new(|v| {
                    v["actions"]["1"]["gmm"]["means"][0] = serde_json::json!([1.0, 2.0, 3.0, 4.0])
                }),
                "shape",
                "`gmm.means[0]` has 4 values",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["covariances"][0] = serde_json::json!([1.0])),
                "shape",
                "`gmm.covariances[0]` has 1 values",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["weights"][0] = serde_json::json!(-0.5)),
                "shape",
                "`gmm.weights[0]` is negative",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["weights"][0] = serde_json::json!(7.0)),
                "shape",
                "`gmm.weights` sum to",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["means"] = serde_json::json!([])),
                "shape",
                "`gmm.means` 0",
            ),
            (
                Box::new(|v| {
                    v["actions"]["1"]["gmm"]["covariances"][0][1] = serde_json::json!(9.0)
                }),
                "shape",
                "not symmetric",
            ),
            (
                Box::new(|v| {
                    v["actions"]["1"]["gmm"]["covariances"][0] =
                        serde_json::json!([-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
                }),
                "shape",
                "not positive definite",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["dim"] = serde_json::json!(4)),
                "shape",
                "`gmm.dim` is 4",
            ),
            (
                Box::new(|v| v["actions"]["1"]["labels"][0] = serde_json::json!(7)),
                "shape",
                "`labels`[0] is 7",
            ),
            (
                Box::new(|v| v["actions"]["1"]["action"] = serde_json::json!(2)),
                "shape",
                "`action` is 2",
            ),
            (
                Box::new(|v| {
                    let c = v["actions"]["1"]["centroids"][0].clone();
                    v["actions"]["1"]["centroids"]
                        .as_array_mut()
                        .unwrap()
                        .extend([c.clone(), c]);
                }),
                "shape",
                "at most 3",
            ),
            (
                Box::new(|v| v["dim"] = serde_json::json!(0)),
                "shape",
                "`dim` is 0",
            ),
        ];
        for (edit, kind, needle) in cases {
            let e = load_error(edit);
            let msg = e.to_string();
            let ok = match kind {
                "shape" => matches!(e, RefineError::Shape(_)),
                _ => matches!(e, RefineError::Json(_)),
            };
            assert!(ok && msg.contains(needle), "{needle}: {e:?}");
            if kind == "shape" && needle != "`dim` is 0" {
                assert!(msg.contains("action 1"), "{msg}");
            }
        }
    }

    #[test]
    fn non_finite_values_in_concepts_are_refused() {
        let mut c = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3))).unwrap();
        let ac = c.actions.get_mut(&1).unwrap();
        ac.gmm.means[0][1] = f64::NAN;
        let e = c.validate().unwrap_err();
        assert!(
            matches!(&e, RefineError::NonFinite(m) if m.contains("`gmm.means[0]`") && m.contains("action 1")),
            "{e:?}"
        );
        let mut c = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3))).unwrap();
        c.actions.get_mut(&1).unwrap().score_threshold = f64::NAN;
        let e = c.validate().unwrap_err();
        assert!(
            matches!(&e, RefineError::NonFinite(m) if m.contains("`score_threshold`")),
            "{e:?}"
        );
        let mut c = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3))).unwrap();
        c.actions.get_mut(&1).unwrap().gmm.weights[0] = f64::INFINITY;
        let e = c.validate().unwrap_err();
        assert!(
            matches!(&e, RefineError::NonFinite(m) if m.contains("`gmm.weights[0]`")),
            "{e:?}"
        );
        // A bad covariance given directly to the score is an error, not a panic.
        let mut g = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3)))
            .unwrap()
            .actions[&1]
            .gmm
            .clone();
        g.covariances[0].pop();
        assert!(matches!(
            g.log_likelihood(&[0.0, 0.0, 0.0]),
            Err(RefineError::Shape(_))
        ));
    }

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
