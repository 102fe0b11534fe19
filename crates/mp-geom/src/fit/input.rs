//! Input checks shared by every fit, and small allocation-free helpers.

use ndarray::ArrayView2;

use crate::error::{GeomError, Result};

/// Weight of frame `i` (1 when no weights are given).
#[inline(always)]
pub(crate) fn wt(weights: Option<&[f64]>, i: usize) -> f64 {
    match weights {
        Some(w) => w[i],
        None => 1.0,
    }
}

/// What the checks learned about one segment.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Summary {
    /// Frames in the segment.
    pub n: usize,
    /// Dimensions per point.
    pub d: usize,
    /// Frames with weight > 0.
    pub n_valid: usize,
    /// Sum of weights.
    pub w_sum: f64,
    /// First and last frame with weight > 0.
    pub first: usize,
    pub last: usize,
}

/// Checks shapes, weights and finiteness.
///
/// * no frame or no dimension → [`GeomError::TooShort`] / [`GeomError::Shape`];
/// * weights of the wrong length → [`GeomError::Shape`];
/// * a NaN or infinite weight → [`GeomError::NonFinite`]; a negative weight →
///   [`GeomError::InvalidParam`] (`weights`);
/// * a non-finite coordinate in a frame of weight > 0 → [`GeomError::NonFinite`]
///   naming the frame and axis (frames of weight 0 are missing and never read);
/// * every weight 0 → [`GeomError::NoData`].
pub(crate) fn check(
    what: &'static str,
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
) -> Result<Summary> {
    let (n, d) = points.dim();
    if n == 0 {
        return Err(GeomError::TooShort {
            what,
            needed: 1,
            got: 0,
        });
    }
    if d == 0 {
        return Err(GeomError::Shape(format!(
            "{what}: points have 0 dimensions"
        )));
    }
    if let Some(w) = weights {
        if w.len() != n {
            return Err(GeomError::Shape(format!(
                "{what}: {} weights for {n} frames",
                w.len()
            )));
        }
    }
    let mut n_valid = 0usize;
    let mut w_sum = 0.0;
    let mut first = usize::MAX;
    let mut last = 0usize;
    for (i, row) in points.outer_iter().enumerate() {
        let w = wt(weights, i);
        if !w.is_finite() {
            return Err(GeomError::NonFinite(format!(
                "{what}: weight of frame {i} is {w}"
            )));
        }
        if w < 0.0 {
            return Err(GeomError::param(
                "weights",
                format!("{what}: weight of frame {i} is negative ({w})"),
            ));
        }
        if w == 0.0 {
            continue;
        }
        for (k, v) in row.iter().enumerate() {
            if !v.is_finite() {
                return Err(GeomError::NonFinite(format!(
                    "{what}: frame {i}, axis {k} is {v}"
                )));
            }
        }
        n_valid += 1;
        w_sum += w;
        first = first.min(i);
        last = i;
    }
    if n_valid == 0 {
        return Err(GeomError::NoData(format!(
            "{what}: all {n} frames have weight 0"
        )));
    }
    Ok(Summary {
        n,
        d,
        n_valid,
        w_sum,
        first,
        last,
    })
}

/// Weighted least-squares polynomial of degree ≤ 3 in `t` (t = frame index),
/// shared by line, spline and the angle of circles.
///
/// The normal equations are built in the centred, scaled variable
/// `τ = (t − t_c) / h`, which
/// keeps the 4 × 4 system well conditioned for long segments; the solution is
/// converted back to powers of `t`. (`t_c` is the middle of the valid time
/// range and `h` its half-width, so `|τ| ≤ 1`.)
#[derive(Debug, Clone, Copy)]
pub(crate) struct PolyLs {
    deg: usize,
    tc: f64,
    h: f64,
    /// LU factors (Doolittle, partial pivoting) of the Gram matrix.
    lu: [[f64; 4]; 4],
    perm: [usize; 4],
}

impl PolyLs {
    /// Prepares a fit of degree `min(deg, n_valid − 1)` over the frames with weight > 0.
    pub(crate) fn new(
        what: &'static str,
        n: usize,
        weights: Option<&[f64]>,
        s: &Summary,
        deg: usize,
    ) -> Result<Self> {
        let mut deg = deg.min(3).min(s.n_valid.saturating_sub(1));
        // A nearly singular system (few valid frames far apart in time) falls
        // back to a lower degree; degree 0 is always solvable (Σw > 0).
        loop {
            match Self::with_degree(what, n, weights, s, deg) {
                Ok(p) => return Ok(p),
                Err(e) if deg == 0 => return Err(e),
                Err(_) => deg -= 1,
            }
        }
    }

    fn with_degree(
        what: &'static str,
        n: usize,
        weights: Option<&[f64]>,
        s: &Summary,
        deg: usize,
    ) -> Result<Self> {
        // centre and half-width of the valid time range: |τ| ≤ 1
        let tc = 0.5 * (s.first as f64 + s.last as f64);
        let h = 0.5 * (s.last as f64 - s.first as f64);
        let h = if h > 0.0 { h } else { 1.0 };
        // moments Σ w τ^k, k = 0..2 deg
        let mut mom = [0.0f64; 7];
        for i in 0..n {
            let w = wt(weights, i);
            if w == 0.0 {
                continue;
            }
            let tau = (i as f64 - tc) / h;
            let mut p = w;
            for m in mom.iter_mut().take(2 * deg + 1) {
                *m += p;
                p *= tau;
            }
        }
        let mut a = [[0.0f64; 4]; 4];
        for (r, row) in a.iter_mut().enumerate().take(deg + 1) {
            for (c, v) in row.iter_mut().enumerate().take(deg + 1) {
                *v = mom[r + c];
            }
        }
        // LU with partial pivoting
        let m = deg + 1;
        let mut perm = [0usize, 1, 2, 3];
        for col in 0..m {
            let mut piv = col;
            for r in col + 1..m {
                if a[r][col].abs() > a[piv][col].abs() {
                    piv = r;
                }
            }
            if a[piv][col].abs() <= 1e-13 * mom[0] {
                return Err(GeomError::NoData(format!(
                    "{what}: singular least-squares system (degree {deg}, {} valid frames)",
                    s.n_valid
                )));
            }
            a.swap(col, piv);
            perm.swap(col, piv);
            for r in col + 1..m {
                let (top, bottom) = a.split_at_mut(r);
                let (pivot, row) = (&top[col], &mut bottom[0]);
                let f = row[col] / pivot[col];
                row[col] = f;
                for (x, p) in row[col + 1..m].iter_mut().zip(&pivot[col + 1..m]) {
                    *x -= f * p;
                }
            }
        }
        Ok(PolyLs {
            deg,
            tc,
            h,
            lu: a,
            perm,
        })
    }

    /// Effective degree.
    pub(crate) fn degree(&self) -> usize {
        self.deg
    }

    /// `τ` of frame `i`.
    #[inline(always)]
    fn tau(&self, i: usize) -> f64 {
        (i as f64 - self.tc) / self.h
    }

    /// Accumulates the right-hand side `Σ w τ^k y` for one frame.
    #[inline(always)]
    pub(crate) fn accumulate(&self, rhs: &mut [f64; 4], i: usize, w: f64, y: f64) {
        let tau = self.tau(i);
        let mut p = w * y;
        for r in rhs.iter_mut().take(self.deg + 1) {
            *r += p;
            p *= tau;
        }
    }

    /// Solves for the coefficients, returned in powers of `t`: `c[k]` multiplies `t^k`
    /// (entries above the degree are 0).
    pub(crate) fn solve(&self, rhs: &[f64; 4]) -> [f64; 4] {
        let m = self.deg + 1;
        let mut x = [0.0f64; 4];
        for r in 0..m {
            x[r] = rhs[self.perm[r]];
        }
        for r in 0..m {
            for c in 0..r {
                x[r] -= self.lu[r][c] * x[c];
            }
        }
        for r in (0..m).rev() {
            for c in r + 1..m {
                x[r] -= self.lu[r][c] * x[c];
            }
            x[r] /= self.lu[r][r];
        }
        // p(t) = Σ_j x_j ((t − tc)/h)^j = Σ_j (x_j / h^j) Σ_i C(j,i) t^i (−tc)^(j−i)
        const BINOM: [[f64; 4]; 4] = [
            [1.0, 0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0, 0.0],
            [1.0, 2.0, 1.0, 0.0],
            [1.0, 3.0, 3.0, 1.0],
        ];
        let mut out = [0.0f64; 4];
        let mut hj = 1.0;
        for j in 0..m {
            let bj = x[j] / hj;
            let mut neg = 1.0; // (−tc)^(j−i), built from i = j downwards
            for i in (0..=j).rev() {
                out[i] += bj * BINOM[j][i] * neg;
                neg *= -self.tc;
            }
            hj *= self.h;
        }
        out
    }

    /// Fits every column of `points`, calling `f(axis, coeffs)` for each.
    pub(crate) fn fit_columns(
        &self,
        points: ArrayView2<'_, f64>,
        weights: Option<&[f64]>,
        mut f: impl FnMut(usize, [f64; 4]),
    ) {
        let d = points.ncols();
        if d <= 4 {
            // one pass over the rows for all axes
            let mut rhs = [[0.0f64; 4]; 4];
            for (i, row) in points.outer_iter().enumerate() {
                let w = wt(weights, i);
                if w == 0.0 {
                    continue;
                }
                let tau = self.tau(i);
                for (r, &y) in rhs.iter_mut().zip(row.iter()) {
                    let mut p = w * y;
                    for v in r.iter_mut().take(self.deg + 1) {
                        *v += p;
                        p *= tau;
                    }
                }
            }
            for (k, r) in rhs.iter().enumerate().take(d) {
                f(k, self.solve(r));
            }
            return;
        }
        for k in 0..d {
            let mut rhs = [0.0f64; 4];
            for (i, &y) in points.column(k).iter().enumerate() {
                let w = wt(weights, i);
                if w == 0.0 {
                    continue;
                }
                self.accumulate(&mut rhs, i, w, y);
            }
            f(k, self.solve(&rhs));
        }
    }
}
