//! The selection rules of `fit_best` (docs/ALGORITHMS.md, concrete programs).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::fit::{fit_best, fit_circle, fit_line, fit_stationary, ErrorNorm, FitParams};
use crate::{Primitive, PrimitiveKind};
use ndarray::Array2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn execute(p: &Primitive, n: usize) -> Array2<f64> {
    let d = p.dims();
    Array2::from_shape_fn((n, d), |(i, k)| p.eval(i as f64)[k])
}

fn jitter(a: &mut Array2<f64>, amp: f64, seed: u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    a.mapv_inplace(|v| v + rng.random_range(-amp..amp));
}

fn circle(r: f64, vel: f64) -> Primitive {
    Primitive::Circle {
        center: vec![256.0, 256.0],
        radius: r,
        angle_start: -90.0,
        angle_vel: vel,
        angle_acc: 0.0,
        axes: vec![],
    }
}

#[test]
fn picks_each_kind() {
    let p = FitParams::default();
    let line = Primitive::Line {
        start: vec![100.0, 300.0],
        velocity: vec![4.0, -3.0],
    };
    let mut pts = execute(&line, 20);
    jitter(&mut pts, 0.5, 1);
    assert_eq!(
        fit_best(pts.view(), None, &p).unwrap().primitive.kind(),
        PrimitiveKind::Line
    );

    let mut pts = execute(&circle(80.0, 8.0), 30);
    jitter(&mut pts, 0.5, 2);
    let b = fit_best(pts.view(), None, &p).unwrap();
    assert_eq!(b.primitive.kind(), PrimitiveKind::Circle);
    // 30 ≤ r ≤ 100: no penalty, the error is the plain fit error
    assert_eq!(b.error, fit_circle(pts.view(), None, &p).unwrap().error);

    let mut pts = execute(
        &Primitive::Stationary {
            point: vec![10.0, 20.0],
        },
        12,
    );
    jitter(&mut pts, 2.0, 3);
    assert_eq!(
        fit_best(pts.view(), None, &p).unwrap().primitive.kind(),
        PrimitiveKind::Stationary
    );
}

#[test]
fn stationary_thresholds() {
    // a slow line: bbox diagonal 4 px < 5 → stationary even though the line fits exactly
    let slow = Primitive::Line {
        start: vec![0.0, 0.0],
        velocity: vec![0.2, 0.0],
    };
    let pts = execute(&slow, 21);
    let p = FitParams::default();
    let b = fit_best(pts.view(), None, &p).unwrap();
    assert_eq!(b.primitive.kind(), PrimitiveKind::Stationary);
    assert_eq!(b.error, fit_stationary(pts.view(), None, &p).unwrap().error);
    // with a zero bbox threshold the mean residual (1.05 px < 3) still picks stationary
    let p2 = FitParams {
        stationary_bbox_px: 0.0,
        ..FitParams::default()
    };
    assert_eq!(
        fit_best(pts.view(), None, &p2).unwrap().primitive.kind(),
        PrimitiveKind::Stationary
    );
    // with both thresholds 0 (and no span rejection) the line wins
    let p3 = FitParams {
        stationary_bbox_px: 0.0,
        stationary_mean_residual_px: 0.0,
        min_span_px: 0.0,
        ..FitParams::default()
    };
    assert_eq!(
        fit_best(pts.view(), None, &p3).unwrap().primitive.kind(),
        PrimitiveKind::Line
    );
    // thresholds scale with unit_scale: the same motion in "metres" (1 px = 0.01)
    let metres = pts.mapv(|v| v * 0.01);
    let pm = FitParams {
        unit_scale: 0.01,
        ..FitParams::default()
    };
    assert_eq!(
        fit_best(metres.view(), None, &pm).unwrap().primitive.kind(),
        PrimitiveKind::Stationary
    );
    let pm3 = FitParams {
        unit_scale: 0.01,
        ..p3.clone()
    };
    assert_eq!(
        fit_best(metres.view(), None, &pm3)
            .unwrap()
            .primitive
            .kind(),
        PrimitiveKind::Line
    );
}

#[test]
fn span_rejects_line_and_circle() {
    // a full circle returns to its start: |end − start| ≈ 0 → circle and line rejected
    let pts = execute(&circle(60.0, 360.0 / 30.0), 31);
    let p = FitParams {
        kinds: vec![
            PrimitiveKind::Stationary,
            PrimitiveKind::Line,
            PrimitiveKind::Circle,
            PrimitiveKind::Spline,
        ],
        ..FitParams::default()
    };
    let b = fit_best(pts.view(), None, &p).unwrap();
    assert_eq!(b.primitive.kind(), PrimitiveKind::Spline);
    // without spline, stationary is all that is left
    let b = fit_best(pts.view(), None, &FitParams::default()).unwrap();
    assert_eq!(b.primitive.kind(), PrimitiveKind::Stationary);
    // when every allowed kind would be rejected, nothing is
    let only = FitParams {
        kinds: vec![PrimitiveKind::Circle, PrimitiveKind::Line],
        ..FitParams::default()
    };
    let b = fit_best(pts.view(), None, &only).unwrap();
    assert_eq!(b.primitive.kind(), PrimitiveKind::Circle);
    assert!(b.error < 1e-6);
}

#[test]
fn radius_penalties() {
    let p = FitParams {
        min_span_px: 0.0,
        ..FitParams::default()
    };
    // small circle: r = 20 < 30 → + 3·20
    let pts = execute(&circle(20.0, 10.0), 20);
    let only = FitParams {
        kinds: vec![PrimitiveKind::Circle],
        ..p.clone()
    };
    let raw = fit_circle(pts.view(), None, &only).unwrap().error;
    let b = fit_best(pts.view(), None, &only).unwrap();
    assert!(
        (b.error - (raw + 60.0)).abs() < 1e-9,
        "{} vs {}",
        b.error,
        raw + 60.0
    );
    // large circle: r = 150 > 100 → + 3·50
    let pts = execute(&circle(150.0, 2.0), 20);
    let raw = fit_circle(pts.view(), None, &only).unwrap().error;
    let b = fit_best(pts.view(), None, &only).unwrap();
    assert!((b.error - (raw + 150.0)).abs() < 1e-9);
    assert_eq!(p.circle_penalty(150.0), 150.0);
    assert_eq!(p.circle_penalty(20.0), 60.0);
    assert_eq!(p.circle_penalty(50.0), 0.0);
    let ps = FitParams {
        unit_scale: 2.0,
        ..p.clone()
    };
    assert_eq!(ps.circle_penalty(100.0), 0.0);
    assert_eq!(ps.circle_penalty(50.0), 150.0);
    // a slightly curved, nearly straight arc (huge radius): the line wins by the penalty
    let mut pts = execute(&circle(5000.0, 0.1), 30);
    jitter(&mut pts, 0.3, 9);
    let b = fit_best(pts.view(), None, &p).unwrap();
    assert_eq!(b.primitive.kind(), PrimitiveKind::Line);
    assert_eq!(b.error, fit_line(pts.view(), None, &p).unwrap().error);
}

#[test]
fn squared_norm_and_ties() {
    let line = Primitive::Line {
        start: vec![0.0, 0.0, 0.0],
        velocity: vec![3.0, 1.0, -2.0],
    };
    let pts = execute(&line, 10);
    // an exact line is also an exact spline: the tie goes to the simpler kind
    let p = FitParams {
        kinds: vec![PrimitiveKind::Spline, PrimitiveKind::Line],
        norm: ErrorNorm::Squared,
        ..FitParams::default()
    };
    let b = fit_best(pts.view(), None, &p).unwrap();
    assert!(b.error < 1e-18);
    assert!(matches!(
        b.primitive.kind(),
        PrimitiveKind::Line | PrimitiveKind::Spline
    ));
    let exact = pts.mapv(|v| v.round());
    let b = fit_best(exact.view(), None, &p).unwrap();
    assert_eq!(b.primitive.kind(), PrimitiveKind::Line);
}
