//! One step of the search (see the module docs): the per-joint paths it
//! reads, its running state, and the evaluation of a candidate segment
//! `k..n` in four stages — the O(1) bounds of every joint, the one-pass
//! costs (in single precision where there are bounds to compare, circles
//! deferred while they cannot drop the candidate), the deferred circles, and
//! the exact costs of the joints the first stage only bounded.

use mp_geom::{Checked, FitParams};

use super::bounds::{quick, Quick};
use super::carry::{joint_lb, Known};
use super::circle::CircleScratch;
use super::coarse::{coarse_stage, Coarse};
use super::moments::{anchors, Acc2};
use super::{
    joint_circle, joint_err, joint_stage, span_frames, with_circle, JointTrack, Rules, SearchStats,
    Stage, Staged,
};
use crate::error::{ConcreteError, Result};

/// What every candidate of one search reads: the joints, their names (for
/// errors), the fit parameters, the selection rules and the joints' paths.
pub(super) struct Inputs<'a> {
    pub joints: &'a [JointTrack<'a>],
    pub names: &'a [String],
    pub fit: &'a Checked<FitParams>,
    pub rules: Rules,
    pub paths: JointPaths,
}

impl Inputs<'_> {
    /// The cheap stage of joint `j`'s cost on `k..n` ([`joint_stage`]).
    fn stage(&self, acc: &Acc2, q: &Quick, j: usize, k: usize, n: usize) -> Result<Staged> {
        joint_stage(
            &self.joints[j],
            self.paths.fast[j].as_deref(),
            &self.paths.steps[j],
            acc,
            q,
            &self.rules,
            self.fit,
            k,
            n,
        )
        .map_err(|e| joint_err(self.names, j, k, n, e))
    }

    /// The cost of a joint no kind could be fitted to: the candidate loses
    /// when there is an incumbent, and the search fails without one.
    fn no_fit(&self, best_n: f64, j: usize, k: usize, n: usize) -> Result<f64> {
        if best_n.is_finite() {
            Ok(f64::INFINITY)
        } else {
            Err(joint_err(
                self.names,
                j,
                k,
                n,
                "no primitive kind could be fitted",
            ))
        }
    }
}

/// What the search reads of each joint besides its points: the 2D fast
/// path's points (missing frames zeroed), the points the moments are taken
/// about, the step lengths between consecutive valid frames, and the
/// single-precision copy. `None` (or empty) for a joint off the fast path
/// (3D, or with the spline kind allowed).
pub(super) struct JointPaths {
    fast: Vec<Option<Vec<[f64; 2]>>>,
    anchor: Vec<Option<Vec<[f64; 2]>>>,
    steps: Vec<Vec<f64>>,
    coarse: Vec<Option<Coarse>>,
}

impl JointPaths {
    pub(super) fn new(joints: &[JointTrack<'_>], rules: &Rules, spline: bool, t: usize) -> Self {
        // Per joint: 2D fast path data (points with missing frames zeroed).
        let fast: Vec<Option<Vec<[f64; 2]>>> = joints
            .iter()
            .map(|jt| {
                if jt.points.ncols() != 2 || spline {
                    return None;
                }
                Some(
                    jt.points
                        .outer_iter()
                        .zip(jt.weights)
                        .map(|(r, &w)| if w > 0.0 { [r[0], r[1]] } else { [0.0, 0.0] })
                        .collect(),
                )
            })
            .collect();
        // Per joint: the points the moments are taken about (see `moments::anchors`).
        let anchor: Vec<Option<Vec<[f64; 2]>>> = fast
            .iter()
            .zip(joints)
            .map(|(f, jt)| f.as_ref().map(|p| anchors(p, jt.weights)))
            .collect();
        // Step lengths of consecutive valid frames (−1 where a frame is missing).
        let steps: Vec<Vec<f64>> = fast
            .iter()
            .zip(joints)
            .map(|(f, jt)| match f {
                Some(p) => (0..t)
                    .map(|i| {
                        if i + 1 < t && jt.weights[i] > 0.0 && jt.weights[i + 1] > 0.0 {
                            let (dx, dy) = (p[i + 1][0] - p[i][0], p[i + 1][1] - p[i][1]);
                            (dx * dx + dy * dy).sqrt()
                        } else {
                            -1.0
                        }
                    })
                    .collect(),
                None => Vec::new(),
            })
            .collect();
        // Per joint: the single-precision copy (Euclidean norm, fast path).
        let coarse: Vec<Option<Coarse>> = fast
            .iter()
            .zip(joints)
            .zip(&steps)
            .map(|((f, jt), st)| match f {
                Some(p) if !rules.squared && !rules.quadratic => {
                    Some(Coarse::new(p, jt.weights, st))
                }
                _ => None,
            })
            .collect();
        JointPaths {
            fast,
            anchor,
            steps,
            coarse,
        }
    }
}

/// The search's running state: the DP's best costs and arguments, the
/// per-joint accumulators and bounds of the candidate in hand, the joint
/// order, the statistics and the ring of what the exact stage measured.
pub(super) struct SearchState {
    best: Vec<f64>,
    arg: Vec<usize>,
    accs: Vec<Acc2>,
    quicks: Vec<Quick>,
    lbs: Vec<f64>,
    costs: Vec<f64>,
    deferred: Vec<(usize, f64, f64)>,
    circ: Vec<f64>,
    bounded: Vec<bool>,
    gaps: Vec<f64>,
    order: Vec<usize>,
    stats: SearchStats,
    scratch: CircleScratch,
    ring: usize,
    known: Vec<Known>,
}

impl SearchState {
    pub(super) fn new(nj: usize, t: usize, window: usize) -> Self {
        let mut best = vec![f64::INFINITY; t + 1];
        let arg = vec![0usize; t + 1];
        best[0] = 0.0;
        let accs = vec![Acc2::default(); nj];
        let quicks = vec![Quick::default(); nj];
        let lbs = vec![0.0f64; nj];
        let costs = vec![0.0f64; nj];
        let deferred: Vec<(usize, f64, f64)> = Vec::with_capacity(nj);
        // Per joint, for the candidate in hand: the exact circle's own cost
        // where it was fitted (`NaN`: not fitted), and whether its cost so far is
        // a single-precision bound.
        let circ = vec![f64::NAN; nj];
        let bounded = vec![false; nj];
        // Joints by how much their exact cost has exceeded their O(1) bound so
        // far (most first): the candidates that cannot win are dropped sooner.
        let gaps = vec![0.0f64; nj];
        let order: Vec<usize> = (0..nj).collect();
        let stats = SearchStats::default();
        let scratch = CircleScratch::default();
        // What the exact stage measured, per joint, on the candidates of this
        // end frame and the previous one (slot `k mod (W + 2)`).
        let ring = window + 2;
        let known = vec![Known::NONE; nj * ring];
        SearchState {
            best,
            arg,
            accs,
            quicks,
            lbs,
            costs,
            deferred,
            circ,
            bounded,
            gaps,
            order,
            stats,
            scratch,
            ring,
            known,
        }
    }

    /// The DP's best costs and arguments, and the statistics.
    pub(super) fn finish(self) -> (Vec<f64>, Vec<usize>, SearchStats) {
        (self.best, self.arg, self.stats)
    }

    /// The best segmentation of `0..n`: every start `k` within `window`
    /// frames, the start of the previous frame's last segment first.
    pub(super) fn end_frame(
        &mut self,
        inp: &Inputs<'_>,
        n: usize,
        lam: f64,
        window: usize,
    ) -> Result<()> {
        if n.is_multiple_of(64) {
            let gaps = &self.gaps;
            self.order
                .sort_by(|&a, &b| gaps[b].total_cmp(&gaps[a]).then(a.cmp(&b)));
            for g in self.gaps.iter_mut() {
                *g *= 0.5;
            }
        }
        let lo = n.saturating_sub(window);
        let mut best_n = f64::INFINITY;
        let mut arg_n = n - 1;
        // First the start of the previous frame's last segment (the segment
        // extended by one frame: usually near the optimum, a strong
        // incumbent), then every start from the shortest segment up.
        let seed = self.arg[n - 1].max(lo);
        for pass in 0..2 {
            if pass == 0 && (n < 2 || seed + 1 >= n) {
                continue;
            }
            self.start_segments(inp, n);
            let stop = if pass == 0 { seed } else { lo };
            for k in (stop..n).rev() {
                self.add_frame(inp, k, n);
                if (pass == 0 && k != seed) || (pass == 1 && k == seed && seed + 1 < n && n >= 2) {
                    continue;
                }
                if let Some(e) = self.candidate(inp, k, n, lam, best_n)? {
                    if e < best_n || (e == best_n && k < arg_n) {
                        best_n = e;
                        arg_n = k;
                    }
                }
            }
        }
        self.best[n] = best_n;
        self.arg[n] = arg_n;
        Ok(())
    }

    /// Empty segments ending at frame `n − 1`, their moments about its anchors.
    fn start_segments(&mut self, inp: &Inputs<'_>, n: usize) {
        for (j, acc) in self.accs.iter_mut().enumerate() {
            let (rx, ry) = match &inp.paths.anchor[j] {
                Some(a) => (a[n - 1][0], a[n - 1][1]),
                None => (0.0, 0.0),
            };
            acc.reset(n - 1, rx, ry);
        }
    }

    /// Frame `k` added to every joint's segment (`k..n`).
    fn add_frame(&mut self, inp: &Inputs<'_>, k: usize, n: usize) {
        let tau = k as f64 - (n - 1) as f64;
        for (j, acc) in self.accs.iter_mut().enumerate() {
            if inp.joints[j].weights[k] > 0.0 {
                match &inp.paths.fast[j] {
                    Some(p) => acc.add(k, tau, p[k][0], p[k][1], inp.paths.steps[j][k]),
                    None => {
                        if acc.count == 0 {
                            acc.last = k;
                        }
                        acc.first = k;
                        acc.count += 1;
                    }
                }
            }
        }
    }

    /// The cost `E[k] + λ + Σ costs` of segment `k..n`, or `None` once it
    /// cannot beat the incumbent `best_n`.
    fn candidate(
        &mut self,
        inp: &Inputs<'_>,
        k: usize,
        n: usize,
        lam: f64,
        best_n: f64,
    ) -> Result<Option<f64>> {
        self.stats.candidates += 1;
        let base = self.best[k];
        // Prune on λ alone (costs are ≥ 0).
        if !base.is_finite() || base + lam > best_n {
            self.stats.pruned_lambda += 1;
            return Ok(None);
        }
        let bar = Bar { base, lam, best_n };
        let Some(lb_sum) = self.bounds(inp, k, n, bar) else {
            self.stats.pruned_bounds += 1;
            return Ok(None);
        };
        self.stats.survivors += 1;
        let (mut sum, any_coarse, mut dead) = self.one_pass(inp, k, n, bar, lb_sum)?;
        if !dead {
            dead = self.deferred_circles(inp, k, n, bar, &mut sum)?;
        }
        if dead {
            if any_coarse {
                self.stats.dropped_coarse += 1;
            } else {
                self.stats.dropped_exact += 1;
            }
            return Ok(None);
        }
        if self.exact_costs(inp, k, n, bar, &mut sum)? {
            self.stats.dropped_exact += 1;
            return Ok(None);
        }
        // In joint order, whatever order the bounds took.
        let total: f64 = self.costs.iter().sum();
        let e = base + (total + lam);
        if e.is_nan() {
            return Err(ConcreteError::Track(format!(
                "segment cost of frames {k}..{n} is NaN"
            )));
        }
        Ok(Some(e))
    }

    /// The O(1) bounds of every joint, in the current order, into `lbs`:
    /// their sum, or `None` once it drops the candidate.
    fn bounds(&mut self, inp: &Inputs<'_>, k: usize, n: usize, bar: Bar) -> Option<f64> {
        let Bar { base, lam, best_n } = bar;
        let ring = self.ring;
        let mut lb_sum = 0.0;
        for oi in 0..self.order.len() {
            let j = self.order[oi];
            let acc = &self.accs[j];
            let lb = if acc.count == 0 {
                0.0
            } else if let Some(p) = &inp.paths.fast[j] {
                self.quicks[j] = quick(acc, p, &inp.rules, inp.fit);
                let olds = [
                    &self.known[j * ring + k % ring],
                    &self.known[j * ring + (k + 1) % ring],
                ];
                joint_lb(
                    olds,
                    acc,
                    &self.quicks[j],
                    p,
                    inp.joints[j].weights,
                    &inp.rules,
                    k,
                    n,
                )
            } else {
                0.0
            };
            self.lbs[j] = lb;
            lb_sum += lb;
            if base + (lb_sum + lam) > best_n {
                return None;
            }
        }
        Some(lb_sum)
    }

    /// The circle of joint `j` on `k..n` fitted exactly ([`joint_circle`]).
    fn fit_circle(
        &mut self,
        inp: &Inputs<'_>,
        j: usize,
        best: f64,
        slot: usize,
        k: usize,
        n: usize,
    ) -> (Option<f64>, f64) {
        let p = inp.paths.fast[j].as_deref().unwrap_or(&[]);
        joint_circle(
            &inp.joints[j],
            p,
            &self.accs[j],
            best,
            &inp.rules,
            inp.fit,
            &mut self.stats,
            &mut self.known[slot],
            &mut self.scratch,
            k,
            n,
        )
    }

    /// Costs joint by joint (circles only where one can win), dropped as
    /// soon as the partial sum plus the remaining bounds exceeds the
    /// incumbent: single-precision bounds of the one-pass errors where there
    /// are (`coarse`), exact costs elsewhere. Returns the partial sum, whether
    /// any joint was bounded, and whether the candidate was dropped.
    fn one_pass(
        &mut self,
        inp: &Inputs<'_>,
        k: usize,
        n: usize,
        bar: Bar,
        lb_sum: f64,
    ) -> Result<(f64, bool, bool)> {
        let Bar { base, lam, best_n } = bar;
        let mut rest = lb_sum;
        let mut sum = 0.0;
        let mut any_coarse = false;
        self.deferred.clear();
        for oi in 0..self.order.len() {
            let j = self.order[oi];
            rest -= self.lbs[j];
            self.circ[j] = f64::NAN;
            self.bounded[j] = false;
            let (stage, errors) = match (&inp.paths.coarse[j], self.accs[j].count) {
                (Some(c), 1..) => {
                    self.stats.coarse_joints += 1;
                    self.stats.coarse_frames += span_frames(&self.accs[j], k, n, true);
                    self.bounded[j] = true;
                    any_coarse = true;
                    let (stage, errors) =
                        coarse_stage(c, &self.quicks[j], &self.accs[j], &inp.rules);
                    (stage, Some(errors))
                }
                _ => {
                    self.stats.exact_joints += 1;
                    self.stats.exact_frames +=
                        span_frames(&self.accs[j], k, n, inp.paths.fast[j].is_some());
                    inp.stage(&self.accs[j], &self.quicks[j], j, k, n)?
                }
            };
            let slot = j * self.ring + k % self.ring;
            if let Some(errors) = errors {
                self.known[slot] = Known::new(k, n, errors, &self.quicks[j]);
            }
            let cost = match stage {
                Stage::Done(Some(c)) => c,
                Stage::Done(None) => inp.no_fit(best_n, j, k, n)?,
                Stage::Circle { lb, best } => {
                    // Fitted now only if it can drop the candidate;
                    // otherwise later, if the candidate survives.
                    if base + (sum + best + rest.max(0.0) + lam) > best_n {
                        let (c, own) = self.fit_circle(inp, j, best, slot, k, n);
                        self.circ[j] = own;
                        match c {
                            Some(c) => c,
                            None => inp.no_fit(best_n, j, k, n)?,
                        }
                    } else {
                        // Provisionally its largest known bound.
                        let lb = lb.max(self.lbs[j]);
                        self.deferred.push((j, lb, best));
                        lb
                    }
                }
            };
            self.costs[j] = cost;
            let g = cost - self.lbs[j];
            if g.is_finite() {
                self.gaps[j] += g;
            }
            sum += cost;
            if base + (sum + rest.max(0.0) + lam) > best_n {
                self.deferred.clear();
                return Ok((sum, any_coarse, true));
            }
        }
        Ok((sum, any_coarse, false))
    }

    /// The deferred circles, those that may rise most first, added to `sum`;
    /// true once the candidate is dropped.
    fn deferred_circles(
        &mut self,
        inp: &Inputs<'_>,
        k: usize,
        n: usize,
        bar: Bar,
        sum: &mut f64,
    ) -> Result<bool> {
        let Bar { base, lam, best_n } = bar;
        self.deferred
            .sort_by(|a, b| (b.2 - b.1).total_cmp(&(a.2 - a.1)));
        for di in 0..self.deferred.len() {
            let (j, lb, best) = self.deferred[di];
            let slot = j * self.ring + k % self.ring;
            let (c, own) = self.fit_circle(inp, j, best, slot, k, n);
            self.circ[j] = own;
            let cost = match c {
                Some(c) => c,
                None => inp.no_fit(best_n, j, k, n)?,
            };
            self.costs[j] = cost;
            let g = cost - lb;
            if g.is_finite() {
                self.gaps[j] += g;
            }
            *sum += cost - lb;
            if base + (*sum + lam) > best_n {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// The exact one-pass costs where the first stage had bounds, replacing
    /// them in `sum`; true once the candidate is dropped.
    fn exact_costs(
        &mut self,
        inp: &Inputs<'_>,
        k: usize,
        n: usize,
        bar: Bar,
        sum: &mut f64,
    ) -> Result<bool> {
        let Bar { base, lam, best_n } = bar;
        for j in 0..self.bounded.len() {
            if !self.bounded[j] {
                continue;
            }
            self.stats.exact_joints += 1;
            self.stats.exact_frames += span_frames(&self.accs[j], k, n, true);
            let (stage, errors) = inp.stage(&self.accs[j], &self.quicks[j], j, k, n)?;
            let slot = j * self.ring + k % self.ring;
            if let Some(errors) = errors {
                // (Keeping the exact circle fitted in the first stage.)
                self.known[slot].errors = errors;
            }
            let cost = match stage {
                Stage::Done(Some(c)) => c,
                Stage::Done(None) => inp.no_fit(best_n, j, k, n)?,
                Stage::Circle { best, .. } => {
                    let own = if self.circ[j].is_nan() {
                        self.fit_circle(inp, j, best, slot, k, n).1
                    } else {
                        self.circ[j]
                    };
                    match with_circle(own, best) {
                        Some(c) => c,
                        None => inp.no_fit(best_n, j, k, n)?,
                    }
                }
            };
            *sum += cost - self.costs[j];
            self.costs[j] = cost;
            if base + (*sum + lam) > best_n {
                return Ok(true);
            }
        }
        Ok(false)
    }
}

/// What a candidate's costs are compared against: `E[k]`, `λ` and the
/// incumbent `E[n]`; it is dropped once `E[k] + (Σ + λ) > E[n]`.
#[derive(Clone, Copy)]
struct Bar {
    base: f64,
    lam: f64,
    best_n: f64,
}
