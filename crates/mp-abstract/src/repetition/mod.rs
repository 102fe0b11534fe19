//! Repetition API: detected repetitive intervals in frames, with iteration
//! boundaries and a repetition count.
//!
//! Three steps live in their own modules: the loop intervals of an abstract
//! program (here), the dominant period of a stretch of motion
//! (`period`: autocorrelation of joint velocities) and the repetitive
//! intervals of a long recording (`segment`: local periodicity and dynamic
//! programming). [`crate::count`] combines them into the counts a user gets.

mod concordance;
mod period;
mod segment;

pub(crate) use period::estimate_period_and_peaks;
pub use period::{estimate_period, PeriodEstimate, PeriodParams};
pub use segment::{segment_repetitions, IntervalParams, PeriodicSegment};

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

/// Which joints the periodicity analyses ([`estimate_period`],
/// [`segment_repetitions`]) read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[non_exhaustive]
pub enum JointSelection {
    /// Every joint of the track.
    All,
    /// The twelve COCO limb joints (shoulders, elbows, wrists, hips, knees,
    /// ankles) when the skeleton maps to COCO-17; every joint otherwise. Face,
    /// hand and foot landmarks are small, noisy and redundant with the limbs:
    /// on a BlazePose-33 track they are 21 of the 33 joints and would
    /// otherwise dominate the average.
    #[default]
    Limbs,
}

/// Indices of the joints a [`JointSelection`] picks on `skeleton` (never empty
/// for a non-empty skeleton).
pub fn selected_joints(skeleton: &mp_geom::Skeleton, sel: JointSelection) -> Vec<usize> {
    let all: Vec<usize> = (0..skeleton.len()).collect();
    match sel {
        JointSelection::All => all,
        JointSelection::Limbs => {
            if !skeleton.maps_to_coco17() {
                return all;
            }
            let limbs: Vec<usize> = skeleton
                .coco17
                .iter()
                .skip(5)
                .flatten()
                .copied()
                .filter(|&j| j < skeleton.len())
                .collect();
            if limbs.is_empty() {
                all
            } else {
                limbs
            }
        }
    }
}

/// Coordinate `k` of joint `ji` over `frames[start..end]` into `out` (at
/// least `end - start` long), missing frames filled by linear interpolation
/// between the nearest valid frames of the range (edges held; left as they
/// are when the joint is never valid in the range) — what
/// [`mp_geom::Track::fill_missing`] does to a slice of the track, without
/// copying it.
pub(crate) fn filled_column(
    track: &mp_geom::Track,
    ji: usize,
    k: usize,
    start: usize,
    end: usize,
    out: &mut [f64],
) {
    let pos = track.positions();
    let conf = track.confidence();
    let valid: Vec<usize> = (0..end - start)
        .filter(|&ti| conf[[start + ti, ji]] > 0.0)
        .collect();
    for (ti, o) in out.iter_mut().enumerate().take(end - start) {
        *o = if valid.is_empty() || conf[[start + ti, ji]] > 0.0 {
            pos[[start + ti, ji, k]]
        } else {
            match mp_geom::bracket(&valid, ti) {
                Some((a, b, w)) => {
                    pos[[start + a, ji, k]] * (1.0 - w) + pos[[start + b, ji, k]] * w
                }
                None => pos[[start + ti, ji, k]],
            }
        };
    }
}

/// `frames[start..end]` of the selected joints as a `T × C` matrix (row-major),
/// missing joints filled by linear interpolation; `None` when no joint is ever valid.
pub(crate) fn channels(
    track: &mp_geom::Track,
    start: usize,
    end: usize,
    sel: JointSelection,
    centre_frames: bool,
) -> crate::Result<Option<(Vec<f64>, usize, usize)>> {
    use crate::AbstractError;
    if start >= end || end > track.n_frames() {
        return Err(AbstractError::param(
            "frames",
            format!("{start}..{end} outside 0..{}", track.n_frames()),
        ));
    }
    // Every joint valid on every frame of the range (a thumbnail track
    // always): read in place. Otherwise a copy of the range, filled.
    let conf = track.confidence();
    let conf = conf.slice(ndarray::s![start..end, ..]);
    let filled;
    let pos = if !conf.is_empty() && conf.iter().all(|&c| c > 0.0) {
        track
            .positions()
            .slice_move(ndarray::s![start..end, .., ..])
    } else {
        let mut t = track.slice_frames(start, end)?;
        if t.valid_count() == 0 {
            return Ok(None);
        }
        t.fill_missing();
        filled = t;
        filled.positions()
    };
    let joints = selected_joints(track.skeleton(), sel);
    let (n, _, d) = pos.dim();
    let c = joints.len() * d;
    let mut y = vec![0.0; n * c];
    for ti in 0..n {
        for (a, &ji) in joints.iter().enumerate() {
            for k in 0..d {
                y[ti * c + a * d + k] = pos[[ti, ji, k]];
            }
        }
        if centre_frames && !joints.is_empty() {
            for k in 0..d {
                let m = (0..joints.len())
                    .map(|a| y[ti * c + a * d + k])
                    .sum::<f64>()
                    / joints.len() as f64;
                for a in 0..joints.len() {
                    y[ti * c + a * d + k] -= m;
                }
            }
        }
    }
    Ok(Some((y, n, c)))
}

/// Standardises each column of a row-major `m × dims` matrix (constant columns become 0).
pub(crate) fn standardise(v: &mut [f64], m: usize, dims: usize) {
    for c in 0..dims {
        let mean = (0..m).map(|ti| v[ti * dims + c]).sum::<f64>() / m as f64;
        let var = (0..m)
            .map(|ti| (v[ti * dims + c] - mean).powi(2))
            .sum::<f64>()
            / m as f64;
        let sd = var.sqrt();
        for ti in 0..m {
            v[ti * dims + c] = if sd > 1e-12 {
                (v[ti * dims + c] - mean) / sd
            } else {
                0.0
            };
        }
    }
}
