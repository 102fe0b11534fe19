//! Single primitive fits on 30-frame segments (the inner loop of the
//! segmentation DP), in 2D and 3D, plus the O(1) prefix-sum path and the
//! circle fit's angles.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // bench code: failing loudly is the point

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use mp_geom::{
    fit_best, fit_circle, fit_line, fit_spline, fit_stationary, residual_error, ErrorNorm,
    FitParams, PrefixFits,
};
use ndarray::Array2;

const N: usize = 30;

/// A noisy circular arc in 2D or 3D (deterministic "noise").
fn segment(d: usize) -> Array2<f64> {
    Array2::from_shape_fn((N, d), |(i, k)| {
        let th = (40.0 + 3.0 * i as f64).to_radians();
        let wobble = 0.7 * ((i * 7 + k * 3) as f64).sin();
        match k {
            0 => 250.0 + 90.0 * th.cos() + wobble,
            1 => 180.0 + 90.0 * th.sin() + wobble,
            _ => 20.0 + 0.3 * i as f64 + wobble,
        }
    })
}

fn bench_fits(c: &mut Criterion) {
    let params = FitParams::default();
    for d in [2usize, 3] {
        let pts = segment(d);
        let w = vec![1.0; N];
        let mut g = c.benchmark_group(format!("fit_{d}d_30"));
        g.bench_function("stationary", |b| {
            b.iter(|| fit_stationary(black_box(pts.view()), None, &params))
        });
        g.bench_function("line", |b| {
            b.iter(|| fit_line(black_box(pts.view()), None, &params))
        });
        g.bench_function("circle", |b| {
            b.iter(|| fit_circle(black_box(pts.view()), None, &params))
        });
        g.bench_function("spline", |b| {
            b.iter(|| fit_spline(black_box(pts.view()), None, &params))
        });
        g.bench_function("best", |b| {
            b.iter(|| fit_best(black_box(pts.view()), None, &params))
        });
        g.bench_function("best_weighted", |b| {
            b.iter(|| fit_best(black_box(pts.view()), Some(&w), &params))
        });
        // a joint's trajectory inside a T × J × D array (strided rows, as in the DP)
        let tjd = ndarray::Array3::from_shape_fn((N, 17, d), |(i, j, k)| pts[[i, k]] + j as f64);
        let joint = tjd.slice(ndarray::s![.., 5, ..]);
        g.bench_function("best_strided_view", |b| {
            b.iter(|| fit_best(black_box(joint), None, &params))
        });
        let line = fit_line(pts.view(), None, &params).unwrap().primitive;
        g.bench_function("residual_error_line", |b| {
            b.iter(|| residual_error(black_box(&line), pts.view(), None, ErrorNorm::Euclidean))
        });
        g.finish();
    }
    // prefix sums: build once for a 10k-frame trajectory, then O(1) segments
    let long = Array2::from_shape_fn((10_000, 2), |(i, k)| {
        200.0 + 50.0 * ((i as f64) * 0.05 + k as f64).sin()
    });
    let pf = PrefixFits::new(long.view(), None).unwrap();
    let mut g = c.benchmark_group("prefix_2d");
    g.bench_function("build_10k", |b| {
        b.iter(|| PrefixFits::new(black_box(long.view()), None))
    });
    g.bench_function("line_sq_error_30", |b| {
        b.iter(|| pf.line_sq_error(black_box(5000), black_box(5030)))
    });
    g.bench_function("line_fit_30", |b| {
        b.iter(|| pf.line(black_box(5000), black_box(5030)))
    });
    g.finish();
}

/// The circle fit's angles: 1,024 points, the C library's `atan2` one by one
/// against the batch of `mp_geom::atan` (four lanes, AVX2 where the CPU
/// has it).
fn bench_atan2(c: &mut Criterion) {
    let n = 1024;
    let ys: Vec<f64> = (0..n).map(|i| ((i * 7919) % 1000) as f64 - 500.0).collect();
    let xs: Vec<f64> = (0..n)
        .map(|i| ((i * 104_729) % 997) as f64 - 498.0)
        .collect();
    let mut out = vec![0.0; n];
    let mut g = c.benchmark_group("atan2_1024");
    g.bench_function("libm", |b| {
        b.iter(|| {
            for ((o, &y), &x) in out.iter_mut().zip(&ys).zip(&xs) {
                *o = black_box(y).atan2(x);
            }
        })
    });
    g.bench_function("batch", |b| {
        b.iter(|| mp_geom::atan2_into(black_box(&ys), &xs, &mut out))
    });
    g.finish();
}

criterion_group!(benches, bench_fits, bench_atan2);
criterion_main!(benches);
