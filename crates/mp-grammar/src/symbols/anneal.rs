//! Stage 2, the fine search (§4.3): simulated annealing with *Slide* and
//! *Resize* moves and incremental cluster updates.

use std::collections::HashMap;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::cluster::FxBuild;
use super::{SaParams, SymbolParams, SymbolSearchStats, SymbolSegment, SymbolString};
use crate::distance::{FrameSpan, PoseFeatures};
use crate::kmedoids::Clustering;
use crate::objective::ClusterQuality;

type IntervalKey = (u32, u32, u32, u32);

pub(super) struct Annealer<'a> {
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
    pub(super) fn new(
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

    fn seg(&self, i: usize) -> FrameSpan {
        FrameSpan::new(self.bounds[i], self.bounds[i + 1])
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

    pub(super) fn run(
        &mut self,
        sa: &SaParams,
        step: usize,
        rng: &mut ChaCha8Rng,
        stats: &mut SymbolSearchStats,
    ) {
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

    pub(super) fn into_symbols(
        self,
        feat: &PoseFeatures,
        p: &SymbolParams,
        d_max: f64,
        stats: SymbolSearchStats,
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
