//! `fit::prefix` agrees with the direct fits (squared norm).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::fit::{fit_line, fit_stationary, prefix::PrefixFits, ErrorNorm, FitParams};
use crate::Primitive;
use ndarray::{s, Array2};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn random_walk(n: usize, d: usize, seed: u64) -> Array2<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut a = Array2::zeros((n, d));
    for k in 0..d {
        let mut x = rng.random_range(0.0..512.0);
        for i in 0..n {
            x += rng.random_range(-4.0..4.0);
            a[[i, k]] = x;
        }
    }
    a
}

fn same_params(a: &Primitive, b: &Primitive, tol: f64) -> bool {
    let (va, vb) = match (a, b) {
        (
            Primitive::Line {
                start: s0,
                velocity: v0,
            },
            Primitive::Line {
                start: s1,
                velocity: v1,
            },
        ) => (
            [s0.clone(), v0.clone()].concat(),
            [s1.clone(), v1.clone()].concat(),
        ),
        (Primitive::Stationary { point: p0 }, Primitive::Stationary { point: p1 }) => {
            (p0.clone(), p1.clone())
        }
        _ => return false,
    };
    va.iter()
        .zip(&vb)
        .all(|(x, y)| (x - y).abs() <= tol * (1.0 + x.abs()))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn matches_direct_fits(seed in 0u64..1000, d in 1usize..=3, a in 0usize..150, len in 1usize..50, gaps in 0usize..4) {
        let n = 200;
        let pts = random_walk(n, d, seed);
        let mut w = vec![1.0; n];
        let mut rng = ChaCha8Rng::seed_from_u64(seed + 1);
        for _ in 0..gaps * 10 {
            let i = rng.random_range(0..n);
            w[i] = if rng.random_bool(0.5) { 0.0 } else { rng.random_range(0.1..1.0) };
        }
        let b = (a + len).min(n);
        let pf = PrefixFits::new(pts.view(), Some(&w)).unwrap();
        let seg = pts.slice(s![a..b, ..]);
        let ws = &w[a..b];
        let params = FitParams { norm: ErrorNorm::Squared, ..FitParams::default() };
        match fit_line(seg, Some(ws), &params) {
            Ok(direct) => {
                let fast = pf.line(a, b).unwrap();
                prop_assert!((fast.error - direct.error).abs() <= 1e-7 * (1.0 + direct.error), "{} vs {}", fast.error, direct.error);
                prop_assert!((pf.line_sq_error(a, b).unwrap() - fast.error).abs() == 0.0);
                prop_assert!(same_params(&fast.primitive, &direct.primitive, 1e-8), "{:?} vs {:?}", fast.primitive, direct.primitive);
                let st = fit_stationary(seg, Some(ws), &params).unwrap();
                let fs = pf.stationary(a, b).unwrap();
                prop_assert!((fs.error - st.error).abs() <= 1e-7 * (1.0 + st.error));
                prop_assert!(same_params(&fs.primitive, &st.primitive, 1e-10));
            }
            Err(_) => prop_assert!(pf.line(a, b).is_err()),
        }
    }
}

#[test]
fn long_track_accuracy() {
    // 100k frames of pixel-sized data: segments near the end are as accurate as at the start
    let n = 100_000;
    let pts = random_walk(n, 2, 5).mapv(|v| v + 1000.0);
    let pf = PrefixFits::new(pts.view(), None).unwrap();
    let params = FitParams {
        norm: ErrorNorm::Squared,
        ..FitParams::default()
    };
    for a in [0usize, 50_000, 99_960] {
        let b = a + 30;
        let direct = fit_line(pts.slice(s![a..b, ..]), None, &params).unwrap();
        let fast = pf.line(a, b).unwrap();
        assert!(
            (fast.error - direct.error).abs() <= 1e-8 * direct.error,
            "{a}: {} vs {}",
            fast.error,
            direct.error
        );
        assert!(same_params(&fast.primitive, &direct.primitive, 1e-9));
    }
}
