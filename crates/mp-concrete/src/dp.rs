//! Optimal segmentation by dynamic programming (paper eq. 1), independent of
//! what a segment costs.
//!
//! `E[0] = 0`, `E[n] = min_{n−W ≤ k < n} E[k] + cost(k, n)`, where
//! `cost(k, n)` is the cost of one segment covering frames `k..n` (end
//! exclusive) *including* the per-segment penalty λ. With a maximum segment
//! length `W` the recurrence takes `O(T·W)` evaluations of `cost`.

use rayon::prelude::*;

use crate::error::{ConcreteError, Result};

/// A segmentation of frames `0..T` and its total cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Segmentation {
    /// Boundaries `0 = b0 < b1 < … < bm = T`; segment `i` is `b[i]..b[i+1]`.
    pub boundaries: Vec<usize>,
    /// Total cost (sum of segment costs).
    pub cost: f64,
}

impl Segmentation {
    /// Segment lengths in frames.
    pub fn durations(&self) -> Vec<usize> {
        self.boundaries.windows(2).map(|w| w[1] - w[0]).collect()
    }
    /// Number of segments.
    pub fn n_segments(&self) -> usize {
        self.boundaries.len().saturating_sub(1)
    }

    /// Minimum-cost segmentation of `0..n_frames` into segments of at most
    /// `window` frames by dynamic programming, `cost(k, n)` the cost of
    /// segment `k..n` (see the module docs), `O(T·W)`. Ties go to the
    /// earliest split point `k` (the longest last segment). Costs may be `+∞`
    /// (forbidden segments); NaN costs are an error.
    pub fn dp(
        n_frames: usize,
        window: usize,
        cost: impl Fn(usize, usize) -> f64,
    ) -> Result<Segmentation> {
        check(n_frames, window)?;
        let mut best = vec![f64::INFINITY; n_frames + 1];
        let mut arg = vec![0usize; n_frames + 1];
        best[0] = 0.0;
        for n in 1..=n_frames {
            let lo = n.saturating_sub(window);
            for k in lo..n {
                let c = cost(k, n);
                if c.is_nan() {
                    return Err(ConcreteError::Track(format!(
                        "segment cost of frames {k}..{n} is NaN"
                    )));
                }
                let e = best[k] + c;
                if e < best[n] {
                    best[n] = e;
                    arg[n] = k;
                }
            }
        }
        backtrack(&best, &arg, window)
    }
}

/// Segment costs `cost(k, n)` for all `n − W ≤ k < n`, stored densely
/// (`T × W`, entry `(n − 1)·W + (n − k − 1)`).
#[derive(Debug, Clone)]
pub struct CostTable {
    n_frames: usize,
    window: usize,
    costs: Vec<f64>,
}

impl CostTable {
    /// A table of `+∞` for `n_frames` frames and segments of at most `window` frames.
    pub fn new(n_frames: usize, window: usize) -> Self {
        CostTable {
            n_frames,
            window,
            costs: vec![f64::INFINITY; n_frames * window],
        }
    }
    /// Fills the table from a function (sequentially).
    pub fn from_fn(
        n_frames: usize,
        window: usize,
        mut cost: impl FnMut(usize, usize) -> f64,
    ) -> Self {
        let mut t = Self::new(n_frames, window);
        for n in 1..=n_frames {
            for len in 1..=window.min(n) {
                t.costs[(n - 1) * window + len - 1] = cost(n - len, n);
            }
        }
        t
    }
    /// Fills the table from a fallible function, one row (end frame) per
    /// task on the rayon pool; the first error stops the fill and is returned.
    pub fn try_from_fn_parallel<E: Send>(
        n_frames: usize,
        window: usize,
        cost: impl Fn(usize, usize) -> std::result::Result<f64, E> + Sync,
    ) -> std::result::Result<Self, E> {
        let mut t = Self::new(n_frames, window);
        t.rows_mut()
            .collect::<Vec<_>>()
            .into_par_iter()
            .enumerate()
            .try_for_each(|(row, cells)| {
                let n = row + 1;
                for len in 1..=window.min(n) {
                    cells[len - 1] = cost(n - len, n)?;
                }
                Ok(())
            })?;
        Ok(t)
    }
    /// Number of frames T.
    pub fn n_frames(&self) -> usize {
        self.n_frames
    }
    /// Maximum segment length W.
    pub fn window(&self) -> usize {
        self.window
    }
    /// Cost of segment `k..n`, `+∞` when outside the table.
    pub fn get(&self, k: usize, n: usize) -> f64 {
        if k >= n || n > self.n_frames || n - k > self.window {
            return f64::INFINITY;
        }
        self.costs[(n - 1) * self.window + (n - k - 1)]
    }
    /// The row of segments ending at `n` (1-based end, exclusive), indexed by `length − 1`.
    pub fn row_mut(&mut self, n: usize) -> &mut [f64] {
        let w = self.window;
        &mut self.costs[(n - 1) * w..n * w]
    }
    /// Mutable rows for parallel filling: row `n − 1` holds segments ending at `n`.
    pub fn rows_mut(&mut self) -> std::slice::ChunksMut<'_, f64> {
        let w = self.window.max(1);
        self.costs.chunks_mut(w)
    }
}

fn check(n_frames: usize, window: usize) -> Result<()> {
    if n_frames == 0 {
        return Err(ConcreteError::Track("cannot segment 0 frames".into()));
    }
    if window == 0 {
        return Err(ConcreteError::param("max_segment_frames", "must be ≥ 1"));
    }
    Ok(())
}

/// The segmentation from a DP's optimal costs `best[n]` of frames `0..n`
/// (`best[0] = 0`) and the start `arg[n]` of the last segment of each optimum;
/// an error when the whole track has no finite-cost segmentation.
pub(crate) fn backtrack(best: &[f64], arg: &[usize], window: usize) -> Result<Segmentation> {
    let n_frames = best.len().saturating_sub(1);
    let cost = best.get(n_frames).copied().unwrap_or(f64::INFINITY);
    if !cost.is_finite() {
        return Err(ConcreteError::Track(format!(
            "no finite-cost segmentation of {n_frames} frames with segments of at most {window} frames"
        )));
    }
    let mut b = vec![n_frames];
    let mut n = n_frames;
    while n > 0 {
        n = arg[n];
        b.push(n);
    }
    b.reverse();
    Ok(Segmentation {
        boundaries: b,
        cost,
    })
}

/// [`Segmentation::dp`] over a precomputed table.
pub(crate) fn segment_table(table: &CostTable) -> Result<Segmentation> {
    Segmentation::dp(table.n_frames(), table.window(), |k, n| table.get(k, n))
}

/// Exhaustive search over all `2^(T−1)` segmentations (segments of at most
/// `window` frames), for testing the DP. Refuses `T > 20`.
#[cfg(test)]
pub(crate) fn segment_brute_force(
    n_frames: usize,
    window: usize,
    cost: impl Fn(usize, usize) -> f64,
) -> Result<Segmentation> {
    check(n_frames, window)?;
    if n_frames > 20 {
        return Err(ConcreteError::param(
            "n_frames",
            format!("brute force is limited to 20 frames, got {n_frames}"),
        ));
    }
    let mut best: Option<Segmentation> = None;
    for mask in 0u32..(1u32 << (n_frames - 1)) {
        let mut b = vec![0usize];
        for i in 1..n_frames {
            if mask & (1 << (i - 1)) != 0 {
                b.push(i);
            }
        }
        b.push(n_frames);
        if b.windows(2).any(|w| w[1] - w[0] > window) {
            continue;
        }
        let c: f64 = b.windows(2).map(|w| cost(w[0], w[1])).sum();
        if c.is_finite() && best.as_ref().is_none_or(|s| c < s.cost) {
            best = Some(Segmentation {
                boundaries: b,
                cost: c,
            });
        }
    }
    best.ok_or_else(|| ConcreteError::Track("no finite-cost segmentation".into()))
}
