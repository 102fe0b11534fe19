//! The anchor samples that concepts are learned from: the anchors of the
//! spline segmentation of each clip, put in the canonical frame.

use mp_geom::MsrAction3D;
use mp_geom::{Skeleton, Track, Units};
use ndarray::Axis;

use super::{anchor_feature, AnchorSample, ConceptParams};
use crate::error::Result;
use crate::motion::{canonicalize, HIP_CENTRE, NET_FRAMES};
use crate::segment::{segment_track, SegmentParams};

/// The MSR Action3D subjects that concepts are not learned from unless
/// asked for: they are kept for judging the refinement.
pub const HELD_OUT_SUBJECTS: [u32; 1] = [9];

/// Clips shorter than this many frames are not learned from.
pub const MIN_CLIP_FRAMES: usize = 8;

/// Anchor samples (canonical clips, anchors of the spline segmentation) of
/// a track labelled `action`, in the feature of `params`.
pub fn canonical_anchor_samples(
    track: &Track,
    action: u32,
    seg: &SegmentParams,
    params: &ConceptParams,
) -> Result<Vec<AnchorSample>> {
    let (c, frame) = canonicalize(track)?;
    let dur = (frame.source_frames.saturating_sub(1)) as f64 / frame.source_fps;
    let fps = if dur > 0.0 {
        (NET_FRAMES - 1) as f64 / dur
    } else {
        frame.source_fps
    };
    let t = Track::new(c.clone(), None, fps, Units::Metres, Skeleton::msr20())?;
    let s = segment_track(&t, seg)?;
    let root = Some(params.root_joint.unwrap_or(HIP_CENTRE));
    s.anchors
        .iter()
        .map(|&a| {
            Ok(AnchorSample {
                action,
                feature: anchor_feature(c.index_axis(Axis(0), a), root, params.scale_normalise)?,
            })
        })
        .collect()
}

/// The MSR Action3D clips concepts are learned from: those of `subjects`
/// (every subject but [`HELD_OUT_SUBJECTS`] when `None`) with at least
/// [`MIN_CLIP_FRAMES`] frames.
pub fn msr_training_clips(data: &MsrAction3D, subjects: Option<&[u32]>) -> Vec<usize> {
    data.clips()
        .iter()
        .filter(|c| match subjects {
            Some(s) => s.contains(&c.subject),
            None => !HELD_OUT_SUBJECTS.contains(&c.subject),
        })
        .filter(|c| c.rows.len() >= MIN_CLIP_FRAMES)
        .map(|c| c.index)
        .collect()
}

/// Anchor samples of the MSR clips `idx`.
pub fn msr_anchor_samples(
    data: &MsrAction3D,
    idx: &[usize],
    seg: &SegmentParams,
    params: &ConceptParams,
) -> Result<Vec<AnchorSample>> {
    let mut out = Vec::new();
    for &i in idx {
        let tr = data.clip(i)?;
        out.extend(canonical_anchor_samples(
            &tr,
            data.clip_info(i)?.action,
            seg,
            params,
        )?);
    }
    Ok(out)
}
