//! The four-quadrant arctangent of the circle fit, for batches of points.
//!
//! A circle fit takes the angle of every point about the centre, and the
//! segmentation fits circles to hundreds of thousands of candidate segments,
//! so the angles are its largest single cost. [`atan2_lanes`] computes them
//! without branches, four points at once ([`crate::lanes`]: AVX2 where the
//! CPU has it, checked at run time), with the same result on every CPU: only
//! additions, multiplications, one division and selections, never a fused
//! multiply-add.
//!
//! Steps, for `(y, x)`:
//!
//! 1. `a = min(|x|, |y|)`, `b = max(|x|, |y|)`, so the angle `atan(a / b)`
//!    lies in `[0, π/4]`;
//! 2. above `tan(π/8)` it is `π/4 + atan((a − b) / (a + b))`, so the
//!    argument `z` of the polynomial has `|z| ≤ tan(π/8)`;
//! 3. `atan z = z + z·s·Q(s)`, `s = z²`, with `Q` of degree 10: a Chebyshev
//!    fit of `(atan(√s)/√s − 1)/s` on `[0, tan²(π/8)]`, within `3.2·10⁻¹⁷`
//!    (so within about half an ulp of `atan z` before rounding);
//! 4. back to the quadrant: `π/2 − θ` where `|y| > |x|`, `π − θ` where `x`
//!    is negative (or `−0`), and the sign of `y`.
//!
//! Against the C library's `atan2` the result differs by at most a few ulp
//! (a test checks 4 ulp of the result's magnitude); `atan2(±0, ±0)` is `±0`
//! or `±π` as in C.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

#[cfg(target_arch = "x86_64")]
use crate::lanes::Avx2;
use crate::lanes::{has_avx2, F64x4, Portable};

/// `tan(π/8) = √2 − 1`.
const TAN_PI_8: f64 = 0.414_213_562_373_095_05;

/// `Q(s)` from the highest degree down (see the module docs).
const Q: [f64; 11] = [
    -0.019_175_404_711_104_935,
    0.039_230_447_784_793_09,
    -0.050_854_078_345_894_844,
    0.058_581_409_048_663_28,
    -0.066_645_105_255_089_36,
    0.076_921_831_253_768_92,
    -0.090_909_045_753_064_9,
    0.111_111_110_151_870_18,
    -0.142_857_142_846_656_82,
    0.199_999_999_999_955_16,
    -0.333_333_333_333_333_3,
];

/// `atan2(y, x)` of one point (see the module docs): lane 0 of
/// [`atan2_lanes`] on [`Portable`], so it equals the batches bit for bit.
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    atan2_lanes(Portable::splat(y), Portable::splat(x)).to_array()[0]
}

/// `atan2(y, x)` lane by lane (see the module docs).
#[inline(always)]
pub fn atan2_lanes<V: F64x4>(y: V, x: V) -> V {
    let (ax, ay) = (x.abs(), y.abs());
    let swap = ay.gt(ax);
    let a = V::select(swap, ax, ay);
    let b = V::select(swap, ay, ax);
    let big = a.gt(V::splat(TAN_PI_8).mul(b));
    let num = V::select(big, a.sub(b), a);
    let den = V::select(big, a.add(b), b);
    // 0/0 (the point at the centre) reads as angle 0.
    let z = V::select(den.gt(V::splat(0.0)), num.div(den), V::splat(0.0));
    let s = z.mul(z);
    let mut q = V::splat(Q[0]);
    for &c in &Q[1..] {
        q = q.mul(s).add(V::splat(c));
    }
    let mut th = z.add(z.mul(s.mul(q)));
    th = V::select(big, th.add(V::splat(FRAC_PI_4)), th);
    th = V::select(swap, V::splat(FRAC_PI_2).sub(th), th);
    // (`x` as the mask: its sign bit, −0 included.)
    th = V::select(x, V::splat(PI).sub(th), th);
    th.copysign(y)
}

/// `out[i] = atan2(ys[i], xs[i])` over the shortest of the three slices.
pub fn atan2_into(ys: &[f64], xs: &[f64], out: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if has_avx2() {
            // SAFETY: the CPU has AVX2 (checked just above), the only
            // requirement of a `target_feature(enable = "avx2")` function.
            unsafe { atan2_avx2(ys, xs, out) };
            return;
        }
    }
    atan2_chunks::<Portable>(ys, xs, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn atan2_avx2(ys: &[f64], xs: &[f64], out: &mut [f64]) {
    atan2_chunks::<Avx2>(ys, xs, out);
}

#[inline(always)]
fn atan2_chunks<V: F64x4>(ys: &[f64], xs: &[f64], out: &mut [f64]) {
    let n = ys.len().min(xs.len()).min(out.len());
    let (yc, yr) = ys[..n].as_chunks::<4>();
    let (xc, xr) = xs[..n].as_chunks::<4>();
    let (oc, or) = out[..n].as_chunks_mut::<4>();
    for ((o, y), x) in oc.iter_mut().zip(yc).zip(xc) {
        *o = atan2_lanes(V::load(y), V::load(x)).to_array();
    }
    for ((o, &y), &x) in or.iter_mut().zip(yr).zip(xr) {
        *o = atan2(y, x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn close(got: f64, want: f64) -> bool {
        (got - want).abs() <= (4.0 * f64::EPSILON * want.abs()).max(f64::MIN_POSITIVE)
    }

    /// Within 2 ulp of the C library (4 for any single point) on a million points of every quadrant
    /// and scale, on the axes, the diagonals and the octant boundaries.
    #[test]
    fn matches_the_c_library() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut ys = Vec::new();
        let mut xs = Vec::new();
        for _ in 0..1_000_000 {
            let scale = 10f64.powi(rng.random_range(-6..7));
            ys.push(rng.random_range(-1.0..1.0) * scale);
            xs.push(rng.random_range(-1.0..1.0) * scale);
        }
        for &(y, x) in &[
            (0.0, 1.0),
            (1.0, 0.0),
            (0.0, -1.0),
            (-1.0, 0.0),
            (1.0, 1.0),
            (-1.0, -1.0),
            (TAN_PI_8, 1.0),
            (-TAN_PI_8, -1.0),
            (1.0, TAN_PI_8),
            (1e-300, -1.0),
            (-1e-300, -1.0),
            (3.0, -1e-300),
        ] {
            ys.push(y);
            xs.push(x);
        }
        let mut out = vec![0.0; ys.len()];
        atan2_into(&ys, &xs, &mut out);
        let mut worst = 0.0f64;
        for ((&y, &x), &got) in ys.iter().zip(&xs).zip(&out) {
            let want = y.atan2(x);
            assert!(close(got, want), "atan2({y}, {x}) = {got}, C: {want}");
            assert_eq!(got, atan2(y, x), "batch and single differ at ({y}, {x})");
            worst = worst.max((got - want).abs() / (want.abs() * f64::EPSILON));
        }
        assert!(worst <= 2.0, "{worst} ulp");
    }

    #[test]
    fn signed_zeros_follow_the_c_convention() {
        for (y, x) in [(0.0, 0.0), (-0.0, 0.0), (0.0, -0.0), (-0.0, -0.0)] {
            let (got, want) = (atan2(y, x), f64::atan2(y, x));
            assert_eq!(got.to_bits(), want.to_bits(), "atan2({y}, {x})");
        }
    }
}
