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
//!
//! # Layout
//!
//! * `params`: [`SymbolParams`] with [`GaParams`] and [`SaParams`], their
//!   defaults, limits and validation.
//! * `string`: the result, [`SymbolString`] of [`SymbolSegment`]s with
//!   [`SymbolSearchStats`], and [`symbol_name`].
//! * `cluster`: segment distances and the clustering of a segmentation —
//!   the candidate grid, the shared segment-distance table, k-medoids from
//!   the first `K` segments and `F`.
//! * `ga`: stage 1, the genetic algorithm with genome repair.
//! * `anneal`: stage 2, the simulated annealing with incremental cluster
//!   updates.
//! * this module: [`identify_symbols`], which runs the two stages.

use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::distance::PoseFeatures;
use crate::error::{GrammarError, Result};

mod anneal;
mod cluster;
mod ga;
mod params;
mod string;

pub use params::{GaParams, SaParams, SymbolParams};
#[cfg(test)]
pub(crate) use params::{MAX_ITERATIONS, MAX_POPULATION, MAX_SEGMENT_FRAMES, MAX_SYMBOLS};
pub use string::{symbol_name, SymbolSearchStats, SymbolSegment, SymbolString};

use anneal::Annealer;
use cluster::{cluster_bounds, Grid, PairCache};
use ga::{run_ga, Problem, Scored};

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
    let mut stats = SymbolSearchStats::default();
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
    let chunk_results: Vec<Result<(Scored, SymbolSearchStats)>> = (0..n_chunks)
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
            let mut st = SymbolSearchStats::default();
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
