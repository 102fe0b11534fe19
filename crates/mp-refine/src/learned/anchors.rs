//! Steps 1 and 2, anchor recognition and quality score: anchors at the
//! peaks of the recognition network (or the segmentation's junctions), and
//! each interior anchor scored by its action's Gaussian mixture (or by its
//! distance to the nearest concept, [`NetRefiner::with_nearest_concept`]).

use std::collections::BTreeMap;

use mp_geom::{Skeleton, Track};
use ndarray::{Array3, ArrayView3};

use super::{check_finite, sigmoid, AnchorDetection, AnchorReport, NetRefiner};
use crate::concepts::{anchor_feature, AnchorSample, Concepts};
use crate::error::{RefineError, Result};
use crate::motion::NET_FRAMES;
use crate::segment::segment_track;

/// Per action, the `1 − quantile` quantile of the distances between the
/// training anchors `samples` and their nearest concept: the threshold of
/// [`NetRefiner::with_nearest_concept`] (anchors farther than this from
/// every concept of their action are flawed).
pub fn nearest_concept_thresholds(
    concepts: &Concepts,
    samples: &[AnchorSample],
    quantile: f64,
) -> Result<BTreeMap<u32, f64>> {
    if !(0.0..=1.0).contains(&quantile) {
        return Err(RefineError::param(
            "quantile",
            format!("must be in [0, 1], got {quantile}"),
        ));
    }
    let mut dists: BTreeMap<u32, Vec<f64>> = BTreeMap::new();
    for s in samples {
        let ac = concepts.action(s.action)?;
        if let Some((_, d)) = ac.nearest(&s.feature) {
            dists.entry(s.action).or_default().push(d);
        }
    }
    Ok(dists
        .into_iter()
        .map(|(a, mut v)| {
            v.sort_by(f64::total_cmp);
            let i = ((v.len() - 1) as f64 * (1.0 - quantile)).ceil() as usize;
            (a, v[i.min(v.len() - 1)])
        })
        .collect())
}

/// Interior local maxima of `p` above `thr`, thinned so that kept frames are
/// at least `gap` apart (most probable first).
pub fn anchor_peaks(p: &[f64], thr: f64, gap: usize) -> Vec<usize> {
    let n = p.len();
    let mut cands: Vec<usize> = (1..n.saturating_sub(1))
        .filter(|&f| p[f] > thr && p[f] >= p[f - 1] && p[f] >= p[f + 1])
        .collect();
    cands.sort_by(|&a, &b| p[b].total_cmp(&p[a]).then(a.cmp(&b)));
    let mut kept: Vec<usize> = Vec::new();
    for f in cands {
        // Too close to the ends or to a kept anchor: dropped.
        if f < gap || f + gap > n - 1 {
            continue;
        }
        if kept.iter().all(|&k| k.abs_diff(f) >= gap) {
            kept.push(f);
        }
    }
    kept.sort_unstable();
    kept
}

impl NetRefiner<'_> {
    /// Step 1: the anchor probability of every canonical frame (from the
    /// recognition network's logits of the clip's features `flat`) and the
    /// anchor frames, first and last included.
    pub(super) fn recognise_anchors(
        &self,
        clip: ArrayView3<'_, f64>,
        flat: &[f32],
    ) -> Result<(Vec<f64>, Vec<usize>)> {
        let p = self.params;
        let logits = self.nets.anchor_logits(flat)?;
        check_finite("anchor recognition", &logits)?;
        let prob: Vec<f64> = logits.iter().map(|&l| sigmoid(l)).collect();
        let anchors = match p.anchor_source {
            AnchorDetection::Network => {
                let mut a = vec![0];
                a.extend(anchor_peaks(
                    &prob,
                    p.anchor_probability,
                    p.min_anchor_gap_frames,
                ));
                a.push(NET_FRAMES - 1);
                a
            }
            AnchorDetection::Segmentation => {
                let t = Track::new(
                    clip.to_owned(),
                    None,
                    15.0,
                    mp_geom::Units::Metres,
                    Skeleton::msr20(),
                )?;
                segment_track(&t, &p.segment)?.anchors
            }
        };
        Ok((prob, anchors))
    }

    /// Step 2: the report of every anchor of `x` (canonical clip) with its
    /// score and whether it is flawed (interior anchors only).
    pub(super) fn score_anchors(
        &self,
        x: &Array3<f64>,
        action: u32,
        anchors: &[usize],
        prob: &[f64],
    ) -> Result<Vec<AnchorReport>> {
        let threshold = self.threshold(action)?;
        let mut reports = Vec::with_capacity(anchors.len());
        for (i, &f) in anchors.iter().enumerate() {
            let interior = i > 0 && i + 1 < anchors.len();
            let score = if interior {
                Some(self.score(x, action, f)?)
            } else {
                None
            };
            reports.push(AnchorReport {
                frame: f,
                source_frame: 0,
                probability: prob[f],
                score,
                threshold,
                // NaN scores count as flawed.
                flawed: score.is_some_and(|s| s < threshold || s.is_nan()),
                repaired: false,
                concept: None,
            });
        }
        Ok(reports)
    }

    /// GMM score of the pose at canonical frame `f`.
    fn score(&self, x: &Array3<f64>, action: u32, f: usize) -> Result<f64> {
        let pose = x.index_axis(ndarray::Axis(0), f);
        let feat = anchor_feature(pose, self.root, self.concepts.params.scale_normalise)?;
        match self.distance_thresholds {
            None => self.concepts.score(action, &feat),
            Some(_) => Ok(-self
                .concepts
                .action(action)?
                .nearest(&feat)
                .map(|(_, d)| d)
                .unwrap_or(f64::INFINITY)),
        }
    }

    /// The flaw threshold of `action` (score margin included).
    fn threshold(&self, action: u32) -> Result<f64> {
        let base = match self.distance_thresholds {
            None => self.concepts.action(action)?.score_threshold,
            Some(t) => -*t.get(&action).ok_or(RefineError::UnknownAction(action))?,
        };
        Ok(base - self.params.score_margin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peaks_are_local_maxima_above_threshold_and_spaced() {
        let mut p = vec![0.0; 20];
        p[5] = 0.9;
        p[6] = 0.8; // not a local maximum
        p[7] = 0.85; // local max but 2 frames from 5: gap 3 drops it
        p[12] = 0.6;
        p[15] = 0.4; // below threshold
        p[19] = 0.99; // last frame: never an interior anchor
        assert_eq!(anchor_peaks(&p, 0.5, 3), vec![5, 12]);
        assert_eq!(anchor_peaks(&p, 0.5, 2), vec![5, 7, 12]);
        assert!(anchor_peaks(&[], 0.5, 2).is_empty());
    }
}
