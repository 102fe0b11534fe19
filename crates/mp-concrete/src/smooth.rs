//! Smooth programs: consecutive segments share their boundary pose (C0).
//!
//! With [`Continuity::C0`] the segmentation is the one the DP chose for
//! independently fitted segments; then, per joint, all of that joint's
//! primitives are refitted **jointly** so that every segment ends where the
//! next begins: segment `i` evaluated at `t = duration_i` (the first frame of
//! segment `i + 1`) equals segment `i + 1` at `t = 0`. Executing such a
//! program gives a continuous trajectory; the step between the last frame of
//! a segment and the first frame of the next is the primitive's own last step.
//!
//! # The refit
//!
//! The unknowns of a joint are its **knots** `v_0 … v_S` (the pose at each
//! boundary, `D` values each; `v_S` is the end of the last segment extended by
//! one frame) and, for splines, two interior coefficients per axis. With
//! `s = t / n` (`n` the segment's duration) each kind keeps its shape:
//!
//! * **line**: `p(t) = (1 − s)·v_i + s·v_{i+1}` (start `v_i`, velocity `(v_{i+1} − v_i) / n`);
//! * **spline**: the line plus `s(1 − s)·(a + b·s)` per axis (still a cubic);
//! * **circle (2D)**: the fitted arc moved by the similarity (rotation and
//!   scale, as complex numbers) that maps its chord `p(n) − p(0)` onto
//!   `v_{i+1} − v_i`: `p(t) = v_i + (v_{i+1} − v_i)·w(t)` with the fixed complex
//!   `w(t) = (p(t) − p(0)) / (p(n) − p(0))`. The result is a circle with the same
//!   angular velocity and acceleration, a scaled radius and a turned start angle.
//!   An arc whose `|w(t)|` exceeds [`MAX_SIMILARITY_GAIN`] (more than about
//!   240°, or a vanishing chord), and every circle in 3D, is **rigid** instead:
//!   translated as a whole, `v_{i+1} = v_i + p(n) − p(0)`;
//! * **stationary**: rigid with a zero chord, `v_{i+1} = v_i` (the held pose
//!   is the shared knot).
//!
//! Every position is linear in the unknowns, so the refit is one weighted
//! least-squares problem per joint: squared residuals over the observed
//! frames (weight 1), plus the gap-filled positions (linear between
//! observations) of the frames where the joint is not observed with weight
//! [`GAP_WEIGHT`], so that a segment cannot swing far from the track where
//! nothing pins it (a segment where the joint is never observed uses the
//! gap-filled positions with weight 1, as the independent fit does). Rigid segments tie their two
//! knots, which removes one knot; the normal equations are banded (each
//! segment couples its two knots and its interior coefficients) and are
//! solved by a banded Cholesky factorisation in `O(S·D³)` per joint. A ridge
//! of weight [`RIDGE`] towards the independent fits' boundary poses keeps the
//! system positive definite where a joint has no data at all.
//!
//! A rigid segment can be forced far from its data by its neighbours (a held
//! joint between two different positions). After the solve, a stationary
//! segment whose mean residual grew by more than `stationary_mean_residual_px`
//! (the threshold of the stationary rule, 3 px at the 512-px reference) over
//! its independent fit becomes a line, a rigid circle a cubic spline, and the
//! joint is solved again (until nothing changes). These are the only changes
//! of kind.
//!
//! With [`RefitNorm::Euclidean`] each solve above is followed by
//! iteratively reweighted least squares: every observed frame's weight is
//! multiplied by `c·f / max(‖rᵢ‖, f)` (its residual in the previous solve, `f` =
//! [`IRLS_FLOOR_PX`] reference pixels, `c` fixed so that the observed frames
//! weigh 1 on average in the first reweighted solve, as in the least-squares
//! one); gap-filled frames keep their weight (they are not data, and without
//! `c` the interpolated positions would outweigh the data).
//! Each step lowers the Euclidean error of the observed frames (Huber's loss
//! with its corner at `f`, the Euclidean error above it) plus the
//! least-squares terms of the gap-filled frames: a majorise–minimise step,
//! as in Weiszfeld's algorithm. It stops when a step gains less than 0.1 %
//! or after [`IRLS_STEPS`] solves and keeps the best solution. The default
//! is [`RefitNorm::Squared`].
//!
//! The segmentation's cost ([`crate::Synthesis::segmentation`]) stays that of
//! the independent fits the DP minimised.

use mp_geom::fit::FitParams;
use mp_geom::Primitive;
use ndarray::ArrayView2;
use serde::{Deserialize, Serialize};

/// Whether consecutive segments of a program share their boundary pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Continuity {
    /// Segments fitted independently: the pose may jump at a boundary.
    /// Programs written before the field existed read as this.
    #[default]
    None,
    /// Segment `i` at `t = duration_i` equals segment `i + 1` at `t = 0`, for
    /// every joint (see the [module docs](self)).
    C0,
}

impl Continuity {
    /// The name used in the DSL header and on the command line (`none`, `c0`).
    pub fn as_str(self) -> &'static str {
        match self {
            Continuity::None => "none",
            Continuity::C0 => "c0",
        }
    }

    /// Parses [`Continuity::as_str`]'s names.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "none" => Some(Continuity::None),
            "c0" => Some(Continuity::C0),
            _ => None,
        }
    }
}

impl std::fmt::Display for Continuity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Continuity {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        Continuity::from_name(&s.to_ascii_lowercase())
            .ok_or_else(|| format!("unknown continuity `{s}` (expected `none` or `c0`)"))
    }
}

/// What the C0 refit minimises per joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RefitNorm {
    /// `Σ w‖rᵢ‖²`: one least-squares solve per joint.
    #[default]
    Squared,
    /// `Σ w‖rᵢ‖` (the Euclidean error the segmentation minimises under the
    /// default norm): iteratively reweighted least squares, starting from
    /// the least-squares solution (see the [module docs](self)).
    Euclidean,
}

impl RefitNorm {
    /// The name used on the command line (`squared`, `euclidean`).
    pub fn as_str(self) -> &'static str {
        match self {
            RefitNorm::Squared => "squared",
            RefitNorm::Euclidean => "euclidean",
        }
    }
}

impl std::fmt::Display for RefitNorm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for RefitNorm {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "squared" => Ok(RefitNorm::Squared),
            "euclidean" => Ok(RefitNorm::Euclidean),
            _ => Err(format!(
                "unknown refit norm `{s}` (expected `squared` or `euclidean`)"
            )),
        }
    }
}

/// Largest `|w(t)|` (the arc's distance from its start relative to its chord)
/// for which a 2D circle is refitted by a similarity; beyond it the circle
/// is moved rigidly. 3 allows arcs up to about 240°.
pub const MAX_SIMILARITY_GAIN: f64 = 3.0;

/// Weight of a frame where the joint is not observed (the gap-filled
/// position, interpolated between observations) in a segment where it is
/// observed elsewhere; an observed frame weighs 1.
pub const GAP_WEIGHT: f64 = 0.01;

/// Weight of the ridge towards the independent fits' boundary poses (per
/// unknown; a frame of data weighs 1).
pub const RIDGE: f64 = 1e-6;

/// How one segment of one joint depends on the unknowns.
#[derive(Debug, Clone)]
enum Elem {
    /// `p(t) = v_i + shape(t)`, `v_{i+1} = v_i + shape(n)`; `shape` of length `(n + 1)·D`.
    Rigid { shape: Vec<f64> },
    /// Line between the knots.
    Linear,
    /// Line plus `s(1 − s)(a + b s)` per axis.
    Cubic,
    /// 2D arc: `v_i + (v_{i+1} − v_i)·w(t)`, `w` complex per frame (length `n`).
    Similar { w: Vec<(f64, f64)> },
}

/// One joint's data: positions `T × D` (gap-filled) and 0/1 weights.
pub(crate) struct JointSeries<'a> {
    pub points: ArrayView2<'a, f64>,
    pub weights: &'a [f64],
}

/// Variable layout of one solve.
struct Layout {
    /// Per knot: index of its group's first unknown.
    knot_var: Vec<usize>,
    /// Per knot: offset from its group's value (rigid chains), `D` values.
    knot_off: Vec<Vec<f64>>,
    /// Per segment: index of the first interior unknown (cubic only).
    interior: Vec<Option<usize>>,
    /// Number of unknowns.
    n: usize,
    /// Half bandwidth of the normal matrix.
    bw: usize,
}

fn layout(elems: &[Elem], d: usize) -> Layout {
    let s = elems.len();
    let mut knot_var = Vec::with_capacity(s + 1);
    let mut knot_off = Vec::with_capacity(s + 1);
    let mut interior = Vec::with_capacity(s);
    knot_var.push(0);
    knot_off.push(vec![0.0; d]);
    let mut n = d;
    let mut bw = d - 1;
    for (i, e) in elems.iter().enumerate() {
        let first = knot_var[i];
        let mut hi = first + d - 1;
        if let Elem::Cubic = e {
            interior.push(Some(n));
            n += 2 * d;
            hi = n - 1;
        } else {
            interior.push(None);
        }
        match e {
            Elem::Rigid { shape } => {
                let nn = shape.len() / d - 1;
                let off: Vec<f64> = (0..d).map(|k| knot_off[i][k] + shape[nn * d + k]).collect();
                knot_var.push(first);
                knot_off.push(off);
            }
            _ => {
                knot_var.push(n);
                knot_off.push(vec![0.0; d]);
                n += d;
                hi = n - 1;
            }
        }
        bw = bw.max(hi - first);
    }
    Layout {
        knot_var,
        knot_off,
        interior,
        n,
        bw,
    }
}

/// Symmetric banded matrix (upper band) and right-hand side.
struct Normal {
    n: usize,
    w: usize,
    h: Vec<f64>,
    g: Vec<f64>,
}

impl Normal {
    fn new(n: usize, bw: usize) -> Self {
        let w = bw + 1;
        Normal {
            n,
            w,
            h: vec![0.0; n * w],
            g: vec![0.0; n],
        }
    }

    /// Adds `weight · (Σ coef·z[idx] − y)²` to the objective.
    fn add_row(&mut self, row: &[(usize, f64)], y: f64, weight: f64) {
        for &(a, ca) in row {
            self.g[a] += weight * ca * y;
            for &(b, cb) in row {
                if b >= a {
                    self.h[a * self.w + (b - a)] += weight * ca * cb;
                }
            }
        }
    }

    /// Solves by banded Cholesky; `None` when the matrix is not positive definite.
    fn solve(mut self) -> Option<Vec<f64>> {
        let (n, w) = (self.n, self.w);
        let bw = w - 1;
        let h = &mut self.h;
        for i in 0..n {
            for j in i..(i + w).min(n) {
                let mut sum = h[i * w + (j - i)];
                for k in j.saturating_sub(bw)..i {
                    sum -= h[k * w + (i - k)] * h[k * w + (j - k)];
                }
                if j == i {
                    if sum.is_nan() || sum <= 0.0 {
                        return None;
                    }
                    h[i * w] = sum.sqrt();
                } else {
                    h[i * w + (j - i)] = sum / h[i * w];
                }
            }
        }
        let b = &mut self.g;
        for i in 0..n {
            let mut s = b[i];
            for k in i.saturating_sub(bw)..i {
                s -= h[k * w + (i - k)] * b[k];
            }
            b[i] = s / h[i * w];
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for j in (i + 1)..(i + w).min(n) {
                s -= h[i * w + (j - i)] * b[j];
            }
            b[i] = s / h[i * w];
        }
        b.iter().all(|x| x.is_finite()).then_some(self.g)
    }
}

/// The element of a fitted primitive over `n` frames of `d` dimensions.
fn elem_of(p: &Primitive, n: usize, d: usize) -> Elem {
    let rigid = |p: &Primitive| {
        let p0 = p.eval(0.0);
        let mut shape = Vec::with_capacity((n + 1) * d);
        for t in 0..=n {
            let pt = p.eval(t as f64);
            shape.extend(pt.iter().zip(&p0).map(|(a, b)| a - b));
        }
        Elem::Rigid { shape }
    };
    match p {
        Primitive::Stationary { .. } => Elem::Rigid {
            shape: vec![0.0; (n + 1) * d],
        },
        Primitive::Line { .. } => Elem::Linear,
        Primitive::Spline { .. } => Elem::Cubic,
        Primitive::Circle { .. } if d == 2 => {
            let p0 = p.eval(0.0);
            let pn = p.eval(n as f64);
            let (cx, cy) = (pn[0] - p0[0], pn[1] - p0[1]);
            let c2 = cx * cx + cy * cy;
            let scale = p0[0].abs().max(p0[1].abs()).max(1.0);
            let chord = c2.sqrt();
            if chord.is_nan() || chord <= 1e-9 * scale {
                return rigid(p);
            }
            let mut w = Vec::with_capacity(n);
            for t in 0..n {
                let q = p.eval(t as f64);
                let (dx, dy) = (q[0] - p0[0], q[1] - p0[1]);
                // (dx + i dy) / (cx + i cy)
                let wr = (dx * cx + dy * cy) / c2;
                let wi = (dy * cx - dx * cy) / c2;
                if wr.hypot(wi) > MAX_SIMILARITY_GAIN {
                    return rigid(p);
                }
                w.push((wr, wi));
            }
            Elem::Similar { w }
        }
        Primitive::Circle { .. } => rigid(p),
    }
}

/// Per-knot initial poses: the independent fits' boundary poses (mean of the
/// end of one segment and the start of the next).
fn initial_knots(prims: &[Primitive], durations: &[usize]) -> Vec<Vec<f64>> {
    let s = prims.len();
    let mut out = Vec::with_capacity(s + 1);
    for i in 0..=s {
        let a = (i > 0).then(|| prims[i - 1].eval(durations[i - 1] as f64));
        let b = (i < s).then(|| prims[i].eval(0.0));
        out.push(match (a, b) {
            (Some(a), Some(b)) => a.iter().zip(&b).map(|(x, y)| 0.5 * (x + y)).collect(),
            (Some(a), None) => a,
            (None, Some(b)) => b,
            (None, None) => Vec::new(),
        });
    }
    out
}

/// Solves one joint's knots and interior coefficients for the given elements.
fn solve(
    series: &JointSeries<'_>,
    bounds: &[usize],
    elems: &[Elem],
    init: &[Vec<f64>],
    d: usize,
    reweight: Option<&[f64]>,
) -> Option<(Vec<Vec<f64>>, Vec<f64>)> {
    let lay = layout(elems, d);
    let mut ne = Normal::new(lay.n, lay.bw);
    let mut row: Vec<(usize, f64)> = Vec::with_capacity(4 * d);
    for (i, e) in elems.iter().enumerate() {
        let (k0, k1) = (bounds[i], bounds[i + 1]);
        let n = k1 - k0;
        let observed = series.weights[k0..k1].iter().any(|&w| w > 0.0);
        let (va, vb) = (lay.knot_var[i], lay.knot_var[i + 1]);
        let (oa, ob) = (&lay.knot_off[i], &lay.knot_off[i + 1]);
        for t in 0..n {
            let wt = refit_weight(series, observed, k0 + t) * reweight.map_or(1.0, |r| r[k0 + t]);
            if wt <= 0.0 {
                continue;
            }
            let s = t as f64 / n as f64;
            for k in 0..d {
                row.clear();
                let x = series.points[[k0 + t, k]];
                // The constant part of the row goes to the target.
                let mut c = 0.0;
                match e {
                    Elem::Rigid { shape } => {
                        row.push((va + k, 1.0));
                        c += oa[k] + shape[t * d + k];
                    }
                    Elem::Linear | Elem::Cubic => {
                        row.push((va + k, 1.0 - s));
                        row.push((vb + k, s));
                        c += (1.0 - s) * oa[k] + s * ob[k];
                        if let (Elem::Cubic, Some(iv)) = (e, lay.interior[i]) {
                            row.push((iv + k, s * (1.0 - s)));
                            row.push((iv + d + k, s * s * (1.0 - s)));
                        }
                    }
                    Elem::Similar { w } => {
                        let (wr, wi) = w[t];
                        // x = a_x(1 − wr) + a_y·wi + b_x·wr − b_y·wi
                        // y = −a_x·wi + a_y(1 − wr) + b_x·wi + b_y·wr
                        let coefs = if k == 0 {
                            [1.0 - wr, wi, wr, -wi]
                        } else {
                            [-wi, 1.0 - wr, wi, wr]
                        };
                        row.push((va, coefs[0]));
                        row.push((va + 1, coefs[1]));
                        row.push((vb, coefs[2]));
                        row.push((vb + 1, coefs[3]));
                        c += coefs[0] * oa[0]
                            + coefs[1] * oa[1]
                            + coefs[2] * ob[0]
                            + coefs[3] * ob[1];
                    }
                }
                ne.add_row(&row, x - c, wt);
            }
        }
    }
    // Ridge: each group's value towards its first knot's initial pose, interiors towards 0.
    for (i, &v) in lay.knot_var.iter().enumerate() {
        if i > 0 && lay.knot_var[i - 1] == v {
            continue;
        }
        for k in 0..d {
            let y = init[i].get(k).copied().unwrap_or(0.0);
            ne.add_row(&[(v + k, 1.0)], y, RIDGE);
        }
    }
    for iv in lay.interior.iter().flatten() {
        for k in 0..2 * d {
            ne.add_row(&[(iv + k, 1.0)], 0.0, RIDGE);
        }
    }
    let z = ne.solve()?;
    let knots: Vec<Vec<f64>> = (0..lay.knot_var.len())
        .map(|i| {
            (0..d)
                .map(|k| z[lay.knot_var[i] + k] + lay.knot_off[i][k])
                .collect()
        })
        .collect();
    let mut interiors = vec![0.0; elems.len() * 2 * d];
    for (i, iv) in lay.interior.iter().enumerate() {
        if let Some(iv) = iv {
            interiors[i * 2 * d..(i + 1) * 2 * d].copy_from_slice(&z[*iv..*iv + 2 * d]);
        }
    }
    Some((knots, interiors))
}

/// The primitive of segment `i` from the solved knots.
fn primitive_of(
    orig: &Primitive,
    e: &Elem,
    n: usize,
    a: &[f64],
    b: &[f64],
    interior: &[f64],
) -> Primitive {
    let d = a.len();
    let nf = n as f64;
    match e {
        Elem::Linear => Primitive::Line {
            start: a.to_vec(),
            velocity: a.iter().zip(b).map(|(x, y)| (y - x) / nf).collect(),
        },
        Elem::Cubic => {
            // Polynomial in s: c0 + c1 s + c2 s² + c3 s³, then in t = n s.
            let coeffs = (0..d)
                .map(|k| {
                    let (ia, ib) = (interior[k], interior[d + k]);
                    let c0 = a[k];
                    let c1 = b[k] - a[k] + ia;
                    let c2 = ib - ia;
                    let c3 = -ib;
                    [c3 / (nf * nf * nf), c2 / (nf * nf), c1 / nf, c0]
                })
                .collect();
            Primitive::Spline { coeffs }
        }
        Elem::Rigid { .. } => match orig {
            Primitive::Stationary { .. } => Primitive::Stationary { point: a.to_vec() },
            other => {
                let p0 = other.eval(0.0);
                Primitive::translated(
                    other,
                    &a.iter().zip(&p0).map(|(x, y)| x - y).collect::<Vec<_>>(),
                )
            }
        },
        Elem::Similar { .. } => similar_circle(orig, n, a, b),
    }
}

/// Every segment's primitive from the solved knots and interiors.
fn primitives_of(
    prims: &[Primitive],
    elems: &[Elem],
    durations: &[usize],
    knots: &[Vec<f64>],
    interiors: &[f64],
) -> Vec<Primitive> {
    let d2 = interiors.len() / prims.len().max(1);
    (0..prims.len())
        .map(|i| {
            primitive_of(
                &prims[i],
                &elems[i],
                durations[i],
                &knots[i],
                &knots[i + 1],
                &interiors[i * d2..(i + 1) * d2],
            )
        })
        .collect()
}

/// The 2D circle `orig` mapped by the similarity taking its chord onto `b − a`, starting at `a`.
fn similar_circle(orig: &Primitive, n: usize, a: &[f64], b: &[f64]) -> Primitive {
    let Primitive::Circle {
        center,
        radius,
        angle_start,
        angle_vel,
        angle_acc,
        axes,
    } = orig
    else {
        return orig.clone();
    };
    let p0 = orig.eval(0.0);
    let pn = orig.eval(n as f64);
    let (cx, cy) = (pn[0] - p0[0], pn[1] - p0[1]);
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let c2 = cx * cx + cy * cy;
    // A = (ex + i ey) / (cx + i cy)
    let ar = (ex * cx + ey * cy) / c2;
    let ai = (ey * cx - ex * cy) / c2;
    let (ux, uy) = (center[0] - p0[0], center[1] - p0[1]);
    let new_center = vec![a[0] + ar * ux - ai * uy, a[1] + ai * ux + ar * uy];
    let phi = ai.atan2(ar).to_degrees();
    let mut start = angle_start + phi;
    start -= 360.0 * ((start - 180.0) / 360.0).ceil();
    Primitive::Circle {
        center: new_center,
        radius: radius * ar.hypot(ai),
        angle_start: start,
        angle_vel: *angle_vel,
        angle_acc: *angle_acc,
        axes: axes.clone(),
    }
}

/// A frame's weight in the refit: its 0/1 weight raised to [`GAP_WEIGHT`]
/// in a segment where the joint is observed somewhere (`observed`), 1 in a
/// segment where it never is.
fn refit_weight(series: &JointSeries<'_>, observed: bool, i: usize) -> f64 {
    if observed {
        series.weights[i].max(GAP_WEIGHT)
    } else {
        1.0
    }
}

/// Distance between `p` at segment time `t` and the joint's position at frame `i`.
fn distance_at(
    p: &Primitive,
    t: usize,
    series: &JointSeries<'_>,
    i: usize,
    buf: &mut [f64],
) -> f64 {
    p.eval_into(t as f64, buf);
    buf.iter()
        .zip(series.points.row(i).iter())
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt()
}

/// Mean Euclidean residual of `p` on frames `k0..k1` (weights as in the refit).
fn mean_residual(p: &Primitive, series: &JointSeries<'_>, k0: usize, k1: usize) -> f64 {
    let observed = series.weights[k0..k1].iter().any(|&w| w > 0.0);
    let (mut sum, mut wsum) = (0.0, 0.0);
    let mut buf = vec![0.0; series.points.ncols()];
    for t in 0..(k1 - k0) {
        let w = if observed {
            series.weights[k0 + t]
        } else {
            1.0
        };
        if w <= 0.0 {
            continue;
        }
        sum += w * distance_at(p, t, series, k0 + t, &mut buf);
        wsum += w;
    }
    if wsum > 0.0 {
        sum / wsum
    } else {
        0.0
    }
}

/// Largest number of reweighted solves of [`reweighted`].
pub const IRLS_STEPS: usize = 20;

/// Residuals below this (reference pixels) weigh as much as it does in the
/// reweighted solves.
pub const IRLS_FLOOR_PX: f64 = 0.05;

/// Per-frame residual lengths of `prims` (into `out`) and the objective the
/// reweighted solves lower: `c·Σ 2f·ρ_f(‖rᵢ‖)` over the observed frames (Huber's
/// loss with its corner at `f`: `‖r‖²` below it, `2f‖r‖ − f²` above, so the
/// Euclidean error up to a constant for residuals above `f`) plus the
/// least-squares terms of the gap-filled frames, with their refit weights.
fn irls_objective(
    series: &JointSeries<'_>,
    bounds: &[usize],
    prims: &[Primitive],
    f: f64,
    c: f64,
    out: &mut [f64],
) -> f64 {
    let d = series.points.ncols();
    let mut buf = vec![0.0; d];
    let mut total = 0.0;
    for (i, p) in prims.iter().enumerate() {
        let (k0, k1) = (bounds[i], bounds[i + 1]);
        let observed = series.weights[k0..k1].iter().any(|&w| w > 0.0);
        for t in 0..(k1 - k0) {
            let r = distance_at(p, t, series, k0 + t, &mut buf);
            out[k0 + t] = r;
            total += if series.weights[k0 + t] > 0.0 {
                c * if r <= f { r * r } else { 2.0 * f * r - f * f }
            } else {
                refit_weight(series, observed, k0 + t) * r * r
            };
        }
    }
    total
}

/// The refit under the Euclidean norm: iteratively reweighted least squares.
/// Each observed frame's weight is multiplied by `c·f / max(‖rᵢ‖, f)` from the
/// previous solve (see the module docs for `c`); gap-filled frames keep their
/// least-squares weight (they are not data). Each solve lowers [`irls_objective`] (a majorise–minimise
/// step). It stops when a step gains less than 0.1 % or after
/// [`IRLS_STEPS`], and keeps the best solution seen.
fn reweighted(
    series: &JointSeries<'_>,
    bounds: &[usize],
    elems: &[Elem],
    init: &[Vec<f64>],
    fit: &FitParams,
    prims: &[Primitive],
    start: Vec<Primitive>,
) -> Vec<Primitive> {
    let (t, d) = series.points.dim();
    let durations: Vec<usize> = bounds.windows(2).map(|w| w[1] - w[0]).collect();
    let floor = IRLS_FLOOR_PX * fit.unit_scale;
    let mut res = vec![0.0; t];
    let mut best = start;
    irls_objective(series, bounds, &best, floor, 1.0, &mut res);
    // Observed frames weigh 1 on average in the first reweighted solve, as
    // in the least-squares one, against the gap-filled frames.
    let (mut sum, mut n) = (0.0, 0usize);
    for (r, &obs) in res.iter().zip(series.weights) {
        if obs > 0.0 {
            sum += floor / r.max(floor);
            n += 1;
        }
    }
    if n == 0 || sum <= 0.0 {
        return best;
    }
    let c = n as f64 / sum;
    let mut best_err = irls_objective(series, bounds, &best, floor, c, &mut res);
    let mut weights = vec![0.0; t];
    for _ in 0..IRLS_STEPS {
        for ((w, r), &obs) in weights.iter_mut().zip(&res).zip(series.weights) {
            *w = if obs > 0.0 {
                c * floor / r.max(floor)
            } else {
                1.0
            };
        }
        let Some((knots, interiors)) = solve(series, bounds, elems, init, d, Some(&weights)) else {
            break;
        };
        let cand = primitives_of(prims, elems, &durations, &knots, &interiors);
        let mut cand_res = vec![0.0; t];
        let err = irls_objective(series, bounds, &cand, floor, c, &mut cand_res);
        if err.is_nan() || err >= best_err {
            break;
        }
        let gain = (best_err - err) / best_err.max(f64::MIN_POSITIVE);
        best = cand;
        best_err = err;
        res = cand_res;
        if gain < 1e-3 {
            break;
        }
    }
    best
}

/// Refits one joint's primitives (one per segment of `bounds`) so that
/// consecutive ones share their boundary pose. `None` when the normal
/// equations cannot be solved (non-finite input).
pub(crate) fn refit_joint(
    series: &JointSeries<'_>,
    bounds: &[usize],
    prims: &[Primitive],
    fit: &FitParams,
    norm: RefitNorm,
) -> Option<Vec<Primitive>> {
    let d = series.points.ncols();
    if prims.is_empty() || d == 0 || bounds.len() != prims.len() + 1 {
        return None;
    }
    let durations: Vec<usize> = bounds.windows(2).map(|w| w[1] - w[0]).collect();
    let mut elems: Vec<Elem> = prims
        .iter()
        .zip(&durations)
        .map(|(p, &n)| elem_of(p, n, d))
        .collect();
    let init = initial_knots(prims, &durations);
    let before: Vec<f64> = prims
        .iter()
        .enumerate()
        .map(|(i, p)| mean_residual(p, series, bounds[i], bounds[i + 1]))
        .collect();
    let limit = fit.stationary_mean_residual_px * fit.unit_scale;
    // Each pass turns at least one rigid segment into a flexible one, so this ends.
    loop {
        let (knots, interiors) = solve(series, bounds, &elems, &init, d, None)?;
        let mut out = primitives_of(prims, &elems, &durations, &knots, &interiors);
        if norm == RefitNorm::Euclidean {
            out = reweighted(series, bounds, &elems, &init, fit, prims, out);
        }
        let mut changed = false;
        for (i, e) in elems.iter_mut().enumerate() {
            if !matches!(e, Elem::Rigid { .. }) {
                continue;
            }
            let after = mean_residual(&out[i], series, bounds[i], bounds[i + 1]);
            if after > before[i] + limit {
                *e = match prims[i] {
                    Primitive::Stationary { .. } => Elem::Linear,
                    _ => Elem::Cubic,
                };
                changed = true;
            }
        }
        if !changed {
            return Some(out);
        }
    }
}

/// The largest distance, over joints and boundaries, between the end of a
/// segment (its primitive at `t = duration`) and the start of the next.
pub fn max_boundary_gap(program: &crate::Program) -> f64 {
    let mut worst: f64 = 0.0;
    for pair in program.segments.windows(2) {
        let n = pair[0].duration_frames as f64;
        for (p, q) in pair[0].primitives.iter().zip(&pair[1].primitives) {
            let a = p.eval(n);
            let b = q.eval(0.0);
            let dist = a
                .iter()
                .zip(&b)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f64>()
                .sqrt();
            worst = worst.max(dist);
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)] // test code: failing loudly is the point

    use super::*;
    use ndarray::Array2;

    /// Three lines (a zigzag) with small deterministic noise and a few
    /// large spikes; returns the points, 0/1 weights and the boundaries.
    fn zigzag() -> (Array2<f64>, Vec<f64>, Vec<usize>) {
        let t = 90;
        let mut pts = Array2::zeros((t, 2));
        for i in 0..t {
            let s = i as f64;
            let (x, y) = if i < 30 {
                (2.0 * s, s)
            } else if i < 60 {
                (60.0 + (s - 30.0), 30.0 - 2.0 * (s - 30.0))
            } else {
                (90.0 + 3.0 * (s - 60.0), -30.0 + 0.5 * (s - 60.0))
            };
            let noise = 0.3 * ((i * 7919) % 13) as f64 / 13.0 - 0.15;
            let spike = if i % 11 == 5 { 25.0 } else { 0.0 };
            pts[[i, 0]] = x + noise + spike;
            pts[[i, 1]] = y - noise;
        }
        let mut weights = vec![1.0; t];
        weights[44] = 0.0; // one missing frame (gap-filled position, small weight)
        (pts, weights, vec![0, 30, 60, 90])
    }

    fn line(a: [f64; 2], v: [f64; 2]) -> Primitive {
        Primitive::Line {
            start: a.to_vec(),
            velocity: v.to_vec(),
        }
    }

    #[test]
    fn euclidean_refit_lowers_the_euclidean_error_and_stays_c0() {
        let (pts, weights, bounds) = zigzag();
        let series = JointSeries {
            points: pts.view(),
            weights: &weights,
        };
        let prims = vec![
            line([0.0, 0.0], [2.0, 1.0]),
            line([60.0, 30.0], [1.0, -2.0]),
            line([90.0, -30.0], [3.0, 0.5]),
        ];
        let fit = FitParams::default();
        let sq = refit_joint(&series, &bounds, &prims, &fit, RefitNorm::Squared).unwrap();
        let eu = refit_joint(&series, &bounds, &prims, &fit, RefitNorm::Euclidean).unwrap();
        let mut res = vec![0.0; pts.nrows()];
        // Σ‖rᵢ‖ over the observed frames (`res` keeps the last one's residuals).
        let mut observed_sum = |p: &[Primitive]| {
            irls_objective(&series, &bounds, p, 0.0, 1.0, &mut res);
            (0..pts.nrows())
                .filter(|&i| weights[i] > 0.0)
                .map(|i| res[i])
                .sum::<f64>()
        };
        let e_sq = observed_sum(&sq);
        let e_eu = observed_sum(&eu);
        // The spikes pull the least-squares lines; the Euclidean refit lies
        // on the clean frames (their noise is at most 0.15 per axis).
        assert!(e_eu < 0.8 * e_sq, "Σ‖r‖ {e_eu} vs least squares {e_sq}");
        let clean: Vec<f64> = (0..pts.nrows())
            .filter(|i| i % 11 != 5 && weights[*i] > 0.0)
            .map(|i| res[i])
            .collect();
        let worst = clean.iter().cloned().fold(0.0, f64::max);
        assert!(worst < 1.0, "largest residual on a clean frame {worst}");
        // Both share their boundary poses.
        for p in [&sq, &eu] {
            for i in 0..2 {
                let n = (bounds[i + 1] - bounds[i]) as f64;
                let (a, b) = (p[i].eval(n), p[i + 1].eval(0.0));
                let gap = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                assert!(gap < 1e-9, "boundary {i}: gap {gap}");
            }
        }
    }

    #[test]
    fn refit_norm_names_round_trip() {
        for n in [RefitNorm::Squared, RefitNorm::Euclidean] {
            assert_eq!(n.as_str().parse::<RefitNorm>().unwrap(), n);
        }
        let err = "l1".parse::<RefitNorm>().unwrap_err();
        assert!(err.contains("unknown refit norm `l1`"), "{err}");
    }
}
