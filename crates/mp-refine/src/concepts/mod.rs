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
//!
//! The steps live in submodules: `feature` (anchor features and collecting
//! a track's anchors), `cluster` (the clustering methods and the
//! clustering step), `gmm` (the quality model), `params` (the learning
//! parameters), `model` (the learned [`Concepts`] and their checks) and
//! `learn` ([`learn_concepts`]: clustering and quality model, action by
//! action), `samples` (the anchor samples of tracks and of MSR Action3D
//! clips that concepts are learned from).

mod cluster;
mod feature;
mod gmm;
mod learn;
mod model;
mod params;
mod samples;

pub use cluster::{ClusterMethod, Linkage};
pub use feature::{anchor_feature, collect_anchors, feature_rms, root_of, AnchorSample};
pub use gmm::Gmm;
pub use learn::learn_concepts;
pub use model::{ActionConcepts, Concepts};
pub use params::ConceptParams;
pub use samples::{
    canonical_anchor_samples, msr_anchor_samples, msr_training_clips, HELD_OUT_SUBJECTS,
    MIN_CLIP_FRAMES,
};

/// Anchor samples and learning parameters shared by the tests of the
/// submodules.
#[cfg(test)]
mod test_data {
    use super::*;

    /// Two tight blobs of `n` points each in 3D, far apart, and one far
    /// outlier.
    pub(super) fn blobs(n: usize) -> Vec<AnchorSample> {
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

    pub(super) fn params(method: ClusterMethod) -> ConceptParams {
        ConceptParams {
            method,
            gmm_components: 1,
            ..ConceptParams::default()
        }
    }
}
