//! Motion synthesis from a string of symbols (paper §6): one source segment
//! per symbol, chosen greedily, stitched with a short cross-fade.
//!
//! # Segment selection
//!
//! Each symbol stands for the segments of the source motion labelled with
//! it. The first segment is drawn at random among its symbol's segments
//! (seeded; the paper: "an arbitrary segment"), or is the symbol's medoid
//! ([`FirstSegment`]). Every following segment is the one of its symbol
//! whose **first** pose is closest to the **last** pose of the previous
//! segment, by the pose distance `d` of `distance` (ties: the
//! earlier segment). When a segment must also lead into a fixed one (the
//! last segment of a regenerated region), the sum of both seam distances is
//! minimised.
//!
//! # Stitching
//!
//! The motion is handled as rows of numbers, one per frame: joint
//! coordinates for a track, channel values for a BVH (so BVH output is
//! built by slicing and joining channels, with the source hierarchy).
//!
//! * **Root alignment.** Each segment is translated on the *aligned axes*
//!   ([`RootAlignment`]; by default the ground plane x, z of a 3-D / BVH
//!   motion with y up, x of a 2-D track, nothing for feature tracks) so that
//!   its root continues from the previous segment's last root position by
//!   one step of the mean root velocity at the seam (the mean of the last
//!   step before and the first step after). The vertical axis is left as it
//!   is, so the body does not float or sink. For a BVH the translation is
//!   added to the root's position channels.
//! * **Cross-fade.** Let `Δ` be the difference between the last frame `p`
//!   before the seam and the first frame `c` after it, taken root-relative
//!   on the aligned axes (`Δ_j = (p_j − c_j) − (p_root − c_root)`), absolute
//!   on the other axes, and wrapped to `(−180°, 180°]` for BVH rotation
//!   channels. The first `B = min(blend_frames, L − 1)` frames of the
//!   incoming segment (length `L`) get `w_k · Δ` added, with the cosine ramp
//!   `w_k = ½ (1 + cos(π (k + 1) / (B + 1)))`, `k = 0 … B − 1`, which falls
//!   from just below 1 to just above 0. For a track the root-relative pose
//!   at the seam moves by the factor `1 − w_0` towards the previous pose, so
//!   the seam pose distance after blending is `(1 − w_0)` times the one
//!   before (never larger). For a BVH the fade acts on joint angles, which
//!   shrinks the seam the same way up to the non-linearity of forward
//!   kinematics. A regenerated region also fades its *last* `B` frames
//!   towards the (kept) frame after it, so the frames outside the region do
//!   not change.
//!
//! Rotation about the vertical axis is not aligned: segments keep their
//! facing direction, and the greedy choice prefers segments whose start
//! faces like the previous end, since the pose distance is not invariant
//! to it.
//!
//! # Layout
//!
//! * `frames`: the motion as frame rows — preparing a [`Stitcher`] from a
//!   source motion, root alignment on the aligned axes, and the cross-fade
//!   difference `Δ`.
//! * `select`: segment selection (seam gaps, the greedy choice).
//! * `stitch`: stitching selected segments into a [`SynthesizedMotion`], the
//!   cross-fade ramp [`blend_weight`], and synthesis from a grammar or a
//!   finite-state machine.
//! * `regenerate`: [`Stitcher::regenerate`], re-deriving and re-stitching
//!   one region.
//! * this module: the parameters, the result types and the limits.

use std::ops::Range;

use mp_geom::Bvh;
use mp_geom::{Track, Units};
use ndarray::Array2;
use serde::{Deserialize, Serialize};

use crate::derive::{Derivation, Regeneration};
use crate::distance::{FrameSpan, PoseDistanceParams, PoseFeatures};
use crate::error::{GrammarError, Result};
use crate::symbols::SymbolSegment;

mod frames;
mod regenerate;
mod select;
mod stitch;

pub use stitch::blend_weight;

use frames::FrameSpace;

/// Axes along which segments are translated so the root does not jump.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
#[non_exhaustive]
pub enum RootAlignment {
    /// x and z for 3-D positions and BVH (y up), x for 2-D positions,
    /// none for feature tracks. Default.
    #[default]
    Auto,
    /// No translation.
    None,
    /// These coordinate axes (0 = x, 1 = y, 2 = z).
    Axes(Vec<usize>),
}

/// How the first segment of a synthesis is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[non_exhaustive]
pub enum FirstSegment {
    /// At random among the symbol's segments (seeded). Default.
    #[default]
    Random,
    /// The symbol's medoid segment.
    Medoid,
}

/// Parameters of segment selection and stitching.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StitchParams {
    /// Cross-fade length at each seam, frames; 0 = no blending. Default 8
    /// (0.27 s at 30 fps).
    pub blend_frames: usize,
    /// Root translation alignment (explicit axes distinct). Default [`RootAlignment::Auto`].
    pub root_alignment: RootAlignment,
    /// Pose distance for choosing segments (should be the one the symbols
    /// were found with). Default: [`PoseDistanceParams::default`].
    pub distance: PoseDistanceParams,
    /// First segment. Default `FirstSegment::Random`.
    pub first_segment: FirstSegment,
}

impl Default for StitchParams {
    fn default() -> Self {
        StitchParams {
            blend_frames: 8,
            root_alignment: RootAlignment::Auto,
            distance: PoseDistanceParams::default(),
            first_segment: FirstSegment::Random,
        }
    }
}

impl StitchParams {
    /// Checks every field: explicit root-alignment axes distinct, and an
    /// explicit joint list of the pose distance non-empty. (Axes beyond the
    /// motion's dimensions are caught by [`Stitcher::new`], which knows them.)
    pub fn validate(&self) -> Result<()> {
        if let RootAlignment::Axes(axes) = &self.root_alignment {
            for (i, a) in axes.iter().enumerate() {
                if axes[..i].contains(a) {
                    return Err(GrammarError::param(
                        "root_alignment",
                        format!("axis {a} is listed twice"),
                    ));
                }
            }
        }
        if self.distance.joints.as_ref().is_some_and(|j| j.is_empty()) {
            return Err(GrammarError::param("distance.joints", "empty joint list"));
        }
        Ok(())
    }
}

/// One segment of a synthesised motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Piece {
    /// Its symbol.
    pub symbol: usize,
    /// Index of the source segment (into the symbol string's segments).
    pub segment: usize,
    /// Frames of the source motion.
    pub source: FrameSpan,
    /// First frame in the synthesised motion.
    pub start_frame: usize,
}

/// A synthesised motion.
#[derive(Debug, Clone)]
pub struct SynthesizedMotion {
    /// Symbol of every piece.
    pub symbols: Vec<usize>,
    /// The pieces in order.
    pub pieces: Vec<Piece>,
    /// The derivation the symbols came from (grammar synthesis only).
    pub derivation: Option<Derivation>,
    /// The motion.
    pub track: Track,
    /// The motion as BVH (when the source is one).
    pub bvh: Option<Bvh>,
    rows: Array2<f64>,
    conf: Array2<f64>,
}

impl SynthesizedMotion {
    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.rows.nrows()
    }
    /// First frame of every piece after the first (the frame after a seam).
    pub fn seam_frames(&self) -> Vec<usize> {
        self.pieces.iter().skip(1).map(|p| p.start_frame).collect()
    }
    /// Frame range of piece `i`.
    pub fn piece_frames(&self, i: usize) -> Option<Range<usize>> {
        let p = self.pieces.get(i)?;
        Some(p.start_frame..p.start_frame + p.source.len())
    }
}

/// The result of [`Stitcher::regenerate`].
#[derive(Debug, Clone)]
pub struct Regenerated {
    /// The new motion.
    pub synthesis: SynthesizedMotion,
    /// The derivation change.
    pub regeneration: Regeneration,
    /// Frames of the replaced region in the old motion.
    pub old_frames: Range<usize>,
    /// Frames of the new region in the new motion. Frames before it are
    /// unchanged; frames after it are the old ones translated on the aligned
    /// axes by one constant offset.
    pub new_frames: Range<usize>,
}

#[derive(Debug, Clone)]
enum Output {
    Positions {
        n_joints: usize,
        dims: usize,
        fps: f64,
        units: Units,
        skeleton: mp_geom::Skeleton,
    },
    Bvh {
        template: Bvh,
        units: Units,
    },
}

/// The most output cells (frames × joints) one synthesis may produce (the
/// bound of concrete-program execution, `mp_geom::MAX_FRAME_JOINTS`).
pub use mp_geom::MAX_FRAME_JOINTS;

/// The most segments a synthesis may request (`segments` of
/// [`Stitcher::synthesize`] and [`Stitcher::synthesize_fsm`]), whatever
/// their length: one million. The frames they imply must also fit
/// [`MAX_FRAME_JOINTS`], counting every segment at the source's longest.
pub const MAX_SEGMENTS: usize = 1_000_000;

/// A source motion cut into symbol segments, ready to stitch.
#[derive(Debug, Clone)]
pub struct Stitcher {
    params: StitchParams,
    features: PoseFeatures,
    segments: Vec<SymbolSegment>,
    members: Vec<Vec<usize>>,
    medoids: Vec<usize>,
    space: FrameSpace,
    rows: Array2<f64>,
    conf: Array2<f64>,
    output: Output,
}

impl Stitcher {
    /// Segments a synthesis derives at least when no count is chosen
    /// ([`Self::synthesize`], [`Self::synthesize_fsm`]): 20.
    pub const DEFAULT_SEGMENTS: usize = 20;

    /// Levels above the terminal's nearest nonterminal ancestor that
    /// [`Self::regenerate`] climbs when none are chosen: 0 (that ancestor).
    pub const DEFAULT_REGENERATE_LEVELS: usize = 0;

    /// The parameters.
    pub fn params(&self) -> &StitchParams {
        &self.params
    }
    /// Number of symbols.
    pub fn k(&self) -> usize {
        self.members.len()
    }
    /// The source segments.
    pub fn segments(&self) -> &[SymbolSegment] {
        &self.segments
    }
    /// Features of the source motion (distance and body size).
    pub fn features(&self) -> &PoseFeatures {
        &self.features
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stitch_params_reject_bad_fields() {
        assert!(StitchParams::default().validate().is_ok());
        let p = StitchParams {
            root_alignment: RootAlignment::Axes(vec![0, 2, 0]),
            ..StitchParams::default()
        };
        assert!(matches!(
            p.validate(),
            Err(GrammarError::InvalidParam {
                name: "root_alignment",
                ..
            })
        ));
        let mut p = StitchParams::default();
        p.distance.joints = Some(Vec::new());
        assert!(matches!(
            p.validate(),
            Err(GrammarError::InvalidParam {
                name: "distance.joints",
                ..
            })
        ));
    }
}
