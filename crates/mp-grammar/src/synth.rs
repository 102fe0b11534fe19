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
//! segment, by the pose distance `d` of [`crate::distance`] (ties: the
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

use std::ops::Range;

use mp_geom::io::bvh::{Bvh, BvhTrackParams};
use mp_geom::{Track, Units};
use ndarray::{s, Array2, Array3, ArrayView1};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::derive::{derive_at_least, regenerate, Derivation, DeriveParams, Fsm, Regeneration};
use crate::distance::{PoseDistanceParams, PoseFeatures, Segment};
use crate::error::{GrammarError, Result};
use crate::grammar::Grammar;
use crate::symbols::{symbol_name, SymbolSegment, SymbolString};

/// Axes along which segments are translated so the root does not jump.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
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
    /// First segment. Default [`FirstSegment::Random`].
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

/// Blend weight `w_k` of the cosine ramp over `b` frames.
pub fn blend_weight(k: usize, b: usize) -> f64 {
    0.5 * (1.0 + (std::f64::consts::PI * (k + 1) as f64 / (b + 1) as f64).cos())
}

/// One segment of a synthesised motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Piece {
    /// Its symbol.
    pub symbol: usize,
    /// Index of the source segment (into the symbol string's segments).
    pub segment: usize,
    /// Frames of the source motion.
    pub source: Segment,
    /// First frame in the synthesised motion.
    pub start_frame: usize,
}

/// A synthesised motion.
#[derive(Debug, Clone)]
pub struct Synthesis {
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

impl Synthesis {
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
    pub synthesis: Synthesis,
    /// The derivation change.
    pub regeneration: Regeneration,
    /// Frames of the replaced region in the old motion.
    pub old_frames: Range<usize>,
    /// Frames of the new region in the new motion. Frames before it are
    /// unchanged; frames after it are the old ones translated on the aligned
    /// axes by one constant offset.
    pub new_frames: Range<usize>,
}

/// How a frame row is laid out.
#[derive(Debug, Clone)]
struct FrameSpace {
    /// Per aligned axis: (axis, columns averaged for the root position,
    /// columns translated with the root).
    axes: Vec<(usize, Vec<usize>, Vec<usize>)>,
    /// Rotation channels (wrapped differences).
    angle: Vec<bool>,
}

fn wrap_deg(x: f64) -> f64 {
    let mut v = (x + 180.0).rem_euclid(360.0) - 180.0;
    if v == -180.0 {
        v = 180.0;
    }
    v
}

impl FrameSpace {
    fn root(&self, row: ArrayView1<'_, f64>, ai: usize) -> f64 {
        let cols = &self.axes[ai].1;
        cols.iter().map(|&c| row[c]).sum::<f64>() / cols.len().max(1) as f64
    }

    /// `Δ` taking `cur` towards `prev` (see the module documentation).
    fn delta(&self, prev: ArrayView1<'_, f64>, cur: ArrayView1<'_, f64>) -> Vec<f64> {
        let mut d: Vec<f64> = prev
            .iter()
            .zip(cur.iter())
            .zip(&self.angle)
            .map(|((p, c), &ang)| if ang { wrap_deg(p - c) } else { p - c })
            .collect();
        for (ai, (_, _, moved)) in self.axes.iter().enumerate() {
            let rd = self.root(prev, ai) - self.root(cur, ai);
            for &c in moved {
                d[c] -= rd;
            }
        }
        d
    }

    /// Offset per aligned axis placing `next` (its first rows) after `prev`
    /// (its last rows).
    fn placement(
        &self,
        prev: &Array2<f64>,
        prev_end: usize,
        next: &Array2<f64>,
        next_start: usize,
    ) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.axes.len());
        for ai in 0..self.axes.len() {
            let last = self.root(prev.row(prev_end - 1), ai);
            let mut steps = Vec::new();
            if prev_end >= 2 {
                steps.push(last - self.root(prev.row(prev_end - 2), ai));
            }
            if next_start + 1 < next.nrows() {
                steps.push(
                    self.root(next.row(next_start + 1), ai) - self.root(next.row(next_start), ai),
                );
            }
            let v = if steps.is_empty() {
                0.0
            } else {
                steps.iter().sum::<f64>() / steps.len() as f64
            };
            out.push(last + v - self.root(next.row(next_start), ai));
        }
        out
    }

    fn translate(&self, rows: &mut Array2<f64>, range: Range<usize>, offset: &[f64]) {
        for (ai, (_, _, moved)) in self.axes.iter().enumerate() {
            let o = offset[ai];
            if o == 0.0 {
                continue;
            }
            for t in range.clone() {
                for &c in moved {
                    rows[[t, c]] += o;
                }
            }
        }
    }
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

/// The most output cells (frames × joints) one synthesis may produce: 10
/// million (the same bound as concrete-program execution,
/// `mp_concrete::exec::MAX_FRAME_JOINTS`), i.e. at most 240 MB of positions
/// at 3 dimensions × 8 bytes.
pub const MAX_FRAME_JOINTS: usize = 10_000_000;

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

fn axes_for(alignment: &RootAlignment, default: &[usize], dims: usize) -> Result<Vec<usize>> {
    let axes = match alignment {
        RootAlignment::Auto => default.to_vec(),
        RootAlignment::None => Vec::new(),
        RootAlignment::Axes(a) => a.clone(),
    };
    if let Some(&bad) = axes.iter().find(|&&a| a >= dims) {
        return Err(GrammarError::param(
            "root_alignment",
            format!("axis {bad} outside 0..{dims}"),
        ));
    }
    Ok(axes)
}

impl Stitcher {
    /// Segments a synthesis derives at least when no count is chosen
    /// ([`Self::synthesize`], [`Self::synthesize_fsm`]): 20.
    pub const DEFAULT_SEGMENTS: usize = 20;

    /// Levels above the terminal's nearest nonterminal ancestor that
    /// [`Self::regenerate`] climbs when none are chosen: 0 (that ancestor).
    pub const DEFAULT_REGENERATE_LEVELS: usize = 0;

    /// Prepares `track` (and its BVH, whose forward kinematics with length
    /// scale 1 the track must be) cut into the segments of `symbols`.
    ///
    /// Errors: frame counts that disagree, segments outside the motion, a
    /// symbol without segments, or bad parameters.
    pub fn new(
        track: &Track,
        bvh: Option<&Bvh>,
        symbols: &SymbolString,
        params: &StitchParams,
    ) -> Result<Self> {
        params.validate()?;
        let t_len = track.n_frames();
        if symbols.n_frames != t_len {
            return Err(GrammarError::Invalid(format!(
                "the symbols were found on {} frames, the motion has {t_len}",
                symbols.n_frames
            )));
        }
        if symbols.segments.is_empty() {
            return Err(GrammarError::Empty("symbol string has no segment".into()));
        }
        for (i, s) in symbols.segments.iter().enumerate() {
            if s.start >= s.end || s.end > t_len {
                return Err(GrammarError::Invalid(format!(
                    "segment {i}: frames {}..{} are empty or outside 0..{t_len}",
                    s.start, s.end
                )));
            }
            if s.symbol >= symbols.k {
                return Err(GrammarError::Invalid(format!(
                    "segment {i}: symbol {} outside 0..{}",
                    s.symbol, symbols.k
                )));
            }
        }
        let members = symbols.members();
        let medoids: Vec<usize> = (0..symbols.k)
            .map(|k| {
                symbols
                    .medoids
                    .get(k)
                    .copied()
                    .filter(|&m| symbols.segments.get(m).is_some_and(|s| s.symbol == k))
                    .or_else(|| members[k].first().copied())
                    .unwrap_or(0)
            })
            .collect();
        let features = PoseFeatures::from_track(track, &params.distance)?;
        let mut filled = track.clone();
        filled.fill_missing();
        let (space, rows, output) = match bvh {
            Some(b) => {
                if b.n_frames() != t_len || b.joints().len() != track.n_joints() {
                    return Err(GrammarError::Invalid(format!(
                        "BVH has {} frames and {} joints, the track {t_len} frames and {} joints",
                        b.n_frames(),
                        b.joints().len(),
                        track.n_joints()
                    )));
                }
                let root = b
                    .joints()
                    .first()
                    .ok_or_else(|| GrammarError::Empty("BVH has no joint".into()))?;
                let axes = axes_for(&params.root_alignment, &[0, 2], 3)?;
                let mut ax = Vec::new();
                for a in axes {
                    let col = root.channels.iter().enumerate().find_map(|(k, ch)| {
                        (ch.is_position() && ch.axis() == a).then_some(root.first_channel + k)
                    });
                    if let Some(c) = col {
                        ax.push((a, vec![c], vec![c]));
                    }
                }
                let mut angle = vec![false; b.n_channels()];
                for j in b.joints() {
                    for (k, ch) in j.channels.iter().enumerate() {
                        if !ch.is_position() {
                            if let Some(v) = angle.get_mut(j.first_channel + k) {
                                *v = true;
                            }
                        }
                    }
                }
                (
                    FrameSpace { axes: ax, angle },
                    b.motion().to_owned(),
                    Output::Bvh {
                        template: b.slice_frames(0, 1)?,
                        units: track.units(),
                    },
                )
            }
            None => {
                let (nj, d) = (track.n_joints(), track.dims());
                let default: &[usize] = match (track.units(), d) {
                    (Units::Unitless, _) => &[],
                    (_, 2) => &[0],
                    (_, 3) => &[0, 2],
                    _ => &[],
                };
                let axes = axes_for(&params.root_alignment, default, d)?;
                let conf = filled.confidence();
                let root = track
                    .skeleton()
                    .root
                    .filter(|&r| r < nj && (0..t_len).any(|t| conf[[t, r]] > 0.0));
                let ax = axes
                    .into_iter()
                    .map(|a| {
                        let moved: Vec<usize> = (0..nj).map(|j| j * d + a).collect();
                        let rc = match root {
                            Some(r) => vec![r * d + a],
                            None => moved.clone(),
                        };
                        (a, rc, moved)
                    })
                    .collect();
                let rows = filled
                    .positions()
                    .to_owned()
                    .into_shape_with_order((t_len, nj * d))
                    .map_err(|e| GrammarError::Invalid(e.to_string()))?;
                (
                    FrameSpace {
                        axes: ax,
                        angle: vec![false; nj * d],
                    },
                    rows,
                    Output::Positions {
                        n_joints: nj,
                        dims: d,
                        fps: track.fps(),
                        units: track.units(),
                        skeleton: track.skeleton().clone(),
                    },
                )
            }
        };
        Ok(Stitcher {
            params: params.clone(),
            features,
            segments: symbols.segments.clone(),
            members,
            medoids,
            space,
            rows,
            conf: track.confidence().to_owned(),
            output,
        })
    }

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

    /// Pose distance between the last frame of segment `a` and the first
    /// frame of segment `b` (the seam distance before blending).
    pub fn gap(&self, a: usize, b: usize) -> f64 {
        match (self.segments.get(a), self.segments.get(b)) {
            (Some(x), Some(y)) => self.features.dist_unchecked(x.end - 1, y.start),
            _ => f64::INFINITY,
        }
    }

    /// Seam distances before blending of a sequence of segment indices.
    pub fn gaps(&self, segments: &[usize]) -> Vec<f64> {
        segments.windows(2).map(|w| self.gap(w[0], w[1])).collect()
    }

    /// Symbol index of each grammar terminal (terminals are named by
    /// [`symbol_name`]).
    pub fn terminal_symbols(&self, grammar: &Grammar) -> Result<Vec<usize>> {
        grammar
            .terminals
            .iter()
            .map(|name| {
                (0..self.k())
                    .find(|&s| symbol_name(s) == *name)
                    .ok_or_else(|| {
                        GrammarError::Invalid(format!(
                            "grammar terminal `{name}` is none of the {} symbols of the motion",
                            self.k()
                        ))
                    })
            })
            .collect()
    }

    fn check_symbols(&self, symbols: &[usize]) -> Result<()> {
        if symbols.is_empty() {
            return Err(GrammarError::Empty(
                "symbol string to synthesise is empty".into(),
            ));
        }
        for (i, &s) in symbols.iter().enumerate() {
            if self.members.get(s).is_none_or(|m| m.is_empty()) {
                return Err(GrammarError::Invalid(format!(
                    "symbol {s} at position {i} has no segment in the source motion"
                )));
            }
        }
        Ok(())
    }

    /// Greedy segment choice for `symbols`, after segment `prev` and before
    /// segment `next` when given.
    fn select_between(
        &self,
        symbols: &[usize],
        prev: Option<usize>,
        next: Option<usize>,
        rng: &mut ChaCha8Rng,
    ) -> Vec<usize> {
        let mut out = Vec::with_capacity(symbols.len());
        let mut last = prev;
        let n = symbols.len();
        for (i, &s) in symbols.iter().enumerate() {
            let mem = &self.members[s];
            let follow = if i + 1 == n { next } else { None };
            let choice = match (last, follow) {
                (None, None) => match self.params.first_segment {
                    FirstSegment::Random => mem[rng.random_range(0..mem.len())],
                    FirstSegment::Medoid => self.medoids[s],
                },
                _ => {
                    let mut best = (f64::INFINITY, mem[0]);
                    for &c in mem {
                        let mut v = 0.0;
                        if let Some(p) = last {
                            v += self.gap(p, c);
                        }
                        if let Some(f) = follow {
                            v += self.gap(c, f);
                        }
                        if v < best.0 {
                            best = (v, c);
                        }
                    }
                    best.1
                }
            };
            out.push(choice);
            last = Some(choice);
        }
        out
    }

    /// Greedy segment choice (see the module documentation) for a symbol
    /// string, seeded (the first segment).
    pub fn select(&self, symbols: &[usize], seed: u64) -> Result<Vec<usize>> {
        self.check_symbols(symbols)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(1);
        Ok(self.select_between(symbols, None, None, &mut rng))
    }

    /// Appends segment `seg` to `out` (rows `0..len` in use), placed and
    /// head-blended after the rows already there. Returns the new length.
    fn append(
        &self,
        out: &mut Array2<f64>,
        conf: &mut Array2<f64>,
        len: usize,
        seg: usize,
    ) -> usize {
        let s = self.segments[seg];
        let l = s.len();
        let mut block = self.rows.slice(s![s.start..s.end, ..]).to_owned();
        if len > 0 {
            let off = self.space.placement(out, len, &block, 0);
            self.space.translate(&mut block, 0..l, &off);
            let d = self.space.delta(out.row(len - 1), block.row(0));
            let b = self.params.blend_frames.min(l.saturating_sub(1));
            for k in 0..b {
                let w = blend_weight(k, b);
                let mut row = block.row_mut(k);
                for (v, dv) in row.iter_mut().zip(&d) {
                    *v += w * dv;
                }
            }
        }
        out.slice_mut(s![len..len + l, ..]).assign(&block);
        conf.slice_mut(s![len..len + l, ..])
            .assign(&self.conf.slice(s![s.start..s.end, ..]));
        len + l
    }

    fn build(
        &self,
        symbols: Vec<usize>,
        pieces: Vec<Piece>,
        derivation: Option<Derivation>,
        rows: Array2<f64>,
        conf: Array2<f64>,
    ) -> Result<Synthesis> {
        let (track, bvh) = match &self.output {
            Output::Positions {
                n_joints,
                dims,
                fps,
                units,
                skeleton,
            } => {
                let t = rows.nrows();
                let pos: Array3<f64> = rows
                    .clone()
                    .into_shape_with_order((t, *n_joints, *dims))
                    .map_err(|e| GrammarError::Invalid(e.to_string()))?;
                (
                    Track::new(pos, Some(conf.clone()), *fps, *units, skeleton.clone())?,
                    None,
                )
            }
            Output::Bvh { template, units } => {
                let b = Bvh::from_parts(
                    template.joints().to_vec(),
                    template.frame_time_s(),
                    rows.clone(),
                )?;
                let t = b.to_track(&BvhTrackParams {
                    units: *units,
                    ..Default::default()
                })?;
                (t, Some(b))
            }
        };
        Ok(Synthesis {
            symbols,
            pieces,
            derivation,
            track,
            bvh,
            rows,
            conf,
        })
    }

    fn pieces_of(&self, segs: &[usize], first_frame: usize) -> Vec<Piece> {
        let mut f = first_frame;
        segs.iter()
            .map(|&i| {
                let s = self.segments[i];
                let p = Piece {
                    symbol: s.symbol,
                    segment: i,
                    source: s.segment(),
                    start_frame: f,
                };
                f += s.len();
                p
            })
            .collect()
    }

    /// Checks a requested segment count against [`MAX_SEGMENTS`] and, at the
    /// source's longest segment, against [`MAX_FRAME_JOINTS`]; the error
    /// names `segments`, the value and the limit.
    pub fn check_segments(&self, segments: usize) -> Result<()> {
        let longest = self
            .segments
            .iter()
            .map(|s| s.len())
            .max()
            .unwrap_or(1)
            .max(1);
        let joints = self.conf.ncols().max(1);
        let by_frames = (MAX_FRAME_JOINTS / joints / longest).max(1);
        let limit = by_frames.min(MAX_SEGMENTS);
        if segments > limit {
            return Err(GrammarError::param(
                "segments",
                format!(
                    "{segments} is too large: at most {limit} segments ({MAX_SEGMENTS}, or \
                     {MAX_FRAME_JOINTS} frame·joints at {longest} frames × {joints} joints \
                     per segment, whichever is fewer)"
                ),
            ));
        }
        Ok(())
    }

    /// Stitches the given source segments in order.
    pub fn render(&self, segments: &[usize]) -> Result<Synthesis> {
        if segments.is_empty() {
            return Err(GrammarError::Empty("no segment to stitch".into()));
        }
        if let Some(&bad) = segments.iter().find(|&&i| i >= self.segments.len()) {
            return Err(GrammarError::Invalid(format!(
                "segment index {bad} outside 0..{}",
                self.segments.len()
            )));
        }
        let total: usize = segments.iter().map(|&i| self.segments[i].len()).sum();
        let joints = self.conf.ncols().max(1);
        if total.saturating_mul(joints) > MAX_FRAME_JOINTS {
            return Err(GrammarError::param(
                "segments",
                format!(
                    "{} segments of {total} frames are too large: at most {} frames of \
                     {joints} joints ({MAX_FRAME_JOINTS} frame·joints)",
                    segments.len(),
                    MAX_FRAME_JOINTS / joints
                ),
            ));
        }
        let mut rows = Array2::zeros((total, self.rows.ncols()));
        let mut conf = Array2::zeros((total, self.conf.ncols()));
        let mut len = 0;
        for &i in segments {
            len = self.append(&mut rows, &mut conf, len, i);
        }
        let pieces = self.pieces_of(segments, 0);
        let symbols = pieces.iter().map(|p| p.symbol).collect();
        self.build(symbols, pieces, None, rows, conf)
    }

    /// Greedy selection and stitching of a symbol string.
    pub fn stitch(&self, symbols: &[usize], seed: u64) -> Result<Synthesis> {
        let segs = self.select(symbols, seed)?;
        self.render(&segs)
    }

    /// Derives sentences from `grammar` until they hold at least
    /// `min_segments` terminals, then stitches them (seeded).
    pub fn synthesize(
        &self,
        grammar: &Grammar,
        derive: &DeriveParams,
        min_segments: usize,
        seed: u64,
    ) -> Result<Synthesis> {
        self.check_segments(min_segments)?;
        let map = self.terminal_symbols(grammar)?;
        let derivation = derive_at_least(grammar, derive, min_segments.max(1), seed)?;
        let symbols: Vec<usize> = derivation
            .terminals()
            .iter()
            .map(|&t| map[t as usize])
            .collect();
        let mut s = self.stitch(&symbols, seed)?;
        s.derivation = Some(derivation);
        Ok(s)
    }

    /// `n_segments` symbols from the finite-state machine, stitched (seeded).
    pub fn synthesize_fsm(&self, fsm: &Fsm, n_segments: usize, seed: u64) -> Result<Synthesis> {
        self.check_segments(n_segments)?;
        if fsm.k() != self.k() {
            return Err(GrammarError::Invalid(format!(
                "the state machine has {} symbols, the motion {}",
                fsm.k(),
                self.k()
            )));
        }
        let symbols: Vec<usize> = fsm
            .generate(n_segments.max(1), seed)
            .iter()
            .map(|&s| s as usize)
            .collect();
        self.stitch(&symbols, seed)
    }

    /// Seam pose distances of a synthesis after blending (frames `s − 1`
    /// and `s` of every seam), in the source's distance units (the source
    /// body size normalises them).
    pub fn seam_distances(&self, synth: &Synthesis) -> Result<Vec<f64>> {
        let f = PoseFeatures::from_track_with_scale(
            &synth.track,
            &self.params.distance,
            Some(self.features.body_scale()),
        )?;
        synth
            .seam_frames()
            .iter()
            .map(|&s| f.pose_distance(s - 1, s))
            .collect()
    }

    /// The paper's authoring interaction: derives anew the nonterminal that
    /// produced terminal `terminal` (`levels` = 0: its nearest nonterminal
    /// ancestor; more climbs the tree) with `seed`, chooses segments for the
    /// new terminals (greedy from the segment before, the last one also
    /// leading into the segment after), and re-stitches only that region.
    ///
    /// Errors: a synthesis without derivation, a terminal out of range.
    pub fn regenerate(
        &self,
        grammar: &Grammar,
        synth: &Synthesis,
        terminal: usize,
        levels: usize,
        derive: &DeriveParams,
        seed: u64,
    ) -> Result<Regenerated> {
        let derivation = synth.derivation.as_ref().ok_or_else(|| {
            GrammarError::Invalid("the synthesis has no derivation to regenerate".into())
        })?;
        if derivation.len() != synth.pieces.len() {
            return Err(GrammarError::Invalid(format!(
                "derivation has {} terminals, the synthesis {} pieces",
                derivation.len(),
                synth.pieces.len()
            )));
        }
        let map = self.terminal_symbols(grammar)?;
        let regen = regenerate(grammar, derivation, terminal, levels, derive, seed)?;
        let old = regen.ancestor.terminals.clone();
        let all: Vec<u32> = regen.derivation.terminals();
        let new_syms: Vec<usize> = all[regen.new_terminals.clone()]
            .iter()
            .map(|&t| map[t as usize])
            .collect();
        if !new_syms.is_empty() {
            self.check_symbols(&new_syms)?;
        }
        let n_old = synth.pieces.len();
        let prev = old.start.checked_sub(1).map(|i| synth.pieces[i].segment);
        let next = (old.end < n_old).then(|| synth.pieces[old.end].segment);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(2);
        let new_segs = self.select_between(&new_syms, prev, next, &mut rng);

        let total_old = synth.n_frames();
        let f_b = synth
            .pieces
            .get(old.start)
            .map_or(total_old, |p| p.start_frame);
        let f_e = synth
            .pieces
            .get(old.end)
            .map_or(total_old, |p| p.start_frame);
        let span_len: usize = new_segs.iter().map(|&i| self.segments[i].len()).sum();
        let total = f_b + span_len + (total_old - f_e);
        if total == 0 {
            return Err(GrammarError::Empty(
                "the regenerated motion would have no frame".into(),
            ));
        }
        let mut rows = Array2::zeros((total, self.rows.ncols()));
        let mut conf = Array2::zeros((total, self.conf.ncols()));
        rows.slice_mut(s![..f_b, ..])
            .assign(&synth.rows.slice(s![..f_b, ..]));
        conf.slice_mut(s![..f_b, ..])
            .assign(&synth.conf.slice(s![..f_b, ..]));
        let mut len = f_b;
        for &i in &new_segs {
            len = self.append(&mut rows, &mut conf, len, i);
        }
        // The kept frames after the region, translated to follow it.
        let suffix = synth.rows.slice(s![f_e.., ..]).to_owned();
        if !suffix.is_empty() {
            let mut suffix = suffix;
            if len > 0 {
                let off = self.space.placement(&rows, len, &suffix, 0);
                let n_suf = suffix.nrows();
                self.space.translate(&mut suffix, 0..n_suf, &off);
                if let Some(&last) = new_segs.last() {
                    // Fade the region's tail towards the kept frame after it.
                    let d = self.space.delta(suffix.row(0), rows.row(len - 1));
                    let b = self
                        .params
                        .blend_frames
                        .min(self.segments[last].len().saturating_sub(1));
                    for k in 0..b {
                        let w = blend_weight(k, b);
                        let mut row = rows.row_mut(len - 1 - k);
                        for (v, dv) in row.iter_mut().zip(&d) {
                            *v += w * dv;
                        }
                    }
                }
            }
            rows.slice_mut(s![len.., ..]).assign(&suffix);
            conf.slice_mut(s![len.., ..])
                .assign(&synth.conf.slice(s![f_e.., ..]));
        }
        let mut pieces: Vec<Piece> = synth.pieces[..old.start].to_vec();
        pieces.extend(self.pieces_of(&new_segs, f_b));
        let shift = (f_b + span_len) as isize - f_e as isize;
        for p in &synth.pieces[old.end..] {
            let mut q = *p;
            q.start_frame = (p.start_frame as isize + shift) as usize;
            pieces.push(q);
        }
        let symbols = pieces.iter().map(|p| p.symbol).collect();
        let synthesis = self.build(symbols, pieces, Some(regen.derivation.clone()), rows, conf)?;
        Ok(Regenerated {
            synthesis,
            regeneration: regen,
            old_frames: f_b..f_e,
            new_frames: f_b..f_b + span_len,
        })
    }
}

/// Fraction of the `n`-grams (windows of `n` consecutive symbols) of
/// `generated` that occur somewhere in `training` (1 when `generated` is
/// shorter than `n`).
pub fn ngram_overlap(generated: &[usize], training: &[usize], n: usize) -> f64 {
    if n == 0 || generated.len() < n {
        return 1.0;
    }
    let seen: std::collections::HashSet<&[usize]> = training.windows(n).collect();
    let w: Vec<&[usize]> = generated.windows(n).collect();
    w.iter().filter(|g| seen.contains(*g)).count() as f64 / w.len() as f64
}

/// Mean length of the runs of equal consecutive symbols (0 for an empty
/// string).
pub fn mean_run_length(symbols: &[usize]) -> f64 {
    if symbols.is_empty() {
        return 0.0;
    }
    let runs = 1 + symbols.windows(2).filter(|w| w[0] != w[1]).count();
    symbols.len() as f64 / runs as f64
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

    #[test]
    fn weights_fall_from_one_to_zero() {
        let b = 8;
        let w: Vec<f64> = (0..b).map(|k| blend_weight(k, b)).collect();
        assert!(w[0] < 1.0 && w[0] > 0.9);
        assert!(w[b - 1] > 0.0 && w[b - 1] < 0.1);
        for p in w.windows(2) {
            assert!(p[1] < p[0]);
        }
        // Symmetric ramp: w_k + w_{B-1-k} = 1.
        for k in 0..b {
            assert!((w[k] + w[b - 1 - k] - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn wrapping() {
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-190.0), 170.0);
        assert_eq!(wrap_deg(180.0), 180.0);
        assert_eq!(wrap_deg(10.0), 10.0);
    }

    #[test]
    fn structure_measures() {
        assert_eq!(mean_run_length(&[1, 1, 2, 2, 2, 3]), 2.0);
        assert_eq!(mean_run_length(&[]), 0.0);
        assert_eq!(ngram_overlap(&[1, 2, 3], &[1, 2, 4], 2), 0.5);
        assert_eq!(ngram_overlap(&[1], &[1, 2], 2), 1.0);
    }
}
