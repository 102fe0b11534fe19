//! Loop detection over a sequence of deterministic abstract primitives
//! (paper §3.2; docs/ALGORITHMS.md).
//!
//! For each loop-body size `k = 1..=max_body`, a window of `W_k` primitives
//! slides over the sequence; the primitives of a window are grouped by their
//! position modulo `k` (paper eq. 2) and a Gaussian is fitted to each group,
//! per joint. The window's score is
//!
//! ```text
//! score = max_j ( mean_i ‖Σ_{i,j}‖_F ) / (J · k) / unit_scale²
//! ```
//!
//! (`Σ_{i,j}` the sample covariance of group `i`, joint `j`, over the joint's
//! `[start, mid, end]` vector; `J` joints; `unit_scale` the track's units per
//! reference pixel of a 512-px frame, which makes the threshold unit-free).
//! Windows start at the table size `W_k` and, for short bouts, also at two
//! iterations (`LoopParams::short_window_iterations`).
//! A window whose score is below `threshold` is a loop; it grows one primitive
//! at a time while the score holds. Candidates of all body sizes are then
//! ranked by the number of primitives they cover (ties: smaller body first)
//! and accepted greedily; a candidate overlapping accepted loops is cut to its
//! largest free part. Every loop is trimmed to a multiple of `k`, must have at
//! least `min_iterations` iterations, and its mean body must actually move
//! (`min_body_motion_px`), so that holding still is not counted as repetition.

use serde::{Deserialize, Serialize};

use crate::error::{AbstractError, Result};
use crate::model::DetPrim;

/// The largest loop-body size [`LoopParams::validate`] accepts: 1000
/// primitives. Detection tries every body size up to `max_body`, each with
/// windows of at least `2·k` primitives, so the work grows with its square;
/// no recorded motion has a repeated unit of more primitives.
pub const MAX_BODY: usize = 1000;

/// The largest window (in primitives) [`LoopParams::validate`] accepts in
/// `windows` and as `short_window_iterations`: one million.
pub const MAX_WINDOW: usize = 1_000_000;

/// Parameters of loop detection. Defaults: the product's (docs/ALGORITHMS.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LoopParams {
    /// Largest loop-body size tried (default 10).
    pub max_body: usize,
    /// Initial window size (in primitives) per body size `k = 1..`; default
    /// `{1:20, 2:10, 3:12, 4:12, 5:15, 6:12, 7:14, 8:16, 9:18, 10:20}`. Body sizes beyond
    /// the list use `2·k`.
    pub windows: Vec<usize>,
    /// Score threshold at the 512-px reference scale (default 8).
    pub threshold: f64,
    /// Track units per reference pixel (512-px frame); see mp-concrete's scale rule.
    pub unit_scale: f64,
    /// Minimum number of iterations of a loop (default 2).
    pub min_iterations: usize,
    /// Minimum path length (reference px) of the mean loop body for its most
    /// moving joint (default 10); loops that do not move are dropped.
    pub min_body_motion_px: f64,
    /// The window table suits long recordings; short bouts (a few repetitions)
    /// never fill it. When set, a second pass slides windows of this many
    /// iterations (`k·n` primitives) as well; candidates of both passes compete
    /// in the selection. Default `Some(2)`; `None` keeps only the table.
    pub short_window_iterations: Option<usize>,
    /// Unit-free alternative for data without a pixel scale (e.g. joint-angle
    /// features): when set, a window with body size `k ≥ 2` is scored by
    /// `max_j mean_i ‖Σ_{i,j}‖_F / ‖Σ_j‖_F` — the within-position spread relative to
    /// the spread of all the window's primitives — and is a loop below this value.
    /// Body size 1 keeps the absolute score. Default `None` (absolute scores only).
    pub relative_threshold: Option<f64>,
}

impl Default for LoopParams {
    fn default() -> Self {
        LoopParams {
            max_body: 10,
            windows: vec![20, 10, 12, 12, 15, 12, 14, 16, 18, 20],
            threshold: 8.0,
            unit_scale: 1.0,
            min_iterations: 2,
            min_body_motion_px: 10.0,
            short_window_iterations: Some(2),
            relative_threshold: None,
        }
    }
}

impl LoopParams {
    /// Validates the parameters.
    pub fn validate(&self) -> Result<()> {
        if self.max_body == 0 {
            return Err(AbstractError::param("max_body", "must be ≥ 1"));
        }
        if self.max_body > MAX_BODY {
            return Err(AbstractError::param(
                "max_body",
                format!("{} is too large: at most {MAX_BODY}", self.max_body),
            ));
        }
        if let Some(&w) = self.windows.iter().find(|&&w| w > MAX_WINDOW) {
            return Err(AbstractError::param(
                "windows",
                format!("a window of {w} primitives is too large: at most {MAX_WINDOW}"),
            ));
        }
        if let Some(n) = self.short_window_iterations.filter(|&n| n > MAX_WINDOW) {
            return Err(AbstractError::param(
                "short_window_iterations",
                format!("{n} is too large: at most {MAX_WINDOW}"),
            ));
        }
        AbstractError::check_positive("threshold", self.threshold)?;
        AbstractError::check_positive("unit_scale", self.unit_scale)?;
        if self.min_iterations < 2 {
            return Err(AbstractError::param(
                "min_iterations",
                "a loop needs at least 2 iterations",
            ));
        }
        if !(self.min_body_motion_px.is_finite() && self.min_body_motion_px >= 0.0) {
            return Err(AbstractError::param(
                "min_body_motion_px",
                "must be finite and ≥ 0",
            ));
        }
        if self.short_window_iterations.is_some_and(|n| n < 2) {
            return Err(AbstractError::param(
                "short_window_iterations",
                "must be ≥ 2",
            ));
        }
        if self
            .relative_threshold
            .is_some_and(|r| !(r.is_finite() && r > 0.0))
        {
            return Err(AbstractError::param(
                "relative_threshold",
                "must be finite and > 0",
            ));
        }
        Ok(())
    }

    /// Window size for body size `k`.
    pub fn window(&self, k: usize) -> usize {
        let w = self.windows.get(k - 1).copied().unwrap_or(2 * k);
        w.max(2 * k)
    }
}

/// A detected loop over primitives `start..end` (end exclusive).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DetectedLoop {
    /// First primitive.
    pub start: usize,
    /// One past the last primitive.
    pub end: usize,
    /// Loop-body size k.
    pub body: usize,
    /// Iterations = (end − start) / k.
    pub iterations: usize,
    /// Score (unit-free, below the threshold).
    pub score: f64,
}

/// Running first and second moments of one group of one joint.
#[derive(Clone)]
struct Moments {
    n: usize,
    sum: Vec<f64>,
    sum2: Vec<f64>,
}

impl Moments {
    fn new(dim: usize) -> Self {
        Moments {
            n: 0,
            sum: vec![0.0; dim],
            sum2: vec![0.0; dim * dim],
        }
    }
    fn add(&mut self, x: &[f64]) {
        let d = self.sum.len();
        self.n += 1;
        for a in 0..d {
            self.sum[a] += x[a];
            for b in 0..d {
                self.sum2[a * d + b] += x[a] * x[b];
            }
        }
    }
    /// Frobenius norm of the sample covariance (n − 1 denominator).
    fn cov_norm(&self) -> f64 {
        if self.n < 2 {
            return f64::INFINITY;
        }
        let d = self.sum.len();
        let n = self.n as f64;
        let mut s = 0.0;
        for a in 0..d {
            for b in 0..d {
                let c = (self.sum2[a * d + b] - self.sum[a] * self.sum[b] / n) / (n - 1.0);
                s += c * c;
            }
        }
        s.sqrt()
    }
}

/// Incremental window statistics for one body size.
struct Window {
    k: usize,
    joints: usize,
    /// `groups[i * joints + j]`
    groups: Vec<Moments>,
    len: usize,
}

impl Window {
    fn new(k: usize, joints: usize, dim: usize) -> Self {
        Window {
            k,
            joints,
            groups: vec![Moments::new(dim); k * joints],
            len: 0,
        }
    }
    fn push(&mut self, p: &DetPrim) {
        let i = self.len % self.k;
        for (j, v) in p.points.iter().enumerate() {
            self.groups[i * self.joints + j].add(v);
        }
        self.len += 1;
    }
    /// Score in the mode `params` selects for this body size, and the threshold it is compared with.
    fn score_mode(&self, params: &LoopParams) -> (f64, f64) {
        match params.relative_threshold {
            Some(r) if self.k >= 2 => (self.relative_score(), r),
            _ => (self.score(params.unit_scale), params.threshold),
        }
    }
    fn relative_score(&self) -> f64 {
        let mut worst: f64 = 0.0;
        for j in 0..self.joints {
            let dim = self.groups[j].sum.len();
            let mut total = Moments::new(dim);
            let mut acc = 0.0;
            for i in 0..self.k {
                let g = &self.groups[i * self.joints + j];
                total.n += g.n;
                for (a, b) in total.sum.iter_mut().zip(&g.sum) {
                    *a += b;
                }
                for (a, b) in total.sum2.iter_mut().zip(&g.sum2) {
                    *a += b;
                }
                acc += g.cov_norm();
            }
            let tn = total.cov_norm();
            let rel = if tn > 1e-12 {
                acc / self.k as f64 / tn
            } else {
                f64::INFINITY
            };
            worst = worst.max(rel);
        }
        worst
    }
    fn score(&self, unit_scale: f64) -> f64 {
        let mut worst: f64 = 0.0;
        for j in 0..self.joints {
            let mut acc = 0.0;
            for i in 0..self.k {
                acc += self.groups[i * self.joints + j].cov_norm();
            }
            worst = worst.max(acc / self.k as f64);
        }
        worst / (self.joints * self.k) as f64 / (unit_scale * unit_scale)
    }
}

fn check_prims(prims: &[DetPrim]) -> Result<(usize, usize)> {
    let first = prims.first().ok_or_else(|| {
        AbstractError::Empty("loop detection needs at least one primitive".into())
    })?;
    let joints = first.points.len();
    if joints == 0 {
        return Err(AbstractError::Shape("primitives have no joints".into()));
    }
    let dim = first.points[0].len();
    for (i, p) in prims.iter().enumerate() {
        if p.points.len() != joints || p.points.iter().any(|v| v.len() != dim) {
            return Err(AbstractError::Shape(format!(
                "primitive {i} has a different joint count or dimension than primitive 0"
            )));
        }
        if p.points.iter().flatten().any(|v| !v.is_finite()) {
            return Err(AbstractError::NonFinite(format!(
                "primitive {i} has a non-finite point"
            )));
        }
    }
    Ok((joints, dim))
}

/// The window of body size `k` over primitives `start..end`.
#[cfg(test)]
fn filled_window(prims: &[DetPrim], start: usize, end: usize, k: usize) -> Result<Window> {
    let (joints, dim) = check_prims(prims)?;
    if k == 0 || start >= end || end > prims.len() {
        return Err(AbstractError::param(
            "window",
            format!("{start}..{end} with body {k} is invalid"),
        ));
    }
    let mut w = Window::new(k, joints, dim);
    for p in &prims[start..end] {
        w.push(p);
    }
    Ok(w)
}

/// Score of primitives `start..end` with body size `k` (unit-free; infinite
/// when a group has fewer than two members).
#[cfg(test)]
pub fn window_score(
    prims: &[DetPrim],
    start: usize,
    end: usize,
    k: usize,
    unit_scale: f64,
) -> Result<f64> {
    Ok(filled_window(prims, start, end, k)?.score(unit_scale))
}

/// Score of primitives `start..end` with body size `k` in the mode `params`
/// selects (absolute or relative), with the threshold it is compared against.
#[cfg(test)]
pub fn window_score_with(
    prims: &[DetPrim],
    start: usize,
    end: usize,
    k: usize,
    params: &LoopParams,
) -> Result<(f64, f64)> {
    Ok(filled_window(prims, start, end, k)?.score_mode(params))
}

/// Path length of the mean loop body of the most moving joint, in track units.
fn body_motion(prims: &[DetPrim], start: usize, end: usize, k: usize) -> f64 {
    let joints = prims[start].points.len();
    let dim3 = prims[start].points[0].len();
    let d = dim3 / 3;
    let iters = (end - start) / k;
    let mut best: f64 = 0.0;
    for j in 0..joints {
        let mut path = 0.0;
        for i in 0..k {
            let mut mean = vec![0.0; dim3];
            for it in 0..iters {
                for (m, v) in mean.iter_mut().zip(&prims[start + it * k + i].points[j]) {
                    *m += v / iters as f64;
                }
            }
            let dist = |a: usize, b: usize| -> f64 {
                (0..d)
                    .map(|c| (mean[a * d + c] - mean[b * d + c]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            };
            path += dist(0, 1) + dist(1, 2);
        }
        best = best.max(path);
    }
    best
}

/// Candidates of one body size: slide, detect, grow.
fn candidates_for(
    prims: &[DetPrim],
    k: usize,
    w: usize,
    params: &LoopParams,
    joints: usize,
    dim: usize,
) -> Vec<DetectedLoop> {
    let n = prims.len();
    let mut out = Vec::new();
    let mut i = 0;
    while i + w <= n {
        let mut win = Window::new(k, joints, dim);
        for p in &prims[i..i + w] {
            win.push(p);
        }
        let (s, thr) = win.score_mode(params);
        if s < thr {
            let mut end = i + w;
            let mut score = s;
            while end < n {
                win.push(&prims[end]);
                let (s2, _) = win.score_mode(params);
                if s2 < thr {
                    end += 1;
                    score = s2;
                } else {
                    break;
                }
            }
            let len = (end - i) / k * k;
            out.push(DetectedLoop {
                start: i,
                end: i + len,
                body: k,
                iterations: len / k,
                score,
            });
            i = end;
        } else {
            i += 1;
        }
    }
    out
}

/// Detects loops in a sequence of deterministic abstract primitives.
/// Returns non-overlapping loops sorted by start.
pub fn detect_loops(prims: &[DetPrim], params: &LoopParams) -> Result<Vec<DetectedLoop>> {
    params.validate()?;
    let (joints, dim) = check_prims(prims)?;
    if dim % 3 != 0 {
        return Err(AbstractError::Shape(format!(
            "abstract points must hold start, mid and end (3·D values), got {dim}"
        )));
    }
    let mut cands: Vec<DetectedLoop> = (1..=params.max_body)
        .flat_map(|k| {
            let mut c = candidates_for(prims, k, params.window(k), params, joints, dim);
            if let Some(n) = params.short_window_iterations {
                let w = (k * n).min(params.window(k));
                if w < params.window(k) {
                    c.extend(candidates_for(prims, k, w, params, joints, dim));
                }
            }
            c
        })
        .collect();
    cands.sort_by(|a, b| {
        (b.end - b.start)
            .cmp(&(a.end - a.start))
            .then(a.body.cmp(&b.body))
            .then(a.start.cmp(&b.start))
    });
    let mut taken = vec![false; prims.len()];
    let mut accepted: Vec<DetectedLoop> = Vec::new();
    for c in cands {
        // Largest free run inside the candidate.
        let (mut best_s, mut best_len) = (c.start, 0);
        let mut run_s = c.start;
        for p in c.start..=c.end {
            if p == c.end || taken.get(p).copied().unwrap_or(true) {
                if p - run_s > best_len {
                    best_s = run_s;
                    best_len = p - run_s;
                }
                run_s = p + 1;
            }
        }
        let k = c.body;
        let len = best_len / k * k;
        if len / k < params.min_iterations {
            continue;
        }
        let (s, e) = (best_s, best_s + len);
        let mut win = Window::new(k, joints, dim);
        for p in &prims[s..e] {
            win.push(p);
        }
        let (score, thr) = win.score_mode(params);
        if score >= thr {
            continue;
        }
        if body_motion(prims, s, e, k) < params.min_body_motion_px * params.unit_scale {
            continue;
        }
        for t in taken.iter_mut().take(e).skip(s) {
            *t = true;
        }
        accepted.push(DetectedLoop {
            start: s,
            end: e,
            body: k,
            iterations: len / k,
            score,
        });
    }
    accepted.sort_by_key(|l| l.start);
    Ok(accepted)
}
