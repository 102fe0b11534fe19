//! Primitive fitting in 2D and 3D.
//!
//! Every fit takes the points of one joint over one segment (`n × D`, frame
//! `i` of the segment is time `t = i`), optional per-frame weights
//! (confidence; weight 0 = missing, excluded from the fit and its error), and
//! returns the fitted [`Primitive`] with its error (see [`ErrorNorm`]).
//!
//! Thresholds in [`FitParams`] are given at the reference scale of a 512-pixel
//! frame (docs/ALGORITHMS.md); `FitParams::unit_scale` converts them to the data's units
//! (track units per reference pixel), so the same defaults serve pixels of any
//! frame size and metres.
//!
//! ## Conventions
//!
//! * **Weights.** `None` means weight 1 everywhere. Weights must be finite and
//!   ≥ 0; frames of weight 0 are missing: their coordinates are never read
//!   (they may be NaN) but they still count as time (frame `i` is `t = i`).
//!   Fits are weighted least squares, and each frame's residual enters the
//!   error multiplied by its weight: with [`ErrorNorm::Euclidean`] the error is
//!   `Σ wᵢ ‖p(i) − xᵢ‖`, with [`ErrorNorm::Squared`] it is `Σ wᵢ ‖p(i) − xᵢ‖²`
//!   (for 0/1 weights these are the plain sums over the valid frames).
//! * **Bad input** is a typed error, never a NaN result: no frames →
//!   [`GeomError::TooShort`]; all weights 0 →
//!   [`GeomError::NoData`]; a non-finite coordinate
//!   in a frame of weight > 0, or a non-finite weight →
//!   [`GeomError::NonFinite`] naming the frame;
//!   a negative weight or an invalid [`FitParams`] field →
//!   [`GeomError::InvalidParam`]; a weight
//!   slice of the wrong length or `D = 0` → [`GeomError::Shape`].
//! * **Dimensions.** Stationary, line and spline accept any `D ≥ 1`; circles
//!   need `D = 2` or `3`.
//! * **Circles** need 3 valid frames
//!   ([`GeomError::TooShort`] otherwise) and points
//!   that are not collinear or coincident
//!   ([`GeomError::NoData`] otherwise).
//!
//! ## Selection ([`fit_best`])
//!
//! With `s = unit_scale`, over the kinds listed in [`FitParams::kinds`]:
//!
//! 1. If stationary is allowed, it wins outright when the diagonal of the
//!    bounding box of the valid points is `< stationary_bbox_px·s`, or when
//!    its weighted mean Euclidean residual `Σ wᵢ‖x̄ − xᵢ‖ / Σ wᵢ` is
//!    `< stationary_mean_residual_px·s` (whatever the norm).
//! 2. Line and circle are rejected when the distance between the first and
//!    the last valid point of the segment is `< min_span_px·s`, unless every
//!    allowed kind is a line or a circle (then nothing is rejected).
//! 3. A circle's error gets, once per segment (not per point), the penalty
//!    `radius_penalty·max(r − max_radius_px·s, 0)` plus `radius_penalty·r`
//!    when `r < min_radius_px·s`, in the data's units whatever the norm. A
//!    circle that cannot be fitted (collinear points) is skipped.
//! 4. The remaining candidate with the lowest error wins; ties go to the
//!    simpler kind (order of [`PrimitiveKind::ALL`]). The returned error
//!    includes the penalty.

use ndarray::ArrayView2;
use serde::{Deserialize, Serialize};

pub mod atan;
mod circle;
mod input;
pub mod prefix;

pub use circle::{bullock_from_sums, bullock_terms, unwrap_degrees};

use crate::checked::{Checked, Validate};
use crate::error::{GeomError, Result};
use crate::primitive::{Primitive, PrimitiveKind};

/// How residuals are summed into a fit error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ErrorNorm {
    /// Sum of Euclidean distances (the reference code's convention; default).
    Euclidean,
    /// Sum of squared Euclidean distances.
    Squared,
}

/// Parameters of primitive fitting and selection. Defaults: the product's (docs/ALGORITHMS.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FitParams {
    /// Which primitive kinds may be chosen by [`fit_best`].
    pub kinds: Vec<PrimitiveKind>,
    /// Residual norm.
    pub norm: ErrorNorm,
    /// Track units per reference pixel (512-px frame). 1.0 for pixels of a 512-px frame.
    pub unit_scale: f64,
    /// Stationary wins when the segment's bounding-box diagonal is below this (reference px).
    pub stationary_bbox_px: f64,
    /// Stationary wins when its mean residual is below this (reference px). Default 3.
    pub stationary_mean_residual_px: f64,
    /// Line/circle are rejected when |end − start| is below this (reference px).
    pub min_span_px: f64,
    /// Circle radius above which a penalty `radius_penalty · (r − max)` is added (reference px). Default 100.
    pub max_radius_px: f64,
    /// Circle radius below which a penalty `radius_penalty · r` is added (reference px). Default 30.
    pub min_radius_px: f64,
    /// Penalty factor for implausible radii. Default 3.
    pub radius_penalty: f64,
    /// Allow a quadratic angle term (bounded by `max_angle_acc_deg`).
    pub quadratic_angle: bool,
    /// Bound on |angle_acc| in degrees per frame². Default 0.4.
    pub max_angle_acc_deg: f64,
}

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            kinds: vec![
                PrimitiveKind::Stationary,
                PrimitiveKind::Line,
                PrimitiveKind::Circle,
            ],
            norm: ErrorNorm::Euclidean,
            unit_scale: 1.0,
            stationary_bbox_px: 5.0,
            stationary_mean_residual_px: 3.0,
            min_span_px: 5.0,
            max_radius_px: 100.0,
            min_radius_px: 30.0,
            radius_penalty: 3.0,
            quadratic_angle: false,
            max_angle_acc_deg: 0.4,
        }
    }
}

impl Validate for FitParams {
    type Error = GeomError;

    fn validate(&self) -> Result<()> {
        FitParams::validate(self)
    }
}

impl FitParams {
    /// Checks every field: `kinds` non-empty, `unit_scale` finite and > 0,
    /// every threshold finite and ≥ 0.
    pub fn validate(&self) -> Result<()> {
        if self.kinds.is_empty() {
            return Err(GeomError::param(
                "kinds",
                "at least one primitive kind is needed",
            ));
        }
        if !(self.unit_scale.is_finite() && self.unit_scale > 0.0) {
            return Err(GeomError::param(
                "unit_scale",
                format!("must be finite and > 0, got {}", self.unit_scale),
            ));
        }
        let nonneg: [(&'static str, f64); 7] = [
            ("stationary_bbox_px", self.stationary_bbox_px),
            (
                "stationary_mean_residual_px",
                self.stationary_mean_residual_px,
            ),
            ("min_span_px", self.min_span_px),
            ("max_radius_px", self.max_radius_px),
            ("min_radius_px", self.min_radius_px),
            ("radius_penalty", self.radius_penalty),
            ("max_angle_acc_deg", self.max_angle_acc_deg),
        ];
        for (name, v) in nonneg {
            if !(v.is_finite() && v >= 0.0) {
                return Err(GeomError::param(
                    name,
                    format!("must be finite and ≥ 0, got {v}"),
                ));
            }
        }
        Ok(())
    }

    /// Returns the parameters if [`FitParams::validate`] accepts them.
    pub fn checked(self) -> Result<Self> {
        self.validate()?;
        Ok(self)
    }

    /// The radius penalty that [`fit_best`] adds to a circle of radius `r`
    /// (data units): `radius_penalty·max(r − max_radius_px·s, 0)` plus
    /// `radius_penalty·r` when `r < min_radius_px·s`.
    pub fn circle_penalty(&self, r: f64) -> f64 {
        let s = self.unit_scale;
        let mut p = self.radius_penalty * (r - self.max_radius_px * s).max(0.0);
        if r < self.min_radius_px * s {
            p += self.radius_penalty * r;
        }
        p
    }
}

/// A fitted primitive and its error (in the data's units, summed per [`ErrorNorm`],
/// including any selection penalty applied by [`fit_best`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fit {
    /// The fitted primitive.
    pub primitive: Primitive,
    /// Fit error.
    pub error: f64,
}

// --- API -----------------------------------------------------------------

/// Whether `primitive` can be executed into `d` dimensions without reading
/// past its parameter vectors.
fn shape_matches(primitive: &Primitive, d: usize) -> bool {
    match primitive {
        Primitive::Stationary { point } => point.len() == d,
        Primitive::Line { start, velocity } => start.len() == d && velocity.len() == d,
        Primitive::Circle { center, axes, .. } => {
            center.len() == d
                && d >= 2
                && (center.len() == 2
                    || axes.len() < 2
                    || axes.iter().take(2).all(|a| a.len() >= d))
        }
        Primitive::Spline { coeffs } => coeffs.len() == d,
    }
}

/// `(Σ wᵢ‖p(i) − xᵢ‖, Σ wᵢ‖p(i) − xᵢ‖²)` over frames of weight > 0, or `None`
/// when the shapes disagree.
pub(crate) fn residual_sums(
    primitive: &Primitive,
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
) -> Option<(f64, f64)> {
    let (n, d) = points.dim();
    if !shape_matches(primitive, d) || weights.is_some_and(|w| w.len() != n) {
        return None;
    }
    // One loop per kind, so that the per-frame evaluation is inlined.
    #[inline(always)]
    fn run(
        points: ArrayView2<'_, f64>,
        weights: Option<&[f64]>,
        mut sq_dist: impl FnMut(f64, ndarray::ArrayView1<'_, f64>) -> f64,
    ) -> (f64, f64) {
        let mut sum = 0.0;
        let mut sum2 = 0.0;
        for (i, row) in points.outer_iter().enumerate() {
            let w = input::wt(weights, i);
            if w == 0.0 {
                continue;
            }
            let dd = sq_dist(i as f64, row);
            sum += w * dd.sqrt();
            sum2 += w * dd;
        }
        (sum, sum2)
    }
    let sums = match primitive {
        Primitive::Stationary { point } => run(points, weights, |_, row| {
            point
                .iter()
                .zip(row.iter())
                .map(|(a, b)| (a - b) * (a - b))
                .sum()
        }),
        Primitive::Line { start, velocity } => run(points, weights, |t, row| {
            let mut dd = 0.0;
            for ((s0, v), x) in start.iter().zip(velocity).zip(row.iter()) {
                let e = s0 + v * t - x;
                dd += e * e;
            }
            dd
        }),
        Primitive::Spline { coeffs } => run(points, weights, |t, row| {
            let mut dd = 0.0;
            for ([a, b, c, e], x) in coeffs.iter().zip(row.iter()) {
                let r = ((a * t + b) * t + c) * t + e - x;
                dd += r * r;
            }
            dd
        }),
        Primitive::Circle { .. } => {
            let mut stack = [0.0f64; 8];
            let mut heap = Vec::new();
            let buf: &mut [f64] = if d <= stack.len() {
                &mut stack[..d]
            } else {
                heap.resize(d, 0.0);
                &mut heap
            };
            run(points, weights, |t, row| {
                primitive.eval_into(t, buf);
                buf.iter()
                    .zip(row.iter())
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum()
            })
        }
    };
    Some(sums)
}

/// Error of `primitive` executed at t = 0..n against `points` (`n × D`),
/// skipping frames with weight 0, summed per `norm`.
///
/// Each frame's residual is multiplied by its weight (see the module
/// conventions). Returns `+∞` when the primitive's dimension differs from `D`
/// or the weights have the wrong length, and NaN when a frame of weight > 0
/// holds a non-finite coordinate (it is meant for checked data; the `fit_*`
/// functions check their input).
pub fn residual_error(
    primitive: &Primitive,
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    norm: ErrorNorm,
) -> f64 {
    match residual_sums(primitive, points, weights) {
        None => f64::INFINITY,
        Some((e, e2)) => match norm {
            ErrorNorm::Euclidean => e,
            ErrorNorm::Squared => e2,
        },
    }
}

/// Error per `norm` from the two residual sums.
fn pick(norm: ErrorNorm, sums: Option<(f64, f64)>) -> f64 {
    match (norm, sums) {
        (_, None) => f64::INFINITY,
        (ErrorNorm::Euclidean, Some((e, _))) => e,
        (ErrorNorm::Squared, Some((_, e2))) => e2,
    }
}

fn stationary_impl(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    s: &input::Summary,
) -> Primitive {
    let mut point = vec![0.0; s.d];
    for (i, row) in points.outer_iter().enumerate() {
        let w = input::wt(weights, i);
        if w == 0.0 {
            continue;
        }
        for (m, v) in point.iter_mut().zip(row.iter()) {
            *m += w * v;
        }
    }
    for m in &mut point {
        *m /= s.w_sum;
    }
    Primitive::Stationary { point }
}

fn line_impl(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    s: &input::Summary,
) -> Result<Primitive> {
    let ls = input::PolyLs::new("line fit", s.n, weights, s, 1)?;
    let mut start = vec![0.0; s.d];
    let mut velocity = vec![0.0; s.d];
    ls.fit_columns(points, weights, |k, c| {
        start[k] = c[0];
        velocity[k] = c[1];
    });
    Ok(Primitive::Line { start, velocity })
}

fn spline_impl(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    s: &input::Summary,
) -> Result<Primitive> {
    let ls = input::PolyLs::new("spline fit", s.n, weights, s, 3)?;
    let mut coeffs = vec![[0.0; 4]; s.d];
    ls.fit_columns(points, weights, |k, c| {
        coeffs[k] = [c[3], c[2], c[1], c[0]];
    });
    Ok(Primitive::Spline { coeffs })
}

fn finish(
    primitive: Primitive,
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    norm: ErrorNorm,
    what: &str,
) -> Result<Fit> {
    let error = pick(norm, residual_sums(&primitive, points, weights));
    if !primitive.is_finite() || !error.is_finite() {
        return Err(GeomError::NonFinite(format!(
            "{what}: the fitted {} has non-finite parameters or error (input too large?)",
            primitive.kind().as_str()
        )));
    }
    Ok(Fit { primitive, error })
}

/// Fits a stationary point (weighted mean).
pub fn fit_stationary(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    params: &FitParams,
) -> Result<Fit> {
    params.validate()?;
    let s = input::check("stationary fit", points, weights)?;
    finish(
        stationary_impl(points, weights, &s),
        points,
        weights,
        params.norm,
        "stationary fit",
    )
}

/// Fits constant-velocity linear motion (least squares per axis against time).
///
/// `start` is the position at t = 0 (the segment's first frame, valid or
/// not). With a single valid frame the velocity is 0. Vertical (or any)
/// motion is handled since every axis is fitted against time.
pub fn fit_line(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    params: &FitParams,
) -> Result<Fit> {
    params.validate()?;
    let s = input::check("line fit", points, weights)?;
    finish(
        line_impl(points, weights, &s)?,
        points,
        weights,
        params.norm,
        "line fit",
    )
}

/// Fits circular motion: Bullock least squares for the circle (in the best-fit plane in 3D),
/// then the unwrapped angle against time.
///
/// 2D: `θ = atan2(y − c_y, x − c_x)`. 3D: the plane is the weighted PCA plane
/// of the points, `axes = [u, v]` with `u` the direction of largest spread
/// and `v = n × u` (n the plane normal), and `θ` is measured in that basis.
/// The angle (degrees) is unwrapped frame to frame (so motion must stay below
/// 180° per frame) and fitted by weighted least squares against time,
/// linearly, or quadratically when `params.quadratic_angle` (then
/// `|angle_acc| ≤ max_angle_acc_deg`: a larger value is clamped and the
/// linear part refitted). `angle_start` is reduced to (−180, 180].
pub fn fit_circle(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    params: &FitParams,
) -> Result<Fit> {
    params.validate()?;
    let s = input::check("circle fit", points, weights)?;
    let prim = circle::fit(points, weights, &s, params)?;
    finish(prim, points, weights, params.norm, "circle fit")
}

/// Fits a cubic polynomial per axis against time.
///
/// With fewer than 4 valid frames the polynomial has degree `n_valid − 1`
/// and passes through them exactly (leading coefficients 0). The least
/// squares are solved in centred, scaled time, so long segments stay well
/// conditioned.
pub fn fit_spline(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    params: &FitParams,
) -> Result<Fit> {
    params.validate()?;
    let s = input::check("spline fit", points, weights)?;
    finish(
        spline_impl(points, weights, &s)?,
        points,
        weights,
        params.norm,
        "spline fit",
    )
}

/// Fits one given kind.
pub fn fit_kind(
    kind: PrimitiveKind,
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    params: &FitParams,
) -> Result<Fit> {
    match kind {
        PrimitiveKind::Stationary => fit_stationary(points, weights, params),
        PrimitiveKind::Line => fit_line(points, weights, params),
        PrimitiveKind::Circle => fit_circle(points, weights, params),
        PrimitiveKind::Spline => fit_spline(points, weights, params),
    }
}

/// Diagonal of the bounding box of the valid points.
fn bbox_diag(points: ArrayView2<'_, f64>, weights: Option<&[f64]>) -> f64 {
    let d = points.ncols();
    if d > 8 {
        let mut acc = 0.0;
        for col in points.columns() {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for (i, v) in col.iter().enumerate() {
                if input::wt(weights, i) > 0.0 {
                    lo = lo.min(*v);
                    hi = hi.max(*v);
                }
            }
            if hi >= lo {
                acc += (hi - lo) * (hi - lo);
            }
        }
        return acc.sqrt();
    }
    let mut lo = [f64::INFINITY; 8];
    let mut hi = [f64::NEG_INFINITY; 8];
    for (i, row) in points.outer_iter().enumerate() {
        if input::wt(weights, i) > 0.0 {
            for ((l, h), v) in lo.iter_mut().zip(hi.iter_mut()).zip(row.iter()) {
                *l = l.min(*v);
                *h = h.max(*v);
            }
        }
    }
    lo.iter()
        .zip(&hi)
        .take(d)
        .filter(|(l, h)| h >= l)
        .map(|(l, h)| (h - l) * (h - l))
        .sum::<f64>()
        .sqrt()
}

/// Fits every kind in `params.kinds` and returns the best by these selection
/// rules (lowest error with penalties; stationary wins under its thresholds).
///
/// With `s = unit_scale`, over the kinds listed in [`FitParams::kinds`]:
///
/// 1. If stationary is allowed, it wins outright when the diagonal of the
///    bounding box of the valid points is `< stationary_bbox_px·s`, or when
///    its weighted mean Euclidean residual `Σ wᵢ‖x̄ − xᵢ‖ / Σ wᵢ` is
///    `< stationary_mean_residual_px·s` (whatever the norm).
/// 2. Line and circle are rejected when the distance between the first and
///    the last valid point of the segment is `< min_span_px·s`, unless every
///    allowed kind is a line or a circle (then nothing is rejected).
/// 3. A circle's error gets, once per segment (not per point), the penalty
///    `radius_penalty·max(r − max_radius_px·s, 0)` plus `radius_penalty·r`
///    when `r < min_radius_px·s`, in the data's units whatever the norm. A
///    circle that cannot be fitted (collinear points) is skipped.
/// 4. The remaining candidate with the lowest error wins; ties go to the
///    simpler kind (order of [`PrimitiveKind::ALL`]). The returned error
///    includes the penalty.
pub fn fit_best(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    params: &FitParams,
) -> Result<Fit> {
    params.validate()?;
    best_fit(points, weights, params)
}

/// [`fit_best`] with parameters checked once beforehand
/// ([`crate::checked::Validate::check`]): for callers that fit many
/// segments with the same parameters.
pub fn fit_best_checked(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    params: &Checked<FitParams>,
) -> Result<Fit> {
    best_fit(points, weights, params)
}

/// The best fit; `params` passed [`FitParams::validate`].
fn best_fit(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    params: &FitParams,
) -> Result<Fit> {
    let s = input::check("fit_best", points, weights)?;
    let scale = params.unit_scale;
    let allowed = |k: PrimitiveKind| params.kinds.contains(&k);

    let mut stationary = None;
    if allowed(PrimitiveKind::Stationary) {
        let prim = stationary_impl(points, weights, &s);
        let (e, e2) =
            residual_sums(&prim, points, weights).unwrap_or((f64::INFINITY, f64::INFINITY));
        let error = match params.norm {
            ErrorNorm::Euclidean => e,
            ErrorNorm::Squared => e2,
        };
        let fit = Fit {
            primitive: prim,
            error,
        };
        if bbox_diag(points, weights) < params.stationary_bbox_px * scale
            || e / s.w_sum < params.stationary_mean_residual_px * scale
        {
            return finish(fit.primitive, points, weights, params.norm, "fit_best");
        }
        stationary = Some(fit);
    }

    let span = {
        let a = points.row(s.first);
        let b = points.row(s.last);
        a.iter()
            .zip(b.iter())
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
    };
    let only_moving = params
        .kinds
        .iter()
        .all(|k| matches!(k, PrimitiveKind::Line | PrimitiveKind::Circle));
    let reject_moving = span < params.min_span_px * scale && !only_moving;

    let mut best: Option<Fit> = None;
    let mut last_err = None;
    for kind in PrimitiveKind::ALL {
        if !allowed(kind) {
            continue;
        }
        if reject_moving && matches!(kind, PrimitiveKind::Line | PrimitiveKind::Circle) {
            continue;
        }
        let cand = match kind {
            PrimitiveKind::Stationary => match stationary.take() {
                Some(f) => Ok(f),
                None => continue,
            },
            PrimitiveKind::Line => line_impl(points, weights, &s).map(|p| Fit {
                error: pick(params.norm, residual_sums(&p, points, weights)),
                primitive: p,
            }),
            PrimitiveKind::Circle => circle::fit(points, weights, &s, params).map(|p| {
                let penalty = match &p {
                    Primitive::Circle { radius, .. } => params.circle_penalty(*radius),
                    _ => 0.0,
                };
                Fit {
                    error: pick(params.norm, residual_sums(&p, points, weights)) + penalty,
                    primitive: p,
                }
            }),
            PrimitiveKind::Spline => spline_impl(points, weights, &s).map(|p| Fit {
                error: pick(params.norm, residual_sums(&p, points, weights)),
                primitive: p,
            }),
        };
        match cand {
            Ok(f) if f.error.is_finite() && f.primitive.is_finite() => {
                if best.as_ref().is_none_or(|b| f.error < b.error) {
                    best = Some(f);
                }
            }
            Ok(f) => {
                last_err = Some(GeomError::NonFinite(format!(
                    "fit_best: the fitted {} has non-finite parameters or error",
                    f.primitive.kind().as_str()
                )))
            }
            Err(e) => last_err = Some(e),
        }
    }
    match (best, last_err) {
        (Some(b), _) => Ok(b),
        (None, Some(e)) => Err(e),
        (None, None) => Err(GeomError::NoData(
            "fit_best: no primitive kind could be fitted".into(),
        )),
    }
}
