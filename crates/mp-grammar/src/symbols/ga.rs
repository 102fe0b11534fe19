//! Stage 1, the coarse search (§4.2): a genetic algorithm over bit-strings
//! of candidate cuts; every child is repaired to satisfy the length and
//! count constraints, and fitness is evaluated in parallel and cached per
//! genome.

use std::collections::HashMap;

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::cluster::{Grid, PairCache};
use super::{SymbolParams, SymbolSearchStats};
use crate::derive::pick_weighted;
use crate::distance::{FrameSpan, PoseFeatures};
use crate::error::Result;
use crate::kmedoids::{first_k, DenseMatrix};
use crate::objective::evaluate;

/// Everything a fitness evaluation needs (shared by all threads).
pub(super) struct Problem<'a> {
    pub(super) feat: &'a PoseFeatures,
    /// Frames covered by the grid (the `T` of the objective).
    pub(super) span_frames: usize,
    pub(super) params: &'a SymbolParams,
    pub(super) grid: Grid,
    pub(super) cache: PairCache,
    pub(super) d_max: f64,
}

/// The clustered segmentation of one genome.
pub(super) struct Scored {
    f: f64,
    pub(super) bounds: Vec<usize>,
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
        let segs: Vec<FrameSpan> = (0..n)
            .map(|i| FrameSpan::new(pts[gb[i]], pts[gb[i + 1]]))
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

pub(super) fn run_ga(
    problem: &Problem<'_>,
    rng: &mut ChaCha8Rng,
    stats: &mut SymbolSearchStats,
) -> Result<Scored> {
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
                        stats: &mut SymbolSearchStats|
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
        let pick = |rng: &mut ChaCha8Rng| pick_weighted(&weights, rng);
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
