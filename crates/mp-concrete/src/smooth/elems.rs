//! How each segment of a joint depends on the refit's unknowns (the knots and
//! the cubics' interior coefficients), and the primitives back from them.

use mp_geom::Primitive;

use super::MAX_SIMILARITY_GAIN;

/// How one segment of one joint depends on the unknowns.
#[derive(Debug, Clone)]
pub(super) enum Elem {
    /// `p(t) = v_i + shape(t)`, `v_{i+1} = v_i + shape(n)`; `shape` of length `(n + 1)·D`.
    Rigid { shape: Vec<f64> },
    /// Line between the knots.
    Linear,
    /// Line plus `s(1 − s)(a + b s)` per axis.
    Cubic,
    /// 2D arc: `v_i + (v_{i+1} − v_i)·w(t)`, `w` complex per frame (length `n`).
    Similar { w: Vec<(f64, f64)> },
}

/// The element of a fitted primitive over `n` frames of `d` dimensions.
pub(super) fn elem_of(p: &Primitive, n: usize, d: usize) -> Elem {
    let rigid = |p: &Primitive| {
        let p0 = p.eval(0.0);
        let mut shape = Vec::with_capacity((n + 1) * d);
        for t in 0..=n {
            let pt = p.eval(t as f64);
            shape.extend(pt.iter().zip(&p0).map(|(a, b)| a - b));
        }
        Elem::Rigid { shape }
    };
    match p {
        Primitive::Stationary { .. } => Elem::Rigid {
            shape: vec![0.0; (n + 1) * d],
        },
        Primitive::Line { .. } => Elem::Linear,
        Primitive::Spline { .. } => Elem::Cubic,
        Primitive::Circle { .. } if d == 2 => {
            let p0 = p.eval(0.0);
            let pn = p.eval(n as f64);
            let (cx, cy) = (pn[0] - p0[0], pn[1] - p0[1]);
            let c2 = cx * cx + cy * cy;
            let scale = p0[0].abs().max(p0[1].abs()).max(1.0);
            let chord = c2.sqrt();
            if chord.is_nan() || chord <= 1e-9 * scale {
                return rigid(p);
            }
            let mut w = Vec::with_capacity(n);
            for t in 0..n {
                let q = p.eval(t as f64);
                let (dx, dy) = (q[0] - p0[0], q[1] - p0[1]);
                // (dx + i dy) / (cx + i cy)
                let wr = (dx * cx + dy * cy) / c2;
                let wi = (dy * cx - dx * cy) / c2;
                if wr.hypot(wi) > MAX_SIMILARITY_GAIN {
                    return rigid(p);
                }
                w.push((wr, wi));
            }
            Elem::Similar { w }
        }
        Primitive::Circle { .. } => rigid(p),
    }
}

/// Per-knot initial poses: the independent fits' boundary poses (mean of the
/// end of one segment and the start of the next).
pub(super) fn initial_knots(prims: &[Primitive], durations: &[usize]) -> Vec<Vec<f64>> {
    let s = prims.len();
    let mut out = Vec::with_capacity(s + 1);
    for i in 0..=s {
        let a = (i > 0).then(|| prims[i - 1].eval(durations[i - 1] as f64));
        let b = (i < s).then(|| prims[i].eval(0.0));
        out.push(match (a, b) {
            (Some(a), Some(b)) => a.iter().zip(&b).map(|(x, y)| 0.5 * (x + y)).collect(),
            (Some(a), None) => a,
            (None, Some(b)) => b,
            (None, None) => Vec::new(),
        });
    }
    out
}

/// The primitive of segment `i` from the solved knots.
fn primitive_of(
    orig: &Primitive,
    e: &Elem,
    n: usize,
    a: &[f64],
    b: &[f64],
    interior: &[f64],
) -> Primitive {
    let d = a.len();
    let nf = n as f64;
    match e {
        Elem::Linear => Primitive::Line {
            start: a.to_vec(),
            velocity: a.iter().zip(b).map(|(x, y)| (y - x) / nf).collect(),
        },
        Elem::Cubic => {
            // Polynomial in s: c0 + c1 s + c2 s² + c3 s³, then in t = n s.
            let coeffs = (0..d)
                .map(|k| {
                    let (ia, ib) = (interior[k], interior[d + k]);
                    let c0 = a[k];
                    let c1 = b[k] - a[k] + ia;
                    let c2 = ib - ia;
                    let c3 = -ib;
                    [c3 / (nf * nf * nf), c2 / (nf * nf), c1 / nf, c0]
                })
                .collect();
            Primitive::Spline { coeffs }
        }
        Elem::Rigid { .. } => match orig {
            Primitive::Stationary { .. } => Primitive::Stationary { point: a.to_vec() },
            other => {
                let p0 = other.eval(0.0);
                Primitive::translated(
                    other,
                    &a.iter().zip(&p0).map(|(x, y)| x - y).collect::<Vec<_>>(),
                )
            }
        },
        Elem::Similar { .. } => similar_circle(orig, n, a, b),
    }
}

/// Every segment's primitive from the solved knots and interiors.
pub(super) fn primitives_of(
    prims: &[Primitive],
    elems: &[Elem],
    durations: &[usize],
    knots: &[Vec<f64>],
    interiors: &[f64],
) -> Vec<Primitive> {
    let d2 = interiors.len() / prims.len().max(1);
    (0..prims.len())
        .map(|i| {
            primitive_of(
                &prims[i],
                &elems[i],
                durations[i],
                &knots[i],
                &knots[i + 1],
                &interiors[i * d2..(i + 1) * d2],
            )
        })
        .collect()
}

/// The 2D circle `orig` mapped by the similarity taking its chord onto `b − a`, starting at `a`.
fn similar_circle(orig: &Primitive, n: usize, a: &[f64], b: &[f64]) -> Primitive {
    let Primitive::Circle {
        center,
        radius,
        angle_start,
        angle_vel,
        angle_acc,
        axes,
    } = orig
    else {
        return orig.clone();
    };
    let p0 = orig.eval(0.0);
    let pn = orig.eval(n as f64);
    let (cx, cy) = (pn[0] - p0[0], pn[1] - p0[1]);
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let c2 = cx * cx + cy * cy;
    // A = (ex + i ey) / (cx + i cy)
    let ar = (ex * cx + ey * cy) / c2;
    let ai = (ey * cx - ex * cy) / c2;
    let (ux, uy) = (center[0] - p0[0], center[1] - p0[1]);
    let new_center = vec![a[0] + ar * ux - ai * uy, a[1] + ai * ux + ar * uy];
    let phi = ai.atan2(ar).to_degrees();
    let mut start = angle_start + phi;
    start -= 360.0 * ((start - 180.0) / 360.0).ceil();
    Primitive::Circle {
        center: new_center,
        radius: radius * ar.hypot(ai),
        angle_start: start,
        angle_vel: *angle_vel,
        angle_acc: *angle_acc,
        axes: axes.clone(),
    }
}
