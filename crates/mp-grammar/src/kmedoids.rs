//! k-medoids clustering: PAM (best swap per iteration) and FasterPAM
//! (eager swapping), both started from given medoids.
//!
//! The paper clusters segments with PAM, always starting from the first `K`
//! segments as medoids so that the clustering is a function of the
//! segmentation ([`first_k`]). Only the SWAP phase runs (no BUILD).
//!
//! * [`Pam`]: each iteration evaluates every (medoid, non-medoid) swap and
//!   performs the best one if it lowers the total deviation `TD = Σ_o d(o,
//!   nearest medoid)`; stops when no swap improves. The swap costs of all `k`
//!   medoids for one candidate are computed together in `O(n)` with the
//!   nearest/second-nearest bookkeeping below, so an iteration costs `O(n²)`
//!   (the FastPAM1 result: same swaps as the textbook `O(k n²)` PAM).
//! * [`FasterPam`]: Schubert & Rousseeuw (2021), "Fast and eager k-medoids
//!   clustering: O(k) runtime improvement of the PAM, CLARA, and CLARANS
//!   algorithms". Candidates are visited cyclically and a swap is performed
//!   as soon as it improves TD (eager swapping); the loop ends after a full
//!   cycle without a swap. It keeps, for every point, the distance to its
//!   nearest and second-nearest medoid and, for every medoid, its *removal
//!   loss* `Σ_{o ∈ C_i} (d_second(o) − d_nearest(o))`. For a candidate `x`
//!   one pass over the points fills a *shared accumulator* (the gain of the
//!   points that move to `x` whichever medoid leaves) and per-medoid
//!   corrections; the best medoid to replace is the minimum of the `k` sums.
//!
//! Both are deterministic: ties go to the lowest medoid slot and candidates
//! are visited in index order. A swap is taken when its computed change is
//! negative; PAM stops when a swap does not lower the recomputed loss and
//! FasterPAM when a whole pass does not, which guards against swaps whose
//! gain is rounding noise (e.g. two equivalent medoids of a two-member
//! cluster). [`MedoidSwap`] is the seam between them.

use serde::{Deserialize, Serialize};

use crate::error::{GrammarError, Result};

/// A symmetric dissimilarity matrix with zero diagonal (only `get(i, j)` with
/// the candidate medoid first is read in the inner loops, which lets row-major
/// storage be read row by row).
pub trait Dissimilarity {
    /// Number of objects.
    fn len(&self) -> usize;
    /// Dissimilarity between objects `i` and `j` (both `< len()`).
    fn get(&self, i: usize, j: usize) -> f64;
    /// True when there is no object.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Row `i` as a contiguous slice, when the storage has one (fast path).
    fn row(&self, _i: usize) -> Option<&[f64]> {
        None
    }
}

impl<S: ndarray::Data<Elem = f64>> Dissimilarity for ndarray::ArrayBase<S, ndarray::Ix2> {
    fn len(&self) -> usize {
        self.nrows()
    }
    #[inline]
    fn get(&self, i: usize, j: usize) -> f64 {
        self[[i, j]]
    }
}

/// A dense row-major `n × n` matrix.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct DenseMatrix {
    n: usize,
    data: Vec<f64>,
}

impl DenseMatrix {
    /// Fills a matrix from a symmetric function (called for `i < j` only).
    pub fn from_fn(n: usize, mut f: impl FnMut(usize, usize) -> f64) -> Self {
        let mut data = vec![0.0; n * n];
        for i in 0..n {
            for j in (i + 1)..n {
                let v = f(i, j);
                data[i * n + j] = v;
                data[j * n + i] = v;
            }
        }
        DenseMatrix { n, data }
    }
}

impl Dissimilarity for DenseMatrix {
    fn len(&self) -> usize {
        self.n
    }
    #[inline]
    fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.n + j]
    }
    #[inline]
    fn row(&self, i: usize) -> Option<&[f64]> {
        self.data.get(i * self.n..(i + 1) * self.n)
    }
}

/// The strict lower triangle in row order without the diagonal:
/// `data = [d(1,0), d(2,0), d(2,1), d(3,0), …]` (the layout of the
/// `kmedoids` crate's `LowerTriangle`); the tests' dissimilarities.
#[cfg(test)]
#[derive(Debug, Clone, PartialEq)]
pub struct LowerTriangle {
    n: usize,
    data: Vec<f64>,
}

#[cfg(test)]
impl LowerTriangle {
    /// Checks that `data` holds `n (n − 1) / 2` values.
    pub fn new(n: usize, data: Vec<f64>) -> Result<Self> {
        let need = n * n.saturating_sub(1) / 2;
        if data.len() != need {
            return Err(GrammarError::Invalid(format!(
                "lower triangle of {n} objects needs {need} values, got {}",
                data.len()
            )));
        }
        Ok(LowerTriangle { n, data })
    }
}

#[cfg(test)]
impl Dissimilarity for LowerTriangle {
    fn len(&self) -> usize {
        self.n
    }
    #[inline]
    fn get(&self, i: usize, j: usize) -> f64 {
        use std::cmp::Ordering::*;
        match i.cmp(&j) {
            Less => self.data[j * (j - 1) / 2 + i],
            Greater => self.data[i * (i - 1) / 2 + j],
            Equal => 0.0,
        }
    }
}

/// The first `k` objects as initial medoids (the paper's deterministic start).
pub fn first_k(k: usize) -> Vec<usize> {
    (0..k).collect()
}

/// Result of a k-medoids run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Clustering {
    /// Total deviation `Σ_o d(o, nearest medoid)`.
    pub loss: f64,
    /// Medoid object of each cluster (cluster `i` = slot `i`).
    pub medoids: Vec<usize>,
    /// Cluster (medoid slot) of every object.
    pub assignment: Vec<usize>,
    /// Iterations (PAM: swap rounds; FasterPAM: passes over the candidates).
    pub iterations: usize,
    /// Swaps performed.
    pub swaps: usize,
}

/// Which swap strategy to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[non_exhaustive]
pub enum SwapMethod {
    /// Best swap per iteration (classic PAM SWAP).
    Pam,
    /// Eager swapping (FasterPAM). Default.
    #[default]
    FasterPam,
}

/// Parameters shared by both swap strategies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KMedoidsParams {
    /// Which strategy. Default [`SwapMethod::FasterPam`].
    pub method: SwapMethod,
    /// Maximum iterations (see [`Clustering::iterations`]). Default 100.
    pub max_iter: usize,
}

impl Default for KMedoidsParams {
    fn default() -> Self {
        KMedoidsParams {
            method: SwapMethod::FasterPam,
            max_iter: 100,
        }
    }
}

impl KMedoidsParams {
    /// Runs the selected strategy from `initial` medoids.
    pub fn fit<D: Dissimilarity + ?Sized>(&self, d: &D, initial: &[usize]) -> Result<Clustering> {
        match self.method {
            SwapMethod::Pam => Pam {
                max_iter: self.max_iter,
            }
            .fit(d, initial),
            SwapMethod::FasterPam => FasterPam {
                max_iter: self.max_iter,
            }
            .fit(d, initial),
        }
    }
}

/// The seam between swap strategies.
pub trait MedoidSwap {
    /// Improves `initial` medoids by swapping; validates the input.
    fn fit<D: Dissimilarity + ?Sized>(&self, d: &D, initial: &[usize]) -> Result<Clustering>;
}

/// Classic PAM SWAP (best improvement per iteration).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pam {
    /// Maximum number of swaps. Default 100.
    pub max_iter: usize,
}

impl Default for Pam {
    fn default() -> Self {
        Pam { max_iter: 100 }
    }
}

/// FasterPAM (eager swapping).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FasterPam {
    /// Maximum number of passes over the candidates. Default 100.
    pub max_iter: usize,
}

impl Default for FasterPam {
    fn default() -> Self {
        FasterPam { max_iter: 100 }
    }
}

#[derive(Clone, Copy, Debug)]
struct Rec {
    slot: usize,
    dist: f64,
}

/// Nearest / second-nearest bookkeeping shared by both strategies.
struct State {
    medoids: Vec<usize>,
    is_med: Vec<bool>,
    near: Vec<Rec>,
    second: Vec<Rec>,
    loss: f64,
}

fn validate<D: Dissimilarity + ?Sized>(d: &D, initial: &[usize]) -> Result<()> {
    let n = d.len();
    let k = initial.len();
    if k == 0 {
        return Err(GrammarError::param("k", "must be ≥ 1"));
    }
    if k > n {
        return Err(GrammarError::param(
            "k",
            format!("{k} medoids for {n} objects (k must be ≤ n)"),
        ));
    }
    let mut seen = vec![false; n];
    for &m in initial {
        if m >= n {
            return Err(GrammarError::Invalid(format!(
                "initial medoid {m} outside 0..{n}"
            )));
        }
        if seen[m] {
            return Err(GrammarError::Invalid(format!(
                "initial medoid {m} given twice"
            )));
        }
        seen[m] = true;
    }
    Ok(())
}

impl State {
    fn new<D: Dissimilarity + ?Sized>(d: &D, medoids: &[usize]) -> Self {
        let n = d.len();
        let mut is_med = vec![false; n];
        for &m in medoids {
            is_med[m] = true;
        }
        let mut s = State {
            medoids: medoids.to_vec(),
            is_med,
            near: vec![Rec { slot: 0, dist: 0.0 }; n],
            second: vec![
                Rec {
                    slot: 0,
                    dist: f64::INFINITY
                };
                n
            ],
            loss: 0.0,
        };
        for o in 0..n {
            s.assign_full(d, o);
        }
        s.loss = s.near.iter().map(|r| r.dist).sum();
        s
    }

    /// Recomputes nearest and second nearest of `o` from scratch.
    fn assign_full<D: Dissimilarity + ?Sized>(&mut self, d: &D, o: usize) {
        let mut best = Rec {
            slot: 0,
            dist: f64::INFINITY,
        };
        let mut sec = Rec {
            slot: 0,
            dist: f64::INFINITY,
        };
        for (i, &m) in self.medoids.iter().enumerate() {
            let v = if m == o { 0.0 } else { d.get(o, m) };
            if v < best.dist {
                sec = best;
                best = Rec { slot: i, dist: v };
            } else if v < sec.dist {
                sec = Rec { slot: i, dist: v };
            }
        }
        self.near[o] = best;
        self.second[o] = sec;
    }

    /// Second nearest of `o` excluding its nearest slot.
    fn second_full<D: Dissimilarity + ?Sized>(&self, d: &D, o: usize) -> Rec {
        let skip = self.near[o].slot;
        let mut sec = Rec {
            slot: 0,
            dist: f64::INFINITY,
        };
        for (i, &m) in self.medoids.iter().enumerate() {
            if i == skip {
                continue;
            }
            let v = if m == o { 0.0 } else { d.get(o, m) };
            if v < sec.dist {
                sec = Rec { slot: i, dist: v };
            }
        }
        sec
    }

    fn removal_loss(&self) -> Vec<f64> {
        let mut r = vec![0.0; self.medoids.len()];
        if self.medoids.len() < 2 {
            return r;
        }
        for (nr, sr) in self.near.iter().zip(&self.second) {
            r[nr.slot] += sr.dist - nr.dist;
        }
        r
    }

    fn is_medoid(&self, j: usize) -> bool {
        self.is_med[j]
    }

    /// Change of TD for replacing each medoid slot with `j`; returns the best
    /// slot and its change. `removal` must be current.
    fn best_swap<D: Dissimilarity + ?Sized>(
        &self,
        d: &D,
        j: usize,
        removal: &[f64],
        delta: &mut Vec<f64>,
    ) -> (usize, f64) {
        let k = self.medoids.len();
        let n = self.near.len();
        if k == 1 {
            let mut total = 0.0;
            for o in 0..n {
                total += if o == j { 0.0 } else { d.get(j, o) };
            }
            return (0, total - self.loss);
        }
        delta.clear();
        delta.extend_from_slice(removal);
        let mut acc = 0.0;
        let row = d.row(j);
        for o in 0..n {
            let doj = match row {
                Some(r) => r[o],
                None if o == j => 0.0,
                None => d.get(j, o),
            };
            let nr = self.near[o];
            if doj < nr.dist {
                acc += doj - nr.dist;
                delta[nr.slot] += nr.dist - self.second[o].dist;
            } else {
                let sd = self.second[o].dist;
                if doj < sd {
                    delta[nr.slot] += doj - sd;
                }
            }
        }
        let mut b = 0;
        for i in 1..k {
            if delta[i] < delta[b] {
                b = i;
            }
        }
        (b, delta[b] + acc)
    }

    /// Replaces the medoid in `slot` with `j` and updates the bookkeeping.
    fn swap<D: Dissimilarity + ?Sized>(&mut self, d: &D, slot: usize, j: usize) {
        self.is_med[self.medoids[slot]] = false;
        self.is_med[j] = true;
        self.medoids[slot] = j;
        let n = self.near.len();
        let row = d.row(j);
        for o in 0..n {
            let doj = match row {
                Some(r) => r[o],
                None if o == j => 0.0,
                None => d.get(j, o),
            };
            let nr = self.near[o];
            let sr = self.second[o];
            if nr.slot == slot {
                if doj < sr.dist {
                    self.near[o] = Rec { slot, dist: doj };
                } else {
                    self.near[o] = sr;
                    self.second[o] = self.second_full(d, o);
                }
            } else if sr.slot == slot {
                if doj < nr.dist {
                    self.second[o] = nr;
                    self.near[o] = Rec { slot, dist: doj };
                } else {
                    self.second[o] = self.second_full(d, o);
                }
            } else if doj < nr.dist {
                self.second[o] = nr;
                self.near[o] = Rec { slot, dist: doj };
            } else if doj < sr.dist {
                self.second[o] = Rec { slot, dist: doj };
            }
        }
        self.loss = self.near.iter().map(|r| r.dist).sum();
    }

    fn finish(self, iterations: usize, swaps: usize) -> Clustering {
        Clustering {
            loss: self.loss,
            assignment: self.near.iter().map(|r| r.slot).collect(),
            medoids: self.medoids,
            iterations,
            swaps,
        }
    }
}

impl MedoidSwap for Pam {
    fn fit<D: Dissimilarity + ?Sized>(&self, d: &D, initial: &[usize]) -> Result<Clustering> {
        validate(d, initial)?;
        let n = d.len();
        let mut st = State::new(d, initial);
        let mut delta = Vec::with_capacity(initial.len());
        let mut iterations = 0;
        let mut swaps = 0;
        while iterations < self.max_iter {
            iterations += 1;
            let removal = st.removal_loss();
            let mut best: Option<(f64, usize, usize)> = None;
            for j in 0..n {
                if st.is_medoid(j) {
                    continue;
                }
                let (slot, change) = st.best_swap(d, j, &removal, &mut delta);
                if best.is_none_or(|(c, _, _)| change < c) {
                    best = Some((change, slot, j));
                }
            }
            match best {
                Some((change, slot, j)) if change < 0.0 => {
                    let before = st.loss;
                    st.swap(d, slot, j);
                    swaps += 1;
                    if st.loss >= before {
                        // The computed gain was rounding noise.
                        break;
                    }
                }
                _ => break,
            }
        }
        Ok(st.finish(iterations, swaps))
    }
}

impl MedoidSwap for FasterPam {
    fn fit<D: Dissimilarity + ?Sized>(&self, d: &D, initial: &[usize]) -> Result<Clustering> {
        validate(d, initial)?;
        let n = d.len();
        let mut st = State::new(d, initial);
        if initial.len() == n {
            return Ok(st.finish(0, 0));
        }
        let mut removal = st.removal_loss();
        let mut delta = Vec::with_capacity(initial.len());
        let mut iterations = 0;
        let mut swaps = 0;
        let mut last_swap: Option<usize> = None;
        'outer: while iterations < self.max_iter {
            iterations += 1;
            let swaps_before = swaps;
            let loss_before = st.loss;
            for j in 0..n {
                if last_swap == Some(j) {
                    break 'outer;
                }
                if st.is_medoid(j) {
                    continue;
                }
                let (slot, change) = st.best_swap(d, j, &removal, &mut delta);
                if change < 0.0 {
                    st.swap(d, slot, j);
                    removal = st.removal_loss();
                    swaps += 1;
                    last_swap = Some(j);
                }
            }
            if swaps == swaps_before || st.loss >= loss_before {
                // Converged; a pass whose swaps did not lower the loss only
                // moved between equivalent configurations (rounding noise).
                break;
            }
        }
        Ok(st.finish(iterations, swaps))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> LowerTriangle {
        LowerTriangle::new(5, vec![1., 2., 3., 4., 5., 6., 7., 8., 9., 1.]).unwrap()
    }

    #[test]
    fn reference_example_fasterpam() {
        let c = FasterPam::default().fit(&example(), &[0, 1]).unwrap();
        assert_eq!(c.loss, 4.0);
        assert_eq!(c.medoids, vec![0, 3]);
        assert_eq!(c.assignment, vec![0, 0, 0, 1, 1]);
    }

    #[test]
    fn reference_example_pam() {
        let c = Pam::default().fit(&example(), &[0, 1]).unwrap();
        assert_eq!(c.loss, 4.0);
        assert_eq!(c.assignment, vec![0, 0, 0, 1, 1]);
        assert_eq!(c.medoids[0], 0);
        assert!(c.medoids[1] == 3 || c.medoids[1] == 4);
    }

    #[test]
    fn single_cluster() {
        let c = FasterPam::default().fit(&example(), &[1]).unwrap();
        assert_eq!(c.loss, 14.0);
        assert_eq!(c.medoids, vec![0]);
        assert_eq!(c.assignment, vec![0; 5]);
    }

    #[test]
    fn bad_input_is_an_error() {
        let e = example();
        assert!(FasterPam::default().fit(&e, &[]).is_err());
        assert!(FasterPam::default().fit(&e, &[0, 1, 2, 3, 4, 0]).is_err());
        assert!(Pam::default().fit(&e, &[0, 0]).is_err());
        assert!(Pam::default().fit(&e, &[7]).is_err());
        assert!(LowerTriangle::new(5, vec![1.0]).is_err());
    }
}
