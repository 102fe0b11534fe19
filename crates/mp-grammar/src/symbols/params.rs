//! Parameters of symbol identification: the GA and SA settings, the limits
//! on their sizes, and [`SymbolParams::validate`].

use serde::{Deserialize, Serialize};

use crate::error::{GrammarError, Result};
use crate::kmedoids::KMedoidsParams;

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
/// (`mp_geom::MAX_FRAME_JOINTS`).
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
