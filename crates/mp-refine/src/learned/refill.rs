//! Refill of flagged frames (step 0): each run of flagged frames of a joint
//! is rebuilt from the nearest unflagged frames before and after it
//! ([`FlawRepair`]).

use nalgebra::{Matrix4, Vector4};
use ndarray::{Array2, Array3};

use super::{FlawRepair, RepairedRun};
use crate::error::{RefineError, Result};

/// Refills the flagged frames of each joint of `pos` (`T × J × D`, flags
/// `T × J`) from the nearest unflagged frames before and after each run.
/// A run at the start or end holds its one clean neighbour; a joint
/// flagged in every frame, and runs longer than `max_run`, are left as
/// they are. Returns the refilled runs.
pub fn repair_flagged(
    pos: &mut Array3<f64>,
    flags: &Array2<bool>,
    method: FlawRepair,
    max_run: usize,
) -> Result<Vec<RepairedRun>> {
    let (t, nj, d) = pos.dim();
    if flags.dim() != (t, nj) {
        return Err(RefineError::Shape(format!(
            "repair_flagged: flags {:?} for positions {:?}",
            flags.dim(),
            pos.dim()
        )));
    }
    let mut runs = Vec::new();
    for j in 0..nj {
        let mut f = 0;
        while f < t {
            if !flags[[f, j]] {
                f += 1;
                continue;
            }
            let r0 = f;
            while f < t && flags[[f, j]] {
                f += 1;
            }
            let r1 = f - 1;
            if r1 - r0 + 1 > max_run || (r0 == 0 && r1 + 1 == t) {
                continue;
            }
            let a = r0.checked_sub(1);
            let b = (r1 + 1 < t).then_some(r1 + 1);
            for k in 0..d {
                match (a, b) {
                    (Some(a), Some(b)) => {
                        let (pa, pb) = (pos[[a, j, k]], pos[[b, j, k]]);
                        let len = (b - a) as f64;
                        let chord = (pb - pa) / len;
                        if let FlawRepair::CubicFit { context } = method {
                            let mut ctx: Vec<usize> = Vec::new();
                            let mut g = a as isize;
                            while g >= 0 && ctx.len() < context.max(1) {
                                if !flags[[g as usize, j]] {
                                    ctx.push(g as usize);
                                }
                                g -= 1;
                            }
                            let n_before = ctx.len();
                            let mut g = b;
                            while g < t && ctx.len() < n_before + context.max(1) {
                                if !flags[[g, j]] {
                                    ctx.push(g);
                                }
                                g += 1;
                            }
                            let fit = poly_fit(
                                &ctx.iter().map(|&g| g as f64).collect::<Vec<_>>(),
                                &ctx.iter().map(|&g| pos[[g, j, k]]).collect::<Vec<_>>(),
                                if ctx.len() >= 6 { 3 } else { 1 },
                                a as f64,
                                len,
                            );
                            if let Some(c) = fit {
                                for g in r0..=r1 {
                                    let u = (g as f64 - a as f64) / len;
                                    pos[[g, j, k]] = ((c[3] * u + c[2]) * u + c[1]) * u + c[0];
                                }
                                continue;
                            }
                        }
                        let (ma, mb) = match method {
                            FlawRepair::Linear | FlawRepair::CubicFit { .. } => (chord, chord),
                            FlawRepair::Cubic => (
                                if a >= 1 && !flags[[a - 1, j]] {
                                    pa - pos[[a - 1, j, k]]
                                } else {
                                    chord
                                },
                                if b + 1 < t && !flags[[b + 1, j]] {
                                    pos[[b + 1, j, k]] - pb
                                } else {
                                    chord
                                },
                            ),
                        };
                        for g in r0..=r1 {
                            let s = (g - a) as f64 / len;
                            let (s2, s3) = (s * s, s * s * s);
                            pos[[g, j, k]] = (2.0 * s3 - 3.0 * s2 + 1.0) * pa
                                + (s3 - 2.0 * s2 + s) * len * ma
                                + (-2.0 * s3 + 3.0 * s2) * pb
                                + (s3 - s2) * len * mb;
                        }
                    }
                    (Some(a), None) => {
                        let v = pos[[a, j, k]];
                        for g in r0..=r1 {
                            pos[[g, j, k]] = v;
                        }
                    }
                    (None, Some(b)) => {
                        let v = pos[[b, j, k]];
                        for g in r0..=r1 {
                            pos[[g, j, k]] = v;
                        }
                    }
                    (None, None) => {}
                }
            }
            runs.push(RepairedRun {
                joint: j,
                start: r0,
                end: r1,
            });
        }
    }
    Ok(runs)
}

/// Least-squares polynomial of degree `deg` (1 or 3) through `(x, y)`, in
/// `u = (x − x0)/scale`; coefficients of `1, u, u², u³`. `None` when the
/// system is singular.
fn poly_fit(x: &[f64], y: &[f64], deg: usize, x0: f64, scale: f64) -> Option<[f64; 4]> {
    let m = deg.min(3) + 1;
    if x.len() < m || scale <= 0.0 {
        return None;
    }
    let mut ata = Matrix4::<f64>::identity();
    let mut aty = Vector4::<f64>::zeros();
    for r in 0..m {
        ata[(r, r)] = 0.0;
    }
    for (&xi, &yi) in x.iter().zip(y) {
        let u = (xi - x0) / scale;
        let v = Vector4::new(1.0, u, u * u, u * u * u);
        for r in 0..m {
            for c in 0..m {
                ata[(r, c)] += v[r] * v[c];
            }
            aty[r] += v[r] * yi;
        }
    }
    let c = ata.try_inverse()? * aty;
    let mut out = [0.0; 4];
    for r in 0..m {
        out[r] = c[r];
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repair_is_exact_on_lines_and_cubics() {
        let t = 20;
        let mut pos = Array3::<f64>::zeros((t, 2, 3));
        for f in 0..t {
            let x = f as f64;
            for k in 0..3 {
                pos[[f, 0, k]] = 0.1 * x + k as f64; // a line
                pos[[f, 1, k]] = 0.001 * x * x * x - 0.02 * x * x + 0.3 * x; // a cubic
            }
        }
        let clean = pos.clone();
        let mut flags = Array2::from_elem((t, 2), false);
        for f in 7..11 {
            flags[[f, 0]] = true;
            flags[[f, 1]] = true;
            pos[[f, 0, 1]] += 0.5;
            pos[[f, 1, 2]] -= 0.5;
        }
        let mut lin = pos.clone();
        let runs = repair_flagged(&mut lin, &flags, FlawRepair::Linear, 30).unwrap();
        assert_eq!(runs.len(), 2);
        assert_eq!((runs[0].joint, runs[0].start, runs[0].end), (0, 7, 10));
        for f in 0..t {
            for k in 0..3 {
                assert!((lin[[f, 0, k]] - clean[[f, 0, k]]).abs() < 1e-12);
            }
        }
        // A Hermite cubic with one-sided velocities is not the cubic itself,
        // but it is much closer than the straight line.
        let mut cub = pos.clone();
        repair_flagged(&mut cub, &flags, FlawRepair::Cubic, 30).unwrap();
        let err = |x: &Array3<f64>| {
            (7..11)
                .map(|f| (x[[f, 1, 2]] - clean[[f, 1, 2]]).abs())
                .fold(0.0, f64::max)
        };
        assert!(err(&cub) < 0.5 * err(&lin), "{} {}", err(&cub), err(&lin));
        // Untouched frames stay bit-identical; runs longer than the limit stay.
        assert_eq!(cub[[3, 1, 2]], pos[[3, 1, 2]]);
        let mut long = pos.clone();
        assert!(repair_flagged(&mut long, &flags, FlawRepair::Linear, 3)
            .unwrap()
            .is_empty());
        assert_eq!(long, pos);
        // A run at the start holds its clean neighbour.
        let mut start = Array2::from_elem((t, 2), false);
        start[[0, 0]] = true;
        start[[1, 0]] = true;
        let mut s0 = pos.clone();
        repair_flagged(&mut s0, &start, FlawRepair::Cubic, 30).unwrap();
        assert_eq!(s0[[0, 0, 1]], pos[[2, 0, 1]]);
        assert!(repair_flagged(
            &mut s0,
            &Array2::from_elem((3, 2), false),
            FlawRepair::Cubic,
            3
        )
        .is_err());
    }
}
