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

/// Parameters of period estimation (see [`estimate_period`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PeriodParams {
    /// Moving-average window applied to positions before differencing (frames). Default 3.
    pub smooth_frames: usize,
    /// Shortest period considered, seconds. Default 0.25.
    pub min_period_s: f64,
    /// The period is the first autocorrelation peak reaching this fraction of the
    /// highest peak (guards against picking a multiple of the period). Default 0.7.
    pub peak_ratio: f64,
}

impl Default for PeriodParams {
    fn default() -> Self {
        PeriodParams {
            smooth_frames: 3,
            min_period_s: 0.25,
            peak_ratio: 0.7,
        }
    }
}

/// A dominant period of a track.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PeriodEstimate {
    /// Period in frames.
    pub period_frames: usize,
    /// Normalised autocorrelation at that lag (−1..1): how periodic the motion is.
    pub strength: f64,
    /// Repetitions over the analysed frames: frames / period.
    pub count: f64,
}

/// Estimates the dominant period of the motion of `track[start..end]` from the
/// autocorrelation of joint velocities: positions are smoothed, differenced
/// (which removes drift and static offsets), each coordinate is standardised,
/// and the autocorrelation (unbiased, averaged over coordinates) is searched,
/// after its first zero crossing and above `min_period_s`, for the first local
/// peak reaching `peak_ratio` of the highest one. Missing joints are filled by
/// linear interpolation first. Returns `None` when no peak exists (too short, no motion).
pub fn estimate_period(
    track: &mp_geom::Track,
    start: usize,
    end: usize,
    params: &PeriodParams,
) -> crate::Result<Option<PeriodEstimate>> {
    use crate::AbstractError;
    if !(params.peak_ratio > 0.0 && params.peak_ratio <= 1.0) {
        return Err(AbstractError::param("peak_ratio", "must be in (0, 1]"));
    }
    if !(params.min_period_s.is_finite() && params.min_period_s >= 0.0) {
        return Err(AbstractError::param(
            "min_period_s",
            "must be finite and ≥ 0",
        ));
    }
    if start >= end || end > track.n_frames() {
        return Err(AbstractError::param(
            "frames",
            format!("{start}..{end} outside 0..{}", track.n_frames()),
        ));
    }
    let mut t = track.slice_frames(start, end)?;
    if t.valid_count() == 0 {
        return Ok(None);
    }
    t.fill_missing();
    let (n, j, d) = t.positions().dim();
    let dims = j * d;
    let w = params.smooth_frames.max(1);
    // Smoothed positions (centred moving average, shrinking at the edges).
    let mut sm = vec![0.0; n * dims];
    for ti in 0..n {
        let lo = ti.saturating_sub(w / 2);
        let hi = (ti + w - w / 2).min(n);
        for ji in 0..j {
            for k in 0..d {
                let mut s = 0.0;
                for q in lo..hi {
                    s += t.positions()[[q, ji, k]];
                }
                sm[ti * dims + ji * d + k] = s / (hi - lo) as f64;
            }
        }
    }
    if n < 4 {
        return Ok(None);
    }
    let m = n - 1;
    let mut v = vec![0.0; m * dims];
    for ti in 0..m {
        for c in 0..dims {
            v[ti * dims + c] = sm[(ti + 1) * dims + c] - sm[ti * dims + c];
        }
    }
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
    let max_lag = m / 2;
    let mut r = vec![0.0; max_lag.max(1)];
    for (lag, rv) in r.iter_mut().enumerate() {
        let mut s = 0.0;
        for ti in 0..m - lag {
            for c in 0..dims {
                s += v[ti * dims + c] * v[(ti + lag) * dims + c];
            }
        }
        *rv = s / (m - lag) as f64;
    }
    if r[0] <= 0.0 {
        return Ok(None);
    }
    let r0 = r[0];
    for x in r.iter_mut() {
        *x /= r0;
    }
    let zero = r.iter().position(|&x| x < 0.0).unwrap_or(r.len());
    let min_lag = zero
        .max((params.min_period_s * track.fps()).round() as usize)
        .max(1);
    let peaks: Vec<usize> = (min_lag + 1..r.len().saturating_sub(1))
        .filter(|&l| r[l] >= r[l - 1] && r[l] >= r[l + 1] && r[l] > 0.0)
        .collect();
    let Some(best) = peaks.iter().map(|&l| r[l]).reduce(f64::max) else {
        return Ok(None);
    };
    let Some(&lag) = peaks.iter().find(|&&l| r[l] >= params.peak_ratio * best) else {
        return Ok(None);
    };
    Ok(Some(PeriodEstimate {
        period_frames: lag,
        strength: r[lag],
        count: n as f64 / lag as f64,
    }))
}
