//! Circle fitting: Bullock's algebraic least squares on centred points, in the
//! best-fit plane for 3D points, then the unwrapped angle against time.
//!
//! Bullock (2006), "Least-squares circle fit": with centred coordinates
//! `(u, v)` and moments `S_uu = Σ w u² / W` etc., the centre `(u_c, v_c)`
//! solves
//!
//! ```text
//! | S_uu  S_uv | |u_c|   1 | S_uuu + S_uvv |
//! | S_uv  S_vv | |v_c| = - | S_vvv + S_vuu |
//!                        2
//! ```
//!
//! and `r² = u_c² + v_c² + S_uu + S_vv`.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use ndarray::ArrayView2;

use super::atan;
use super::input::{self, wt, Summary};
use super::FitParams;
use crate::error::{GeomError, Result};
use crate::lanes::Arith;
use crate::primitive::Primitive;

/// Relative threshold on `det / trace²` of the 2 × 2 scatter matrix (and on
/// the eigenvalue ratio of the 3 × 3 one) below which points count as
/// collinear.
const COLLINEAR_EPS: f64 = 1e-12;

/// The fitted circle in a 2D frame: centre in the local coordinates, radius.
struct Circle2 {
    uc: f64,
    vc: f64,
    r: f64,
}

/// Bullock's fit on already centred local coordinates given by `coord(i)`.
fn bullock(
    n: usize,
    weights: Option<&[f64]>,
    w_sum: f64,
    coord: impl Fn(usize) -> (f64, f64),
) -> Result<Circle2> {
    let mut m = [0.0; 7];
    for i in 0..n {
        let w = wt(weights, i);
        if w == 0.0 {
            continue;
        }
        let (u, v) = coord(i);
        for (s, t) in m.iter_mut().zip(bullock_terms(w, u, v)) {
            *s += t;
        }
    }
    bullock_solve(&m, w_sum)
}

/// One point's terms of the sums that Bullock's fit solves from (see
/// [`bullock_from_sums`]), for one point or four lanes of points.
#[inline(always)]
pub fn bullock_terms<T: Arith>(w: T, u: T, v: T) -> [T; 7] {
    let (uu, vv) = (u.mul(u), v.mul(v));
    [
        w.mul(uu),
        w.mul(u).mul(v),
        w.mul(vv),
        w.mul(uu).mul(u),
        w.mul(u).mul(vv),
        w.mul(vv).mul(v),
        w.mul(v).mul(uu),
    ]
}

fn bullock_solve(m: &[f64; 7], w_sum: f64) -> Result<Circle2> {
    let [suu, suv, svv, suuu, suvv, svvv, svuu] = *m;
    let inv = 1.0 / w_sum;
    let (suu, suv, svv) = (suu * inv, suv * inv, svv * inv);
    let b1 = 0.5 * (suuu + suvv) * inv;
    let b2 = 0.5 * (svvv + svuu) * inv;
    let det = suu * svv - suv * suv;
    let tr = suu + svv;
    if tr.is_nan() || tr <= 0.0 || det <= COLLINEAR_EPS * tr * tr {
        return Err(GeomError::NoData(
            "circle fit: the valid points are collinear or coincident".into(),
        ));
    }
    let uc = (b1 * svv - b2 * suv) / det;
    let vc = (suu * b2 - suv * b1) / det;
    let r = (uc * uc + vc * vc + tr).sqrt();
    if !(uc.is_finite() && vc.is_finite() && r.is_finite() && r > 0.0) {
        return Err(GeomError::NoData(
            "circle fit: the valid points are collinear or coincident".into(),
        ));
    }
    Ok(Circle2 { uc, vc, r })
}

/// Bullock's circle from the sums of [`bullock_terms`] over centred points
/// with weights summing to `w_sum` (for callers that sum the terms their own
/// way, as `mp-concrete`'s branch-and-bound segmentation does).
pub fn bullock_from_sums(sums: &[f64; 7], w_sum: f64) -> Result<(f64, f64, f64)> {
    bullock_solve(sums, w_sum).map(|c| (c.uc, c.vc, c.r))
}

/// Calls `f(i, wᵢ, θᵢ)` for every point `i < n` of non-zero weight (`None`:
/// all 1) with its angle around the centre, in degrees, from its coordinates
/// relative to the centre `local(i)`, unwrapped point to point. The circle fit
/// uses it, and so does `mp-concrete`'s branch-and-bound segmentation, so that
/// both fit the same angles.
pub fn unwrapped_angles(
    n: usize,
    weights: Option<&[f64]>,
    local: impl Fn(usize) -> (f64, f64),
    mut f: impl FnMut(usize, f64, f64),
) {
    // Points in batches, their angles at once (vector code, see `atan`).
    const BATCH: usize = 64;
    let (mut idx, mut xs, mut ys, mut th) =
        ([0usize; BATCH], [0.0; BATCH], [0.0; BATCH], [0.0; BATCH]);
    let mut prev: Option<f64> = None;
    let mut i = 0;
    while i < n {
        let mut m = 0;
        while i < n && m < BATCH {
            if wt(weights, i) != 0.0 {
                let (a, b) = local(i);
                idx[m] = i;
                xs[m] = a;
                ys[m] = b;
                m += 1;
            }
            i += 1;
        }
        atan::atan2_into(&ys[..m], &xs[..m], &mut th[..m]);
        prev = unwrap_degrees(prev, &mut th[..m]);
        for (&i, &a) in idx[..m].iter().zip(&th[..m]) {
            f(i, wt(weights, i), a);
        }
    }
}

/// Turns angles in radians into degrees unwrapped point to point, in
/// place: each differs from its predecessor (`prev` before the first) by at
/// most 180°. Returns the last angle (`prev` for no angles).
/// `unwrapped_angles` uses it, and so does `mp-concrete`'s search.
///
/// The whole turns between consecutive raw angles are independent of each
/// other; only their running count is carried from point to point (an
/// addition), so long batches do not wait on a division and a rounding per
/// point.
#[inline]
pub fn unwrap_degrees(prev: Option<f64>, angles: &mut [f64]) -> Option<f64> {
    // Whole turns in `t` (0 below half a turn; `round` is a library call on
    // some targets).
    let whole = |t: f64| if t.abs() >= 0.5 { t.round() } else { 0.0 };
    // (An empty batch keeps the angle before it.)
    let Some((first, rest)) = angles.split_first_mut() else {
        return prev;
    };
    let raw0 = first.to_degrees();
    let mut turns = prev.map_or(0.0, |p| whole((p - raw0) / 360.0));
    *first = raw0 + 360.0 * turns;
    let mut last_raw = raw0;
    for a in rest.iter_mut() {
        let raw = a.to_degrees();
        turns += whole((last_raw - raw) / 360.0);
        last_raw = raw;
        *a = raw + 360.0 * turns;
    }
    angles.last().copied()
}

/// Fits `θ(t) = acc·t² + vel·t + start` to the unwrapped angles.
fn fit_angle(
    n: usize,
    weights: Option<&[f64]>,
    s: &Summary,
    params: &FitParams,
    local: impl Fn(usize) -> (f64, f64) + Copy,
) -> Result<(f64, f64, f64)> {
    let deg = if params.quadratic_angle { 2 } else { 1 };
    let ls = input::PolyLs::new("circle fit (angle)", n, weights, s, deg)?;
    let mut rhs = [0.0; 4];
    unwrapped_angles(n, weights, local, |i, w, th| {
        ls.accumulate(&mut rhs, i, w, th)
    });
    let c = ls.solve(&rhs);
    let (mut start, mut vel, mut acc) = (c[0], c[1], c[2]);
    if ls.degree() >= 2 && acc.abs() > params.max_angle_acc_deg {
        acc = params.max_angle_acc_deg.copysign(acc);
        let ls1 = input::PolyLs::new("circle fit (angle)", n, weights, s, 1)?;
        let mut rhs = [0.0; 4];
        unwrapped_angles(n, weights, local, |i, w, th| {
            let t = i as f64;
            ls1.accumulate(&mut rhs, i, w, th - acc * t * t)
        });
        let c = ls1.solve(&rhs);
        start = c[0];
        vel = c[1];
    }
    start -= 360.0 * (start / 360.0).round();
    if start <= -180.0 {
        start += 360.0;
    }
    Ok((start, vel, acc))
}

/// Fits a circle to checked input (see [`super::fit_circle`]).
pub(crate) fn fit(
    points: ArrayView2<'_, f64>,
    weights: Option<&[f64]>,
    s: &Summary,
    params: &FitParams,
) -> Result<Primitive> {
    if s.d != 2 && s.d != 3 {
        return Err(GeomError::Shape(format!(
            "circle fit: points need 2 or 3 dimensions, got {}",
            s.d
        )));
    }
    if s.n_valid < 3 {
        return Err(GeomError::TooShort {
            what: "circle fit (valid frames)",
            needed: 3,
            got: s.n_valid,
        });
    }
    let n = s.n;
    // weighted mean
    let mut mu = [0.0f64; 3];
    for i in 0..n {
        let w = wt(weights, i);
        if w == 0.0 {
            continue;
        }
        for (k, m) in mu.iter_mut().enumerate().take(s.d) {
            *m += w * points[[i, k]];
        }
    }
    for m in &mut mu {
        *m /= s.w_sum;
    }

    if s.d == 2 {
        let centred = |i: usize| (points[[i, 0]] - mu[0], points[[i, 1]] - mu[1]);
        let c = bullock(n, weights, s.w_sum, centred)?;
        let local = |i: usize| {
            let (u, v) = centred(i);
            (u - c.uc, v - c.vc)
        };
        let (angle_start, angle_vel, angle_acc) = fit_angle(n, weights, s, params, local)?;
        return Ok(Primitive::Circle {
            center: vec![mu[0] + c.uc, mu[1] + c.vc],
            radius: c.r,
            angle_start,
            angle_vel,
            angle_acc,
            axes: vec![],
        });
    }

    // 3D: the plane of largest spread (weighted PCA).
    let mut cov = Matrix3::<f64>::zeros();
    for i in 0..n {
        let w = wt(weights, i);
        if w == 0.0 {
            continue;
        }
        let p = Vector3::new(
            points[[i, 0]] - mu[0],
            points[[i, 1]] - mu[1],
            points[[i, 2]] - mu[2],
        );
        cov += (w / s.w_sum) * p * p.transpose();
    }
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let (l_max, l_mid) = (eig.eigenvalues[order[0]], eig.eigenvalues[order[1]]);
    if l_max.is_nan() || l_max <= 0.0 || l_mid <= COLLINEAR_EPS.sqrt() * l_max {
        return Err(GeomError::NoData(
            "circle fit: the valid points are collinear or coincident".into(),
        ));
    }
    let u: Vector3<f64> = eig.eigenvectors.column(order[0]).normalize();
    let normal: Vector3<f64> = eig.eigenvectors.column(order[2]).into_owned();
    let v = normal.cross(&u);
    let v_norm = v.norm();
    if v_norm.is_nan() || v_norm <= 0.5 {
        return Err(GeomError::NoData(
            "circle fit: could not build an orthonormal plane basis".into(),
        ));
    }
    let v = v / v_norm;
    let centred = |i: usize| {
        let p = Vector3::new(
            points[[i, 0]] - mu[0],
            points[[i, 1]] - mu[1],
            points[[i, 2]] - mu[2],
        );
        (p.dot(&u), p.dot(&v))
    };
    let c = bullock(n, weights, s.w_sum, centred)?;
    let local = |i: usize| {
        let (a, b) = centred(i);
        (a - c.uc, b - c.vc)
    };
    let (angle_start, angle_vel, angle_acc) = fit_angle(n, weights, s, params, local)?;
    let center: Vec<f64> = (0..3).map(|k| mu[k] + c.uc * u[k] + c.vc * v[k]).collect();
    Ok(Primitive::Circle {
        center,
        radius: c.r,
        angle_start,
        angle_vel,
        angle_acc,
        axes: vec![u.iter().copied().collect(), v.iter().copied().collect()],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The point-to-point unwrapping, one point at a time.
    fn reference(pts: &[(f64, f64)], w: &[f64]) -> Vec<(usize, f64)> {
        let mut out = Vec::new();
        let mut prev: Option<f64> = None;
        for (i, (&(a, b), &wi)) in pts.iter().zip(w).enumerate() {
            if wi == 0.0 {
                continue;
            }
            let mut th = atan::atan2(b, a).to_degrees();
            if let Some(p) = prev {
                let turns = (p - th) / 360.0;
                if turns.abs() >= 0.5 {
                    th += 360.0 * turns.round();
                }
            }
            prev = Some(th);
            out.push((i, th));
        }
        out
    }

    /// A spiral over several turns, both ways, with a gap longer than a
    /// batch: the batched unwrapping gives the one-point-at-a-time angles.
    #[test]
    fn batches_unwrap_like_one_point_at_a_time() {
        let n = 400;
        let pts: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                let t = i as f64;
                let th = 0.2 * t - 0.0012 * t * t; // forward, then back
                ((5.0 + 0.1 * t) * th.cos(), (5.0 + 0.1 * t) * th.sin())
            })
            .collect();
        let w: Vec<f64> = (0..n)
            .map(|i| {
                if (150..230).contains(&i) || i % 7 == 3 {
                    0.0
                } else {
                    1.0
                }
            })
            .collect();
        let mut got = Vec::new();
        unwrapped_angles(n, Some(&w), |i| pts[i], |i, _, th| got.push((i, th)));
        let want = reference(&pts, &w);
        assert_eq!(got.len(), want.len());
        for (g, r) in got.iter().zip(&want) {
            assert_eq!(g.0, r.0);
            assert!(
                (g.1 - r.1).abs() <= 1e-9 * (1.0 + r.1.abs()),
                "{g:?} vs {r:?}"
            );
        }
        let span = want.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max)
            - want.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        assert!(span > 720.0, "the spiral turns more than twice: {span}");
        assert_eq!(unwrap_degrees(Some(725.0), &mut []), Some(725.0));
    }
}
