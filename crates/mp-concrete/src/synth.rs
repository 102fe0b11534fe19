//! Synthesis of a concrete program from a track (paper §3.1): the shared
//! segmentation minimising Σ segments (Σ joints best-fit error + λ) is found
//! by [`segment`] — an exact branch and bound over the DP of [`crate::dp`]
//! with segment moments updated in O(1) per candidate and lower bounds of the
//! fit errors ([`crate::search`], module docs there) — and the chosen
//! segments are fitted once more with [`mp_geom::fit::fit_best`] (in parallel)
//! to get their primitives. The costs are those of `fit_best` on every
//! candidate segment `k..n` of at most `W` frames; [`segment_exhaustive`]
//! still computes them all into a [`CostTable`] and is the reference the
//! tests compare with (same optimum; `O(T·W)` memory and `O(T·W²·J)` time).
//!
//! # Scale
//!
//! Thresholds and λ are given at the reference scale of a 512-pixel frame
//! (SPEC.md). `unit_scale` (track units per reference pixel) converts them:
//!
//! * [`Scale::FrameSize`]: `unit_scale = max(H, W) / 512` (pixels, frame size known);
//! * [`Scale::Auto`] (default): `unit_scale = track.scale() / REFERENCE_EXTENT_PX`,
//!   where `track.scale()` is the diagonal of the bounding box of all valid
//!   positions and [`REFERENCE_EXTENT_PX`] = 256 is that diagonal for a typical
//!   clip at 512 px (the median over the Penn Action training clips, rescaled
//!   to a 512-px frame, is 257 px). Works for metres as well as pixels;
//! * [`Scale::UnitScale`]: given explicitly.
//!
//! With the Euclidean norm (error in units·frames) λ scales by `unit_scale`;
//! with the squared norm by `unit_scale²`.
//!
//! # λ
//!
//! * [`Lambda::Fixed`]: the same λ for every segment (reference 1600).
//! * [`Lambda::Adaptive`]: per frame `f`, take the window of frames
//!   `f − h ..= f + h` (`h = window_frames / 2`, clipped to the track); for
//!   each joint with ≥ 2 valid frames there, the `D × D` population
//!   covariance of its valid positions; `C(f)` = the mean of these over the
//!   joints, expressed in reference pixels² (divided by `unit_scale²`);
//!   `λ_ref(f) = clamp(‖C(f)‖_F, min_ref, max_ref)` (default [100, 1600]; a
//!   window with no such joint gets `max_ref`). A segment `k..n` pays the λ
//!   of its last frame `n − 1`.
//! * [`Lambda::Spread`]: like `Adaptive`, in the cost's own units:
//!   `λ_ref(f) = clamp(√‖C(f)‖_F · seconds · fps, min_ref, max_ref)` — the
//!   spread of the keypoints around the frame (reference px) held for
//!   `seconds` (frames at the track's rate), where `Adaptive` takes the
//!   covariance (px²) as it is. A segment pays the λ of its last frame.
//! * [`Lambda::Budget`]: a parameter budget instead of a price per segment:
//!   the program with the smallest fixed λ whose parameters
//!   ([`Program::n_params`]) are at most `ratio` of the raw numbers `T·J·D`,
//!   found by bisection on λ (reference scale, [`BUDGET_LAMBDA_RANGE`], steps
//!   of [`BUDGET_LAMBDA_STEP`]); each step is one synthesis, so this costs
//!   about a dozen syntheses. A budget below the smallest program's size is an
//!   error naming both.

use mp_geom::fit::{fit_best_unchecked, ErrorNorm, FitParams};
use mp_geom::{Primitive, Track};
use ndarray::{s, Array2};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::dp::{segment_table, CostTable, Segmentation};
use crate::error::{ConcreteError, Result};
use crate::program::{Program, Segment};
use crate::search::{segment_search, JointTrack, SearchStats};
use crate::smooth::{refit_joint, Continuity, JointSeries, RefitNorm};

/// Reference pixels of a 512-px frame.
pub const REFERENCE_FRAME_PX: f64 = 512.0;
/// Bounding-box diagonal of a typical clip's valid keypoints at the 512-px reference scale.
pub const REFERENCE_EXTENT_PX: f64 = 256.0;

/// How the segment penalty λ is chosen (values at the 512-px reference scale).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Lambda {
    /// The same λ for every segment.
    Fixed {
        /// λ in reference px·frames (Euclidean norm). Default 1600.
        lambda_ref: f64,
    },
    /// The smallest fixed λ whose program has at most `ratio · T·J·D`
    /// parameters (see the module docs).
    Budget {
        /// Program parameters over raw numbers, in (0, 1].
        ratio: f64,
    },
    /// λ from the spread of the keypoints around each frame, in px·frames
    /// (see the module docs).
    Spread {
        /// How long an error of the local spread is worth one segment. Default 1.
        seconds: f64,
        /// Window length in frames (centred on the frame). Default 31.
        window_frames: usize,
        /// Lower clamp (reference scale). Default 100.
        min_ref: f64,
        /// Upper clamp (reference scale). Default 1600.
        max_ref: f64,
    },
    /// λ from the covariance of the keypoints around each frame (see the module docs).
    Adaptive {
        /// Window length in frames (centred on the frame). Default 31.
        window_frames: usize,
        /// Lower clamp (reference scale). Default 100.
        min_ref: f64,
        /// Upper clamp (reference scale). Default 1600.
        max_ref: f64,
    },
}

impl Lambda {
    /// Default fixed λ: 1600.
    pub const DEFAULT_FIXED: f64 = 1600.0;
    /// The default adaptive setting: window 31, clamp [100, 1600].
    pub fn adaptive() -> Self {
        Lambda::Adaptive {
            window_frames: 31,
            min_ref: 100.0,
            max_ref: 1600.0,
        }
    }
    /// A fixed λ (reference scale).
    pub fn fixed(lambda_ref: f64) -> Self {
        Lambda::Fixed { lambda_ref }
    }
    /// A parameter budget: at most `ratio` of the raw numbers.
    pub fn budget(ratio: f64) -> Self {
        Lambda::Budget { ratio }
    }
    /// λ from the local spread held for `seconds` (window 31, clamp [100, 1600]).
    pub fn spread(seconds: f64) -> Self {
        Lambda::Spread {
            seconds,
            window_frames: 31,
            min_ref: 100.0,
            max_ref: 1600.0,
        }
    }

    /// The window (frames) and clamp (reference scale) of a rule read from
    /// the keypoints around each frame (`Adaptive`, `Spread`).
    pub(crate) fn window_clamp(&self) -> Option<(usize, f64, f64)> {
        match *self {
            Lambda::Adaptive {
                window_frames,
                min_ref,
                max_ref,
            }
            | Lambda::Spread {
                window_frames,
                min_ref,
                max_ref,
                ..
            } => Some((window_frames, min_ref, max_ref)),
            Lambda::Fixed { .. } | Lambda::Budget { .. } => None,
        }
    }

    /// The same rule with its window and clamp mapped by `f` (other rules
    /// unchanged).
    pub(crate) fn map_window_clamp(
        self,
        f: impl FnOnce(usize, f64, f64) -> (usize, f64, f64),
    ) -> Self {
        match self {
            Lambda::Adaptive {
                window_frames,
                min_ref,
                max_ref,
            } => {
                let (window_frames, min_ref, max_ref) = f(window_frames, min_ref, max_ref);
                Lambda::Adaptive {
                    window_frames,
                    min_ref,
                    max_ref,
                }
            }
            Lambda::Spread {
                seconds,
                window_frames,
                min_ref,
                max_ref,
            } => {
                let (window_frames, min_ref, max_ref) = f(window_frames, min_ref, max_ref);
                Lambda::Spread {
                    seconds,
                    window_frames,
                    min_ref,
                    max_ref,
                }
            }
            other => other,
        }
    }
}

/// The fixed λ (reference scale) a [`Lambda::Budget`] searches between.
pub const BUDGET_LAMBDA_RANGE: (f64, f64) = (1.0, 1e7);
/// The bisection of a [`Lambda::Budget`] stops when its bracket is this
/// narrow (the ratio of its ends).
pub const BUDGET_LAMBDA_STEP: f64 = 1.02;

impl Default for Lambda {
    fn default() -> Self {
        Lambda::fixed(Self::DEFAULT_FIXED)
    }
}

/// How `unit_scale` (track units per reference pixel) is found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Scale {
    /// `track.scale() / REFERENCE_EXTENT_PX` (1 when the track has no extent).
    #[default]
    Auto,
    /// `frame_px / 512`: the largest side of the video frame in pixels.
    FrameSize {
        /// max(H, W) of the frame, pixels.
        frame_px: f64,
    },
    /// Given directly.
    UnitScale {
        /// Track units per reference pixel.
        unit_scale: f64,
    },
}

/// Parameters of synthesis. Defaults follow SPEC.md.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SynthParams {
    /// Segment penalty. Default: fixed 1600.
    pub lambda: Lambda,
    /// Maximum segment length W in frames (the DP is O(T·W)). Default 60.
    pub max_segment_frames: usize,
    /// Primitive fitting and selection (its `unit_scale` is replaced by the one from `scale`).
    pub fit: FitParams,
    /// How to find `unit_scale`. Default: [`Scale::Auto`].
    pub scale: Scale,
    /// A joint counts as observed in a frame when its confidence is above this. Default 0.
    pub min_confidence: f64,
    /// What to do with a joint that is observed in no frame at all (e.g. an
    /// all-NaN column, or a joint occluded for a whole clip). Default: error.
    pub unobserved_joints: UnobservedJoints,
    /// Whether consecutive segments share their boundary pose (the chosen
    /// segmentation refitted per joint, [`crate::smooth`]). Default: C0.
    /// Parameters serialised before the field existed read as C0.
    #[serde(default = "default_continuity")]
    pub continuity: Continuity,
    /// What the C0 refit minimises ([`crate::smooth`]). Default: squared residuals.
    #[serde(default)]
    pub refit_norm: RefitNorm,
}

fn default_continuity() -> Continuity {
    SynthParams::DEFAULT_CONTINUITY
}

/// Policy for joints that are observed in no frame of the track.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UnobservedJoints {
    /// Refuse the track, naming the joint ([`ConcreteError::Track`]).
    #[default]
    Error,
    /// Keep the joint out of the segmentation cost and fit its primitives to
    /// the positions stored in the track (which carry no evidence).
    Ignore,
}

impl Default for SynthParams {
    fn default() -> Self {
        SynthParams {
            lambda: Lambda::default(),
            max_segment_frames: 60,
            fit: FitParams::default(),
            scale: Scale::Auto,
            min_confidence: 0.0,
            unobserved_joints: UnobservedJoints::Error,
            continuity: Self::DEFAULT_CONTINUITY,
            refit_norm: RefitNorm::Squared,
        }
    }
}

/// The window and clamp of an adaptive λ rule.
fn check_window_clamp(window_frames: usize, min_ref: f64, max_ref: f64) -> Result<()> {
    finite_nonneg("lambda.min_ref", min_ref)?;
    finite_nonneg("lambda.max_ref", max_ref)?;
    if min_ref > max_ref {
        return Err(ConcreteError::param(
            "lambda.min_ref",
            format!("{min_ref} is above lambda.max_ref {max_ref}"),
        ));
    }
    if window_frames == 0 {
        return Err(ConcreteError::param("lambda.window_frames", "must be ≥ 1"));
    }
    Ok(())
}

fn finite_nonneg(name: &'static str, v: f64) -> Result<()> {
    if !v.is_finite() || v < 0.0 {
        return Err(ConcreteError::param(
            name,
            format!("must be finite and ≥ 0, got {v}"),
        ));
    }
    Ok(())
}

impl SynthParams {
    /// The default of [`SynthParams::continuity`].
    pub const DEFAULT_CONTINUITY: Continuity = Continuity::C0;

    /// Checks every field: λ finite and ≥ 0 (min ≤ max, window ≥ 1 for adaptive),
    /// W ≥ 1, scales finite and > 0, `min_confidence` in [0, 1), at least one primitive kind.
    pub fn validate(&self) -> Result<()> {
        match self.lambda {
            Lambda::Fixed { lambda_ref } => finite_nonneg("lambda", lambda_ref)?,
            Lambda::Budget { ratio } => {
                if !(ratio.is_finite() && ratio > 0.0 && ratio <= 1.0) {
                    return Err(ConcreteError::param(
                        "lambda.ratio",
                        format!("a parameter budget must be in (0, 1], got {ratio}"),
                    ));
                }
            }
            Lambda::Spread { seconds, .. } => {
                if !(seconds.is_finite() && seconds > 0.0) {
                    return Err(ConcreteError::param(
                        "lambda.seconds",
                        format!("must be a positive number of seconds, got {seconds}"),
                    ));
                }
            }
            Lambda::Adaptive { .. } => {}
        }
        if let Some((window_frames, min_ref, max_ref)) = self.lambda.window_clamp() {
            check_window_clamp(window_frames, min_ref, max_ref)?;
        }
        if self.max_segment_frames == 0 {
            return Err(ConcreteError::param("max_segment_frames", "must be ≥ 1"));
        }
        match self.scale {
            Scale::Auto => {}
            Scale::FrameSize { frame_px } => {
                if !(frame_px.is_finite() && frame_px > 0.0) {
                    return Err(ConcreteError::param(
                        "scale.frame_px",
                        format!("must be finite and > 0, got {frame_px}"),
                    ));
                }
            }
            Scale::UnitScale { unit_scale } => {
                if !(unit_scale.is_finite() && unit_scale > 0.0) {
                    return Err(ConcreteError::param(
                        "scale.unit_scale",
                        format!("must be finite and > 0, got {unit_scale}"),
                    ));
                }
            }
        }
        if !(0.0..1.0).contains(&self.min_confidence) {
            return Err(ConcreteError::param(
                "min_confidence",
                format!("must be in [0, 1), got {}", self.min_confidence),
            ));
        }
        if self.fit.kinds.is_empty() {
            return Err(ConcreteError::param(
                "fit.kinds",
                "no primitive kind allowed",
            ));
        }
        Ok(())
    }

    /// `unit_scale` for a track (see the module docs).
    pub fn unit_scale(&self, track: &Track) -> f64 {
        match self.scale {
            Scale::Auto => {
                let e = track.scale();
                if e.is_finite() && e > 0.0 {
                    e / REFERENCE_EXTENT_PX
                } else {
                    1.0
                }
            }
            Scale::FrameSize { frame_px } => frame_px / REFERENCE_FRAME_PX,
            Scale::UnitScale { unit_scale } => unit_scale,
        }
    }
}

/// The result of [`synthesize_detailed`].
#[derive(Debug, Clone, PartialEq)]
pub struct Synthesis {
    /// The program.
    pub program: Program,
    /// The segmentation and its total DP cost (fit errors + λ, track units).
    pub segmentation: Segmentation,
    /// Track units per reference pixel used for thresholds and λ.
    pub unit_scale: f64,
    /// λ per frame in track units (segment `k..n` pays `lambda[n − 1]`).
    pub lambda: Vec<f64>,
}

/// Track data prepared for fitting: gap-filled trajectories and 0/1 weights per joint.
struct Prepared {
    /// Per joint `T × D` (missing frames filled by interpolation).
    points: Vec<Array2<f64>>,
    /// Per joint, weight per frame (1 observed, 0 missing).
    weights: Vec<Vec<f64>>,
    /// Per joint, prefix count of observed frames (length T + 1).
    prefix_valid: Vec<Vec<usize>>,
}

fn prepare(track: &Track, min_conf: f64, unobserved: UnobservedJoints) -> Result<Prepared> {
    let (t, j) = (track.n_frames(), track.n_joints());
    if t == 0 {
        return Err(ConcreteError::Track("the track has no frames".into()));
    }
    if t < 2 {
        return Err(ConcreteError::Track(format!(
            "the track has {t} frame; synthesis needs at least 2"
        )));
    }
    if j == 0 {
        return Err(ConcreteError::Track("the track has no joints".into()));
    }
    let conf = track.confidence();
    if conf.iter().all(|&c| c <= min_conf) {
        return Err(ConcreteError::Track(format!(
            "every joint of every frame has confidence ≤ {min_conf} (nothing observed)"
        )));
    }
    let names = &track.skeleton().joints;
    let mut filled = track.clone();
    // Mark low-confidence entries missing before filling.
    {
        let mut c = filled.confidence_mut();
        c.mapv_inplace(|v| if v > min_conf { v } else { 0.0 });
    }
    filled.fill_missing();
    let mut points = Vec::with_capacity(j);
    let mut weights = Vec::with_capacity(j);
    let mut prefix_valid = Vec::with_capacity(j);
    for ji in 0..j {
        let w: Vec<f64> = (0..t)
            .map(|ti| if conf[[ti, ji]] > min_conf { 1.0 } else { 0.0 })
            .collect();
        if w.iter().all(|&x| x == 0.0) && unobserved == UnobservedJoints::Error {
            let name = names.get(ji).map(String::as_str).unwrap_or("?");
            return Err(ConcreteError::Track(format!(
                "joint {ji} (`{name}`) is missing in every frame (confidence ≤ {min_conf} or non-finite positions); set `unobserved_joints` to ignore it"
            )));
        }
        let mut pre = vec![0usize; t + 1];
        for ti in 0..t {
            pre[ti + 1] = pre[ti] + usize::from(w[ti] > 0.0);
        }
        points.push(filled.joint(ji).to_owned());
        weights.push(w);
        prefix_valid.push(pre);
    }
    Ok(Prepared {
        points,
        weights,
        prefix_valid,
    })
}

/// Per-frame λ in track units (see the module docs).
pub fn lambda_per_frame(track: &Track, params: &SynthParams, unit_scale: f64) -> Vec<f64> {
    let t = track.n_frames();
    let factor = match params.fit.norm {
        ErrorNorm::Euclidean => unit_scale,
        ErrorNorm::Squared => unit_scale * unit_scale,
    };
    let Some((window_frames, min_ref, max_ref)) = params.lambda.window_clamp() else {
        return match params.lambda {
            Lambda::Fixed { lambda_ref } => vec![lambda_ref * factor; t],
            // A budget is resolved to a fixed λ before any segmentation
            // (`resolve_budget`); on its own, the upper end of its range
            // (the most compact program).
            _ => vec![BUDGET_LAMBDA_RANGE.1 * factor; t],
        };
    };
    // `Adaptive` prices a segment at the covariance's norm (px²), `Spread` at
    // its square root (px) held for `seconds` of frames.
    let hold = match params.lambda {
        Lambda::Spread { seconds, .. } => Some(seconds * track.fps()),
        _ => None,
    };
    let price = |c: f64| hold.map_or(c, |frames| c.sqrt() * frames);
    adaptive_lambda_ref(track, params.min_confidence, window_frames, unit_scale)
        .into_iter()
        .map(|c| c.map_or(max_ref, |c| price(c).clamp(min_ref, max_ref)) * factor)
        .collect()
}

/// ‖mean-over-joints covariance‖_F per frame in reference px² (`None` where no joint has 2 valid frames).
fn adaptive_lambda_ref(
    track: &Track,
    min_conf: f64,
    window: usize,
    unit_scale: f64,
) -> Vec<Option<f64>> {
    let (t, j, d) = (track.n_frames(), track.n_joints(), track.dims());
    let pos = track.positions();
    let conf = track.confidence();
    let half = window / 2;
    let mut cov_sum = vec![0.0; t * d * d];
    let mut n_joints = vec![0usize; t];
    // Prefix sums for one joint at a time: count, Σx (D), Σxxᵀ (D×D).
    let stride = 1 + d + d * d;
    let mut pre = vec![0.0; (t + 1) * stride];
    for ji in 0..j {
        for ti in 0..t {
            let (a, b) = pre.split_at_mut((ti + 1) * stride);
            let prev = &a[ti * stride..];
            let cur = &mut b[..stride];
            cur.copy_from_slice(&prev[..stride]);
            if conf[[ti, ji]] > min_conf {
                cur[0] += 1.0;
                for k in 0..d {
                    let xk = pos[[ti, ji, k]];
                    cur[1 + k] += xk;
                    for l in 0..d {
                        cur[1 + d + k * d + l] += xk * pos[[ti, ji, l]];
                    }
                }
            }
        }
        for f in 0..t {
            let lo = f.saturating_sub(half);
            let hi = (f + half + 1).min(t);
            let n = pre[hi * stride] - pre[lo * stride];
            if n < 2.0 {
                continue;
            }
            n_joints[f] += 1;
            let m: Vec<f64> = (0..d)
                .map(|k| (pre[hi * stride + 1 + k] - pre[lo * stride + 1 + k]) / n)
                .collect();
            for k in 0..d {
                for l in 0..d {
                    let sxx =
                        pre[hi * stride + 1 + d + k * d + l] - pre[lo * stride + 1 + d + k * d + l];
                    cov_sum[f * d * d + k * d + l] += sxx / n - m[k] * m[l];
                }
            }
        }
    }
    let s2 = unit_scale * unit_scale;
    (0..t)
        .map(|f| {
            if n_joints[f] == 0 {
                return None;
            }
            let nj = n_joints[f] as f64;
            let fro = cov_sum[f * d * d..(f + 1) * d * d]
                .iter()
                .map(|c| {
                    let c = c / nj / s2;
                    c * c
                })
                .sum::<f64>()
                .sqrt();
            Some(fro)
        })
        .collect()
}

fn joint_name(track: &Track, j: usize) -> String {
    track
        .skeleton()
        .joints
        .get(j)
        .cloned()
        .unwrap_or_else(|| format!("{j}"))
}

fn segment_cost(
    prep: &Prepared,
    fit: &FitParams,
    track: &Track,
    k: usize,
    n: usize,
) -> Result<f64> {
    let mut total = 0.0;
    for (ji, pts) in prep.points.iter().enumerate() {
        if prep.prefix_valid[ji][n] == prep.prefix_valid[ji][k] {
            continue; // joint unobserved in this segment: no evidence, no cost
        }
        let f = fit_best_unchecked(pts.slice(s![k..n, ..]), Some(&prep.weights[ji][k..n]), fit)
            .map_err(|e| {
                ConcreteError::Track(format!(
                    "fitting joint `{}` on frames {k}..{n}: {e}",
                    joint_name(track, ji)
                ))
            })?;
        total += f.error;
    }
    Ok(total)
}

/// Fills the cost table (fit errors summed over joints + λ of the segment's last frame) in parallel.
fn cost_table(
    prep: &Prepared,
    fit: &FitParams,
    track: &Track,
    lambda: &[f64],
    window: usize,
) -> Result<CostTable> {
    let t = track.n_frames();
    let mut table = CostTable::new(t, window);
    table
        .rows_mut()
        .collect::<Vec<_>>()
        .into_par_iter()
        .enumerate()
        .try_for_each(|(row, cells)| -> Result<()> {
            let n = row + 1;
            for len in 1..=window.min(n) {
                let k = n - len;
                cells[len - 1] = segment_cost(prep, fit, track, k, n)? + lambda[n - 1];
            }
            Ok(())
        })?;
    Ok(table)
}

/// Fits the primitives of one segment for every joint. A joint unobserved in
/// the whole segment gets the best fit to its gap-filled trajectory.
fn fit_segment(
    prep: &Prepared,
    fit: &FitParams,
    track: &Track,
    k: usize,
    n: usize,
) -> Result<Vec<Primitive>> {
    prep.points
        .iter()
        .enumerate()
        .map(|(ji, pts)| {
            let observed = prep.prefix_valid[ji][n] > prep.prefix_valid[ji][k];
            let w = observed.then(|| &prep.weights[ji][k..n]);
            fit_best_unchecked(pts.slice(s![k..n, ..]), w, fit)
                .map(|f| f.primitive)
                .map_err(|e| {
                    ConcreteError::Track(format!(
                        "fitting joint `{}` on frames {k}..{n}: {e}",
                        joint_name(track, ji)
                    ))
                })
        })
        .collect()
}

/// The fit parameters at the track's `unit_scale`, validated once here: the
/// DP then fits every candidate segment with [`fit_best_unchecked`].
fn scaled_fit(params: &SynthParams, unit_scale: f64) -> Result<FitParams> {
    let mut fit = params.fit.clone();
    fit.unit_scale = unit_scale;
    fit.validate()?;
    Ok(fit)
}

/// The DP's cost table for a track: `cost(k, n)` = Σ over joints of the best
/// fit error on frames `k..n` + λ of frame `n − 1` (track units), for every
/// segment of at most `max_segment_frames` frames. [`synthesize`] segments
/// with exactly this table.
pub fn segment_costs(track: &Track, params: &SynthParams) -> Result<CostTable> {
    params.validate()?;
    let params = &resolve_budget(track, params)?;
    let su = setup(track, params)?;
    cost_table(
        &su.prep,
        &su.fit,
        track,
        &su.lambda,
        params.max_segment_frames,
    )
}

/// What every segmentation of a track starts from.
struct Setup {
    /// The joints' points and weights.
    prep: Prepared,
    /// The fit parameters at the track's scale.
    fit: FitParams,
    unit_scale: f64,
    /// λ per frame (track units).
    lambda: Vec<f64>,
}

/// The [`Setup`] of `track` (`params` validated, a budget resolved).
fn setup(track: &Track, params: &SynthParams) -> Result<Setup> {
    let prep = prepare(track, params.min_confidence, params.unobserved_joints)?;
    let unit_scale = params.unit_scale(track);
    let fit = scaled_fit(params, unit_scale)?;
    let lambda = lambda_per_frame(track, params, unit_scale);
    Ok(Setup {
        prep,
        fit,
        unit_scale,
        lambda,
    })
}

/// The optimal segmentation by branch and bound over the DP ([`crate::search`]).
fn search_prepared(
    su: &Setup,
    track: &Track,
    window: usize,
) -> Result<(Segmentation, SearchStats)> {
    let (prep, fit, lambda) = (&su.prep, &su.fit, &su.lambda);
    let joints: Vec<JointTrack<'_>> = prep
        .points
        .iter()
        .zip(&prep.weights)
        .map(|(points, weights)| JointTrack {
            points,
            weights: weights.as_slice(),
        })
        .collect();
    segment_search(&joints, &track.skeleton().joints, fit, lambda, window)
}

/// The reference segmentation: every candidate segment refitted with
/// [`mp_geom::fit::fit_best`] into the full cost table ([`segment_costs`],
/// `O(T·W)` memory, `O(T·W²·J)` time), then the exhaustive DP over it.
/// [`synthesize`] finds the same optimum much faster (same costs up to
/// rounding); this is kept for tests and benchmarks.
pub fn segment_exhaustive(track: &Track, params: &SynthParams) -> Result<Segmentation> {
    segment_table(&segment_costs(track, params)?)
}

/// The segmentation that [`synthesize`] uses (branch and bound, no cost table).
pub fn segment(track: &Track, params: &SynthParams) -> Result<Segmentation> {
    if let Lambda::Budget { ratio } = params.lambda {
        params.validate()?;
        // The bisection has segmented at the λ it chose already.
        return synthesize_budget(track, params, ratio).map(|(s, _)| s.segmentation);
    }
    // (Validates the parameters.)
    segment_with_stats(track, params).map(|(s, _)| s)
}

/// [`segment`] and the work its search did ([`SearchStats`]). With a
/// [`Lambda::Budget`], the search at the fixed λ the budget chose (the
/// bisection's other searches are not counted).
pub fn segment_with_stats(
    track: &Track,
    params: &SynthParams,
) -> Result<(Segmentation, SearchStats)> {
    params.validate()?;
    let params = &resolve_budget(track, params)?;
    search_prepared(&setup(track, params)?, track, params.max_segment_frames)
}

/// Refits every joint's primitives of the chosen segmentation so that
/// consecutive segments share their boundary pose ([`crate::smooth`]).
fn smooth_segments(
    prep: &Prepared,
    fit: &FitParams,
    norm: RefitNorm,
    track: &Track,
    bounds: &[usize],
    mut segments: Vec<Segment>,
) -> Result<Vec<Segment>> {
    let per_joint = (0..prep.points.len())
        .into_par_iter()
        .map(|ji| {
            let series = JointSeries {
                points: prep.points[ji].view(),
                weights: &prep.weights[ji],
            };
            let prims: Vec<Primitive> = segments.iter().map(|s| s.primitives[ji].clone()).collect();
            refit_joint(&series, bounds, &prims, fit, norm).ok_or_else(|| {
                ConcreteError::Track(format!(
                    "joint `{}`: the continuous (C0) refit has no solution (non-finite positions?)",
                    joint_name(track, ji)
                ))
            })
        })
        .collect::<Result<Vec<_>>>()?;
    for (ji, prims) in per_joint.into_iter().enumerate() {
        for (seg, p) in segments.iter_mut().zip(prims) {
            seg.primitives[ji] = p;
        }
    }
    Ok(segments)
}

/// Synthesises a concrete program with all details (segmentation cost, scale, λ).
pub fn synthesize_detailed(track: &Track, params: &SynthParams) -> Result<Synthesis> {
    params.validate()?;
    if let Lambda::Budget { ratio } = params.lambda {
        return synthesize_budget(track, params, ratio).map(|(s, _)| s);
    }
    let su = setup(track, params)?;
    let (segmentation, _) = search_prepared(&su, track, params.max_segment_frames)?;
    let Setup {
        prep,
        fit,
        unit_scale,
        lambda,
    } = su;
    let segments = segmentation
        .boundaries
        .windows(2)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|w| {
            Ok(Segment {
                duration_frames: w[1] - w[0],
                primitives: fit_segment(&prep, &fit, track, w[0], w[1])?,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let segments = match params.continuity {
        Continuity::None => segments,
        Continuity::C0 => smooth_segments(
            &prep,
            &fit,
            params.refit_norm,
            track,
            &segmentation.boundaries,
            segments,
        )?,
    };
    let program = Program {
        continuity: params.continuity,
        fps: track.fps(),
        units: track.units(),
        dims: track.dims(),
        skeleton: track.skeleton().name.clone(),
        joints: track.skeleton().joints.clone(),
        segments,
    };
    Ok(Synthesis {
        program,
        segmentation,
        unit_scale,
        lambda,
    })
}

/// `params` with a [`Lambda::Budget`] replaced by the fixed λ it resolves to.
fn resolve_budget(track: &Track, params: &SynthParams) -> Result<SynthParams> {
    Ok(match params.lambda {
        Lambda::Budget { ratio } => SynthParams {
            lambda: Lambda::fixed(synthesize_budget(track, params, ratio)?.1),
            ..params.clone()
        },
        _ => params.clone(),
    })
}

/// [`Lambda::Budget`]: bisection on a fixed λ (see the module docs); the
/// synthesis and the λ (reference scale) it used.
fn synthesize_budget(track: &Track, params: &SynthParams, ratio: f64) -> Result<(Synthesis, f64)> {
    let raw = (track.n_frames() * track.n_joints() * track.dims()).max(1) as f64;
    let at = |lambda_ref: f64| {
        let p = SynthParams {
            lambda: Lambda::fixed(lambda_ref),
            ..params.clone()
        };
        synthesize_detailed(track, &p).map(|s| {
            let r = s.program.n_params() as f64 / raw;
            (s, r)
        })
    };
    let (mut lo, mut hi) = BUDGET_LAMBDA_RANGE;
    let (first, r_lo) = at(lo)?;
    if r_lo <= ratio {
        return Ok((first, lo));
    }
    let (mut best, r_hi) = at(hi)?;
    if r_hi > ratio {
        return Err(ConcreteError::param(
            "lambda.ratio",
            format!(
                "a parameter budget of {ratio} is below the most compact program of this track \
                 ({r_hi:.4} of its {raw} numbers at λ = {hi})"
            ),
        ));
    }
    while hi / lo > BUDGET_LAMBDA_STEP {
        let mid = (lo * hi).sqrt();
        let (s, r) = at(mid)?;
        if r <= ratio {
            hi = mid;
            best = s;
        } else {
            lo = mid;
        }
    }
    Ok((best, hi))
}

/// Synthesises a concrete program from a track.
///
/// Errors: invalid parameters; a track with fewer than 2 frames or no
/// joints; nothing observed at all; a joint missing in every frame (named in
/// the message) unless [`SynthParams::unobserved_joints`] says to ignore it.
pub fn synthesize(track: &Track, params: &SynthParams) -> Result<Program> {
    synthesize_detailed(track, params).map(|s| s.program)
}
