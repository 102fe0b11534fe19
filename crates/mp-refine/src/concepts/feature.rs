//! Anchor features: a pose made root-relative and optionally
//! scale-normalised ([`anchor_feature`]), and the anchors of a track
//! collected as features ([`collect_anchors`]).

use mp_geom::Track;
use ndarray::ArrayView2;
use serde::{Deserialize, Serialize};

use super::ConceptParams;
use crate::error::{RefineError, Result};
use crate::segment::{segment_track, SegmentParams};

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
