//! Pose-sequence metrics: KD, PCK, MPJPE, PA-MPJPE, DTW and the largest
//! adjacent-frame jump.
//!
//! Every metric works on [`Poses`]: a `T × J × D` view of positions with an
//! optional `T × J` confidence (joint `j` of frame `t` is *valid* when its
//! confidence is > 0; no confidence means all valid). A [`Track`] or a plain
//! `ArrayView3` converts into [`Poses`] with `.into()`, so every function
//! accepts `&track`, `Poses::new(positions, Some(conf))?` or `array.view()`.
//!
//! Conventions shared by all metrics:
//!
//! * Only joints valid in **both** sequences are compared (PCK: see [`pck`]).
//! * A valid joint with a non-finite coordinate is an error
//!   ([`GeomError::NonFinite`] naming the sequence, frame and joint); invalid
//!   joints are never read.
//! * Per-frame results hold `NaN` for frames that cannot be scored (too few
//!   valid joints); sequence results are the [`nanmean`] of per-frame results
//!   and are an error ([`GeomError::NoData`]) when no frame can be scored.
//! * Empty inputs (`T = 0` or `J = 0`) give [`GeomError::TooShort`] /
//!   [`GeomError::NoData`]; shapes that disagree give [`GeomError::Shape`].
//! * Distances are in the data's units (pixels or metres).

use nalgebra::DMatrix;
use ndarray::{Array2, Array3, ArrayView2, ArrayView3};

use crate::error::{GeomError, Result};
use crate::track::Track;

/// A borrowed pose sequence: positions `T × J × D` and optional confidence `T × J`.
#[derive(Debug, Clone, Copy)]
pub struct Poses<'a> {
    positions: ArrayView3<'a, f64>,
    confidence: Option<ArrayView2<'a, f64>>,
}

impl<'a> Poses<'a> {
    /// Wraps positions and an optional confidence (valid when > 0), checking shapes.
    pub fn new(
        positions: ArrayView3<'a, f64>,
        confidence: Option<ArrayView2<'a, f64>>,
    ) -> Result<Self> {
        let (t, j, _) = positions.dim();
        if let Some(c) = confidence {
            if c.dim() != (t, j) {
                return Err(GeomError::Shape(format!(
                    "confidence has shape {:?}, positions need ({t}, {j})",
                    c.dim()
                )));
            }
        }
        Ok(Poses {
            positions,
            confidence,
        })
    }
    /// Number of frames T.
    pub fn n_frames(&self) -> usize {
        self.positions.dim().0
    }
    /// Number of joints J.
    pub fn n_joints(&self) -> usize {
        self.positions.dim().1
    }
    /// Dimensions D.
    pub fn dims(&self) -> usize {
        self.positions.dim().2
    }
    /// Positions.
    pub fn positions(&self) -> ArrayView3<'a, f64> {
        self.positions
    }
    /// Whether joint `j` of frame `t` is valid (confidence > 0, or no confidence given).
    #[inline]
    pub fn valid(&self, t: usize, j: usize) -> bool {
        match &self.confidence {
            Some(c) => c[[t, j]] > 0.0,
            None => true,
        }
    }
    #[inline]
    fn p(&self, t: usize, j: usize, k: usize) -> f64 {
        self.positions[[t, j, k]]
    }

    /// Non-empty, finite where valid, NaN confidence rejected.
    fn check(&self, name: &str) -> Result<()> {
        let (t, j, d) = self.positions.dim();
        if t == 0 {
            return Err(GeomError::TooShort {
                what: "metric",
                needed: 1,
                got: 0,
            });
        }
        if j == 0 || d == 0 {
            return Err(GeomError::NoData(format!(
                "{name}: poses have {j} joints of {d} dimensions"
            )));
        }
        for ti in 0..t {
            for ji in 0..j {
                if let Some(c) = &self.confidence {
                    let cv = c[[ti, ji]];
                    if cv.is_nan() {
                        return Err(GeomError::NonFinite(format!(
                            "{name}: confidence of frame {ti}, joint {ji} is NaN"
                        )));
                    }
                }
                if !self.valid(ti, ji) {
                    continue;
                }
                for k in 0..d {
                    let v = self.p(ti, ji, k);
                    if !v.is_finite() {
                        return Err(GeomError::NonFinite(format!(
                            "{name}: frame {ti}, joint {ji}, axis {k} is {v}"
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    /// Euclidean distance between joint `j` of frame `t` here and frame `u` of `other`.
    #[inline]
    fn dist(&self, t: usize, other: &Poses<'_>, u: usize, j: usize) -> f64 {
        let mut s = 0.0;
        for k in 0..self.dims() {
            let d = self.p(t, j, k) - other.p(u, j, k);
            s += d * d;
        }
        s.sqrt()
    }
}

impl<'a> From<&'a Track> for Poses<'a> {
    fn from(t: &'a Track) -> Self {
        Poses {
            positions: t.positions(),
            confidence: Some(t.confidence()),
        }
    }
}

impl<'a> From<ArrayView3<'a, f64>> for Poses<'a> {
    /// All joints valid.
    fn from(positions: ArrayView3<'a, f64>) -> Self {
        Poses {
            positions,
            confidence: None,
        }
    }
}

impl<'a> From<&'a Array3<f64>> for Poses<'a> {
    /// All joints valid.
    fn from(positions: &'a Array3<f64>) -> Self {
        Poses {
            positions: positions.view(),
            confidence: None,
        }
    }
}

/// Checks both sequences and that they have the same shape (`same_t`: also T).
fn check_pair(a: &Poses<'_>, b: &Poses<'_>, what: &str, same_t: bool) -> Result<()> {
    a.check(&format!("{what} (first sequence)"))?;
    b.check(&format!("{what} (second sequence)"))?;
    let (ta, ja, da) = a.positions.dim();
    let (tb, jb, db) = b.positions.dim();
    if ja != jb || da != db || (same_t && ta != tb) {
        return Err(GeomError::Shape(format!(
            "{what}: sequences have shapes ({ta}, {ja}, {da}) and ({tb}, {jb}, {db})"
        )));
    }
    Ok(())
}

/// Mean of the non-NaN values; NaN when there is none (like numpy's `nanmean`).
pub fn nanmean(values: &[f64]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for v in values {
        if !v.is_nan() {
            s += v;
            n += 1;
        }
    }
    if n == 0 {
        f64::NAN
    } else {
        s / n as f64
    }
}

fn nanmean_or_err(values: &[f64], what: &str) -> Result<f64> {
    let m = nanmean(values);
    if m.is_nan() {
        return Err(GeomError::NoData(format!(
            "{what}: no frame could be scored"
        )));
    }
    Ok(m)
}

// --- KD ---------------------------------------------------------------------

/// Keypoint difference per frame: mean Euclidean distance over the joints
/// valid in both sequences; NaN for frames without such a joint.
pub fn kd_per_frame<'a, 'b>(a: impl Into<Poses<'a>>, b: impl Into<Poses<'b>>) -> Result<Vec<f64>> {
    let (a, b) = (a.into(), b.into());
    check_pair(&a, &b, "kd", true)?;
    Ok((0..a.n_frames())
        .map(|t| {
            let (mut s, mut n) = (0.0, 0usize);
            for j in 0..a.n_joints() {
                if a.valid(t, j) && b.valid(t, j) {
                    s += a.dist(t, &b, t, j);
                    n += 1;
                }
            }
            if n == 0 {
                f64::NAN
            } else {
                s / n as f64
            }
        })
        .collect())
}

/// Keypoint difference (KD, paper 000 §4.1): the mean Euclidean distance over
/// **all (frame, joint) pairs** valid in both sequences (not the mean of
/// per-frame means: frames with more valid joints weigh more).
pub fn kd<'a, 'b>(a: impl Into<Poses<'a>>, b: impl Into<Poses<'b>>) -> Result<f64> {
    let (a, b) = (a.into(), b.into());
    check_pair(&a, &b, "kd", true)?;
    let (mut s, mut n) = (0.0, 0usize);
    for t in 0..a.n_frames() {
        for j in 0..a.n_joints() {
            if a.valid(t, j) && b.valid(t, j) {
                s += a.dist(t, &b, t, j);
                n += 1;
            }
        }
    }
    if n == 0 {
        return Err(GeomError::NoData(
            "kd: no joint is valid in both sequences".into(),
        ));
    }
    Ok(s / n as f64)
}

// --- PCK --------------------------------------------------------------------

/// Parameters of [`pck_with`] / [`pck_per_frame`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PckParams {
    /// Threshold as a fraction of the bounding-box size. Default 0.05.
    pub alpha: f64,
    /// Frames with fewer visible ground-truth joints are not scored (NaN). Default 6.
    pub min_visible: usize,
}

impl Default for PckParams {
    fn default() -> Self {
        PckParams {
            alpha: 0.05,
            min_visible: 6,
        }
    }
}

impl PckParams {
    /// `alpha` finite and ≥ 0.
    pub fn validate(&self) -> Result<()> {
        if !(self.alpha.is_finite() && self.alpha >= 0.0) {
            return Err(GeomError::param(
                "alpha",
                format!("must be finite and ≥ 0, got {}", self.alpha),
            ));
        }
        Ok(())
    }
}

/// PCK per frame, in percent, NaN for frames that are not scored.
///
/// For frame t, the *visible* joints are those valid in `gt`; the frame is
/// scored when there are at least `min_visible` of them. The size of the
/// ground truth is the larger side of the axis-aligned bounding box of its
/// visible joints (the largest extent over the D axes). The prediction is
/// first mapped by the scale `s` and translation `τ` minimising
/// `Σ ‖s·Pⱼ + τ − Gⱼ‖²` over the visible joints that are also valid in
/// `pred` (closed form: with centred `P̃, G̃`, `s = ⟨P̃, G̃⟩ / ‖P̃‖²`, or
/// `s = 1` when all those predicted joints coincide; `τ = Ḡ − s·P̄`). A
/// visible joint is correct when `‖s·Pⱼ + τ − Gⱼ‖ ≤ α·size`; a visible joint
/// missing from `pred` counts as wrong. The frame's PCK is
/// `100 · correct / visible`.
pub fn pck_per_frame<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    params: &PckParams,
) -> Result<Vec<f64>> {
    pck_per_frame_sized(pred, gt, None, params)
}

/// [`pck_per_frame`] with the reference size of every ground-truth frame
/// given (e.g. the larger side of a data set's annotated person box) instead
/// of the extent of the visible joints. `sizes` must hold one entry per
/// ground-truth frame; a frame whose size is not finite and > 0 (a missing
/// annotation) falls back to the extent of its visible joints. `None` is
/// [`pck_per_frame`].
pub fn pck_per_frame_sized<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    sizes: Option<&[f64]>,
    params: &PckParams,
) -> Result<Vec<f64>> {
    let (pred, gt) = (pred.into(), gt.into());
    params.validate()?;
    check_pair(&pred, &gt, "pck", true)?;
    if let Some(sz) = sizes {
        if sz.len() != gt.n_frames() {
            return Err(GeomError::Shape(format!(
                "pck: {} reference sizes for {} ground-truth frames",
                sz.len(),
                gt.n_frames()
            )));
        }
    }
    let (_, nj, d) = gt.positions.dim();
    let mut pm = vec![0.0; d];
    let mut gm = vec![0.0; d];
    let mut lo = vec![0.0; d];
    let mut hi = vec![0.0; d];
    let mut out = Vec::with_capacity(gt.n_frames());
    for t in 0..gt.n_frames() {
        let visible = (0..nj).filter(|&j| gt.valid(t, j)).count();
        if visible < params.min_visible.max(1) {
            out.push(f64::NAN);
            continue;
        }
        lo.fill(f64::INFINITY);
        hi.fill(f64::NEG_INFINITY);
        pm.fill(0.0);
        gm.fill(0.0);
        let mut both = 0usize;
        for j in 0..nj {
            if !gt.valid(t, j) {
                continue;
            }
            for k in 0..d {
                let g = gt.p(t, j, k);
                lo[k] = lo[k].min(g);
                hi[k] = hi[k].max(g);
            }
            if pred.valid(t, j) {
                both += 1;
                for k in 0..d {
                    pm[k] += pred.p(t, j, k);
                    gm[k] += gt.p(t, j, k);
                }
            }
        }
        let size = match sizes.map(|sz| sz[t]) {
            Some(v) if v.is_finite() && v > 0.0 => v,
            _ => lo.iter().zip(&hi).map(|(a, b)| b - a).fold(0.0, f64::max),
        };
        if both == 0 {
            out.push(0.0);
            continue;
        }
        for k in 0..d {
            pm[k] /= both as f64;
            gm[k] /= both as f64;
        }
        let (mut pg, mut pp) = (0.0, 0.0);
        for j in 0..nj {
            if gt.valid(t, j) && pred.valid(t, j) {
                for k in 0..d {
                    let p = pred.p(t, j, k) - pm[k];
                    pg += p * (gt.p(t, j, k) - gm[k]);
                    pp += p * p;
                }
            }
        }
        let s = if pp > 0.0 { pg / pp } else { 1.0 };
        let thr = params.alpha * size;
        let mut correct = 0usize;
        for j in 0..nj {
            if gt.valid(t, j) && pred.valid(t, j) {
                let mut e = 0.0;
                for k in 0..d {
                    let x = s * (pred.p(t, j, k) - pm[k]) + gm[k] - gt.p(t, j, k);
                    e += x * x;
                }
                if e.sqrt() <= thr {
                    correct += 1;
                }
            }
        }
        out.push(100.0 * correct as f64 / visible as f64);
    }
    Ok(out)
}

/// PCK in percent with the given parameters: the [`nanmean`] of [`pck_per_frame`].
pub fn pck_with<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    params: &PckParams,
) -> Result<f64> {
    nanmean_or_err(&pck_per_frame(pred, gt, params)?, "pck")
}

/// PCK@α in percent (`min_visible` = 6): see [`pck_per_frame`].
pub fn pck<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    alpha: f64,
) -> Result<f64> {
    pck_with(
        pred,
        gt,
        &PckParams {
            alpha,
            ..PckParams::default()
        },
    )
}

// --- MPJPE ------------------------------------------------------------------

/// MPJPE per frame after root alignment; NaN for frames that cannot be scored.
///
/// The joints compared in frame t are those valid in both sequences. With
/// `root = Some(r)`, each pose is translated so that joint `r` is at the
/// origin (frames where the root is invalid in either sequence are NaN);
/// with `None`, each pose is translated by the mean of the compared joints.
/// The frame's value is the mean Euclidean distance over the compared joints.
pub fn mpjpe_per_frame<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    root: Option<usize>,
) -> Result<Vec<f64>> {
    let (pred, gt) = (pred.into(), gt.into());
    check_pair(&pred, &gt, "mpjpe", true)?;
    let (_, nj, d) = gt.positions.dim();
    if let Some(r) = root {
        if r >= nj {
            return Err(GeomError::param(
                "root",
                format!("joint {r} is out of range 0..{nj}"),
            ));
        }
    }
    let mut pr = vec![0.0; d];
    let mut gr = vec![0.0; d];
    let mut out = Vec::with_capacity(gt.n_frames());
    for t in 0..gt.n_frames() {
        let both = |j: usize| pred.valid(t, j) && gt.valid(t, j);
        let n = (0..nj).filter(|&j| both(j)).count();
        if n == 0 {
            out.push(f64::NAN);
            continue;
        }
        match root {
            Some(r) => {
                if !both(r) {
                    out.push(f64::NAN);
                    continue;
                }
                for k in 0..d {
                    pr[k] = pred.p(t, r, k);
                    gr[k] = gt.p(t, r, k);
                }
            }
            None => {
                pr.fill(0.0);
                gr.fill(0.0);
                for j in (0..nj).filter(|&j| both(j)) {
                    for k in 0..d {
                        pr[k] += pred.p(t, j, k) / n as f64;
                        gr[k] += gt.p(t, j, k) / n as f64;
                    }
                }
            }
        }
        let mut s = 0.0;
        for j in (0..nj).filter(|&j| both(j)) {
            let mut e = 0.0;
            for k in 0..d {
                let x = (pred.p(t, j, k) - pr[k]) - (gt.p(t, j, k) - gr[k]);
                e += x * x;
            }
            s += e.sqrt();
        }
        out.push(s / n as f64);
    }
    Ok(out)
}

/// MPJPE: the [`nanmean`] over frames of [`mpjpe_per_frame`].
pub fn mpjpe<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    root: Option<usize>,
) -> Result<f64> {
    nanmean_or_err(&mpjpe_per_frame(pred, gt, root)?, "mpjpe")
}

/// A similarity transform `x ↦ scale·R·x + translation`.
#[derive(Debug, Clone, PartialEq)]
pub struct Similarity {
    /// Scale (≥ 0).
    pub scale: f64,
    /// Rotation `D × D`, `det = +1`.
    pub rotation: DMatrix<f64>,
    /// Translation (length D).
    pub translation: Vec<f64>,
}

/// The similarity transform (Umeyama 1991) minimising `Σ ‖s·R·xᵢ + τ − yᵢ‖²`
/// over point pairs `x`, `y` (`N × D`), with `R` a proper rotation: the
/// reflection fix flips the sign of the last singular direction when
/// `det(U Vᵀ) < 0`. With all `x` coincident, `s = 0` and `τ = ȳ`.
pub fn procrustes(x: ArrayView2<'_, f64>, y: ArrayView2<'_, f64>) -> Result<Similarity> {
    let (n, d) = x.dim();
    if y.dim() != (n, d) {
        return Err(GeomError::Shape(format!(
            "procrustes: point sets have shapes {:?} and {:?}",
            x.dim(),
            y.dim()
        )));
    }
    if n == 0 || d == 0 {
        return Err(GeomError::NoData("procrustes: no points".into()));
    }
    if x.iter().chain(y.iter()).any(|v| !v.is_finite()) {
        return Err(GeomError::NonFinite(
            "procrustes: a coordinate is not finite".into(),
        ));
    }
    let xm: Vec<f64> = (0..d).map(|k| x.column(k).sum() / n as f64).collect();
    let ym: Vec<f64> = (0..d).map(|k| y.column(k).sum() / n as f64).collect();
    // cross-covariance Σ ỹ x̃ᵀ (D × D) and Σ ‖x̃‖²
    let mut h = DMatrix::<f64>::zeros(d, d);
    let mut xx = 0.0;
    for i in 0..n {
        for a in 0..d {
            let ya = y[[i, a]] - ym[a];
            for b in 0..d {
                h[(a, b)] += ya * (x[[i, b]] - xm[b]);
            }
            let xa = x[[i, a]] - xm[a];
            xx += xa * xa;
        }
    }
    let svd = h.clone().svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Err(GeomError::NoData("procrustes: SVD failed".into()));
    };
    let mut sign = DMatrix::<f64>::identity(d, d);
    if (&u * &vt).determinant() < 0.0 {
        sign[(d - 1, d - 1)] = -1.0;
    }
    let rotation = &u * &sign * &vt;
    let trace: f64 = (0..d).map(|k| svd.singular_values[k] * sign[(k, k)]).sum();
    let scale = if xx > 0.0 { trace / xx } else { 0.0 };
    let translation: Vec<f64> = (0..d)
        .map(|a| ym[a] - scale * (0..d).map(|b| rotation[(a, b)] * xm[b]).sum::<f64>())
        .collect();
    Ok(Similarity {
        scale,
        rotation,
        translation,
    })
}

/// PA-MPJPE per frame: MPJPE after the best similarity transform
/// ([`procrustes`], with the reflection fix) of the prediction onto the
/// ground truth, over the joints valid in both; NaN for frames with fewer
/// than 2 such joints.
pub fn pa_mpjpe_per_frame<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
) -> Result<Vec<f64>> {
    let (pred, gt) = (pred.into(), gt.into());
    check_pair(&pred, &gt, "pa_mpjpe", true)?;
    let (_, nj, d) = gt.positions.dim();
    let mut out = Vec::with_capacity(gt.n_frames());
    for t in 0..gt.n_frames() {
        let joints: Vec<usize> = (0..nj)
            .filter(|&j| pred.valid(t, j) && gt.valid(t, j))
            .collect();
        if joints.len() < 2 {
            out.push(f64::NAN);
            continue;
        }
        let x = Array2::from_shape_fn((joints.len(), d), |(i, k)| pred.p(t, joints[i], k));
        let y = Array2::from_shape_fn((joints.len(), d), |(i, k)| gt.p(t, joints[i], k));
        let sim = procrustes(x.view(), y.view())?;
        let mut s = 0.0;
        for i in 0..joints.len() {
            let mut e = 0.0;
            for a in 0..d {
                let mut v = sim.translation[a];
                for b in 0..d {
                    v += sim.scale * sim.rotation[(a, b)] * x[[i, b]];
                }
                e += (v - y[[i, a]]) * (v - y[[i, a]]);
            }
            s += e.sqrt();
        }
        out.push(s / joints.len() as f64);
    }
    Ok(out)
}

/// PA-MPJPE: the [`nanmean`] over frames of [`pa_mpjpe_per_frame`].
pub fn pa_mpjpe<'a, 'b>(pred: impl Into<Poses<'a>>, gt: impl Into<Poses<'b>>) -> Result<f64> {
    nanmean_or_err(&pa_mpjpe_per_frame(pred, gt)?, "pa_mpjpe")
}

// --- DTW --------------------------------------------------------------------

/// How DTW scores frame pairs and sums them. Let `d(i, j)` be the mean
/// Euclidean distance between frame `i` of `a` and frame `j` of `b` over the
/// joints valid in both, and `q(i, j)` the mean **squared** distance over the
/// same joints.
///
/// Libraries disagree here: e.g. tslearn's `dtw` is `SquaredThenSqrt` on
/// whole-frame vectors, i.e. with the *sum* over joints where this uses the
/// mean (for fully visible frames, tslearn's value = `sqrt(J)·` ours).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DtwCost {
    /// Local cost `d(i, j)`; distance = sum along the path.
    #[default]
    Euclidean,
    /// Local cost `q(i, j)`; distance = sum along the path.
    SquaredEuclidean,
    /// Local cost `q(i, j)`; distance = square root of the sum along the path.
    SquaredThenSqrt,
}

/// Result of [`dtw`].
#[derive(Debug, Clone, PartialEq)]
pub struct DtwResult {
    /// Total cost per the [`DtwCost`] convention.
    pub distance: f64,
    /// Matched frame pairs `(i in a, j in b)`, from `(0, 0)` to `(Ta−1, Tb−1)`,
    /// each step advancing `i`, `j` or both by 1: monotone, every frame of
    /// both sequences matched at least once.
    pub path: Vec<(usize, usize)>,
}

/// Largest DTW cost matrix (`Ta · Tb` cells) accepted: 2²⁶ (one byte per cell
/// is kept for the path).
pub const MAX_DTW_CELLS: usize = 1 << 26;

/// Dynamic time warping between two pose sequences (same J and D; T may
/// differ), with steps (1, 0), (0, 1), (1, 1) and the cost convention `cost`.
///
/// A pair of frames without a joint valid in both has infinite local cost;
/// when no path has a finite cost the result is [`GeomError::NoData`]. Ties
/// between predecessors prefer the diagonal step, then the step in `a`.
pub fn dtw<'a, 'b>(
    a: impl Into<Poses<'a>>,
    b: impl Into<Poses<'b>>,
    cost: DtwCost,
) -> Result<DtwResult> {
    let (a, b) = (a.into(), b.into());
    check_pair(&a, &b, "dtw", false)?;
    let (na, nb) = (a.n_frames(), b.n_frames());
    if na.saturating_mul(nb) > MAX_DTW_CELLS {
        return Err(GeomError::param(
            "dtw",
            format!("{na} × {nb} frames exceed the {MAX_DTW_CELLS}-cell limit"),
        ));
    }
    let nj = a.n_joints();
    let local = |i: usize, j: usize| -> f64 {
        let (mut s, mut n) = (0.0, 0usize);
        for jj in 0..nj {
            if a.valid(i, jj) && b.valid(j, jj) {
                let dd = a.dist(i, &b, j, jj);
                s += match cost {
                    DtwCost::Euclidean => dd,
                    DtwCost::SquaredEuclidean | DtwCost::SquaredThenSqrt => dd * dd,
                };
                n += 1;
            }
        }
        if n == 0 {
            f64::INFINITY
        } else {
            s / n as f64
        }
    };
    // dir: 0 = diagonal, 1 = from (i−1, j), 2 = from (i, j−1)
    let mut dir = vec![0u8; na * nb];
    let mut prev = vec![f64::INFINITY; nb];
    let mut cur = vec![f64::INFINITY; nb];
    for i in 0..na {
        for j in 0..nb {
            let c = local(i, j);
            let (best, from) = if i == 0 && j == 0 {
                (0.0, 0u8)
            } else {
                let diag = if i > 0 && j > 0 {
                    prev[j - 1]
                } else {
                    f64::INFINITY
                };
                let up = if i > 0 { prev[j] } else { f64::INFINITY };
                let left = if j > 0 { cur[j - 1] } else { f64::INFINITY };
                let mut best = (diag, 0u8);
                if up < best.0 {
                    best = (up, 1);
                }
                if left < best.0 {
                    best = (left, 2);
                }
                best
            };
            cur[j] = best + c;
            dir[i * nb + j] = from;
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    let total = prev[nb - 1];
    if !total.is_finite() {
        return Err(GeomError::NoData(
            "dtw: no alignment where every matched pair of frames shares a valid joint".into(),
        ));
    }
    let mut path = Vec::with_capacity(na + nb);
    let (mut i, mut j) = (na - 1, nb - 1);
    path.push((i, j));
    while i > 0 || j > 0 {
        match dir[i * nb + j] {
            0 => {
                i -= 1;
                j -= 1;
            }
            1 => i -= 1,
            _ => j -= 1,
        }
        path.push((i, j));
    }
    path.reverse();
    let distance = match cost {
        DtwCost::SquaredThenSqrt => total.sqrt(),
        _ => total,
    };
    Ok(DtwResult { distance, path })
}

/// A prediction resampled onto the ground truth's frames by [`dtw_align`].
#[derive(Debug, Clone, PartialEq)]
pub struct Aligned {
    /// Positions `T_gt × J × D`.
    pub positions: Array3<f64>,
    /// Confidence `T_gt × J` (0 where no matched prediction frame had the joint).
    pub confidence: Array2<f64>,
    /// The DTW result used.
    pub dtw: DtwResult,
}

impl Aligned {
    /// A [`Poses`] view, ready for [`pck`], [`mpjpe`], ….
    pub fn poses(&self) -> Poses<'_> {
        Poses {
            positions: self.positions.view(),
            confidence: Some(self.confidence.view()),
        }
    }
}

/// Resamples `pred` to `gt`'s length along the DTW path ("metric with DTW"):
/// frame `j` of the result is, joint by joint, the mean of the prediction
/// frames matched to ground-truth frame `j` where that joint is valid, with
/// the mean of their confidences (1 for valid joints without confidence).
pub fn dtw_align<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    cost: DtwCost,
) -> Result<Aligned> {
    let (pred, gt) = (pred.into(), gt.into());
    let res = dtw(pred, gt, cost)?;
    let (tg, nj, d) = gt.positions.dim();
    let mut positions = Array3::<f64>::zeros((tg, nj, d));
    let mut confidence = Array2::<f64>::zeros((tg, nj));
    let mut count = Array2::<f64>::zeros((tg, nj));
    let mut matched = vec![0usize; tg];
    for &(i, j) in &res.path {
        matched[j] += 1;
        for jj in 0..nj {
            if pred.valid(i, jj) {
                count[[j, jj]] += 1.0;
                confidence[[j, jj]] += pred.confidence.map_or(1.0, |c| c[[i, jj]]);
                for k in 0..d {
                    positions[[j, jj, k]] += pred.p(i, jj, k);
                }
            }
        }
    }
    for j in 0..tg {
        for jj in 0..nj {
            let c = count[[j, jj]];
            if c > 0.0 {
                for k in 0..d {
                    positions[[j, jj, k]] /= c;
                }
                confidence[[j, jj]] /= c;
            }
        }
    }
    Ok(Aligned {
        positions,
        confidence,
        dtw: res,
    })
}

// --- smoothness ---------------------------------------------------------------

/// Largest distance that a joint moves between two consecutive frames, over
/// every t and every joint valid in both frames t and t + 1 (paper 000 §4.1:
/// 100.10 px for raw poses vs 76.15 px for program-encoded poses on GolfDB).
pub fn max_adjacent_jump<'a>(poses: impl Into<Poses<'a>>) -> Result<f64> {
    let p = poses.into();
    p.check("max_adjacent_jump")?;
    if p.n_frames() < 2 {
        return Err(GeomError::TooShort {
            what: "max_adjacent_jump",
            needed: 2,
            got: p.n_frames(),
        });
    }
    let mut best: Option<f64> = None;
    for t in 0..p.n_frames() - 1 {
        for j in 0..p.n_joints() {
            if p.valid(t, j) && p.valid(t + 1, j) {
                let dd = p.dist(t, &p, t + 1, j);
                best = Some(best.map_or(dd, |b: f64| b.max(dd)));
            }
        }
    }
    best.ok_or_else(|| {
        GeomError::NoData("max_adjacent_jump: no joint is valid in two consecutive frames".into())
    })
}
