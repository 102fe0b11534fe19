//! Synthetic tracks and test forecasters.
#![allow(dead_code)]

use mp_forecast::{ForecastError, Forecaster};
use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array2, Array3};

/// A Penn-13 standing pose (pixels, y down), torso ≈ 60 px.
pub const BASE: [[f64; 2]; 13] = [
    [100.0, 20.0],  // head
    [85.0, 45.0],   // l shoulder
    [115.0, 45.0],  // r shoulder
    [78.0, 75.0],   // l elbow
    [122.0, 75.0],  // r elbow
    [75.0, 100.0],  // l wrist
    [125.0, 100.0], // r wrist
    [90.0, 105.0],  // l hip
    [110.0, 105.0], // r hip
    [90.0, 145.0],  // l knee
    [110.0, 145.0], // r knee
    [90.0, 185.0],  // l ankle
    [110.0, 185.0], // r ankle
];

/// Penn-13 track of `n` frames: the base pose, arms and knees moving with
/// `f(t)` (a phase per frame), shifted by `drift_px` per frame in x.
pub fn penn_track(n: usize, phase: impl Fn(usize) -> f64, drift_px: f64) -> Track {
    let mut pos = Array3::zeros((n, 13, 2));
    for t in 0..n {
        let p = phase(t);
        for j in 0..13 {
            let [x, y] = BASE[j];
            let (mut dx, mut dy) = (drift_px * t as f64, 0.0);
            match j {
                3 | 5 => {
                    dx -= 15.0 * p.sin() * if j == 5 { 2.0 } else { 1.0 };
                    dy -= 30.0 * p.sin().abs() * if j == 5 { 2.0 } else { 1.0 };
                }
                4 | 6 => {
                    dx += 15.0 * p.sin() * if j == 6 { 2.0 } else { 1.0 };
                    dy -= 30.0 * p.sin().abs() * if j == 6 { 2.0 } else { 1.0 };
                }
                9 | 10 => dx += 10.0 * p.cos(),
                _ => {}
            }
            pos[[t, j, 0]] = x + dx;
            pos[[t, j, 1]] = y + dy;
        }
    }
    Track::new(pos, None, 30.0, Units::Pixels, Skeleton::penn13()).unwrap()
}

/// A periodic Penn-13 track (period `period` frames).
pub fn periodic(n: usize, period: f64) -> Track {
    penn_track(n, |t| 2.0 * std::f64::consts::PI * t as f64 / period, 0.0)
}

/// A track whose every frame is the same pose.
pub fn still(n: usize) -> Track {
    penn_track(n, |_| 0.7, 0.0)
}

/// Forecaster that returns the true continuation of `clip` (it sees the whole
/// past, so the continuation starts at `past.n_frames()`), passed through `map`.
pub struct Oracle<F: Fn(&Track) -> Track + Send + Sync> {
    pub clip: Track,
    pub map: F,
}

impl<F: Fn(&Track) -> Track + Send + Sync> Forecaster for Oracle<F> {
    fn name(&self) -> &str {
        "oracle"
    }
    fn context_frames(&self) -> Option<usize> {
        None
    }
    fn predict(&self, past: &Track, horizon: usize) -> Result<Track, ForecastError> {
        let s = past.n_frames();
        let e = (s + horizon).min(self.clip.n_frames());
        let mut fut = self.clip.slice_frames(s, e)?;
        if fut.n_frames() < horizon {
            // pad by holding the last frame
            let (p, c, fps, u, sk) = fut.into_parts();
            let (n, j, d) = p.dim();
            let mut pp = Array3::zeros((horizon, j, d));
            let mut cc = Array2::zeros((horizon, j));
            for t in 0..horizon {
                let src = t.min(n - 1);
                for jj in 0..j {
                    cc[[t, jj]] = c[[src, jj]];
                    for k in 0..d {
                        pp[[t, jj, k]] = p[[src, jj, k]];
                    }
                }
            }
            fut = Track::new(pp, Some(cc), fps, u, sk)?;
        }
        Ok((self.map)(&fut))
    }
}

/// Applies `f` to every position of a track.
pub fn map_positions(t: &Track, f: impl Fn(usize, &[f64]) -> Vec<f64>) -> Track {
    let (n, j, d) = t.positions().dim();
    let mut p = Array3::zeros((n, j, d));
    for a in 0..n {
        for b in 0..j {
            let v: Vec<f64> = (0..d).map(|k| t.positions()[[a, b, k]]).collect();
            let w = f(a, &v);
            for k in 0..d {
                p[[a, b, k]] = w[k];
            }
        }
    }
    Track::new(
        p,
        Some(t.confidence().to_owned()),
        t.fps(),
        t.units(),
        t.skeleton().clone(),
    )
    .unwrap()
}

/// Frames `idx` of a track, in that order.
pub fn pick_frames(t: &Track, idx: &[usize]) -> Track {
    let (_, j, d) = t.positions().dim();
    let mut p = Array3::zeros((idx.len(), j, d));
    let mut c = Array2::zeros((idx.len(), j));
    for (a, &i) in idx.iter().enumerate() {
        for b in 0..j {
            c[[a, b]] = t.confidence()[[i, b]];
            for k in 0..d {
                p[[a, b, k]] = t.positions()[[i, b, k]];
            }
        }
    }
    Track::new(p, Some(c), t.fps(), t.units(), t.skeleton().clone()).unwrap()
}
