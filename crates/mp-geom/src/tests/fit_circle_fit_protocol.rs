//! The test protocol of the public `circle-fit` package (Python), applied to
//! [`crate::fit::fit_circle`] (Bullock's method): 1000 random circles with
//! centre ~ U(−100, 100)², radius 10^U(0, 2), 100 points around the full
//! circle; the centre and radius errors must stay below 1e-4·r without noise
//! and below 0.1·r with Gaussian noise of σ = 0.1·r, with fewer than 10
//! failures out of 1000.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::fit::{fit_circle, FitParams};
use crate::Primitive;
use ndarray::Array2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    // Box–Muller
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Number of circles whose centre or radius error exceeds `tol·r`.
fn failures(seed: u64, noise: f64, tol: f64) -> usize {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let params = FitParams::default();
    let mut bad = 0;
    for _ in 0..1000 {
        let cx = rng.random_range(-100.0..100.0);
        let cy = rng.random_range(-100.0..100.0);
        let r = 10f64.powf(rng.random_range(0.0..2.0));
        let n = 100;
        let mut pts = Array2::zeros((n, 2));
        for i in 0..n {
            let th = std::f64::consts::TAU * i as f64 / n as f64;
            pts[[i, 0]] = cx + r * th.cos() + noise * r * gauss(&mut rng);
            pts[[i, 1]] = cy + r * th.sin() + noise * r * gauss(&mut rng);
        }
        let ok = match fit_circle(pts.view(), None, &params) {
            Ok(f) => match f.primitive {
                Primitive::Circle { center, radius, .. } => {
                    let ce = (center[0] - cx).hypot(center[1] - cy);
                    ce < tol * r && (radius - r).abs() < tol * r
                }
                _ => false,
            },
            Err(_) => false,
        };
        if !ok {
            bad += 1;
        }
    }
    bad
}

#[test]
fn circle_fit_protocol_noiseless() {
    let bad = failures(7, 0.0, 1e-4);
    assert!(bad < 10, "{bad} of 1000 noiseless circles failed");
    // in fact, none should fail
    assert_eq!(bad, 0);
}

#[test]
fn circle_fit_protocol_noisy() {
    let bad = failures(11, 0.1, 0.1);
    assert!(bad < 10, "{bad} of 1000 noisy circles failed");
}
