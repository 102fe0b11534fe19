//! The segmentation objective (paper eqs. 3–5).
//!
//! For a segmentation of a `T`-frame motion into segments `s_i` (lengths
//! `L(s_i)`) clustered into `K` clusters with medoids `s_{c_k}`:
//!
//! * repetitiveness `R(C) = (1/T) Σ_k L(s_{c_k})` (eq. 3), in `[0, 1]`;
//! * clarity `E′(C) = (1/d_max) Σ_k Σ_{i ∈ C_k} (L(s_i)/T) · D(s_i, s_{c_k})`
//!   (eq. 4), where `d_max` is the largest pose distance over all pairs of
//!   frames ([`PoseFeatures::max_pose_distance`](crate::PoseFeatures::max_pose_distance));
//! * score `F(C) = 1 / (ω R(C) + (1 − ω) E′(C))` (eq. 5), higher is better.
//!
//! When the denominator is 0 (e.g. ω = 0 and every segment equals its
//! medoid) `F` is reported as `f64::MAX`.

use serde::{Deserialize, Serialize};

/// The terms of the objective for one clustered segmentation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClusterQuality {
    /// `R(C)` (eq. 3).
    pub r: f64,
    /// `E′(C)` (eq. 4).
    pub e_prime: f64,
    /// `F(C)` (eq. 5).
    pub f: f64,
}

impl ClusterQuality {
    /// Combines `R` and `E′` with weight `ω`.
    pub fn from_terms(r: f64, e_prime: f64, omega: f64) -> Self {
        let den = omega * r + (1.0 - omega) * e_prime;
        let f = if den > 0.0 { 1.0 / den } else { f64::MAX };
        ClusterQuality { r, e_prime, f }
    }
}

/// Evaluates eqs. 3–5.
///
/// * `lengths[i]`: `L(s_i)` in frames;
/// * `assignment[i]`: cluster of segment `i`; `medoids[k]`: medoid segment of
///   cluster `k`;
/// * `dist(i, j)`: segment distance `D(s_i, s_j)`;
/// * `total_frames`: `T`; `d_max`: largest pose distance; `omega`: ω.
///
/// Indices are trusted (internal use); callers validate them.
pub fn evaluate(
    lengths: &[usize],
    medoids: &[usize],
    assignment: &[usize],
    mut dist: impl FnMut(usize, usize) -> f64,
    total_frames: usize,
    d_max: f64,
    omega: f64,
) -> ClusterQuality {
    let t = total_frames.max(1) as f64;
    let r = medoids.iter().map(|&m| lengths[m] as f64).sum::<f64>() / t;
    let mut e = 0.0;
    for (i, &c) in assignment.iter().enumerate() {
        let m = medoids[c];
        if m != i {
            e += lengths[i] as f64 * dist(i, m);
        }
    }
    let e_prime = if d_max > 0.0 { e / (t * d_max) } else { 0.0 };
    ClusterQuality::from_terms(r, e_prime, omega)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed() {
        // 4 segments of lengths 10, 20, 10, 20 (T = 60), K = 2,
        // medoids 0 and 1, segment 2 in cluster 0 (D = 0.5), 3 in cluster 1 (D = 1).
        let lengths = [10, 20, 10, 20];
        let d = |i: usize, j: usize| match (i.min(j), i.max(j)) {
            (0, 2) => 0.5,
            (1, 3) => 1.0,
            _ => 9.0,
        };
        let q = evaluate(&lengths, &[0, 1], &[0, 1, 0, 1], d, 60, 2.0, 0.25);
        let r = 30.0 / 60.0;
        let e = (10.0 / 60.0 * 0.5 + 20.0 / 60.0 * 1.0) / 2.0;
        assert!((q.r - r).abs() < 1e-12);
        assert!((q.e_prime - e).abs() < 1e-12);
        assert!((q.f - 1.0 / (0.25 * r + 0.75 * e)).abs() < 1e-12);
    }
}
