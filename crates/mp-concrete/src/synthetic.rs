//! Seeded synthetic tracks for benchmarks and tests.
//!
//! Each of 13 joints (Penn Action skeleton, pixels of a 512-px frame, 30 fps)
//! follows a shared random walk plus its own rotation with a random radius,
//! period and phase, with ±0.5 px noise and occasional pauses of 5–20
//! frames: a realistic mix of stationary, linear and circular segments.

use mp_geom::{Skeleton, Track, Units};
use ndarray::Array3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::Result;

/// A seeded synthetic 13-joint track in pixels of a 512-px frame.
pub fn synthetic_track(n_frames: usize, seed: u64) -> Result<Track> {
    let j = 13;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pos = Array3::zeros((n_frames, j, 2));
    let params: Vec<(f64, f64, f64, f64, f64)> = (0..j)
        .map(|_| {
            (
                rng.random_range(150.0..350.0),               // base x
                rng.random_range(150.0..350.0),               // base y
                rng.random_range(10.0..60.0),                 // amplitude
                rng.random_range(20.0..90.0),                 // period, frames
                rng.random_range(0.0..std::f64::consts::TAU), // phase
            )
        })
        .collect();
    let mut walk = [0.0f64; 2];
    let mut paused = 0usize;
    let mut clock = 0.0f64;
    for t in 0..n_frames {
        if paused > 0 {
            paused -= 1;
        } else {
            clock += 1.0;
            for w in walk.iter_mut() {
                *w = (*w + rng.random_range(-1.5..1.5)).clamp(-80.0, 80.0);
            }
            if rng.random_range(0.0..1.0) < 0.01 {
                paused = rng.random_range(5..20);
            }
        }
        for (ji, &(bx, by, a, per, ph)) in params.iter().enumerate() {
            let th = std::f64::consts::TAU * clock / per + ph;
            pos[[t, ji, 0]] = bx + walk[0] + a * th.cos() + rng.random_range(-0.5..0.5);
            pos[[t, ji, 1]] = by + walk[1] + a * th.sin() + rng.random_range(-0.5..0.5);
        }
    }
    Ok(Track::new(
        pos,
        None,
        30.0,
        Units::Pixels,
        Skeleton::penn13(),
    )?)
}
