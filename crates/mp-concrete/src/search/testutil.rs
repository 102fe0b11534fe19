//! Tracks and moments for the unit tests of the search's bounds.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::moments::{anchors, Acc2};

/// Arcs at varying angular speed (back and forth, full turns), lines
/// and pauses, with noise and missing frames.
pub(super) fn track(rng: &mut ChaCha8Rng, t: usize) -> (Vec<[f64; 2]>, Vec<f64>) {
    let mut pts = Vec::with_capacity(t);
    let (mut ang, mut vel) = (rng.random_range(-3.0..3.0), 0.0f64);
    let (c, r) = ([300.0, 250.0], rng.random_range(20.0..150.0));
    let noise = rng.random_range(0.0..6.0);
    for i in 0..t {
        vel = 0.8 * vel + rng.random_range(-0.08..0.08);
        if i % 40 < 8 {
            vel *= 0.3; // a pause
        }
        ang += vel;
        pts.push([
            c[0] + r * ang.cos() + noise * rng.random_range(-1.0..1.0) + 0.3 * i as f64,
            c[1] + r * ang.sin() + noise * rng.random_range(-1.0..1.0),
        ]);
    }
    let wts: Vec<f64> = (0..t)
        .map(|_| if rng.random_bool(0.1) { 0.0 } else { 1.0 })
        .collect();
    for (p, &w) in pts.iter_mut().zip(&wts) {
        if w == 0.0 {
            *p = [0.0, 0.0];
        }
    }
    (pts, wts)
}

/// `track`'s points scaled by `scale` and moved by `(offset, −offset)`;
/// missing frames stay zeroed.
pub(super) fn moved(pts: &mut [[f64; 2]], wts: &[f64], scale: f64, offset: f64) {
    for (p, &w) in pts.iter_mut().zip(wts) {
        if w > 0.0 {
            *p = [p[0] * scale + offset, p[1] * scale - offset];
        }
    }
}

/// The running moments of `k..n` as the search builds them.
pub(super) fn acc_of(pts: &[[f64; 2]], wts: &[f64], steps: &[f64], k: usize, n: usize) -> Acc2 {
    let mut acc = Acc2::default();
    let a = anchors(pts, wts)[n - 1];
    acc.reset(n - 1, a[0], a[1]);
    for i in (k..n).rev() {
        if wts[i] > 0.0 {
            let tau = i as f64 - (n - 1) as f64;
            acc.add(i, tau, pts[i][0], pts[i][1], steps[i]);
        }
    }
    acc
}

/// Step lengths of consecutive valid frames (`−1` where a frame is missing).
pub(super) fn steps_of(pts: &[[f64; 2]], wts: &[f64]) -> Vec<f64> {
    let t = pts.len();
    (0..t)
        .map(|i| {
            if i + 1 < t && wts[i] > 0.0 && wts[i + 1] > 0.0 {
                let (dx, dy) = (pts[i + 1][0] - pts[i][0], pts[i + 1][1] - pts[i][1]);
                (dx * dx + dy * dy).sqrt()
            } else {
                -1.0
            }
        })
        .collect()
}
