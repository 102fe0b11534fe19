//! Segment distances and the clustering of a segmentation: an integer
//! hasher, the grid of candidate cuts with its shared segment-distance
//! table (filled lazily by all GA threads), and k-medoids from the first
//! `K` segments with the objective `F`.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;

use super::SymbolParams;
use crate::distance::{FrameSpan, PoseFeatures};
use crate::error::Result;
use crate::kmedoids::{first_k, Clustering, DenseMatrix};
use crate::objective::{evaluate, ClusterQuality};

// ---------------------------------------------------------------------------
// Small fast hasher for integer keys (FxHash-style multiply-rotate).

#[derive(Default, Clone, Copy)]
pub(super) struct FxHasher(u64);

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

pub(super) type FxBuild = BuildHasherDefault<FxHasher>;

// ---------------------------------------------------------------------------
// Grid of candidate cuts and the shared segment-distance table.

pub(super) struct Grid {
    /// Frame of each grid point: 0, candidates…, T.
    pub(super) points: Vec<usize>,
    /// Widest span (in grid steps) of an admissible segment.
    pub(super) width: usize,
}

impl Grid {
    /// Candidate cuts every `step` frames from `start`, keeping the last
    /// segment at least `min_segment_frames` long, then `end`.
    pub(super) fn new(start: usize, end: usize, p: &SymbolParams) -> Self {
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
    pub(super) fn n_candidates(&self) -> usize {
        self.points.len() - 2
    }
    pub(super) fn id(&self, a: usize, b: usize) -> usize {
        a * self.width + (b - a - 1)
    }
}

/// Segment-pair distance cache for grid segments (values rounded to `f32`,
/// which halves the memory traffic of the GA's inner loop).
pub(super) enum PairCache {
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
    pub(super) fn new(n_ids: usize) -> Self {
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

    pub(super) fn get_or(&self, x: usize, y: usize, f: impl FnOnce() -> f64) -> f64 {
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

/// Clusters a segmentation from its first `K` segments (distances computed
/// in parallel) and evaluates `F`.
pub(super) fn cluster_bounds(
    features: &PoseFeatures,
    bounds: &[usize],
    p: &SymbolParams,
    d_max: f64,
) -> Result<(Clustering, ClusterQuality)> {
    let n = bounds.len() - 1;
    let segs: Vec<FrameSpan> = bounds
        .windows(2)
        .map(|w| FrameSpan::new(w[0], w[1]))
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
