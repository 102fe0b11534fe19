//! Four `f64` lanes, for the loops over frames that the search runs most
//! (the circle fit's angles, sums and residuals).
//!
//! [`F64x4`] is the handful of operations those loops need; code written
//! against it runs on [`Portable`] (an array, any CPU) or on [`Avx2`] (one
//! 256-bit register) inside a function compiled for AVX2, chosen at run time
//! with [`has_avx2`]. Both perform the same IEEE operations lane by lane —
//! additions, multiplications, divisions, square roots, comparisons,
//! selections, no fused multiply-add — so they give the same bits.
//!
//! A mask is a value whose lanes have their sign bit set where true (all
//! bits, from the comparisons); [`F64x4::select`] reads only the sign bit,
//! so any value works as a mask on its own sign.

/// Additions, subtractions and multiplications: a formula written against
/// this runs on one `f64` and on four lanes alike (the same operations in
/// the same order, so the same bits).
pub trait Arith: Copy {
    fn add(self, o: Self) -> Self;
    fn sub(self, o: Self) -> Self;
    fn mul(self, o: Self) -> Self;
}

impl Arith for f64 {
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self + o
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self - o
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self * o
    }
}

/// Four `f64` lanes (see the module docs).
pub trait F64x4: Arith {
    fn splat(v: f64) -> Self;
    fn load(a: &[f64; 4]) -> Self;
    fn to_array(self) -> [f64; 4];
    fn div(self, o: Self) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    /// `self` with the sign of `sign`.
    fn copysign(self, sign: Self) -> Self;
    /// Mask of `self > o` (false for NaN).
    fn gt(self, o: Self) -> Self;
    /// `if_true` where `mask`'s sign bit is set, else `if_false`.
    fn select(mask: Self, if_true: Self, if_false: Self) -> Self;
    /// The lanes added pairwise: `(a₀ + a₁) + (a₂ + a₃)`.
    #[inline(always)]
    fn total(self) -> f64 {
        let a = self.to_array();
        (a[0] + a[1]) + (a[2] + a[3])
    }
}

/// [`F64x4`] on an array: any CPU.
#[derive(Clone, Copy, Debug)]
pub struct Portable([f64; 4]);

impl Portable {
    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Portable(self.0.map(f))
    }

    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        Portable(std::array::from_fn(|l| f(self.0[l], o.0[l])))
    }
}

/// The mask lane of a comparison.
#[inline(always)]
fn mask(b: bool) -> f64 {
    if b {
        f64::from_bits(u64::MAX)
    } else {
        0.0
    }
}

impl Arith for Portable {
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.zip(o, |a, b| a + b)
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.zip(o, |a, b| a - b)
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.zip(o, |a, b| a * b)
    }
}

impl F64x4 for Portable {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        Portable([v; 4])
    }
    #[inline(always)]
    fn load(a: &[f64; 4]) -> Self {
        Portable(*a)
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        self.0
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self.zip(o, |a, b| a / b)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        self.map(f64::abs)
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        self.zip(sign, f64::copysign)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self {
        self.zip(o, |a, b| mask(a > b))
    }
    #[inline(always)]
    fn select(m: Self, t: Self, f: Self) -> Self {
        Portable(std::array::from_fn(|l| {
            if m.0[l].is_sign_negative() {
                t.0[l]
            } else {
                f.0[l]
            }
        }))
    }
}

/// Whether this CPU runs [`Avx2`] (cached by the standard library).
#[inline]
pub fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(target_arch = "x86_64")]
pub use avx::Avx2;

#[cfg(target_arch = "x86_64")]
mod avx {
    use std::arch::x86_64::*;

    use super::{Arith, F64x4};

    /// [`F64x4`] in one AVX register. Use it only inside a function
    /// compiled with `#[target_feature(enable = "avx2")]`, called after
    /// [`super::has_avx2`]: its methods are inlined into that function.
    #[derive(Clone, Copy, Debug)]
    pub struct Avx2(__m256d);

    // SAFETY (every `unsafe` block below): the intrinsics need AVX, which
    // the caller's `target_feature(enable = "avx2")` function provides (see
    // the type's docs); loads and stores read and write whole `[f64; 4]`.
    impl Arith for Avx2 {
        #[inline(always)]
        fn add(self, o: Self) -> Self {
            Avx2(unsafe { _mm256_add_pd(self.0, o.0) })
        }
        #[inline(always)]
        fn sub(self, o: Self) -> Self {
            Avx2(unsafe { _mm256_sub_pd(self.0, o.0) })
        }
        #[inline(always)]
        fn mul(self, o: Self) -> Self {
            Avx2(unsafe { _mm256_mul_pd(self.0, o.0) })
        }
    }

    impl F64x4 for Avx2 {
        #[inline(always)]
        fn splat(v: f64) -> Self {
            Avx2(unsafe { _mm256_set1_pd(v) })
        }
        #[inline(always)]
        fn load(a: &[f64; 4]) -> Self {
            Avx2(unsafe { _mm256_loadu_pd(a.as_ptr()) })
        }
        #[inline(always)]
        fn to_array(self) -> [f64; 4] {
            let mut a = [0.0; 4];
            unsafe { _mm256_storeu_pd(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        fn div(self, o: Self) -> Self {
            Avx2(unsafe { _mm256_div_pd(self.0, o.0) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            Avx2(unsafe { _mm256_sqrt_pd(self.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            Avx2(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
        }
        #[inline(always)]
        fn copysign(self, sign: Self) -> Self {
            unsafe {
                let s = _mm256_set1_pd(-0.0);
                Avx2(_mm256_or_pd(
                    _mm256_andnot_pd(s, self.0),
                    _mm256_and_pd(s, sign.0),
                ))
            }
        }
        #[inline(always)]
        fn gt(self, o: Self) -> Self {
            Avx2(unsafe { _mm256_cmp_pd::<_CMP_GT_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn select(m: Self, t: Self, f: Self) -> Self {
            Avx2(unsafe { _mm256_blendv_pd(f.0, t.0, m.0) })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn ops_avx(a: [f64; 4], b: [f64; 4]) -> Vec<[f64; 4]> {
        ops::<Avx2>(a, b)
    }

    fn ops<V: F64x4>(a: [f64; 4], b: [f64; 4]) -> Vec<[f64; 4]> {
        let (x, y) = (V::load(&a), V::load(&b));
        vec![
            x.add(y).to_array(),
            x.sub(y).to_array(),
            x.mul(y).to_array(),
            x.div(y).to_array(),
            x.abs().sqrt().to_array(),
            x.abs().to_array(),
            x.copysign(y).to_array(),
            V::select(x.gt(y), x, y).to_array(),
            V::select(x, V::splat(1.0), V::splat(2.0)).to_array(),
            [x.total(), 0.0, 0.0, 0.0],
        ]
    }

    /// Both implementations give the same bits (any NaN for a NaN), signed
    /// zeros and NaN comparisons included.
    #[test]
    fn implementations_agree() {
        let a = [1.5, -0.0, f64::NAN, -3.25];
        let b = [0.1, 0.0, 2.0, -7.0];
        let p = ops::<Portable>(a, b);
        assert_eq!(p[7][0], 1.5);
        assert_eq!(p[7][2], 2.0, "NaN compares false");
        assert_eq!(p[8], [2.0, 1.0, 2.0, 1.0], "select by sign bit");
        #[cfg(target_arch = "x86_64")]
        if has_avx2() {
            // SAFETY: the CPU has AVX2.
            let v = unsafe { ops_avx(a, b) };
            for (pr, vr) in p.iter().zip(&v) {
                for (x, y) in pr.iter().zip(vr) {
                    let same = x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
                    assert!(same, "{p:?} vs {v:?}");
                }
            }
        }
    }
}
