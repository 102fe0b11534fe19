//! Terminal symbol identification (paper §4): segment a motion and cluster
//! the segments into `K` symbols, maximising `F(C)` ([`crate::objective`]).
//!
//! The search space is every segmentation with `n ∈ [K, N]` segments whose
//! lengths lie in `[min_segment_frames, max_segment_frames]`; the clustering
//! of a segmentation is a function of it (k-medoids started from the first
//! `K` segments, [`crate::kmedoids`]). Two stages:
//!
//! 1. **Coarse: genetic algorithm** (§4.2) over bit-strings, one bit per
//!    candidate cut `t = step, 2·step, …` (`candidate_step_frames`, 30 by
//!    default). Population 100, up to 500 generations, stopping early after
//!    `stall_generations` generations without a better best. Selection is
//!    fitness-proportional (roulette on `F − F_min + 0.1 (F_max − F_min)` of
//!    the current population, so that selection pressure does not vanish when
//!    all scores are close), one-point crossover, per-bit mutation, `elite`
//!    best genomes copied unchanged. Every child is *repaired* to satisfy the
//!    constraints: cuts are added in the middle of segments that are too long,
//!    random cuts are removed while `n > N` and added while `n < K`. Fitness
//!    is evaluated in parallel (rayon) and cached per genome; segment
//!    distances between grid segments are cached in a lazily filled table
//!    shared by all threads, so each pair is computed once.
//! 2. **Fine: simulated annealing** (§4.3) from the best genome. Each
//!    iteration picks a random segment and applies *Slide* (move both of its
//!    boundaries by `±δ`) or *Resize* (move its end by `±δ`), `δ` uniform in
//!    `1..=d`. The step bound `d` shrinks geometrically from
//!    `initial_step_frames` to `min_step_frames` over `iterations` (1000 by
//!    default, the paper's count); the search then continues at the minimum
//!    step until `patience` iterations pass without improvement. Only the
//!    touched segments leave their clusters and are re-inserted into the
//!    cluster of the nearest medoid (a cluster left empty receives one of
//!    them first); the medoids of the touched clusters are recomputed and
//!    only their terms of `F` are updated. Segment distances are cached by
//!    interval. With `initial_temperature = 0` (default, as in the paper)
//!    only improvements are accepted; otherwise a worse move is accepted
//!    with probability `exp((F_new/F_cur − 1)/τ)`, `τ` decreasing linearly
//!    to 0, and the best state seen is returned.
//!
//! Everything random draws from one `ChaCha8Rng` seeded with `seed`; the
//! parallel parts are pure, so the same seed gives the same symbols.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::distance::{PoseFeatures, Segment};
use crate::error::{GrammarError, Result};
use crate::kmedoids::{first_k, Clustering, DenseMatrix, KMedoidsParams};
use crate::objective::{evaluate, ClusterQuality};

/// Parameters of the genetic algorithm (coarse search).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaParams {
    /// Genomes per generation. Default 100 (paper).
    pub population: usize,
    /// Maximum number of generations. Default 500 (paper).
    pub generations: usize,
    /// Stop when the best score has not improved for this many generations
    /// (the paper's "until the solutions converge"); 0 = never stop early.
    /// Default 50.
    pub stall_generations: usize,
    /// Probability of one-point crossover for a pair of parents. Default 0.9.
    pub crossover_rate: f64,
    /// Per-bit mutation probability; `None` = 1 / (number of candidate cuts).
    pub mutation_rate: Option<f64>,
    /// Best genomes copied unchanged into the next generation. Default 2.
    pub elite: usize,
    /// Probability that a bit is set in the initial population. Default 0.5.
    pub init_cut_probability: f64,
    /// Run one GA per chunk of this many candidate intervals (at least
    /// `2 K`), in parallel, and join the results: the paper's hierarchical
    /// scheme ("split each motion into several subsequences, run the genetic
    /// algorithm for initial segmentation of each subsequence"); the SA then
    /// refines the whole motion. `None` = one GA over the whole motion.
    /// Default `Some(64)` (1,920 frames at the default step).
    pub chunk_candidates: Option<usize>,
}

impl Default for GaParams {
    fn default() -> Self {
        GaParams {
            population: 100,
            generations: 500,
            stall_generations: 50,
            crossover_rate: 0.9,
            mutation_rate: None,
            elite: 2,
            init_cut_probability: 0.5,
            chunk_candidates: Some(64),
        }
    }
}

/// Parameters of the simulated annealing (fine search).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SaParams {
    /// Iterations over which the step shrinks. Default 1000 (paper).
    pub iterations: usize,
    /// Initial step bound `d` in frames; `None` = half the candidate step.
    pub initial_step_frames: Option<usize>,
    /// Final step bound in frames. Default 1.
    pub min_step_frames: usize,
    /// After `iterations`, continue until this many iterations pass without
    /// improvement. Default 200.
    pub patience: usize,
    /// Hard cap on iterations. Default 5 000.
    pub max_iterations: usize,
    /// Initial temperature τ (relative change of F); 0 = accept only
    /// improvements (paper). Default 0.
    pub initial_temperature: f64,
}

impl Default for SaParams {
    fn default() -> Self {
        SaParams {
            iterations: 1000,
            initial_step_frames: None,
            min_step_frames: 1,
            patience: 200,
            max_iterations: 5_000,
            initial_temperature: 0.0,
        }
    }
}

/// The most symbols K [`SymbolParams::validate`] accepts: 10 000 (K-medoids
/// keeps K medoids and a K × K symbol table; motions have far fewer
/// distinct units).
pub const MAX_SYMBOLS: usize = 10_000;

/// The largest GA population [`SymbolParams::validate`] accepts: 10 000
/// genomes (100 times the paper's; each genome holds one bit per candidate
/// cut, and every genome is scored each generation).
pub const MAX_POPULATION: usize = 10_000;

/// The most iterations [`SymbolParams::validate`] accepts for the GA's
/// generations, the simulated annealing (`iterations`, `max_iterations`) and
/// k-medoids: 1 million (the defaults are 500, 1 000 / 5 000 and tens), so
/// that an absurd count is an error rather than a run that never ends.
pub const MAX_ITERATIONS: usize = 1_000_000;

/// The longest segment window (`candidate_step_frames`, `min_segment_frames`,
/// `max_segment_frames`) [`SymbolParams::validate`] accepts: 10 million
/// frames, the most frames a track of one joint may have
/// (`mp_concrete::exec::MAX_FRAME_JOINTS`).
pub const MAX_SEGMENT_FRAMES: usize = 10_000_000;

/// Parameters of symbol identification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SymbolParams {
    /// Number of symbols K. Default 20 (paper's break-dance run).
    pub k: usize,
    /// Weight ω of `R` against `E′` in eq. 5, in `[0, 1]`. Default 0.5.
    pub omega: f64,
    /// Spacing of candidate cuts for the GA, frames. Default 30 (paper).
    pub candidate_step_frames: usize,
    /// Shortest segment, frames. Default 10.
    pub min_segment_frames: usize,
    /// Longest segment, frames; at least twice the candidate step. Default 240.
    pub max_segment_frames: usize,
    /// Most segments N; `None` = no limit beyond the lengths. Default `None`.
    pub max_segments: Option<usize>,
    /// Clustering of the segments. Default FasterPAM, 100 iterations.
    pub kmedoids: KMedoidsParams,
    /// Coarse search.
    pub ga: GaParams,
    /// Fine search.
    pub sa: SaParams,
    /// Seed of every random choice. Default 0.
    pub seed: u64,
}

impl Default for SymbolParams {
    fn default() -> Self {
        SymbolParams {
            k: 20,
            omega: 0.5,
            candidate_step_frames: 30,
            min_segment_frames: 10,
            max_segment_frames: 240,
            max_segments: None,
            kmedoids: KMedoidsParams::default(),
            ga: GaParams::default(),
            sa: SaParams::default(),
            seed: 0,
        }
    }
}

fn unit_interval(name: &'static str, v: f64) -> Result<()> {
    if !(0.0..=1.0).contains(&v) {
        return Err(GrammarError::param(
            name,
            format!("must be in [0, 1], got {v}"),
        ));
    }
    Ok(())
}

impl SymbolParams {
    /// Checks the parameters (independently of any track).
    pub fn validate(&self) -> Result<()> {
        if self.k == 0 {
            return Err(GrammarError::param("k", "must be ≥ 1"));
        }
        if self.k > MAX_SYMBOLS {
            return Err(GrammarError::param(
                "k",
                format!("{} is too large: at most {MAX_SYMBOLS}", self.k),
            ));
        }
        for (name, v) in [
            ("candidate_step_frames", self.candidate_step_frames),
            ("min_segment_frames", self.min_segment_frames),
            ("max_segment_frames", self.max_segment_frames),
        ] {
            if v > MAX_SEGMENT_FRAMES {
                return Err(GrammarError::param(
                    name,
                    format!("{v} is too large: at most {MAX_SEGMENT_FRAMES} frames"),
                ));
            }
        }
        unit_interval("omega", self.omega)?;
        if self.min_segment_frames == 0 {
            return Err(GrammarError::param("min_segment_frames", "must be ≥ 1"));
        }
        if self.candidate_step_frames < self.min_segment_frames {
            return Err(GrammarError::param(
                "candidate_step_frames",
                format!(
                    "must be ≥ min_segment_frames ({}), got {}",
                    self.min_segment_frames, self.candidate_step_frames
                ),
            ));
        }
        if self.max_segment_frames < 2 * self.candidate_step_frames {
            return Err(GrammarError::param(
                "max_segment_frames",
                format!(
                    "must be ≥ 2 × candidate_step_frames ({}), got {}",
                    2 * self.candidate_step_frames,
                    self.max_segment_frames
                ),
            ));
        }
        if let Some(n) = self.max_segments {
            if n < self.k {
                return Err(GrammarError::param(
                    "max_segments",
                    format!("must be ≥ k ({}), got {n}", self.k),
                ));
            }
        }
        if self.kmedoids.max_iter == 0 {
            return Err(GrammarError::param("kmedoids.max_iter", "must be ≥ 1"));
        }
        let ga = &self.ga;
        if ga.population < 2 {
            return Err(GrammarError::param("ga.population", "must be ≥ 2"));
        }
        if ga.population > MAX_POPULATION {
            return Err(GrammarError::param(
                "ga.population",
                format!("{} is too large: at most {MAX_POPULATION}", ga.population),
            ));
        }
        for (name, v) in [
            ("kmedoids.max_iter", self.kmedoids.max_iter),
            ("ga.generations", ga.generations),
            ("sa.iterations", self.sa.iterations),
            ("sa.max_iterations", self.sa.max_iterations),
        ] {
            if v > MAX_ITERATIONS {
                return Err(GrammarError::param(
                    name,
                    format!("{v} is too large: at most {MAX_ITERATIONS}"),
                ));
            }
        }
        if ga.elite >= ga.population {
            return Err(GrammarError::param(
                "ga.elite",
                format!("must be < population ({}), got {}", ga.population, ga.elite),
            ));
        }
        unit_interval("ga.crossover_rate", ga.crossover_rate)?;
        unit_interval("ga.init_cut_probability", ga.init_cut_probability)?;
        if let Some(m) = ga.mutation_rate {
            unit_interval("ga.mutation_rate", m)?;
        }
        let sa = &self.sa;
        if sa.min_step_frames == 0 {
            return Err(GrammarError::param("sa.min_step_frames", "must be ≥ 1"));
        }
        if let Some(s) = sa.initial_step_frames {
            if s < sa.min_step_frames {
                return Err(GrammarError::param(
                    "sa.initial_step_frames",
                    format!(
                        "must be ≥ min_step_frames ({}), got {s}",
                        sa.min_step_frames
                    ),
                ));
            }
        }
        if !(sa.initial_temperature.is_finite() && sa.initial_temperature >= 0.0) {
            return Err(GrammarError::param(
                "sa.initial_temperature",
                format!("must be finite and ≥ 0, got {}", sa.initial_temperature),
            ));
        }
        Ok(())
    }
}

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
    pub fn segment(&self) -> Segment {
        Segment::new(self.start, self.end)
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
pub struct SearchStats {
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
    pub stats: SearchStats,
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

// ---------------------------------------------------------------------------
// Small fast hasher for integer keys (FxHash-style multiply-rotate).

#[derive(Default, Clone, Copy)]
struct FxHasher(u64);

impl Hasher for FxHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(v as u64);
    }
}

type FxBuild = BuildHasherDefault<FxHasher>;

// ---------------------------------------------------------------------------
// Grid of candidate cuts and the shared segment-distance table.

struct Grid {
    /// Frame of each grid point: 0, candidates…, T.
    points: Vec<usize>,
    /// Widest span (in grid steps) of an admissible segment.
    width: usize,
}

impl Grid {
    /// Candidate cuts every `step` frames from `start`, keeping the last
    /// segment at least `min_segment_frames` long, then `end`.
    fn new(start: usize, end: usize, p: &SymbolParams) -> Self {
        let step = p.candidate_step_frames;
        let mut points = vec![start];
        let mut c = start + step;
        while c + p.min_segment_frames <= end {
            points.push(c);
            c += step;
        }
        points.push(end);
        let mut width = 1;
        for a in 0..points.len() {
            let mut b = a + 1;
            while b + 1 < points.len() && points[b + 1] - points[a] <= p.max_segment_frames {
                b += 1;
            }
            width = width.max(b - a);
        }
        Grid { points, width }
    }
    fn n_candidates(&self) -> usize {
        self.points.len() - 2
    }
    fn id(&self, a: usize, b: usize) -> usize {
        a * self.width + (b - a - 1)
    }
}

/// Segment-pair distance cache for grid segments (values rounded to `f32`,
/// which halves the memory traffic of the GA's inner loop).
enum PairCache {
    Dense {
        cells: Vec<AtomicU32>,
    },
    Sparse {
        shards: Vec<std::sync::Mutex<HashMap<u64, f64, FxBuild>>>,
    },
}

const SET: u32 = 1 << 31;
const DENSE_LIMIT: usize = 1 << 26;

impl PairCache {
    fn new(n_ids: usize) -> Self {
        let cells = n_ids.saturating_mul(n_ids.saturating_sub(1)) / 2;
        if cells <= DENSE_LIMIT {
            PairCache::Dense {
                cells: (0..cells).map(|_| AtomicU32::new(0)).collect(),
            }
        } else {
            PairCache::Sparse {
                shards: (0..64).map(|_| Default::default()).collect(),
            }
        }
    }

    fn get_or(&self, x: usize, y: usize, f: impl FnOnce() -> f64) -> f64 {
        let (lo, hi) = if x < y { (x, y) } else { (y, x) };
        if lo == hi {
            return 0.0;
        }
        let idx = hi * (hi - 1) / 2 + lo;
        match self {
            PairCache::Dense { cells } => {
                let v = cells[idx].load(Ordering::Relaxed);
                if v & SET != 0 {
                    return f32::from_bits(v & !SET) as f64;
                }
                let d = f() as f32;
                cells[idx].store(d.to_bits() | SET, Ordering::Relaxed);
                d as f64
            }
            PairCache::Sparse { shards } => {
                let key = idx as u64;
                let shard = &shards[(key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 58) as usize];
                if let Some(&d) = shard
                    .lock()
                    .ok()
                    .and_then(|m| m.get(&key).copied())
                    .as_ref()
                {
                    return d;
                }
                let d = f() as f32 as f64;
                if let Ok(mut m) = shard.lock() {
                    m.insert(key, d);
                }
                d
            }
        }
    }
}

/// Everything a fitness evaluation needs (shared by all threads).
struct Problem<'a> {
    feat: &'a PoseFeatures,
    /// Frames covered by the grid (the `T` of the objective).
    span_frames: usize,
    params: &'a SymbolParams,
    grid: Grid,
    cache: PairCache,
    d_max: f64,
}

/// The clustered segmentation of one genome.
struct Scored {
    f: f64,
    bounds: Vec<usize>,
}

impl Problem<'_> {
    fn bounds_of(&self, bits: &[bool]) -> Vec<usize> {
        let mut b = Vec::with_capacity(bits.len() + 2);
        b.push(0);
        for (i, &on) in bits.iter().enumerate() {
            if on {
                b.push(i + 1);
            }
        }
        b.push(self.grid.points.len() - 1);
        b
    }

    fn score(&self, bits: &[bool]) -> Result<Scored> {
        let gb = self.bounds_of(bits);
        let n = gb.len() - 1;
        let pts = &self.grid.points;
        let ids: Vec<usize> = (0..n).map(|i| self.grid.id(gb[i], gb[i + 1])).collect();
        let segs: Vec<Segment> = (0..n)
            .map(|i| Segment::new(pts[gb[i]], pts[gb[i + 1]]))
            .collect();
        let m = DenseMatrix::from_fn(n, |i, j| {
            self.cache.get_or(ids[i], ids[j], || {
                self.feat.segment_distance_unchecked(segs[i], segs[j])
            })
        });
        let clustering = self.params.kmedoids.fit(&m, &first_k(self.params.k))?;
        let lengths: Vec<usize> = segs.iter().map(|s| s.len()).collect();
        let q = evaluate(
            &lengths,
            &clustering.medoids,
            &clustering.assignment,
            |i, j| crate::kmedoids::Dissimilarity::get(&m, i, j),
            self.span_frames,
            self.d_max,
            self.params.omega,
        );
        let bounds = gb.iter().map(|&g| pts[g]).collect();
        Ok(Scored { f: q.f, bounds })
    }

    /// Makes a genome satisfy the length and count constraints.
    fn repair(&self, bits: &mut [bool], rng: &mut ChaCha8Rng) {
        let pts = &self.grid.points;
        let max_len = self.params.max_segment_frames;
        // 1. Split segments that are too long (cut in the middle candidate).
        loop {
            let gb = self.bounds_of(bits);
            let mut changed = false;
            for w in gb.windows(2) {
                if pts[w[1]] - pts[w[0]] > max_len && w[1] - w[0] >= 2 {
                    let mid = (w[0] + w[1]) / 2;
                    bits[mid - 1] = true;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        let count = |bits: &[bool]| bits.iter().filter(|&&b| b).count() + 1;
        // 2. Too many segments: remove random cuts whose removal keeps lengths.
        if let Some(n_max) = self.params.max_segments {
            let mut n = count(bits);
            if n > n_max {
                let mut on: Vec<usize> = (0..bits.len()).filter(|&i| bits[i]).collect();
                shuffle(&mut on, rng);
                for i in on {
                    if n <= n_max {
                        break;
                    }
                    let prev = (0..i).rev().find(|&j| bits[j]).map_or(0, |j| j + 1);
                    let next = (i + 1..bits.len())
                        .find(|&j| bits[j])
                        .map_or(pts.len() - 1, |j| j + 1);
                    if pts[next] - pts[prev] <= max_len {
                        bits[i] = false;
                        n -= 1;
                    }
                }
            }
        }
        // 3. Too few segments: add random cuts.
        let n = count(bits);
        if n < self.params.k {
            let mut off: Vec<usize> = (0..bits.len()).filter(|&i| !bits[i]).collect();
            shuffle(&mut off, rng);
            for i in off.into_iter().take(self.params.k - n) {
                bits[i] = true;
            }
        }
    }
}

fn shuffle<T>(v: &mut [T], rng: &mut ChaCha8Rng) {
    for i in (1..v.len()).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
}

/// Scores a given segmentation (boundaries `0 = b_0 < … < b_n = T`): the
/// clustering from the first `K` segments and `F`. Useful to compare
/// segmentations (e.g. ground-truth blocks) under the same objective.
pub fn score_segmentation(
    features: &PoseFeatures,
    bounds: &[usize],
    params: &SymbolParams,
) -> Result<(Clustering, ClusterQuality)> {
    params.validate()?;
    let t = features.n_frames();
    if bounds.len() < 2 || bounds[0] != 0 || bounds[bounds.len() - 1] != t {
        return Err(GrammarError::Invalid(format!(
            "segment boundaries must start at 0 and end at {t}"
        )));
    }
    if let Some(w) = bounds.windows(2).find(|w| w[1] <= w[0]) {
        return Err(GrammarError::Invalid(format!(
            "segment boundaries must increase, got {} then {}",
            w[0], w[1]
        )));
    }
    let n = bounds.len() - 1;
    if n < params.k {
        return Err(GrammarError::too_short(
            format!("clustering into k = {} symbols (segments)", params.k),
            params.k,
            n,
        ));
    }
    cluster_bounds(features, bounds, params, features.max_pose_distance())
}

/// Identifies `K` terminal symbols in a motion (GA then SA; see the module
/// documentation).
///
/// Errors: invalid parameters; a motion too short for `K` segments of at
/// least `min_segment_frames` on the candidate grid.
pub fn identify_symbols(features: &PoseFeatures, params: &SymbolParams) -> Result<SymbolString> {
    params.validate()?;
    let t = features.n_frames();
    let p = params;
    let need = p.k * p.candidate_step_frames.max(p.min_segment_frames);
    if t < p.min_segment_frames.max(1) || t < need.min(p.k * p.candidate_step_frames) {
        return Err(GrammarError::too_short(
            format!(
                "motion (frames) for k = {} segments of {} frames",
                p.k, p.candidate_step_frames
            ),
            need,
            t,
        ));
    }
    let grid = Grid::new(0, t, p);
    if grid.n_candidates() + 1 < p.k {
        return Err(GrammarError::too_short(
            format!(
                "motion: candidate cuts every {} frames for k = {} segments (frames)",
                p.candidate_step_frames, p.k
            ),
            p.k * p.candidate_step_frames,
            t,
        ));
    }
    let mut stats = SearchStats::default();
    let t0 = Instant::now();
    let d_max = features.max_pose_distance();
    stats.seconds_dmax = t0.elapsed().as_secs_f64();

    // ---- GA, per chunk of the candidate grid (the paper's hierarchical scheme)
    let t1 = Instant::now();
    let intervals = grid.points.len() - 1;
    let per_chunk = p.ga.chunk_candidates.map_or(intervals, |c| c.max(2 * p.k));
    let n_chunks = (intervals / per_chunk.max(1)).max(1);
    let edges: Vec<usize> = (0..=n_chunks)
        .map(|j| grid.points[j * intervals / n_chunks])
        .collect();
    let chunk_results: Vec<Result<(Scored, SearchStats)>> = (0..n_chunks)
        .into_par_iter()
        .map(|ci| {
            let g = Grid::new(edges[ci], edges[ci + 1], p);
            let n_ids = g.points.len() * g.width;
            let problem = Problem {
                feat: features,
                span_frames: edges[ci + 1] - edges[ci],
                params: p,
                cache: PairCache::new(n_ids),
                grid: g,
                d_max,
            };
            let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
            rng.set_stream(ci as u64 + 1);
            let mut st = SearchStats::default();
            let best = run_ga(&problem, &mut rng, &mut st)?;
            Ok((best, st))
        })
        .collect();
    let mut bounds = vec![0usize];
    for r in chunk_results {
        let (best, st) = r?;
        stats.ga_generations = stats.ga_generations.max(st.ga_generations);
        stats.ga_evaluations += st.ga_evaluations;
        bounds.extend_from_slice(&best.bounds[1..]);
    }
    let (clustering, quality) = cluster_bounds(features, &bounds, p, d_max)?;
    stats.ga_best_f = quality.f;
    stats.seconds_ga = t1.elapsed().as_secs_f64();

    // ---- SA over the whole motion
    let t2 = Instant::now();
    let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
    let mut sa = Annealer::new(features, p, d_max, &bounds, &clustering);
    sa.run(&p.sa, p.candidate_step_frames, &mut rng, &mut stats);
    stats.seconds_sa = t2.elapsed().as_secs_f64();
    Ok(sa.into_symbols(features, p, d_max, stats))
}

/// Clusters a segmentation from its first `K` segments (distances computed
/// in parallel) and evaluates `F`.
fn cluster_bounds(
    features: &PoseFeatures,
    bounds: &[usize],
    p: &SymbolParams,
    d_max: f64,
) -> Result<(Clustering, ClusterQuality)> {
    let n = bounds.len() - 1;
    let segs: Vec<Segment> = bounds
        .windows(2)
        .map(|w| Segment::new(w[0], w[1]))
        .collect();
    let rows: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|i| {
            (0..n)
                .map(|j| {
                    if j > i {
                        features.segment_distance_unchecked(segs[i], segs[j])
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let m = DenseMatrix::from_fn(n, |i, j| rows[i][j]);
    let c = p.kmedoids.fit(&m, &first_k(p.k))?;
    let lengths: Vec<usize> = segs.iter().map(|s| s.len()).collect();
    let q = evaluate(
        &lengths,
        &c.medoids,
        &c.assignment,
        |i, j| crate::kmedoids::Dissimilarity::get(&m, i, j),
        features.n_frames(),
        d_max,
        p.omega,
    );
    Ok((c, q))
}

fn run_ga(problem: &Problem<'_>, rng: &mut ChaCha8Rng, stats: &mut SearchStats) -> Result<Scored> {
    let p = problem.params;
    let ga = &p.ga;
    let n_bits = problem.grid.n_candidates();
    let mutation = ga.mutation_rate.unwrap_or(1.0 / n_bits.max(1) as f64);
    let mut fitness_cache: HashMap<Vec<bool>, f64> = HashMap::new();

    let mut pop: Vec<Vec<bool>> = (0..ga.population)
        .map(|_| {
            let mut g: Vec<bool> = (0..n_bits)
                .map(|_| rng.random::<f64>() < ga.init_cut_probability)
                .collect();
            problem.repair(&mut g, rng);
            g
        })
        .collect();

    let evaluate_pop = |pop: &[Vec<bool>],
                        cache: &mut HashMap<Vec<bool>, f64>,
                        stats: &mut SearchStats|
     -> Result<Vec<f64>> {
        let mut todo: Vec<&Vec<bool>> = pop.iter().filter(|g| !cache.contains_key(*g)).collect();
        todo.sort();
        todo.dedup();
        let scores: Vec<Result<f64>> = todo
            .par_iter()
            .map(|g| problem.score(g).map(|s| s.f))
            .collect();
        stats.ga_evaluations += todo.len();
        for (g, s) in todo.into_iter().zip(scores) {
            cache.insert(g.clone(), s?);
        }
        Ok(pop
            .iter()
            .map(|g| cache.get(g).copied().unwrap_or(0.0))
            .collect())
    };

    let mut fit = evaluate_pop(&pop, &mut fitness_cache, stats)?;
    let mut best_f = f64::NEG_INFINITY;
    let mut best_g = pop[0].clone();
    let mut stall = 0;
    for gen in 0..ga.generations {
        stats.ga_generations = gen + 1;
        // Track the best.
        let mut order: Vec<usize> = (0..pop.len()).collect();
        order.sort_by(|&a, &b| fit[b].total_cmp(&fit[a]).then(a.cmp(&b)));
        if fit[order[0]] > best_f * (1.0 + 1e-12) || best_f == f64::NEG_INFINITY {
            if fit[order[0]] > best_f {
                best_f = fit[order[0]];
                best_g = pop[order[0]].clone();
            }
            stall = 0;
        } else {
            stall += 1;
            if ga.stall_generations > 0 && stall >= ga.stall_generations {
                break;
            }
        }
        if gen + 1 == ga.generations {
            break;
        }
        // Windowed roulette weights.
        let f_max = fit[order[0]];
        let f_min = fit[order[order.len() - 1]];
        let base = f_min - 0.1 * (f_max - f_min);
        let weights: Vec<f64> = fit.iter().map(|&f| (f - base).max(0.0) + 1e-300).collect();
        let total: f64 = weights.iter().sum();
        let pick = |rng: &mut ChaCha8Rng| -> usize {
            let mut x = rng.random::<f64>() * total;
            for (i, w) in weights.iter().enumerate() {
                if x < *w {
                    return i;
                }
                x -= w;
            }
            weights.len() - 1
        };
        let mut next: Vec<Vec<bool>> = order[..ga.elite].iter().map(|&i| pop[i].clone()).collect();
        while next.len() < ga.population {
            let a = pick(rng);
            let b = pick(rng);
            let (mut c1, mut c2) = (pop[a].clone(), pop[b].clone());
            if n_bits > 1 && rng.random::<f64>() < ga.crossover_rate {
                let cut = rng.random_range(1..n_bits);
                for i in cut..n_bits {
                    std::mem::swap(&mut c1[i], &mut c2[i]);
                }
            }
            for c in [&mut c1, &mut c2] {
                for bit in c.iter_mut() {
                    if rng.random::<f64>() < mutation {
                        *bit = !*bit;
                    }
                }
                problem.repair(c, rng);
            }
            next.push(c1);
            if next.len() < ga.population {
                next.push(c2);
            }
        }
        pop = next;
        fit = evaluate_pop(&pop, &mut fitness_cache, stats)?;
    }
    problem.score(&best_g)
}

// ---------------------------------------------------------------------------
// Simulated annealing with incremental cluster updates.

type IntervalKey = (u32, u32, u32, u32);

struct Annealer<'a> {
    feat: &'a PoseFeatures,
    omega: f64,
    d_max: f64,
    t: usize,
    min_len: usize,
    max_len: usize,
    bounds: Vec<usize>,
    label: Vec<usize>,
    members: Vec<Vec<usize>>,
    medoid: Vec<usize>,
    /// Σ_{i ∈ C_k} L(s_i) D(s_i, medoid_k).
    cost: Vec<f64>,
    cache: HashMap<IntervalKey, f64, FxBuild>,
    f: f64,
}

struct BestState {
    bounds: Vec<usize>,
    label: Vec<usize>,
    members: Vec<Vec<usize>>,
    medoid: Vec<usize>,
    cost: Vec<f64>,
    f: f64,
}

struct Snapshot {
    bounds: Vec<(usize, usize)>,
    labels: Vec<(usize, usize)>,
    clusters: Vec<(usize, Vec<usize>, usize, f64)>,
    f: f64,
}

impl<'a> Annealer<'a> {
    fn new(
        feat: &'a PoseFeatures,
        p: &SymbolParams,
        d_max: f64,
        bounds: &[usize],
        c: &Clustering,
    ) -> Self {
        let k = c.medoids.len();
        let mut label = c.assignment.clone();
        for (slot, &m) in c.medoids.iter().enumerate() {
            label[m] = slot;
        }
        let mut members = vec![Vec::new(); k];
        for (i, &l) in label.iter().enumerate() {
            members[l].push(i);
        }
        let mut a = Annealer {
            feat,
            omega: p.omega,
            d_max,
            t: feat.n_frames(),
            min_len: p.min_segment_frames,
            max_len: p.max_segment_frames,
            bounds: bounds.to_vec(),
            label,
            members,
            medoid: c.medoids.clone(),
            cost: vec![0.0; k],
            cache: HashMap::default(),
            f: 0.0,
        };
        for kk in 0..k {
            a.cost[kk] = a.cluster_cost(kk);
        }
        a.f = a.quality().f;
        a
    }

    fn seg(&self, i: usize) -> Segment {
        Segment::new(self.bounds[i], self.bounds[i + 1])
    }

    fn dist(&mut self, i: usize, j: usize) -> f64 {
        if i == j {
            return 0.0;
        }
        let (a, b) = (self.seg(i), self.seg(j));
        let (x, y) = if (a.start, a.end) <= (b.start, b.end) {
            (a, b)
        } else {
            (b, a)
        };
        let key = (x.start as u32, x.end as u32, y.start as u32, y.end as u32);
        if let Some(&d) = self.cache.get(&key) {
            return d;
        }
        let d = self.feat.segment_distance_unchecked(x, y);
        self.cache.insert(key, d);
        d
    }

    fn cluster_cost(&mut self, k: usize) -> f64 {
        let m = self.medoid[k];
        let mem = self.members[k].clone();
        mem.iter()
            .map(|&i| self.seg(i).len() as f64 * self.dist(i, m))
            .sum()
    }

    fn quality(&self) -> ClusterQuality {
        let t = self.t as f64;
        let r = self
            .medoid
            .iter()
            .map(|&m| self.seg(m).len() as f64)
            .sum::<f64>()
            / t;
        let e: f64 = self.cost.iter().sum();
        let e_prime = if self.d_max > 0.0 {
            e / (t * self.d_max)
        } else {
            0.0
        };
        ClusterQuality::from_terms(r, e_prime, self.omega)
    }

    /// Medoid of cluster `k`: the member with the least sum of distances to
    /// the other members (ties: lowest segment index).
    fn best_medoid(&mut self, k: usize) -> usize {
        let mem = self.members[k].clone();
        let mut best = (f64::INFINITY, usize::MAX);
        for &c in &mem {
            let s: f64 = mem.iter().map(|&o| self.dist(o, c)).sum();
            if s < best.0 || (s == best.0 && c < best.1) {
                best = (s, c);
            }
        }
        best.1
    }

    fn valid_len(&self, len: usize) -> bool {
        len >= self.min_len && len <= self.max_len
    }

    /// Tries one move; returns `Some(snapshot)` when applied.
    fn apply(&mut self, moved: &[usize], delta: isize) -> Option<Snapshot> {
        let n = self.bounds.len() - 1;
        // New boundary values.
        let mut newb = Vec::with_capacity(moved.len());
        for &b in moved {
            let v = self.bounds[b] as isize + delta;
            if v <= 0 || v >= self.t as isize {
                return None;
            }
            newb.push((b, v as usize));
        }
        let mut affected: Vec<usize> = Vec::new();
        for &b in moved {
            for s in [b - 1, b] {
                if s < n && !affected.contains(&s) {
                    affected.push(s);
                }
            }
        }
        affected.sort_unstable();
        let val = |b: usize| {
            newb.iter()
                .find(|(x, _)| *x == b)
                .map_or(self.bounds[b], |v| v.1)
        };
        for &s in &affected {
            let (a, e) = (val(s), val(s + 1));
            if e <= a || !self.valid_len(e - a) {
                return None;
            }
        }
        let mut touched: Vec<usize> = affected.iter().map(|&s| self.label[s]).collect();
        touched.sort_unstable();
        touched.dedup();
        let snap = Snapshot {
            bounds: moved.iter().map(|&b| (b, self.bounds[b])).collect(),
            labels: affected.iter().map(|&s| (s, self.label[s])).collect(),
            clusters: touched
                .iter()
                .map(|&k| (k, self.members[k].clone(), self.medoid[k], self.cost[k]))
                .collect(),
            f: self.f,
        };
        // Remove the affected segments from their clusters.
        for &s in &affected {
            let k = self.label[s];
            self.members[k].retain(|&x| x != s);
        }
        for &(b, v) in &newb {
            self.bounds[b] = v;
        }
        let mut changed = touched.clone();
        // Clusters that lost their medoid get a new one from what remains.
        for &k in &touched {
            if affected.contains(&self.medoid[k]) && !self.members[k].is_empty() {
                self.medoid[k] = self.best_medoid(k);
            }
        }
        // Re-insert: empty clusters first, then nearest medoid.
        let mut pending = affected.clone();
        for &k in &touched {
            if self.members[k].is_empty() && !pending.is_empty() {
                let s = pending.remove(0);
                self.members[k].push(s);
                self.label[s] = k;
                self.medoid[k] = s;
            }
        }
        for s in pending {
            let mut best = (f64::INFINITY, 0);
            for k in 0..self.medoid.len() {
                let m = self.medoid[k];
                if affected.contains(&m) && self.members[k] != [m] {
                    // Medoid still being re-inserted; cannot happen after the
                    // steps above, kept for safety.
                    continue;
                }
                let d = self.dist(s, m);
                if d < best.0 {
                    best = (d, k);
                }
            }
            let k = best.1;
            self.members[k].push(s);
            self.label[s] = k;
            if !changed.contains(&k) {
                changed.push(k);
            }
        }
        // Recompute medoids and costs of every changed cluster.
        let mut snap = snap;
        for &k in &changed {
            if !snap.clusters.iter().any(|c| c.0 == k) {
                snap.clusters
                    .push((k, self.members[k].clone(), self.medoid[k], self.cost[k]));
                // The snapshot must hold the state before insertion.
                if let Some(last) = snap.clusters.last_mut() {
                    last.1.retain(|x| !affected.contains(x));
                }
            }
        }
        for &k in &changed {
            self.members[k].sort_unstable();
            self.medoid[k] = self.best_medoid(k);
            self.cost[k] = self.cluster_cost(k);
        }
        self.f = self.quality().f;
        Some(snap)
    }

    fn revert(&mut self, snap: Snapshot) {
        for (b, v) in snap.bounds {
            self.bounds[b] = v;
        }
        for (s, l) in snap.labels {
            self.label[s] = l;
        }
        for (k, mem, med, cost) in snap.clusters {
            self.members[k] = mem;
            self.medoid[k] = med;
            self.cost[k] = cost;
        }
        self.f = snap.f;
    }

    fn run(&mut self, sa: &SaParams, step: usize, rng: &mut ChaCha8Rng, stats: &mut SearchStats) {
        let n = self.bounds.len() - 1;
        if n < 2 {
            return;
        }
        let dmin = sa.min_step_frames;
        let d0 = sa.initial_step_frames.unwrap_or(step / 2).max(dmin);
        let iters = sa.iterations.max(1);
        let mut best_f = self.f;
        let mut best_state: Option<BestState> = None;
        let mut since = 0usize;
        let mut it = 0usize;
        loop {
            if it >= sa.max_iterations || (it >= sa.iterations && since >= sa.patience) {
                break;
            }
            let frac = (it as f64 / iters as f64).min(1.0);
            let d = ((d0 as f64) * (dmin as f64 / d0 as f64).powf(frac))
                .round()
                .max(dmin as f64) as usize;
            let tau = sa.initial_temperature * (1.0 - frac);
            it += 1;
            let i = rng.random_range(0..n);
            let slide = rng.random_bool(0.5);
            let mag = rng.random_range(1..=d) as isize;
            let delta = if rng.random_bool(0.5) { mag } else { -mag };
            let moved: Vec<usize> = if slide {
                [i, i + 1]
                    .into_iter()
                    .filter(|&b| b >= 1 && b < n)
                    .collect()
            } else if i + 1 < n {
                vec![i + 1]
            } else {
                vec![i]
            };
            let old_f = self.f;
            let Some(snap) = self.apply(&moved, delta) else {
                since += 1;
                continue;
            };
            let accept = if self.f > old_f {
                true
            } else if tau > 0.0 && old_f > 0.0 {
                let x: f64 = rng.random();
                x < ((self.f / old_f - 1.0) / tau).exp()
            } else {
                false
            };
            if accept {
                stats.sa_accepted += 1;
            } else {
                self.revert(snap);
            }
            if self.f > best_f * (1.0 + 1e-12) {
                best_f = self.f;
                since = 0;
                if sa.initial_temperature > 0.0 {
                    best_state = Some(self.save());
                }
            } else {
                since += 1;
            }
        }
        stats.sa_iterations = it;
        if let Some(b) = best_state {
            if b.f > self.f {
                self.restore(b);
            }
        }
    }

    fn save(&self) -> BestState {
        BestState {
            bounds: self.bounds.clone(),
            label: self.label.clone(),
            members: self.members.clone(),
            medoid: self.medoid.clone(),
            cost: self.cost.clone(),
            f: self.f,
        }
    }

    fn restore(&mut self, b: BestState) {
        self.bounds = b.bounds;
        self.label = b.label;
        self.members = b.members;
        self.medoid = b.medoid;
        self.cost = b.cost;
        self.f = b.f;
    }

    fn into_symbols(
        self,
        feat: &PoseFeatures,
        p: &SymbolParams,
        d_max: f64,
        stats: SearchStats,
    ) -> SymbolString {
        let n = self.bounds.len() - 1;
        // Number symbols by first occurrence.
        let k = self.medoid.len();
        let mut rename = vec![usize::MAX; k];
        let mut next = 0;
        for i in 0..n {
            let l = self.label[i];
            if rename[l] == usize::MAX {
                rename[l] = next;
                next += 1;
            }
        }
        for r in rename.iter_mut() {
            if *r == usize::MAX {
                *r = next;
                next += 1;
            }
        }
        let segments = (0..n)
            .map(|i| SymbolSegment {
                start: self.bounds[i],
                end: self.bounds[i + 1],
                symbol: rename[self.label[i]],
            })
            .collect();
        let mut medoids = vec![0; k];
        for (old, &m) in self.medoid.iter().enumerate() {
            medoids[rename[old]] = m;
        }
        SymbolString {
            k: p.k,
            n_frames: feat.n_frames(),
            fps: feat.fps(),
            segments,
            medoids,
            quality: self.quality(),
            d_max,
            stats,
        }
    }
}
