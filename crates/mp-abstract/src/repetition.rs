//! Repetition API: detected repetitive intervals in frames, with iteration
//! boundaries and a repetition count.

use serde::{Deserialize, Serialize};

use crate::loops::DetectedLoop;
use crate::model::DetPrim;

/// A repetitive interval of a track.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RepetitiveInterval {
    /// First frame.
    pub start_frame: usize,
    /// One past the last frame.
    pub end_frame: usize,
    /// Loop-body size (primitives per iteration).
    pub body_size: usize,
    /// Number of iterations.
    pub iterations: usize,
    /// Frame where each iteration starts, plus `end_frame` (length iterations + 1).
    pub boundaries: Vec<usize>,
    /// Repetition count of the interval (= iterations).
    pub count: usize,
    /// Loop score (unit-free, below the detection threshold).
    pub score: f64,
}

/// Converts detected loops (in primitive indices) to frame intervals.
pub fn intervals(
    prims: &[DetPrim],
    loops: &[DetectedLoop],
    first_frame: usize,
) -> Vec<RepetitiveInterval> {
    let mut starts = Vec::with_capacity(prims.len() + 1);
    let mut t = first_frame;
    for p in prims {
        starts.push(t);
        t += p.duration;
    }
    starts.push(t);
    loops
        .iter()
        .filter(|l| l.end <= prims.len() && l.body > 0)
        .map(|l| {
            let boundaries: Vec<usize> = (0..=l.iterations)
                .map(|i| starts[l.start + i * l.body])
                .collect();
            RepetitiveInterval {
                start_frame: starts[l.start],
                end_frame: starts[l.end],
                body_size: l.body,
                iterations: l.iterations,
                boundaries,
                count: l.iterations,
                score: l.score,
            }
        })
        .collect()
}

/// Intersection over the minimum length of two frame intervals `[a0, a1)`, `[b0, b1)`.
pub fn iom(a: (usize, usize), b: (usize, usize)) -> f64 {
    let inter = a.1.min(b.1).saturating_sub(a.0.max(b.0)) as f64;
    let m = (a.1 - a.0).min(b.1 - b.0) as f64;
    if m <= 0.0 {
        0.0
    } else {
        inter / m
    }
}

/// Intersection over union of two frame intervals.
pub fn iou(a: (usize, usize), b: (usize, usize)) -> f64 {
    let inter = a.1.min(b.1).saturating_sub(a.0.max(b.0)) as f64;
    let uni = (a.1 - a.0) as f64 + (b.1 - b.0) as f64 - inter;
    if uni <= 0.0 {
        0.0
    } else {
        inter / uni
    }
}
