//! Lin's concordance of a multichannel signal with itself shifted by a lag,
//! over any interval, from prefix sums.

/// Lin's concordance of `x[s..e-l]` and `x[s+l..e]` (all channels pooled, each
/// channel with its own means): 1 when the motion repeats exactly after `l`
/// frames, ≤ 0 when unrelated; a change of mean pose lowers it (unlike a correlation).
///
/// Built from the channels once, it holds all that is read of them: the
/// per-channel prefix sums, the prefix sums of each frame's squared norm, and
/// for each lag the prefix sums of lagged products. Those last are what a
/// long recording would fill memory with (an hour at 30 fps, lags up to 4 s:
/// 120 × 111,975 values), so they are kept only where the segmenter's search
/// reads them — at the grid's nodes and one lag before each node — and
/// anywhere else they are completed from the nearest node with the channels
/// that the per-channel prefix sums hold (`x_t = cs(t + 1) − cs(t)`).
pub(super) struct Concordance {
    c: usize,
    /// Frames.
    n: usize,
    /// Grid step of the nodes, frames.
    step: usize,
    /// Per-channel prefix sums, `(T+1) × C`.
    cs: Vec<f64>,
    /// Prefix sums of the squared norm of each frame.
    cs2: Vec<f64>,
    /// For each lag `l` (index `l − 1`), prefix sums of `⟨x_t, x_{t+l}⟩`.
    cross: Vec<LagSums>,
}

/// The prefix sums `P(t) = Σ_{u<t} ⟨x_u, x_{u+l}⟩` of one lag `l`, kept at
/// the nodes and `l` frames before each node.
struct LagSums {
    /// `P(k · step)` for every `k · step ≤ T − l`.
    at_node: Vec<f64>,
    /// `P(node_k − l)` for the nodes from `first` on (those at least `l`).
    before_node: Vec<f64>,
    first: usize,
}

impl Concordance {
    /// The concordance of the `n` frames × `c` channels of `x` (row-major)
    /// for lags `1..=max_lag`, read fastest at `nodes`: every `step`-th frame
    /// from 0 and `n` itself.
    pub(super) fn new(x: &[f64], n: usize, c: usize, max_lag: usize, step: usize) -> Self {
        use rayon::prelude::*;
        let step = step.max(1);
        let mut cs = vec![0.0; (n + 1) * c];
        let mut cs2 = vec![0.0; n + 1];
        for t in 0..n {
            let mut q = 0.0;
            for k in 0..c {
                let v = x[t * c + k];
                cs[(t + 1) * c + k] = cs[t * c + k] + v;
                q += v * v;
            }
            cs2[t + 1] = cs2[t] + q;
        }
        let nodes = node_frames(n, step);
        let cross = (1..=max_lag.min(n.saturating_sub(1)))
            .into_par_iter()
            .map(|l| {
                // The whole prefix sum of this lag, then only what is read of it.
                let mut p = vec![0.0; n - l + 1];
                for t in 0..n - l {
                    let mut s = 0.0;
                    for k in 0..c {
                        s += x[t * c + k] * x[(t + l) * c + k];
                    }
                    p[t + 1] = p[t] + s;
                }
                let at_node = p.iter().step_by(step).copied().collect();
                let first = nodes.partition_point(|&v| v < l);
                let before_node = nodes[first..].iter().map(|&v| p[v - l]).collect();
                LagSums {
                    at_node,
                    before_node,
                    first,
                }
            })
            .collect();
        Concordance {
            c,
            n,
            step,
            cs,
            cs2,
            cross,
        }
    }

    /// Frame `t`'s channel `k`, from the prefix sums.
    fn x(&self, t: usize, k: usize) -> f64 {
        self.cs[(t + 1) * self.c + k] - self.cs[t * self.c + k]
    }

    /// `P(t)` of lag `l` (see [`LagSums`]); `None` outside `0..=T − l`.
    fn lagged(&self, l: usize, t: usize) -> Option<f64> {
        let p = self.cross.get(l.checked_sub(1)?)?;
        if t + l > self.n {
            return None;
        }
        if t.is_multiple_of(self.step) {
            if let Some(&v) = p.at_node.get(t / self.step) {
                return Some(v);
            }
        }
        let after = t + l;
        let node = if after == self.n {
            Some(node_frames_len(self.n, self.step) - 1)
        } else {
            after.is_multiple_of(self.step).then_some(after / self.step)
        };
        if let Some(&v) = node
            .and_then(|k| k.checked_sub(p.first))
            .and_then(|i| p.before_node.get(i))
        {
            return Some(v);
        }
        // Elsewhere: from the node at or before `t`, adding the products since.
        let k0 = t / self.step;
        let mut v = *p.at_node.get(k0)?;
        for u in k0 * self.step..t {
            v += (0..self.c)
                .map(|k| self.x(u, k) * self.x(u + l, k))
                .sum::<f64>();
        }
        Some(v)
    }

    /// Concordance of `[s, e − l)` with `[s + l, e)`; `None` when undefined.
    pub(super) fn at(&self, s: usize, e: usize, l: usize) -> Option<f64> {
        if l == 0 || e < s + l + 1 || e > self.n {
            return None;
        }
        let n = (e - s - l) as f64;
        let c = self.c;
        // Each channel's sums over both windows, read once.
        let (mut sab, mut ssd, mut saa_all, mut sbb_all) = (0.0, 0.0, 0.0, 0.0);
        for k in 0..c {
            let sa = self.cs[(e - l) * c + k] - self.cs[s * c + k];
            let sb = self.cs[e * c + k] - self.cs[(s + l) * c + k];
            sab += sa * sb;
            ssd += (sa - sb) * (sa - sb);
            saa_all += sa * sa;
            sbb_all += sb * sb;
        }
        let cross = self.lagged(l, e - l)? - self.lagged(l, s)?;
        let cov = cross - sab / n;
        let va = (self.cs2[e - l] - self.cs2[s]) - saa_all / n;
        let vb = (self.cs2[e] - self.cs2[s + l]) - sbb_all / n;
        let md = ssd / n;
        let den = va + vb + md;
        if den > 1e-12 {
            Some(2.0 * cov / den)
        } else {
            None
        }
    }
}

/// The grid's nodes over `n` frames: every `step`-th frame from 0, and `n`.
pub(super) fn node_frames(n: usize, step: usize) -> Vec<usize> {
    let mut nodes: Vec<usize> = (0..n).step_by(step.max(1)).collect();
    if nodes.last() != Some(&n) {
        nodes.push(n);
    }
    nodes
}

/// `node_frames(n, step).len()`.
fn node_frames_len(n: usize, step: usize) -> usize {
    n.div_ceil(step.max(1)) + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The concordance straight from its definition.
    fn direct(x: &[f64], c: usize, s: usize, e: usize, l: usize) -> f64 {
        let m = e - s - l;
        let (mut cov, mut va, mut vb, mut md) = (0.0, 0.0, 0.0, 0.0);
        for k in 0..c {
            let a: Vec<f64> = (s..e - l).map(|t| x[t * c + k]).collect();
            let b: Vec<f64> = (s + l..e).map(|t| x[t * c + k]).collect();
            let (ma, mb) = (
                a.iter().sum::<f64>() / m as f64,
                b.iter().sum::<f64>() / m as f64,
            );
            for (p, q) in a.iter().zip(&b) {
                cov += (p - ma) * (q - mb);
                va += (p - ma).powi(2);
                vb += (q - mb).powi(2);
            }
            md += (ma - mb).powi(2);
        }
        2.0 * cov / (va + vb + m as f64 * md)
    }

    #[test]
    fn matches_the_definition_at_nodes_and_between() {
        let (n, c, step, max_lag) = (157, 3, 6, 40);
        let x: Vec<f64> = (0..n * c)
            .map(|i| {
                let (t, k) = ((i / c) as f64, (i % c) as f64);
                (t * 0.21 + k).sin() + 0.3 * (t * 0.05 * (k + 1.0)).cos() + 5.0 * k
            })
            .collect();
        let conc = Concordance::new(&x, n, c, max_lag, step);
        assert_eq!(node_frames(n, step).len(), node_frames_len(n, step));
        assert_eq!(node_frames(156, step).len(), node_frames_len(156, step));
        for s in (0..n).step_by(5) {
            for e in (s + 2..=n).step_by(7).chain([n]) {
                for l in 1..=max_lag.min(e - s - 1) {
                    let want = direct(&x, c, s, e, l);
                    let got = conc.at(s, e, l).expect("defined");
                    assert!(
                        (got - want).abs() < 1e-9,
                        "{s}..{e} lag {l}: {got} vs {want}"
                    );
                }
            }
        }
        assert_eq!(conc.at(0, n, max_lag + 1), None);
        assert_eq!(conc.at(10, 12, 2), None);
        assert_eq!(conc.at(0, n + 1, 1), None);
    }
}
