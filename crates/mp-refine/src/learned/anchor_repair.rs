//! Step 3, anchor refinement: which flawed anchors are repaired, and the
//! repairs of [`AnchorRepair::Bridge`] (the anchor is dropped and one
//! generated transition spans the gap) and [`AnchorRepair::Network`] (the
//! anchor refinement network's pose, neighbouring transitions rebuilt by the
//! generator); [`AnchorRepair::NearestConcept`] is in
//! [`super::nearest_concept`].

use ndarray::{Array2, Array3};

use super::{check_finite, AnchorRepair, AnchorReport, NetRefiner, TransitionMethod};
use crate::error::Result;
use crate::motion::{FRAME_FEATURES, NET_FRAMES};

/// The state the anchor step leaves to the transition step.
pub(super) struct AnchorRepairs {
    /// The clip's features (`60 × 60`) after the anchor repair.
    pub(super) xf: Array2<f64>,
    /// Per transition between the remaining anchors: whether it borders a
    /// refined anchor (or bridges dropped ones).
    pub(super) next_to_refined: Vec<bool>,
    /// Reports of the anchors a bridge dropped.
    pub(super) bridged: Vec<AnchorReport>,
}

impl NetRefiner<'_> {
    /// Step 3: marks the flawed anchors of `reports` that are repaired and
    /// repairs them in the features `feats` of the canonical clip `x`
    /// (one batch), with the neighbouring transitions. A bridge removes the
    /// dropped anchors from `anchors` and `reports`.
    pub(super) fn repair_anchors(
        &self,
        feats: &Array2<f32>,
        x: &Array3<f64>,
        action: u32,
        anchors: &mut Vec<usize>,
        reports: &mut Vec<AnchorReport>,
    ) -> Result<AnchorRepairs> {
        let p = self.params;
        for r in reports.iter_mut() {
            r.repaired = r.flawed;
        }
        if p.anchor_repair == AnchorRepair::Bridge {
            // Runs of flawed anchors whose bridge would be too long stay.
            let mut i = 1;
            while i + 1 < anchors.len() {
                if !reports[i].flawed {
                    i += 1;
                    continue;
                }
                let r0 = i;
                while i + 1 < anchors.len() && reports[i].flawed {
                    i += 1;
                }
                // reports[i] is the next kept anchor, r0 − 1 the previous one.
                if anchors[i] - anchors[r0 - 1] > p.max_bridge_frames {
                    for r in &mut reports[r0..i] {
                        r.repaired = false;
                    }
                }
            }
        }
        let flawed: Vec<usize> = (0..anchors.len())
            .filter(|&i| reports[i].repaired)
            .collect();
        let mut repairs = AnchorRepairs {
            xf: feats.mapv(|v| v as f64),
            next_to_refined: vec![false; anchors.len().saturating_sub(1)],
            bridged: Vec::new(),
        };
        if !flawed.is_empty() && p.anchor_repair == AnchorRepair::Bridge {
            self.bridge_anchors(anchors, reports, &mut repairs)?;
        } else if !flawed.is_empty() && p.anchor_repair == AnchorRepair::NearestConcept {
            self.move_to_nearest_concepts(x, action, anchors, &flawed, reports, &mut repairs)?;
        } else if !flawed.is_empty() {
            self.refine_with_network(feats, anchors, &flawed, reports, &mut repairs)?;
        }
        Ok(repairs)
    }

    /// [`AnchorRepair::Bridge`]: drops the anchors marked repaired; one
    /// generated transition spans each gap.
    fn bridge_anchors(
        &self,
        anchors: &mut Vec<usize>,
        reports: &mut Vec<AnchorReport>,
        repairs: &mut AnchorRepairs,
    ) -> Result<()> {
        let AnchorRepairs {
            xf,
            next_to_refined,
            bridged: bridged_reports,
        } = repairs;
        // Drop the flawed anchors; one generated transition spans each gap.
        let kept: Vec<usize> = (0..anchors.len())
            .filter(|&i| !reports[i].repaired)
            .collect();
        let kept_frames: Vec<usize> = kept.iter().map(|&i| anchors[i]).collect();
        let mut bridged = vec![false; kept_frames.len() - 1];
        for w in 0..kept.len() - 1 {
            bridged[w] = kept[w + 1] > kept[w] + 1;
        }
        let tr: Vec<usize> = (0..bridged.len()).filter(|&t| bridged[t]).collect();
        self.regenerate(xf, &kept_frames, &tr, TransitionMethod::Generator, None)?;
        // Later steps see the remaining anchors.
        let old: Vec<AnchorReport> = std::mem::take(reports);
        let mut new_reports = Vec::with_capacity(kept.len());
        for (i, r) in old.into_iter().enumerate() {
            if kept.contains(&i) {
                new_reports.push(r);
            } else {
                bridged_reports.push(r);
            }
        }
        *reports = new_reports;
        *anchors = kept_frames;
        *next_to_refined = bridged;
        Ok(())
    }

    /// [`AnchorRepair::Network`]: the anchor refinement network's pose and
    /// concept for each flawed anchor `flawed` (indices into `anchors`), then
    /// the neighbouring transitions rebuilt by the generator.
    fn refine_with_network(
        &self,
        feats: &Array2<f32>,
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
        let nb = flawed.len();
        let mut motion = Vec::with_capacity(nb * NET_FRAMES * FRAME_FEATURES);
        let mut mask = vec![0f32; nb * NET_FRAMES];
        let mut target = vec![0f32; nb * NET_FRAMES];
        for (bi, &i) in flawed.iter().enumerate() {
            let (lo, hi) = (anchors[i - 1], anchors[i + 1]);
            for f in 0..NET_FRAMES {
                let masked = f > lo && f < hi;
                if masked {
                    mask[bi * NET_FRAMES + f] = 1.0;
                }
                for k in 0..FRAME_FEATURES {
                    motion.push(if masked { 0.0 } else { feats[[f, k]] });
                }
            }
            target[bi * NET_FRAMES + anchors[i]] = 1.0;
        }
        let out = self.nets.refine_anchors(&motion, &mask, &target)?;
        check_finite("anchor refinement", &out.anchors)?;
        let kc = self.nets.sizes().concepts;
        for (bi, &i) in flawed.iter().enumerate() {
            let f = anchors[i];
            for k in 0..FRAME_FEATURES {
                xf[[f, k]] = out.anchors[bi * FRAME_FEATURES + k] as f64;
            }
            let row = out
                .concept_logits
                .get(bi * kc..(bi + 1) * kc)
                .unwrap_or(&[]);
            reports[i].concept = row
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map(|(c, _)| c);
            next_to_refined[i - 1] = true;
            next_to_refined[i] = true;
        }
        let tr: Vec<usize> = (0..next_to_refined.len())
            .filter(|&t| next_to_refined[t])
            .collect();
        self.regenerate(xf, anchors, &tr, TransitionMethod::Generator, None)?;
        Ok(())
    }
}
