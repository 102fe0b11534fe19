//! The exact circle of one 2D joint on a candidate segment, where it can
//! still win: the fit of [`mp_geom::fit_circle`] (Bullock's centre, the
//! angles about it unwrapped point to point, the least-squares line of the
//! angle against time) with its error and radius penalty.
//!
//! It is the search's most frequent O(L) step, so it runs over the
//! segment's valid frames gathered into reused buffers, in passes without
//! branches that become vector instructions (AVX2 where the CPU has it,
//! checked at run time): the mean, Bullock's sums, the angles
//! ([`mp_geom::atan2_lanes`]), the unwrapping (the one sequential step), the
//! angle line's sums, and the residuals, with the fitted angle rotated by
//! four frames' turn in four interleaved chains. Every sum runs in four lanes
//! of fixed assignment (frame index mod 4), so the result is the same on
//! every CPU; it is that of `fit_circle` up to rounding.

use mp_geom::atan2_lanes;
#[cfg(target_arch = "x86_64")]
use mp_geom::Avx2;
use mp_geom::{bullock_from_sums, bullock_terms, unwrap_degrees, FitParams};
use mp_geom::{has_avx2, Arith, F64x4, Portable};

use super::Rules;

/// An exact circle of [`circle2`]: its cost and what [`super::carry`]
/// needs to carry its error to a neighbouring segment.
#[derive(Clone, Copy, Debug)]
pub(super) struct CircleFit {
    /// Error with the radius penalty (the joint's cost if the circle wins).
    pub(super) cost: f64,
    /// Euclidean error without the penalty.
    pub(super) error: f64,
    pub(super) center: [f64; 2],
    pub(super) radius: f64,
    /// Angle (radians) at frame `first` and per frame.
    pub(super) angle0: f64,
    pub(super) angle_vel: f64,
    pub(super) first: usize,
    /// Smallest distance of a valid point to the centre.
    pub(super) d_min: f64,
    /// Largest step between consecutive unwrapped angles (radians).
    pub(super) max_step: f64,
    /// Unwrapped angles (radians) of the first and last valid frames, and
    /// their directions from the centre (unit vectors).
    pub(super) angle_first: f64,
    pub(super) angle_last: f64,
    pub(super) dir_first: [f64; 2],
    pub(super) dir_last: [f64; 2],
}

/// Reused buffers of [`circle2`]: the frames of the segment.
#[derive(Default)]
pub(super) struct CircleScratch {
    /// Coordinates and weight.
    x: Vec<f64>,
    y: Vec<f64>,
    w: Vec<f64>,
    /// Coordinates about the centre, then the angles.
    u: Vec<f64>,
    v: Vec<f64>,
    th: Vec<f64>,
}

/// Lanes of every sum.
const L: usize = 4;

/// One joint's frames `first..=last` (both valid) as the exact circle reads
/// them: points (missing ones zeroed) and weights of the whole track.
#[derive(Clone, Copy)]
pub(super) struct Span<'a> {
    pub(super) pts: &'a [[f64; 2]],
    pub(super) wts: &'a [f64],
    pub(super) first: usize,
    pub(super) last: usize,
}

/// The circle of [`mp_geom::fit_circle`] (2D, linear angle) on the
/// valid frames of the span, with its error and radius penalty. `None` when
/// the points are collinear (the circle takes no part, as in `fit_best`).
pub(super) fn circle2(
    span: Span<'_>,
    rules: &Rules,
    fit: &FitParams,
    sc: &mut CircleScratch,
) -> Option<CircleFit> {
    #[cfg(target_arch = "x86_64")]
    {
        if has_avx2() {
            // SAFETY: the CPU has AVX2 (checked just above), the only
            // requirement of a `target_feature(enable = "avx2")` function.
            return unsafe { circle2_avx2(span, rules, fit, sc) };
        }
    }
    circle2_body::<Portable>(span, rules, fit, sc)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn circle2_avx2(
    span: Span<'_>,
    rules: &Rules,
    fit: &FitParams,
    sc: &mut CircleScratch,
) -> Option<CircleFit> {
    circle2_body::<Avx2>(span, rules, fit, sc)
}

/// Rotates `(c, s)` by the angle of `(rc, rs)`.
#[inline(always)]
fn rot<T: Arith>((c, s): (T, T), (rc, rs): (T, T)) -> (T, T) {
    (c.mul(rc).sub(s.mul(rs)), s.mul(rc).add(c.mul(rs)))
}

#[inline(always)]
fn circle2_body<V: F64x4>(
    span: Span<'_>,
    rules: &Rules,
    fit: &FitParams,
    sc: &mut CircleScratch,
) -> Option<CircleFit> {
    let Span {
        pts,
        wts,
        first,
        last,
    } = span;
    // The segment's frames (missing ones zeroed, of weight 0), padded to
    // whole chunks with frames of weight 0.
    let len = last + 1 - first;
    let padded = len.div_ceil(L) * L;
    for b in [
        &mut sc.x, &mut sc.y, &mut sc.w, &mut sc.u, &mut sc.v, &mut sc.th,
    ] {
        b.clear();
        b.resize(padded, 0.0);
    }
    for (i, (p, &w)) in pts[first..=last].iter().zip(&wts[first..=last]).enumerate() {
        sc.x[i] = p[0];
        sc.y[i] = p[1];
        sc.w[i] = w;
    }
    let (x, _) = sc.x.as_chunks::<L>();
    let (y, _) = sc.y.as_chunks::<L>();
    let (w, _) = sc.w.as_chunks::<L>();
    let chunks = || {
        x.iter()
            .zip(y)
            .zip(w)
            .map(|((x, y), w)| (V::load(x), V::load(y), V::load(w)))
    };
    // Bullock's centre, on coordinates about the mean.
    let zero = V::splat(0.0);
    let (mut aw, mut ax, mut ay) = (zero, zero, zero);
    for (xc, yc, wc) in chunks() {
        aw = aw.add(wc);
        ax = ax.add(wc.mul(xc));
        ay = ay.add(wc.mul(yc));
    }
    let w_sum = aw.total();
    let (mx, my) = (ax.total() / w_sum, ay.total() / w_sum);
    let (vmx, vmy) = (V::splat(mx), V::splat(my));
    let mut sums = [zero; 7];
    for (xc, yc, wc) in chunks() {
        let terms = bullock_terms(wc, xc.sub(vmx), yc.sub(vmy));
        for (s, t) in sums.iter_mut().zip(terms) {
            *s = s.add(t);
        }
    }
    let mut totals = [0.0; 7];
    for (t, s) in totals.iter_mut().zip(&sums) {
        *t = s.total();
    }
    let (uc, vc, r) = bullock_from_sums(&totals, w_sum).ok()?;
    let (cx, cy) = (mx + uc, my + vc);
    let (vcx, vcy) = (V::splat(cx), V::splat(cy));
    // Angles about the centre (of every frame; a missing one takes its
    // predecessor's, so it adds no turn), unwrapped, in degrees.
    {
        let (u, _) = sc.u.as_chunks_mut::<L>();
        let (v, _) = sc.v.as_chunks_mut::<L>();
        let (th, _) = sc.th.as_chunks_mut::<L>();
        for ((((uo, vo), to), xc), yc) in u
            .iter_mut()
            .zip(v.iter_mut())
            .zip(th.iter_mut())
            .zip(x)
            .zip(y)
        {
            let (a, b) = (V::load(xc).sub(vcx), V::load(yc).sub(vcy));
            *uo = a.to_array();
            *vo = b.to_array();
            *to = atan2_lanes(b, a).to_array();
        }
    }
    // (Frames `first` and `last` are valid.)
    for i in 1..len {
        if sc.w[i] == 0.0 {
            sc.th[i] = sc.th[i - 1];
        }
    }
    unwrap_degrees(None, &mut sc.th[..len]);
    let mut max_step = 0.0f64;
    for p in sc.th[..len].windows(2) {
        let d = (p[1] - p[0]).abs();
        max_step = if d > max_step { d } else { max_step };
    }
    let (th, _) = sc.th[..padded].as_chunks::<L>();
    // The least-squares angle line, time about the segment's middle frame.
    let t_ref = ((first + last) / 2 - first) as f64;
    let mut tt = V::load(&[-t_ref, 1.0 - t_ref, 2.0 - t_ref, 3.0 - t_ref]);
    let four = V::splat(L as f64);
    let mut ls = [zero; 4];
    for (hc, wc) in th.iter().zip(w) {
        let (h, wv) = (V::load(hc), V::load(wc));
        let wt = wv.mul(tt);
        ls[0] = ls[0].add(wt);
        ls[1] = ls[1].add(wv.mul(h));
        ls[2] = ls[2].add(wt.mul(tt));
        ls[3] = ls[3].add(wt.mul(h));
        tt = tt.add(four);
    }
    let (st, sth, stt, stth) = (ls[0].total(), ls[1].total(), ls[2].total(), ls[3].total());
    let tbar = st / w_sum;
    let thbar = sth / w_sum;
    let vtt = stt - st * tbar;
    let vel = if vtt > 0.0 {
        (stth - st * thbar) / vtt
    } else {
        0.0
    };
    // angle at frame `first`: θ̄ + vel·(t_first − t̄)
    let th0 = (thbar + vel * (-t_ref - tbar)).to_radians();
    let vel_r = vel.to_radians();
    // Residuals: frame `first + i` at angle th0 + vel·i, lane `i mod 4`
    // rotated by 4·vel per step from its own start.
    let (s0, c0) = th0.sin_cos();
    let (s1, c1) = vel_r.sin_cos();
    let step1 = (c1, s1);
    let (mut cos, mut sin) = ([c0; L], [s0; L]);
    for l in 1..L {
        (cos[l], sin[l]) = rot((cos[l - 1], sin[l - 1]), step1);
    }
    let step2 = rot(step1, step1);
    let (c4, s4) = rot(step2, step2);
    let step4 = (V::splat(c4), V::splat(s4));
    let mut cs = (V::load(&cos), V::load(&sin));
    let (u, _) = sc.u.as_chunks::<L>();
    let (v, _) = sc.v.as_chunks::<L>();
    let vr = V::splat(r);
    let (mut e, mut e2, mut dmin2) = (zero, zero, V::splat(f64::INFINITY));
    for ((uc, vc), wc) in u.iter().zip(v).zip(w) {
        let (a, b, wv) = (V::load(uc), V::load(vc), V::load(wc));
        let (ex, ey) = (vr.mul(cs.0).sub(a), vr.mul(cs.1).sub(b));
        let d2 = ex.mul(ex).add(ey.mul(ey));
        e = e.add(wv.mul(d2.sqrt()));
        e2 = e2.add(wv.mul(d2));
        let dd = a.mul(a).add(b.mul(b));
        // (A valid frame nearer than the nearest so far.)
        let nearer = V::select(wv.gt(zero), dmin2.gt(dd), zero);
        dmin2 = V::select(nearer, dd, dmin2);
        cs = rot(cs, step4);
    }
    let (e, e2) = (e.total(), e2.total());
    let dmin2 = dmin2
        .to_array()
        .iter()
        .fold(f64::INFINITY, |m, &d| m.min(d));
    let (u, v) = (&sc.u, &sc.v);
    let unit = |k: usize| {
        let d = (u[k] * u[k] + v[k] * v[k]).sqrt();
        [u[k] / d, v[k] / d]
    };
    let error = if rules.squared { e2 } else { e };
    let cost = error + fit.circle_penalty(r);
    cost.is_finite().then_some(CircleFit {
        cost,
        error,
        center: [cx, cy],
        radius: r,
        angle0: th0,
        angle_vel: vel_r,
        first,
        d_min: dmin2.sqrt(),
        max_step: max_step.to_radians(),
        angle_first: sc.th[0].to_radians(),
        angle_last: sc.th[len - 1].to_radians(),
        dir_first: unit(0),
        dir_last: unit(len - 1),
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
    use super::*;
    use crate::search::testutil::track;
    use mp_geom::fit_circle;
    use mp_geom::Primitive;
    use ndarray::Array2;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// The cost of `fit_circle` (error plus radius penalty) on thousands of
    /// segments with missing frames, to rounding; `None` exactly where it
    /// fails on collinear points.
    #[test]
    fn matches_fit_circle() {
        let fit = FitParams::default();
        let rules = Rules::new(&fit);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut sc = CircleScratch::default();
        let mut checked = 0;
        for _ in 0..20 {
            let t = 80;
            let (pts, wts) = track(&mut rng, t);
            for first in (0..t).filter(|&i| wts[i] > 0.0) {
                for last in (first + 2..t.min(first + 61)).filter(|&i| wts[i] > 0.0) {
                    let span = Span {
                        pts: &pts,
                        wts: &wts,
                        first,
                        last,
                    };
                    let ours = circle2(span, &rules, &fit, &mut sc);
                    let seg =
                        Array2::from_shape_fn((last + 1 - first, 2), |(i, d)| pts[first + i][d]);
                    let reference = fit_circle(seg.view(), Some(&wts[first..=last]), &fit)
                        .ok()
                        .map(|f| match f.primitive {
                            Primitive::Circle { radius, .. } => {
                                f.error + fit.circle_penalty(radius)
                            }
                            _ => panic!("not a circle"),
                        });
                    match (ours, reference) {
                        (Some(c), Some(r)) => {
                            let tol = 1e-9 * (1.0 + r.abs());
                            assert!(
                                (c.cost - r).abs() <= tol,
                                "{first}..={last}: {} vs {r}",
                                c.cost
                            );
                            checked += 1;
                        }
                        (None, None) => {}
                        (a, b) => panic!("{first}..={last}: {a:?} vs {b:?}"),
                    }
                }
            }
        }
        assert!(checked > 40_000, "{checked}");
    }

    /// The moments' circle of the O(1) stage is the exact fit's (centre and
    /// radius within the slack the bounds allow for) 10⁵ px from the origin,
    /// on segments that end on a missing frame too.
    #[test]
    fn moments_circle_is_the_exact_circle_far_from_the_origin() {
        use crate::search::bounds::quick;
        use crate::search::testutil::{acc_of, moved, steps_of};
        let fit = FitParams::default();
        let rules = Rules::new(&fit);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let mut sc = CircleScratch::default();
        let (mut checked, mut missing_end) = (0, 0);
        for _ in 0..10 {
            let t = 90;
            let (mut pts, wts) = track(&mut rng, t);
            moved(&mut pts, &wts, 1.0, 1e5);
            let steps = steps_of(&pts, &wts);
            for n in 4..=t {
                for k in n.saturating_sub(40)..n - 2 {
                    let acc = acc_of(&pts, &wts, &steps, k, n);
                    if acc.count < 3 {
                        continue;
                    }
                    let q = quick(&acc, &pts, &rules, &fit);
                    let span = Span {
                        pts: &pts,
                        wts: &wts,
                        first: acc.first,
                        last: acc.last,
                    };
                    let exact = circle2(span, &rules, &fit, &mut sc);
                    let (Some(c), true) = (exact, q.circle_ok) else {
                        continue;
                    };
                    let off = ((q.cx - c.center[0]).powi(2) + (q.cy - c.center[1]).powi(2)).sqrt();
                    let tol = q.circle_slack;
                    assert!(
                        off <= tol && (q.r - c.radius).abs() <= tol,
                        "{k}..{n}: centre off by {off}, radius {} vs {} (slack {tol})",
                        q.r,
                        c.radius
                    );
                    checked += 1;
                    if wts[n - 1] == 0.0 {
                        missing_end += 1;
                    }
                }
            }
        }
        assert!(
            checked > 10_000 && missing_end > 500,
            "{checked} {missing_end}"
        );
    }
}
