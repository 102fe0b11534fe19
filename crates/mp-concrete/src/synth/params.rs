//! The parameters of synthesis: the scale of a track against the 512-px
//! reference, the segment penalty λ, and [`SynthParams`] with their checks.
//!
//! # Scale
//!
//! Thresholds and λ are given at the reference scale of a 512-pixel frame
//! (docs/ALGORITHMS.md). `unit_scale` (track units per reference pixel) converts them:
//!
//! * [`Scale::FrameSize`]: `unit_scale = max(H, W) / 512` (pixels, frame size known);
//! * [`Scale::Auto`] (default): `unit_scale = track.scale() / REFERENCE_EXTENT_PX`,
//!   where `track.scale()` is the diagonal of the bounding box of all valid
//!   positions and [`Scale::REFERENCE_EXTENT_PX`] = 256 is that diagonal for a
//!   typical clip at 512 px (the median over the Penn Action training clips,
//!   rescaled to a 512-px frame, is 257 px). Works for metres as well as pixels;
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
//!   ([`Program::n_params`](crate::program::Program::n_params)) are at most `ratio` of the raw numbers `T·J·D`,
//!   found by bisection on λ (reference scale, [`BUDGET_LAMBDA_RANGE`], steps
//!   of [`BUDGET_LAMBDA_STEP`]); each step is one synthesis, so this costs
//!   about a dozen syntheses. A budget below the smallest program's size is an
//!   error naming both.

use mp_geom::Track;
use mp_geom::{ErrorNorm, FitParams};
use serde::{Deserialize, Serialize};

use crate::error::{ConcreteError, Result};
use crate::smooth::{Continuity, RefitNorm};

/// How the segment penalty λ is chosen (values at the 512-px reference scale).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
#[non_exhaustive]
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
    /// unchanged): e.g. the rule for a track subsampled ×k, whose window is
    /// k times fewer frames.
    pub fn map_window_clamp(self, f: impl FnOnce(usize, f64, f64) -> (usize, f64, f64)) -> Self {
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

/// How `unit_scale` (track units per reference pixel) is found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "type", rename_all = "lowercase")]
#[non_exhaustive]
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

impl Scale {
    /// Reference pixels of a 512-px frame.
    pub const REFERENCE_FRAME_PX: f64 = 512.0;
    /// Bounding-box diagonal of a typical clip's valid keypoints at the 512-px reference scale.
    pub const REFERENCE_EXTENT_PX: f64 = 256.0;
}

/// Parameters of synthesis. `default()` is the product's, [`SynthParams::paper`]
/// the first paper's (docs/ALGORITHMS.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SynthParams {
    /// Segment penalty. Default: the local spread held for one second
    /// ([`Lambda::spread`]); paper: fixed 1600.
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
    /// all-NaN column, or a joint occluded for a whole clip). Default: fitted
    /// to its stored positions ([`UnobservedJoints::Ignore`]); paper: an error.
    pub unobserved_joints: UnobservedJoints,
    /// Whether consecutive segments share their boundary pose (the chosen
    /// segmentation refitted per joint, `crate::smooth`). Default: C0.
    /// Parameters serialised before the field existed read as C0.
    #[serde(default = "default_continuity")]
    pub continuity: Continuity,
    /// What the C0 refit minimises (`crate::smooth`). Default: Euclidean
    /// residuals; paper, and parameters serialised before the field existed:
    /// squared residuals.
    #[serde(default)]
    pub refit_norm: RefitNorm,
}

fn default_continuity() -> Continuity {
    SynthParams::DEFAULT_CONTINUITY
}

/// Policy for joints that are observed in no frame of the track.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum UnobservedJoints {
    /// Refuse the track, naming the joint ([`ConcreteError::Track`]).
    #[default]
    Error,
    /// Keep the joint out of the segmentation cost and fit its primitives to
    /// the positions stored in the track (which carry no evidence).
    Ignore,
}

impl Default for SynthParams {
    /// The product's synthesis, what `mp fit`, `mp run` and the Python
    /// package use: λ from the local spread of the keypoints held for
    /// [`SynthParams::DEFAULT_SPREAD_SECONDS`], the Euclidean C0 refit, and
    /// joints never observed fitted to their stored positions.
    fn default() -> Self {
        SynthParams {
            lambda: Lambda::spread(Self::DEFAULT_SPREAD_SECONDS),
            refit_norm: RefitNorm::Euclidean,
            unobserved_joints: UnobservedJoints::Ignore,
            ..Self::paper()
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
    /// How long the local spread of the keypoints is held to price one
    /// segment in the default λ (chosen on the validation half of the Penn
    /// Action clips; see docs/results/concrete.md, "Rate–distortion frontier").
    pub const DEFAULT_SPREAD_SECONDS: f64 = 1.0;

    /// The first paper's settings, which its test vectors and the
    /// published comparisons use: a fixed λ = 1600 at the 512-pixel
    /// reference, the squared-residual C0 refit, and an error for a joint
    /// that is never observed.
    pub fn paper() -> Self {
        SynthParams {
            lambda: Lambda::fixed(Lambda::DEFAULT_FIXED),
            max_segment_frames: 60,
            fit: FitParams::default(),
            scale: Scale::Auto,
            min_confidence: 0.0,
            unobserved_joints: UnobservedJoints::Error,
            continuity: Self::DEFAULT_CONTINUITY,
            refit_norm: RefitNorm::Squared,
        }
    }

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
                    e / Scale::REFERENCE_EXTENT_PX
                } else {
                    1.0
                }
            }
            Scale::FrameSize { frame_px } => frame_px / Scale::REFERENCE_FRAME_PX,
            Scale::UnitScale { unit_scale } => unit_scale,
        }
    }
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
