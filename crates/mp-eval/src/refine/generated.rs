//! The generated-motion side of [`crate::refine::evaluation`]: canonical real
//! clips, clips from the generator network, their refinement, and the
//! evaluator's features and logits with the quality figures (FID,
//! accuracy, diversity, multimodality, per-action FID) of a set of clips.

use std::collections::BTreeMap;
use std::time::Instant;

use mp_geom::MsrAction3D;
use ndarray::{Array2, Array3, Axis};
use serde::{Deserialize, Serialize};

use crate::refine::quality::{
    accuracy, diversity, fid, multimodality, per_action_fid, QualityParams,
};
use crate::refine::RefineResult as Result;
use mp_refine::NetRefiner;
use mp_refine::RefineError;
use mp_refine::{canonicalize, to_features, FRAME_FEATURES, NET_FRAMES};
use mp_refine::{RefineNets, N_ACTIONS};

/// Evaluator features and logits of canonical clips (`N × 60 × 60` features), in batches.
pub fn evaluator_outputs(
    nets: &RefineNets,
    clips: &Array3<f32>,
) -> Result<(Array2<f64>, Array2<f64>)> {
    let n = clips.dim().0;
    let nf = nets.sizes().features;
    let mut feats = Array2::<f64>::zeros((n, nf));
    let mut logits = Array2::<f64>::zeros((n, N_ACTIONS));
    let batch = 64;
    let mut start = 0;
    while start < n {
        let end = (start + batch).min(n);
        let flat: Vec<f32> = clips
            .slice(ndarray::s![start..end, .., ..])
            .iter()
            .copied()
            .collect();
        let out = nets.evaluate(&flat)?;
        for (r, i) in (start..end).enumerate() {
            for k in 0..nf {
                feats[[i, k]] = out.features[r * nf + k] as f64;
            }
            for k in 0..N_ACTIONS {
                logits[[i, k]] = out.logits[r * N_ACTIONS + k] as f64;
            }
        }
        start = end;
    }
    if feats.iter().chain(logits.iter()).any(|v| !v.is_finite()) {
        return Err(RefineError::NonFinite(
            "evaluator: non-finite feature or logit".into(),
        ));
    }
    Ok((feats, logits))
}

/// Canonical clips (`N × 60 × 60` features) and actions of MSR clips.
pub fn real_clips(data: &MsrAction3D, idx: &[usize]) -> Result<(Array3<f32>, Vec<u32>)> {
    let mut out = Array3::<f32>::zeros((idx.len(), NET_FRAMES, FRAME_FEATURES));
    let mut labels = Vec::with_capacity(idx.len());
    for (r, &i) in idx.iter().enumerate() {
        let (c, _) = canonicalize(&data.clip(i)?)?;
        out.index_axis_mut(Axis(0), r)
            .assign(&to_features(c.view()));
        labels.push(data.clip_info(i)?.action);
    }
    Ok((out, labels))
}

/// What the refinement did to a set of canonical clips.
#[derive(Debug, Clone, PartialEq)]
pub struct RefinedClips {
    /// Refined clips, `N × 60 × 60` features.
    pub clips: Array3<f32>,
    /// Mean time per clip, milliseconds.
    pub ms_per_clip: f64,
    /// Share of clips changed by any step.
    pub changed_share: f64,
    /// Share of clips with at least one run refilled by the flaw repair.
    pub detector_changed_share: f64,
    /// Mean flagged (frame, joint) cells per clip.
    pub flagged_cells_per_clip: f64,
    /// Mean anchors repaired per clip.
    pub repaired_anchors_per_clip: f64,
    /// Mean joint displacement between the clips and their refinement
    /// (canonical frame, metres).
    pub mean_change_m: f64,
}

/// Refines canonical clips with their labels.
pub fn refine_clips_report(
    refiner: &NetRefiner<'_>,
    clips: &Array3<f32>,
    labels: &[u32],
) -> Result<RefinedClips> {
    let mut out = clips.clone();
    let t0 = Instant::now();
    let (mut changed, mut det, mut cells, mut anchors) = (0usize, 0usize, 0usize, 0usize);
    let mut moved = 0.0;
    for (i, &a) in labels.iter().enumerate() {
        let c = mp_refine::from_features(clips.index_axis(Axis(0), i))?;
        let r = refiner.refine_canonical(c.view(), Some(a))?;
        if r.report.changed() {
            changed += 1;
        }
        if !r.report.repaired_runs.is_empty() {
            det += 1;
        }
        cells += r.report.flaw_cells.len();
        anchors += r.report.anchors.iter().filter(|a| a.repaired).count();
        moved += (&r.clip - &c)
            .lanes(Axis(2))
            .into_iter()
            .map(|l| l.dot(&l).sqrt())
            .sum::<f64>()
            / (c.dim().0 * c.dim().1).max(1) as f64;
        out.index_axis_mut(Axis(0), i)
            .assign(&to_features(r.clip.view()));
    }
    let n = labels.len().max(1) as f64;
    Ok(RefinedClips {
        clips: out,
        ms_per_clip: t0.elapsed().as_secs_f64() * 1e3 / n,
        changed_share: changed as f64 / n,
        detector_changed_share: det as f64 / n,
        flagged_cells_per_clip: cells as f64 / n,
        repaired_anchors_per_clip: anchors as f64 / n,
        mean_change_m: moved / n,
    })
}

/// Refines canonical clips with their labels; returns the refined clips,
/// the mean time per clip in milliseconds and the share of clips changed.
pub fn refine_clips(
    refiner: &NetRefiner<'_>,
    clips: &Array3<f32>,
    labels: &[u32],
) -> Result<(Array3<f32>, f64, f64)> {
    let r = refine_clips_report(refiner, clips, labels)?;
    Ok((r.clips, r.ms_per_clip, r.changed_share))
}

/// Quality of one set of clips against the real set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetQuality {
    /// FID against the real clips.
    pub fid: f64,
    /// Evaluator accuracy with the conditioning action as the label.
    pub accuracy: f64,
    /// Diversity (`S_d` pairs).
    pub diversity: f64,
    /// Multimodality (`S_m` pairs per action).
    pub multimodality: f64,
    /// FID per action against the real clips of that action.
    pub per_action_fid: BTreeMap<u32, f64>,
}

pub(crate) fn set_quality(
    feats: &Array2<f64>,
    logits: &Array2<f64>,
    labels: &[u32],
    real: &Array2<f64>,
    real_labels: &[u32],
    q: &QualityParams,
) -> Result<SetQuality> {
    Ok(SetQuality {
        fid: fid(feats.view(), real.view())?,
        accuracy: accuracy(logits.view(), labels)?,
        diversity: diversity(feats.view(), q)?,
        multimodality: multimodality(feats.view(), labels, q)?,
        per_action_fid: per_action_fid(feats.view(), labels, real.view(), real_labels)?,
    })
}
