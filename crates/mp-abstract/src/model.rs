//! The abstract DSL (paper Table 2): deterministic start/mid/end primitives and
//! `for` loops whose bodies are probabilistic primitives.
//!
//! All joints share one segmentation (as in concrete programs), so one
//! statement covers every joint: a deterministic primitive holds, per joint,
//! the start, middle and end points of the motion (`3·D` numbers: 6-D in 2D,
//! 9-D in 3D) and a duration in frames; a probabilistic primitive holds, per
//! joint, a Gaussian over that `3·D` vector and a frequency distribution over
//! durations.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::error::{AbstractError, Result};

/// A deterministic abstract primitive: `{<start, middle, end>: <Point, Point, Point>, time: Int}`
/// for every joint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DetPrim {
    /// Duration in frames (≥ 1).
    pub duration: usize,
    /// Per joint: `[start…, mid…, end…]` (length `3·D`).
    pub points: Vec<Vec<f64>>,
}

/// A multivariate Gaussian over a joint's `[start, mid, end]` vector.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Gaussian {
    /// Mean (length n = 3·D).
    pub mean: Vec<f64>,
    /// Covariance, row-major `n × n`.
    pub cov: Vec<f64>,
}

impl Gaussian {
    /// Dimension n.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }
    /// Frobenius norm of the covariance.
    pub fn cov_norm(&self) -> f64 {
        self.cov.iter().map(|v| v * v).sum::<f64>().sqrt()
    }
    /// Checks shape and finiteness.
    pub fn validate(&self, what: &str) -> Result<()> {
        let n = self.mean.len();
        if self.cov.len() != n * n {
            return Err(AbstractError::Shape(format!(
                "{what}: covariance has {} entries, mean of length {n} needs {}",
                self.cov.len(),
                n * n
            )));
        }
        if self.mean.iter().any(|v| !v.is_finite()) {
            return Err(AbstractError::NonFinite(format!(
                "{what}: Gaussian `mean` has a non-finite value"
            )));
        }
        if self.cov.iter().any(|v| !v.is_finite()) {
            return Err(AbstractError::NonFinite(format!(
                "{what}: Gaussian `cov` has a non-finite value"
            )));
        }
        Ok(())
    }
}

/// A frequency distribution over positive integers (durations in frames).
/// In JSON it is a list of `[value, count]` pairs.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(into = "Vec<(usize, usize)>", from = "Vec<(usize, usize)>")]
pub struct FreqDist {
    /// Value → count.
    pub counts: BTreeMap<usize, usize>,
}

impl From<FreqDist> for Vec<(usize, usize)> {
    fn from(d: FreqDist) -> Self {
        d.counts.into_iter().collect()
    }
}

impl From<Vec<(usize, usize)>> for FreqDist {
    /// Counts of a repeated value add up (saturating at `usize::MAX`).
    fn from(v: Vec<(usize, usize)>) -> Self {
        let mut counts = BTreeMap::new();
        for (k, c) in v {
            let n: &mut usize = counts.entry(k).or_insert(0);
            *n = n.saturating_add(c);
        }
        FreqDist { counts }
    }
}

impl FreqDist {
    /// Builds a distribution from observed values.
    pub fn from_values(values: impl IntoIterator<Item = usize>) -> Self {
        let mut counts = BTreeMap::new();
        for v in values {
            *counts.entry(v).or_insert(0) += 1;
        }
        FreqDist { counts }
    }
    /// Total count.
    pub fn total(&self) -> usize {
        self.counts
            .values()
            .fold(0usize, |a, &c| a.saturating_add(c))
    }
    /// Most frequent value (smallest on ties); `None` when empty.
    pub fn mode(&self) -> Option<usize> {
        let mut best: Option<(usize, usize)> = None;
        for (&v, &c) in &self.counts {
            if best.is_none_or(|(_, bc)| c > bc) {
                best = Some((v, c));
            }
        }
        best.map(|(v, _)| v)
    }
    /// Mean value rounded to the nearest integer (≥ 1); `None` when empty.
    pub fn mean_rounded(&self) -> Option<usize> {
        let t = self.total();
        if t == 0 {
            return None;
        }
        let s: f64 = self.counts.iter().map(|(&v, &c)| v as f64 * c as f64).sum();
        Some(((s / t as f64).round() as usize).max(1))
    }
    /// Draws a value with probability proportional to its count, from `u ∈ [0, 1)`.
    pub fn sample_with(&self, u: f64) -> Option<usize> {
        let t = self.total();
        if t == 0 {
            return None;
        }
        let target = u * t as f64;
        let mut acc = 0.0;
        for (&v, &c) in &self.counts {
            acc += c as f64;
            if target < acc {
                return Some(v);
            }
        }
        self.counts.keys().next_back().copied()
    }
}

/// A probabilistic abstract primitive: per joint a Gaussian over `<start, mid, end>`,
/// and a duration distribution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProbPrim {
    /// Duration distribution in frames.
    pub duration: FreqDist,
    /// Per joint Gaussian.
    pub joints: Vec<Gaussian>,
}

/// A `for` loop over probabilistic primitives.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Loop {
    /// Number of iterations (≥ 2 when detected; editing may set any ≥ 0).
    pub iterations: usize,
    /// Loop body (k probabilistic primitives).
    pub body: Vec<ProbPrim>,
    /// The observed iterations, one deterministic primitive sequence per
    /// iteration (kept so that the loop can be replayed exactly, an iteration
    /// dropped or repeated). May be empty for loops written by hand.
    #[serde(default)]
    pub observed: Vec<Vec<DetPrim>>,
}

/// A statement of an abstract program.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
#[non_exhaustive]
pub enum Stmt {
    /// A deterministic primitive.
    Prim(DetPrim),
    /// A loop.
    Loop(Loop),
}

/// An abstract motion program.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AbstractProgram {
    /// Frame rate the durations refer to.
    pub fps: f64,
    /// Units of positions (`px`, `m`, `1`).
    pub units: String,
    /// Spatial dimensions D (2 or 3).
    pub dims: usize,
    /// Track units per reference pixel of a 512-px frame (see mp-concrete's
    /// scale rule); execution uses it to scale the primitive-selection thresholds.
    #[serde(default = "one")]
    pub unit_scale: f64,
    /// Joint names.
    pub joints: Vec<String>,
    /// Statements in order.
    pub stmts: Vec<Stmt>,
}

fn one() -> f64 {
    1.0
}

impl AbstractProgram {
    /// Indices (into `stmts`) of the loops, in order.
    pub fn loop_indices(&self) -> Vec<usize> {
        self.stmts
            .iter()
            .enumerate()
            .filter_map(|(i, s)| matches!(s, Stmt::Loop(_)).then_some(i))
            .collect()
    }

    /// The n-th loop (0-based, in program order).
    pub fn loop_mut(&mut self, n: usize) -> Result<&mut Loop> {
        let count = self.loop_indices().len();
        let idx = self.loop_indices().get(n).copied().ok_or_else(|| {
            AbstractError::NotFound(format!("loop {n} (the program has {count} loops)"))
        })?;
        match &mut self.stmts[idx] {
            Stmt::Loop(l) => Ok(l),
            Stmt::Prim(_) => Err(AbstractError::NotFound(format!("loop {n}"))),
        }
    }

    /// Checks that every statement agrees with the header (joint count, dims)
    /// and holds finite numbers.
    pub fn validate(&self) -> Result<()> {
        if !(self.dims == 2 || self.dims == 3 || self.units == "1") || self.dims == 0 {
            return Err(AbstractError::Shape(format!(
                "dims must be 2 or 3, got {}",
                self.dims
            )));
        }
        if !matches!(self.units.as_str(), "px" | "m" | "1") {
            return Err(AbstractError::param(
                "units",
                format!("must be px, m or 1, got `{}`", self.units),
            ));
        }
        if self.joints.is_empty() {
            return Err(AbstractError::Shape("no joints".into()));
        }
        if let Some(bad) = self.joints.iter().find(|n| !crate::dsl::is_name(n)) {
            return Err(AbstractError::param(
                "joints",
                format!(
                    "`{bad}` is not a name (letters, digits, `_`, `-`, `.`, `|`, \
                     not starting like a number)"
                ),
            ));
        }
        if !(self.unit_scale.is_finite() && self.unit_scale > 0.0) {
            return Err(AbstractError::param(
                "unit_scale",
                format!("must be > 0, got {}", self.unit_scale),
            ));
        }
        if !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(AbstractError::param(
                "fps",
                format!("must be > 0, got {}", self.fps),
            ));
        }
        let n = 3 * self.dims;
        let j = self.joints.len();
        let max = crate::dsl::MAX_INTEGER;
        let check_det = |p: &DetPrim, at: &str| -> Result<()> {
            if p.duration == 0 {
                return Err(AbstractError::param(
                    "duration",
                    format!("{at}: must be ≥ 1"),
                ));
            }
            if p.duration > max {
                return Err(AbstractError::param(
                    "duration",
                    format!("{at}: must be ≤ {max}, got {}", p.duration),
                ));
            }
            if p.points.len() != j {
                return Err(AbstractError::Shape(format!(
                    "{at}: {} joints, header has {j}",
                    p.points.len()
                )));
            }
            for (ji, v) in p.points.iter().enumerate() {
                if v.len() != n {
                    return Err(AbstractError::Shape(format!(
                        "{at}, joint {ji}: {} values, expected {n}",
                        v.len()
                    )));
                }
                if v.iter().any(|x| !x.is_finite()) {
                    return Err(AbstractError::NonFinite(format!("{at}, joint {ji}")));
                }
            }
            Ok(())
        };
        for (si, s) in self.stmts.iter().enumerate() {
            match s {
                Stmt::Prim(p) => check_det(p, &format!("statement {si}"))?,
                Stmt::Loop(l) => {
                    if l.iterations > max {
                        return Err(AbstractError::InvalidLoop(format!(
                            "statement {si}: {} iterations, at most {max}",
                            l.iterations
                        )));
                    }
                    if l.body.is_empty() {
                        return Err(AbstractError::InvalidLoop(format!(
                            "statement {si}: empty loop body"
                        )));
                    }
                    for (bi, b) in l.body.iter().enumerate() {
                        let total = b
                            .duration
                            .counts
                            .values()
                            .try_fold(0usize, |a, &c| a.checked_add(c));
                        if total.is_none() {
                            return Err(AbstractError::InvalidLoop(format!(
                                "statement {si}, body {bi}: `duration` counts overflow"
                            )));
                        }
                        if b.duration.counts.iter().any(|(&v, &c)| v > max || c > max) {
                            return Err(AbstractError::InvalidLoop(format!(
                                "statement {si}, body {bi}: a `duration` value or count above {max}"
                            )));
                        }
                        if b.duration.total() == 0 || b.duration.counts.contains_key(&0) {
                            return Err(AbstractError::InvalidLoop(format!(
                                "statement {si}, body {bi}: `duration` distribution is empty or has 0"
                            )));
                        }
                        if b.joints.len() != j {
                            return Err(AbstractError::Shape(format!(
                                "statement {si}, body {bi}: {} joints, header has {j}",
                                b.joints.len()
                            )));
                        }
                        for (ji, g) in b.joints.iter().enumerate() {
                            if g.dim() != n {
                                return Err(AbstractError::Shape(format!(
                                    "statement {si}, body {bi}, joint {ji}: Gaussian `mean` of dimension {}, expected {n}",
                                    g.dim()
                                )));
                            }
                            g.validate(&format!("statement {si}, body {bi}, joint {ji}"))?;
                        }
                    }
                    for (ii, it) in l.observed.iter().enumerate() {
                        if it.len() != l.body.len() {
                            return Err(AbstractError::InvalidLoop(format!(
                                "statement {si}: observed iteration {ii} has {} primitives, body has {}",
                                it.len(),
                                l.body.len()
                            )));
                        }
                        for p in it {
                            check_det(p, &format!("statement {si}, iteration {ii}"))?;
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Expected number of frames when executed deterministically (mean durations).
    pub fn expected_frames(&self) -> usize {
        self.stmts
            .iter()
            .map(|s| match s {
                Stmt::Prim(p) => p.duration,
                Stmt::Loop(l) => l.iterations.saturating_mul(
                    l.body
                        .iter()
                        .map(|b| b.duration.mean_rounded().unwrap_or(1))
                        .fold(0usize, usize::saturating_add),
                ),
            })
            .fold(0usize, usize::saturating_add)
    }
}
