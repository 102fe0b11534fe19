//! O(1) per-segment stationary and line fits from prefix sums.
//!
//! A segmentation DP evaluates fits of every segment `a..b` with
//! `b − a ≤ W`; for stationary and line primitives the weighted
//! least-squares solution and its **squared** error depend only on the
//! moments `Σw, Σw t, Σw t², Σw x, Σw t x, Σw x²` of the segment, so after
//! one O(T·D) pass over a trajectory each segment costs O(D).
//!
//! Time inside a segment starts at 0 (frame `a` is `t = 0`), as everywhere
//! in [`crate::fit`]. Coordinates are stored relative to the weighted mean
//! of the whole trajectory and time relative to the trajectory's middle, and
//! the prefix sums are accumulated in double-double arithmetic (an error-free
//! `TwoSum` keeps the rounding of each addition), so that the difference of
//! two prefix sums is as accurate as summing the segment directly, even on
//! 100k-frame tracks. The results agree with [`super::fit_stationary`] /
//! [`super::fit_line`] with [`super::ErrorNorm::Squared`] up to rounding (see
//! the tests).
//!
//! The Euclidean norm (sum of unsquared distances) has no such closed form:
//! use [`PrefixFits::line`] for the parameters and
//! [`super::residual_error`] for the error when that norm is wanted.

use ndarray::ArrayView2;

use super::input;
use super::Fit;
use crate::error::{GeomError, Result};
use crate::primitive::Primitive;

/// A double-double number `hi + lo` (|lo| ≤ ulp(hi)/2 after each addition).
#[derive(Debug, Clone, Copy, Default)]
struct Dd {
    hi: f64,
    lo: f64,
}

impl Dd {
    /// Adds `x` with Knuth's TwoSum, keeping the rounding error in `lo`.
    #[inline(always)]
    fn add(&mut self, x: f64) {
        let s = self.hi + x;
        let bb = s - self.hi;
        let err = (self.hi - (s - bb)) + (x - bb);
        self.hi = s;
        self.lo += err;
    }
    /// `self − other` rounded to f64.
    #[inline(always)]
    fn sub(&self, other: &Dd) -> f64 {
        (self.hi - other.hi) + (self.lo - other.lo)
    }
}

/// Prefix moments of one trajectory (`T × D`).
#[derive(Debug, Clone)]
pub struct PrefixFits {
    n: usize,
    d: usize,
    /// Offset subtracted from each axis.
    offset: Vec<f64>,
    /// Time origin: stored time is `i − t0`.
    t0: f64,
    /// `(n + 1) × 3`: Σw, Σw t, Σw t² (high and low parts).
    wt: Vec<[Dd; 3]>,
    /// `(n + 1) × D × 3`: Σw x, Σw t x, Σw x² (high and low parts).
    wx: Vec<[Dd; 3]>,
    /// `(n + 1)`: number of frames with weight > 0.
    count: Vec<u32>,
}

impl PrefixFits {
    /// Builds the prefix sums of `points` (`T × D`) with optional weights
    /// (same conventions and checks as the `fit_*` functions; frames of weight
    /// 0 are skipped, so a trajectory may have no valid frame in some
    /// segments; those segments report [`GeomError::NoData`]).
    pub fn new(points: ArrayView2<'_, f64>, weights: Option<&[f64]>) -> Result<Self> {
        let (n, d) = points.dim();
        let s = input::check("prefix fits", points, weights)?;
        if n > u32::MAX as usize {
            return Err(GeomError::param("points", "more than 2³² frames"));
        }
        let mut offset = vec![0.0; d];
        for (i, row) in points.outer_iter().enumerate() {
            let w = input::wt(weights, i);
            if w > 0.0 {
                for (o, v) in offset.iter_mut().zip(row.iter()) {
                    *o += w * v;
                }
            }
        }
        for o in &mut offset {
            *o /= s.w_sum;
        }
        let t0 = (n as f64 - 1.0) / 2.0;
        let mut wt = Vec::with_capacity(n + 1);
        let mut wx = Vec::with_capacity((n + 1) * d);
        let mut count = Vec::with_capacity(n + 1);
        let mut acc_t = [Dd::default(); 3];
        let mut acc_x = vec![[Dd::default(); 3]; d];
        let mut c = 0u32;
        wt.push(acc_t);
        wx.extend_from_slice(&acc_x);
        count.push(c);
        for (i, row) in points.outer_iter().enumerate() {
            let w = input::wt(weights, i);
            if w > 0.0 {
                let t = i as f64 - t0;
                acc_t[0].add(w);
                acc_t[1].add(w * t);
                acc_t[2].add(w * t * t);
                for (k, v) in row.iter().enumerate() {
                    let x = v - offset[k];
                    acc_x[k][0].add(w * x);
                    acc_x[k][1].add(w * t * x);
                    acc_x[k][2].add(w * x * x);
                }
                c += 1;
            }
            wt.push(acc_t);
            wx.extend_from_slice(&acc_x);
            count.push(c);
        }
        Ok(PrefixFits {
            n,
            d,
            offset,
            t0,
            wt,
            wx,
            count,
        })
    }

    /// Number of frames T.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the trajectory has no frame (never true: construction needs one).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    fn check_range(&self, a: usize, b: usize) -> Result<()> {
        if a >= b || b > self.n {
            return Err(GeomError::param(
                "segment",
                format!("range {a}..{b} is empty or outside 0..{}", self.n),
            ));
        }
        if self.count[b] == self.count[a] {
            return Err(GeomError::NoData(format!(
                "segment {a}..{b}: all frames have weight 0"
            )));
        }
        Ok(())
    }

    /// Segment moments of time: `(W, Σw t, Σw t²)` with stored time.
    #[inline]
    fn tmom(&self, a: usize, b: usize) -> [f64; 3] {
        let (p, q) = (&self.wt[a], &self.wt[b]);
        [q[0].sub(&p[0]), q[1].sub(&p[1]), q[2].sub(&p[2])]
    }

    /// Segment moments of axis `k`: `(Σw x, Σw t x, Σw x²)`.
    #[inline]
    fn xmom(&self, a: usize, b: usize, k: usize) -> [f64; 3] {
        let (p, q) = (&self.wx[a * self.d + k], &self.wx[b * self.d + k]);
        [q[0].sub(&p[0]), q[1].sub(&p[1]), q[2].sub(&p[2])]
    }

    /// Squared error of the stationary fit of frames `a..b` (O(D), no allocation).
    pub fn stationary_sq_error(&self, a: usize, b: usize) -> Result<f64> {
        self.check_range(a, b)?;
        let [w, _, _] = self.tmom(a, b);
        let mut e = 0.0;
        for k in 0..self.d {
            let [sx, _, sxx] = self.xmom(a, b, k);
            e += (sxx - sx * sx / w).max(0.0);
        }
        Ok(e)
    }

    /// Squared error of the line fit of frames `a..b` (O(D), no allocation).
    pub fn line_sq_error(&self, a: usize, b: usize) -> Result<f64> {
        self.check_range(a, b)?;
        let [w, st, stt] = self.tmom(a, b);
        // centred time variance Σw (t − t̄)²
        let vtt = stt - st * st / w;
        let single = self.count[b] - self.count[a] == 1;
        let mut e = 0.0;
        for k in 0..self.d {
            let [sx, stx, sxx] = self.xmom(a, b, k);
            let vxx = sxx - sx * sx / w;
            let vtx = stx - st * sx / w;
            let r = if single || vtt <= 0.0 {
                vxx
            } else {
                vxx - vtx * vtx / vtt
            };
            e += r.max(0.0);
        }
        Ok(e)
    }

    /// The stationary fit of frames `a..b` with its squared error.
    pub fn stationary(&self, a: usize, b: usize) -> Result<Fit> {
        let error = self.stationary_sq_error(a, b)?;
        let [w, _, _] = self.tmom(a, b);
        let point = (0..self.d)
            .map(|k| self.xmom(a, b, k)[0] / w + self.offset[k])
            .collect();
        Ok(Fit {
            primitive: Primitive::Stationary { point },
            error,
        })
    }

    /// The line fit of frames `a..b` (time 0 at frame `a`) with its squared error.
    pub fn line(&self, a: usize, b: usize) -> Result<Fit> {
        let error = self.line_sq_error(a, b)?;
        let [w, st, stt] = self.tmom(a, b);
        let vtt = stt - st * st / w;
        let single = self.count[b] - self.count[a] == 1;
        let tbar = st / w; // stored time
        let ta = a as f64 - self.t0; // stored time of frame a
        let mut start = Vec::with_capacity(self.d);
        let mut velocity = Vec::with_capacity(self.d);
        for k in 0..self.d {
            let [sx, stx, _] = self.xmom(a, b, k);
            let xbar = sx / w;
            let vel = if single || vtt <= 0.0 {
                0.0
            } else {
                (stx - st * sx / w) / vtt
            };
            start.push(xbar + vel * (ta - tbar) + self.offset[k]);
            velocity.push(vel);
        }
        Ok(Fit {
            primitive: Primitive::Line { start, velocity },
            error,
        })
    }
}
