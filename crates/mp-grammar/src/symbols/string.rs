//! The result of symbol identification: the labelled segments, the search
//! counters, and symbol names.

use serde::{Deserialize, Serialize};

use crate::distance::FrameSpan;
use crate::objective::ClusterQuality;

/// One labelled segment of the symbol string.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SymbolSegment {
    /// First frame.
    pub start: usize,
    /// One past the last frame.
    pub end: usize,
    /// Symbol index (0-based; symbols are numbered by first occurrence).
    pub symbol: usize,
}

impl SymbolSegment {
    /// The frame interval.
    pub fn segment(&self) -> FrameSpan {
        FrameSpan::new(self.start, self.end)
    }
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.end.saturating_sub(self.start)
    }
    /// True when the segment has no frame.
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }
}

/// Counters and timings of a search.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SymbolSearchStats {
    /// GA generations run.
    pub ga_generations: usize,
    /// Distinct genomes evaluated.
    pub ga_evaluations: usize,
    /// Best `F` after the GA.
    pub ga_best_f: f64,
    /// SA iterations run.
    pub sa_iterations: usize,
    /// SA moves accepted.
    pub sa_accepted: usize,
    /// Seconds spent computing `d_max`.
    pub seconds_dmax: f64,
    /// Seconds spent in the GA.
    pub seconds_ga: f64,
    /// Seconds spent in the SA.
    pub seconds_sa: f64,
}

/// The result of symbol identification: segments labelled with `K` symbols.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SymbolString {
    /// Number of symbols K.
    pub k: usize,
    /// Frames of the source motion.
    pub n_frames: usize,
    /// Frame rate of the source motion.
    pub fps: f64,
    /// Segments in time order, covering `0..n_frames`.
    pub segments: Vec<SymbolSegment>,
    /// Medoid segment (index into `segments`) of each symbol.
    pub medoids: Vec<usize>,
    /// Objective terms of the result.
    pub quality: ClusterQuality,
    /// Largest pose distance `d_max` used in `E′`.
    pub d_max: f64,
    /// Search counters.
    pub stats: SymbolSearchStats,
}

/// Name of symbol `i`: `a`–`z`, then `A`–`Z`, then `s52`, `s53`, ….
pub fn symbol_name(i: usize) -> String {
    const LOWER: &[u8; 26] = b"abcdefghijklmnopqrstuvwxyz";
    const UPPER: &[u8; 26] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZ";
    match i {
        0..=25 => (LOWER[i] as char).to_string(),
        26..=51 => (UPPER[i - 26] as char).to_string(),
        _ => format!("s{i}"),
    }
}

impl SymbolString {
    /// Symbol index of every segment.
    pub fn symbols(&self) -> Vec<usize> {
        self.segments.iter().map(|s| s.symbol).collect()
    }
    /// Symbol names of every segment.
    pub fn names(&self) -> Vec<String> {
        self.segments
            .iter()
            .map(|s| symbol_name(s.symbol))
            .collect()
    }
    /// The string as space-separated symbol names.
    pub fn text(&self) -> String {
        self.names().join(" ")
    }
    /// Symbol of every frame (length `n_frames`).
    pub fn frame_symbols(&self) -> Vec<usize> {
        let mut out = vec![0; self.n_frames];
        for s in &self.segments {
            for v in out.iter_mut().take(s.end.min(self.n_frames)).skip(s.start) {
                *v = s.symbol;
            }
        }
        out
    }
    /// Segments of each symbol (indices into `segments`).
    pub fn members(&self) -> Vec<Vec<usize>> {
        let mut m = vec![Vec::new(); self.k];
        for (i, s) in self.segments.iter().enumerate() {
            if let Some(v) = m.get_mut(s.symbol) {
                v.push(i);
            }
        }
        m
    }
}
