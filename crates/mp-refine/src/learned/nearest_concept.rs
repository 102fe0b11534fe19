//! Step 3 for generated motion
//! ([`AnchorRepair::NearestConcept`](super::AnchorRepair::NearestConcept),
//! [`NetRefineParams::for_generated`](super::NetRefineParams::for_generated)):
//! each flawed anchor moves to its action's nearest concept, and the
//! correction fades out linearly towards the neighbouring anchors.

use ndarray::{Array2, Array3, Axis};

use super::anchor_repair::AnchorRepairs;
use super::{AnchorReport, NetRefiner};
use crate::concepts::{anchor_feature, feature_rms};
use crate::error::{RefineError, Result};
use crate::motion::FRAME_FEATURES;

impl NetRefiner<'_> {
    /// [`AnchorRepair::NearestConcept`](super::AnchorRepair::NearestConcept)
    /// for the flawed anchors `flawed` (indices into `anchors`) of the
    /// canonical clip `x`: the nearest concept of `action` replaces each
    /// anchor pose in the features `repairs.xf`, with a piecewise-linear
    /// correction between the anchors.
    pub(super) fn move_to_nearest_concepts(
        &self,
        x: &Array3<f64>,
        action: u32,
        anchors: &[usize],
        flawed: &[usize],
        reports: &mut [AnchorReport],
        repairs: &mut AnchorRepairs,
    ) -> Result<()> {
        let AnchorRepairs {
            xf,
            next_to_refined,
            ..
        } = repairs;
        let ac = self.concepts.action(action)?;
        let first_id = (action as usize)
            .checked_sub(1)
            .ok_or_else(|| RefineError::param("action", "actions are numbered from 1"))?;
        let per_action = self
            .concepts
            .params
            .method
            .max_concepts()
            .unwrap_or_else(|| {
                self.concepts
                    .actions
                    .values()
                    .map(|a| a.centroids.len())
                    .max()
                    .unwrap_or(0)
            });
        let mut delta = Array2::<f64>::zeros((anchors.len(), FRAME_FEATURES));
        for &i in flawed {
            let f = anchors[i];
            let pose = x.index_axis(Axis(0), f);
            let feat = anchor_feature(pose, self.root, false)?;
            let scale = if self.concepts.params.scale_normalise {
                feature_rms(&feat, pose.nrows())
            } else {
                1.0
            };
            let normed: Vec<f64> = if scale > 0.0 {
                feat.iter().map(|v| v / scale).collect()
            } else {
                feat.clone()
            };
            let Some((c, _)) = ac.nearest(&normed) else {
                // An action without concepts: nothing to move to.
                reports[i].repaired = false;
                continue;
            };
            // A centre of unit-scale features is smaller than they are:
            // back to unit scale, then to the anchor's own.
            let cen = &ac.centroids[c];
            let gain = if self.concepts.params.scale_normalise {
                let rms = feature_rms(cen, pose.nrows());
                if rms > 0.0 {
                    scale / rms
                } else {
                    0.0
                }
            } else {
                1.0
            };
            for (k, (&cv, &fv)) in cen.iter().zip(&feat).enumerate() {
                delta[[i, k]] = cv * gain - fv;
            }
            reports[i].concept = Some(first_id * per_action + c);
            next_to_refined[i - 1] = true;
            next_to_refined[i] = true;
        }
        // Piecewise-linear correction between the anchors.
        for w in 0..anchors.len() - 1 {
            let (a, b) = (anchors[w], anchors[w + 1]);
            for g in a..=b {
                let u = (g - a) as f64 / (b - a).max(1) as f64;
                for k in 0..FRAME_FEATURES {
                    let dv = (1.0 - u) * delta[[w, k]] + u * delta[[w + 1, k]];
                    if g < b || w + 2 == anchors.len() {
                        xf[[g, k]] += dv;
                    }
                }
            }
        }
        Ok(())
    }
}
