//! Noiseless primitives are recovered by their own fit (fit(execute(p)) ≈ p),
//! in 2D and 3D, for every kind.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::fit::{
    fit_best, fit_circle, fit_kind, fit_line, fit_spline, fit_stationary, residual_error,
    ErrorNorm, FitParams,
};
use crate::{Primitive, PrimitiveKind};
use ndarray::Array2;
use proptest::prelude::*;

fn execute(p: &Primitive, n: usize) -> Array2<f64> {
    let d = p.dims();
    let mut out = Array2::zeros((n, d));
    for i in 0..n {
        let v = p.eval(i as f64);
        for k in 0..d {
            out[[i, k]] = v[k];
        }
    }
    out
}

/// Largest distance between two primitives executed over 0..n, relative to `scale`.
fn max_rel_gap(a: &Primitive, b: &Primitive, n: usize, scale: f64) -> f64 {
    let mut m: f64 = 0.0;
    for i in 0..n {
        let (x, y) = (a.eval(i as f64), b.eval(i as f64));
        let d: f64 = x
            .iter()
            .zip(&y)
            .map(|(p, q)| (p - q) * (p - q))
            .sum::<f64>()
            .sqrt();
        m = m.max(d / scale);
    }
    m
}

fn close(a: f64, b: f64, scale: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * scale.max(1e-300)
}

fn angle_diff_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

fn unit_axes(normal: [f64; 3], twist: f64) -> (Vec<f64>, Vec<f64>) {
    let n = {
        let l = normal.iter().map(|v| v * v).sum::<f64>().sqrt();
        [normal[0] / l, normal[1] / l, normal[2] / l]
    };
    // any vector not parallel to n
    let a = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let cross = |x: [f64; 3], y: [f64; 3]| {
        [
            x[1] * y[2] - x[2] * y[1],
            x[2] * y[0] - x[0] * y[2],
            x[0] * y[1] - x[1] * y[0],
        ]
    };
    let norm = |x: [f64; 3]| {
        let l = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        [x[0] / l, x[1] / l, x[2] / l]
    };
    let u0 = norm(cross(n, a));
    let v0 = cross(n, u0);
    let (s, c) = twist.sin_cos();
    let u: Vec<f64> = (0..3).map(|k| c * u0[k] + s * v0[k]).collect();
    let v: Vec<f64> = (0..3).map(|k| -s * u0[k] + c * v0[k]).collect();
    (u, v)
}

#[test]
fn stationary_2d_3d() {
    let p = FitParams::default();
    for point in [vec![3.5, -2.0], vec![1.0, 2.0, 3.0]] {
        let prim = Primitive::Stationary {
            point: point.clone(),
        };
        let pts = execute(&prim, 10);
        let f = fit_stationary(pts.view(), None, &p).unwrap();
        assert_eq!(f.primitive.kind(), PrimitiveKind::Stationary);
        assert!(f.error < 1e-12);
        if let Primitive::Stationary { point: q } = &f.primitive {
            for (a, b) in point.iter().zip(q) {
                assert!((a - b).abs() < 1e-12);
            }
        }
    }
}

#[test]
fn weighted_mean_ignores_zero_weights() {
    let pts = ndarray::array![[0.0, 0.0], [f64::NAN, 7.0], [2.0, 4.0]];
    let w = [1.0, 0.0, 3.0];
    let f = fit_stationary(pts.view(), Some(&w), &FitParams::default()).unwrap();
    assert_eq!(
        f.primitive,
        Primitive::Stationary {
            point: vec![1.5, 3.0]
        }
    );
    // error = 1·‖(1.5,3)‖ + 3·‖(0.5,1)‖
    let e = 1.5f64.hypot(3.0) + 3.0 * 0.5f64.hypot(1.0);
    assert!((f.error - e).abs() < 1e-12, "{} vs {e}", f.error);
    let sq = FitParams {
        norm: ErrorNorm::Squared,
        ..FitParams::default()
    };
    let f = fit_stationary(pts.view(), Some(&w), &sq).unwrap();
    assert!((f.error - (11.25 + 3.0 * 1.25)).abs() < 1e-12);
}

#[test]
fn vertical_line_2d() {
    let prim = Primitive::Line {
        start: vec![120.0, 40.0],
        velocity: vec![0.0, 7.5],
    };
    let pts = execute(&prim, 20);
    let f = fit_line(pts.view(), None, &FitParams::default()).unwrap();
    assert!(f.error < 1e-9);
    let Primitive::Line { start, velocity } = &f.primitive else {
        panic!("not a line")
    };
    assert!(close(start[0], 120.0, 120.0, 1e-9) && close(start[1], 40.0, 40.0, 1e-9));
    assert!(velocity[0].abs() < 1e-9 && close(velocity[1], 7.5, 7.5, 1e-9));
    let best = fit_best(pts.view(), None, &FitParams::default()).unwrap();
    assert_eq!(best.primitive.kind(), PrimitiveKind::Line);
}

#[test]
fn line_3d_with_gaps() {
    let prim = Primitive::Line {
        start: vec![0.1, -0.3, 1.2],
        velocity: vec![0.01, 0.02, -0.005],
    };
    let mut pts = execute(&prim, 15);
    let mut w = vec![1.0; 15];
    for i in [0usize, 3, 4, 14] {
        w[i] = 0.0;
        pts[[i, 1]] = f64::NAN;
    }
    let f = fit_line(pts.view(), Some(&w), &FitParams::default()).unwrap();
    assert!(max_rel_gap(&f.primitive, &prim, 15, 1.0) < 1e-9);
}

#[test]
fn circle_2d_small_arc() {
    // < 90° of arc: 30 frames at 2.5°/frame = 72.5°
    let prim = Primitive::Circle {
        center: vec![220.56, 175.67],
        radius: 108.23,
        angle_start: 79.99,
        angle_vel: 2.5,
        angle_acc: 0.0,
        axes: vec![],
    };
    let pts = execute(&prim, 30);
    let f = fit_circle(pts.view(), None, &FitParams::default()).unwrap();
    let Primitive::Circle {
        center,
        radius,
        angle_start,
        angle_vel,
        angle_acc,
        ..
    } = &f.primitive
    else {
        panic!("not a circle")
    };
    let r = 108.23;
    assert!(close(center[0], 220.56, r, 1e-6) && close(center[1], 175.67, r, 1e-6));
    assert!(close(*radius, r, r, 1e-6));
    assert!(angle_diff_deg(*angle_start, 79.99) < 1e-6);
    assert!(close(*angle_vel, 2.5, 2.5, 1e-6));
    assert_eq!(*angle_acc, 0.0);
    assert!(f.error < 1e-6 * r);
}

#[test]
fn circle_2d_clockwise_wrapping() {
    // crosses ±180° several times, negative velocity
    let prim = Primitive::Circle {
        center: vec![-5.0, 12.0],
        radius: 40.0,
        angle_start: -156.79,
        angle_vel: -23.0,
        angle_acc: 0.0,
        axes: vec![],
    };
    let pts = execute(&prim, 40);
    let f = fit_circle(pts.view(), None, &FitParams::default()).unwrap();
    assert!(max_rel_gap(&f.primitive, &prim, 40, 40.0) < 1e-6);
    let Primitive::Circle { angle_vel, .. } = f.primitive else {
        panic!()
    };
    assert!((angle_vel + 23.0).abs() < 1e-6);
}

#[test]
fn circle_quadratic_angle() {
    let prim = Primitive::Circle {
        center: vec![0.0, 0.0],
        radius: 50.0,
        angle_start: 10.0,
        angle_vel: 1.0,
        angle_acc: 0.3,
        axes: vec![],
    };
    let pts = execute(&prim, 25);
    let params = FitParams {
        quadratic_angle: true,
        ..FitParams::default()
    };
    let f = fit_circle(pts.view(), None, &params).unwrap();
    let Primitive::Circle { angle_acc, .. } = &f.primitive else {
        panic!()
    };
    assert!((angle_acc - 0.3).abs() < 1e-6);
    assert!(max_rel_gap(&f.primitive, &prim, 25, 50.0) < 1e-6);
    // bound: the fitted acceleration is clamped
    let params = FitParams {
        quadratic_angle: true,
        max_angle_acc_deg: 0.1,
        ..FitParams::default()
    };
    let f = fit_circle(pts.view(), None, &params).unwrap();
    let Primitive::Circle { angle_acc, .. } = &f.primitive else {
        panic!()
    };
    assert!((angle_acc - 0.1).abs() < 1e-12);
    // without the quadratic term, the acceleration is 0
    let f = fit_circle(pts.view(), None, &FitParams::default()).unwrap();
    let Primitive::Circle { angle_acc, .. } = &f.primitive else {
        panic!()
    };
    assert_eq!(*angle_acc, 0.0);
}

#[test]
fn circle_3d_tilted() {
    let (u, v) = unit_axes([0.3, -0.5, 0.8], 0.7);
    let prim = Primitive::Circle {
        center: vec![0.2, 1.1, -0.4],
        radius: 0.35,
        angle_start: 30.0,
        angle_vel: 2.0, // 58° over 30 frames
        angle_acc: 0.0,
        axes: vec![u, v],
    };
    let pts = execute(&prim, 30);
    let f = fit_circle(pts.view(), None, &FitParams::default()).unwrap();
    let Primitive::Circle {
        center,
        radius,
        axes,
        angle_vel,
        ..
    } = &f.primitive
    else {
        panic!()
    };
    for k in 0..3 {
        assert!(close(center[k], [0.2, 1.1, -0.4][k], 0.35, 1e-6));
    }
    assert!(close(*radius, 0.35, 0.35, 1e-6));
    assert!((angle_vel.abs() - 2.0).abs() < 1e-6);
    assert_eq!(axes.len(), 2);
    let dot: f64 = axes[0].iter().zip(&axes[1]).map(|(a, b)| a * b).sum();
    assert!(dot.abs() < 1e-12);
    assert!(max_rel_gap(&f.primitive, &prim, 30, 0.35) < 1e-6);
}

#[test]
fn spline_2d_3d_and_short() {
    let prim = Primitive::Spline {
        coeffs: vec![
            [0.01, -0.3, 2.0, 100.0],
            [-0.002, 0.05, -1.0, 50.0],
            [0.0, 0.1, 0.0, -3.0],
        ],
    };
    let pts = execute(&prim, 40);
    let f = fit_spline(pts.view(), None, &FitParams::default()).unwrap();
    let Primitive::Spline { coeffs } = &f.primitive else {
        panic!()
    };
    let Primitive::Spline { coeffs: truth } = &prim else {
        panic!()
    };
    for (c, t) in coeffs.iter().zip(truth) {
        for j in 0..4 {
            assert!(
                (c[j] - t[j]).abs() <= 1e-6 * (1.0 + t[j].abs()),
                "{c:?} vs {t:?}"
            );
        }
    }
    // 2D subset
    let pts2 = pts.slice(ndarray::s![.., 0..2]).to_owned();
    let f2 = fit_spline(pts2.view(), None, &FitParams::default()).unwrap();
    assert!(f2.error < 1e-6);
    // three points: exact quadratic, zero cubic term
    let three = ndarray::array![[0.0, 1.0], [1.0, 3.0], [4.0, 7.0]];
    let f3 = fit_spline(three.view(), None, &FitParams::default()).unwrap();
    let Primitive::Spline { coeffs } = &f3.primitive else {
        panic!()
    };
    assert_eq!(coeffs[0][0], 0.0);
    assert!(f3.error < 1e-9);
    // one point: constant
    let one = ndarray::array![[2.0, 5.0]];
    let f1 = fit_spline(one.view(), None, &FitParams::default()).unwrap();
    assert_eq!(f1.primitive.eval(3.0), vec![2.0, 5.0]);
}

#[test]
fn residual_error_conventions() {
    let prim = Primitive::Line {
        start: vec![0.0, 0.0],
        velocity: vec![1.0, 0.0],
    };
    let pts = ndarray::array![[0.0, 3.0], [1.0, -4.0], [9.0, 9.0]];
    let w = [1.0, 2.0, 0.0];
    assert!(
        (residual_error(&prim, pts.view(), Some(&w), ErrorNorm::Euclidean) - 11.0).abs() < 1e-12
    );
    assert!((residual_error(&prim, pts.view(), Some(&w), ErrorNorm::Squared) - 41.0).abs() < 1e-12);
    // wrong dimension: never fits
    let p3 = Primitive::Stationary {
        point: vec![0.0, 0.0, 0.0],
    };
    assert_eq!(
        residual_error(&p3, pts.view(), None, ErrorNorm::Euclidean),
        f64::INFINITY
    );
    assert_eq!(
        residual_error(&prim, pts.view(), Some(&[1.0]), ErrorNorm::Euclidean),
        f64::INFINITY
    );
}

fn kind_strategy() -> impl Strategy<Value = PrimitiveKind> {
    prop_oneof![
        Just(PrimitiveKind::Stationary),
        Just(PrimitiveKind::Line),
        Just(PrimitiveKind::Circle),
        Just(PrimitiveKind::Spline),
    ]
}

/// A random primitive of `kind` in `d` dimensions with "pixel" magnitudes.
fn make(kind: PrimitiveKind, d: usize, v: &[f64]) -> Primitive {
    match kind {
        PrimitiveKind::Stationary => Primitive::Stationary {
            point: (0..d).map(|k| 500.0 * v[k]).collect(),
        },
        PrimitiveKind::Line => Primitive::Line {
            start: (0..d).map(|k| 500.0 * v[k]).collect(),
            velocity: (0..d).map(|k| 10.0 * v[3 + k]).collect(),
        },
        PrimitiveKind::Circle => {
            let radius = 5.0 + 200.0 * v[6].abs();
            // |vel| between 1° and 15° per frame: arcs of 20°..300° over 20 frames
            let vel = (1.0 + 14.0 * v[7].abs()) * v[8].signum();
            let axes = if d == 3 {
                let (u, w) = unit_axes([v[0], v[1], v[2] + 2.0], v[9] * 3.0);
                vec![u, w]
            } else {
                vec![]
            };
            Primitive::Circle {
                center: (0..d).map(|k| 300.0 * v[3 + k]).collect(),
                radius,
                angle_start: 179.0 * v[10],
                angle_vel: vel,
                angle_acc: 0.0,
                axes,
            }
        }
        PrimitiveKind::Spline => Primitive::Spline {
            coeffs: (0..d)
                .map(|k| {
                    [
                        0.01 * v[k],
                        0.2 * v[3 + k],
                        5.0 * v[6 + k],
                        300.0 * v[9 + (k % 2)],
                    ]
                })
                .collect(),
        },
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn fit_of_execute_recovers(
        kind in kind_strategy(),
        d in 2usize..=3,
        n in 8usize..60,
        v in prop::collection::vec(-1.0f64..1.0, 11),
    ) {
        let prim = make(kind, d, &v);
        let pts = execute(&prim, n);
        let f = fit_kind(kind, pts.view(), None, &FitParams::default()).unwrap();
        let scale = match &prim {
            Primitive::Circle { radius, .. } => *radius,
            _ => 1.0 + pts.iter().fold(0.0f64, |m, x| m.max(x.abs())),
        };
        let gap = max_rel_gap(&f.primitive, &prim, n, scale);
        prop_assert!(gap < 1e-6, "{kind:?} d={d} n={n}: gap {gap:e}\n{:?}\nvs {:?}", f.primitive, prim);
        prop_assert!(f.error <= 1e-6 * scale * n as f64);
        // parameters themselves (2D: unique; 3D circle: basis is free, compare geometry)
        match (&prim, &f.primitive) {
            (Primitive::Circle { center: c0, radius: r0, angle_vel: w0, .. },
             Primitive::Circle { center: c1, radius: r1, angle_vel: w1, angle_start: s1, .. }) => {
                for k in 0..d { prop_assert!((c0[k] - c1[k]).abs() < 1e-6 * r0); }
                prop_assert!((r0 - r1).abs() < 1e-6 * r0);
                if d == 2 {
                    prop_assert!((w0 - w1).abs() < 1e-6 * w0.abs());
                    let Primitive::Circle { angle_start: s0, .. } = &prim else { unreachable!() };
                    prop_assert!(angle_diff_deg(*s0, *s1) < 1e-6 * 360.0);
                } else {
                    prop_assert!((w0.abs() - w1.abs()).abs() < 1e-6 * w0.abs());
                }
            }
            (Primitive::Line { start: a0, velocity: b0 }, Primitive::Line { start: a1, velocity: b1 }) => {
                for k in 0..d {
                    prop_assert!((a0[k] - a1[k]).abs() <= 1e-6 * (1.0 + a0[k].abs()));
                    prop_assert!((b0[k] - b1[k]).abs() <= 1e-6 * (1.0 + b0[k].abs()));
                }
            }
            _ => {}
        }
    }
}
