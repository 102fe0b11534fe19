//! One joint's weighted least-squares problem over the knots: the variable
//! layout, the banded normal equations and their Cholesky solve.

use super::elems::Elem;
use super::{refit_weight, JointSeries, RIDGE};

/// Variable layout of one solve.
struct Layout {
    /// Per knot: index of its group's first unknown.
    knot_var: Vec<usize>,
    /// Per knot: offset from its group's value (rigid chains), `D` values.
    knot_off: Vec<Vec<f64>>,
    /// Per segment: index of the first interior unknown (cubic only).
    interior: Vec<Option<usize>>,
    /// Number of unknowns.
    n: usize,
    /// Half bandwidth of the normal matrix.
    bw: usize,
}

fn layout(elems: &[Elem], d: usize) -> Layout {
    let s = elems.len();
    let mut knot_var = Vec::with_capacity(s + 1);
    let mut knot_off = Vec::with_capacity(s + 1);
    let mut interior = Vec::with_capacity(s);
    knot_var.push(0);
    knot_off.push(vec![0.0; d]);
    let mut n = d;
    let mut bw = d - 1;
    for (i, e) in elems.iter().enumerate() {
        let first = knot_var[i];
        let mut hi = first + d - 1;
        if let Elem::Cubic = e {
            interior.push(Some(n));
            n += 2 * d;
            hi = n - 1;
        } else {
            interior.push(None);
        }
        match e {
            Elem::Rigid { shape } => {
                let nn = shape.len() / d - 1;
                let off: Vec<f64> = (0..d).map(|k| knot_off[i][k] + shape[nn * d + k]).collect();
                knot_var.push(first);
                knot_off.push(off);
            }
            _ => {
                knot_var.push(n);
                knot_off.push(vec![0.0; d]);
                n += d;
                hi = n - 1;
            }
        }
        bw = bw.max(hi - first);
    }
    Layout {
        knot_var,
        knot_off,
        interior,
        n,
        bw,
    }
}

/// Symmetric banded matrix (upper band) and right-hand side.
struct Normal {
    n: usize,
    w: usize,
    h: Vec<f64>,
    g: Vec<f64>,
}

impl Normal {
    fn new(n: usize, bw: usize) -> Self {
        let w = bw + 1;
        Normal {
            n,
            w,
            h: vec![0.0; n * w],
            g: vec![0.0; n],
        }
    }

    /// Adds `weight · (Σ coef·z[idx] − y)²` to the objective.
    fn add_row(&mut self, row: &[(usize, f64)], y: f64, weight: f64) {
        for &(a, ca) in row {
            self.g[a] += weight * ca * y;
            for &(b, cb) in row {
                if b >= a {
                    self.h[a * self.w + (b - a)] += weight * ca * cb;
                }
            }
        }
    }

    /// Solves by banded Cholesky; `None` when the matrix is not positive definite.
    fn solve(mut self) -> Option<Vec<f64>> {
        let (n, w) = (self.n, self.w);
        let bw = w - 1;
        let h = &mut self.h;
        for i in 0..n {
            for j in i..(i + w).min(n) {
                let mut sum = h[i * w + (j - i)];
                for k in j.saturating_sub(bw)..i {
                    sum -= h[k * w + (i - k)] * h[k * w + (j - k)];
                }
                if j == i {
                    if sum.is_nan() || sum <= 0.0 {
                        return None;
                    }
                    h[i * w] = sum.sqrt();
                } else {
                    h[i * w + (j - i)] = sum / h[i * w];
                }
            }
        }
        let b = &mut self.g;
        for i in 0..n {
            let mut s = b[i];
            for k in i.saturating_sub(bw)..i {
                s -= h[k * w + (i - k)] * b[k];
            }
            b[i] = s / h[i * w];
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for j in (i + 1)..(i + w).min(n) {
                s -= h[i * w + (j - i)] * b[j];
            }
            b[i] = s / h[i * w];
        }
        b.iter().all(|x| x.is_finite()).then_some(self.g)
    }
}

/// Solves one joint's knots and interior coefficients for the given elements.
pub(super) fn solve(
    series: &JointSeries<'_>,
    bounds: &[usize],
    elems: &[Elem],
    init: &[Vec<f64>],
    d: usize,
    reweight: Option<&[f64]>,
) -> Option<(Vec<Vec<f64>>, Vec<f64>)> {
    let lay = layout(elems, d);
    let mut ne = Normal::new(lay.n, lay.bw);
    let mut row: Vec<(usize, f64)> = Vec::with_capacity(4 * d);
    for (i, e) in elems.iter().enumerate() {
        let (k0, k1) = (bounds[i], bounds[i + 1]);
        let n = k1 - k0;
        let observed = series.weights[k0..k1].iter().any(|&w| w > 0.0);
        let (va, vb) = (lay.knot_var[i], lay.knot_var[i + 1]);
        let (oa, ob) = (&lay.knot_off[i], &lay.knot_off[i + 1]);
        for t in 0..n {
            let wt = refit_weight(series, observed, k0 + t) * reweight.map_or(1.0, |r| r[k0 + t]);
            if wt <= 0.0 {
                continue;
            }
            let s = t as f64 / n as f64;
            for k in 0..d {
                row.clear();
                let x = series.points[[k0 + t, k]];
                // The constant part of the row goes to the target.
                let mut c = 0.0;
                match e {
                    Elem::Rigid { shape } => {
                        row.push((va + k, 1.0));
                        c += oa[k] + shape[t * d + k];
                    }
                    Elem::Linear | Elem::Cubic => {
                        row.push((va + k, 1.0 - s));
                        row.push((vb + k, s));
                        c += (1.0 - s) * oa[k] + s * ob[k];
                        if let (Elem::Cubic, Some(iv)) = (e, lay.interior[i]) {
                            row.push((iv + k, s * (1.0 - s)));
                            row.push((iv + d + k, s * s * (1.0 - s)));
                        }
                    }
                    Elem::Similar { w } => {
                        let (wr, wi) = w[t];
                        // x = a_x(1 − wr) + a_y·wi + b_x·wr − b_y·wi
                        // y = −a_x·wi + a_y(1 − wr) + b_x·wi + b_y·wr
                        let coefs = if k == 0 {
                            [1.0 - wr, wi, wr, -wi]
                        } else {
                            [-wi, 1.0 - wr, wi, wr]
                        };
                        row.push((va, coefs[0]));
                        row.push((va + 1, coefs[1]));
                        row.push((vb, coefs[2]));
                        row.push((vb + 1, coefs[3]));
                        c += coefs[0] * oa[0]
                            + coefs[1] * oa[1]
                            + coefs[2] * ob[0]
                            + coefs[3] * ob[1];
                    }
                }
                ne.add_row(&row, x - c, wt);
            }
        }
    }
    // Ridge: each group's value towards its first knot's initial pose, interiors towards 0.
    for (i, &v) in lay.knot_var.iter().enumerate() {
        if i > 0 && lay.knot_var[i - 1] == v {
            continue;
        }
        for k in 0..d {
            let y = init[i].get(k).copied().unwrap_or(0.0);
            ne.add_row(&[(v + k, 1.0)], y, RIDGE);
        }
    }
    for iv in lay.interior.iter().flatten() {
        for k in 0..2 * d {
            ne.add_row(&[(iv + k, 1.0)], 0.0, RIDGE);
        }
    }
    let z = ne.solve()?;
    let knots: Vec<Vec<f64>> = (0..lay.knot_var.len())
        .map(|i| {
            (0..d)
                .map(|k| z[lay.knot_var[i] + k] + lay.knot_off[i][k])
                .collect()
        })
        .collect();
    let mut interiors = vec![0.0; elems.len() * 2 * d];
    for (i, iv) in lay.interior.iter().enumerate() {
        if let Some(iv) = iv {
            interiors[i * 2 * d..(i + 1) * 2 * d].copy_from_slice(&z[*iv..*iv + 2 * d]);
        }
    }
    Some((knots, interiors))
}
