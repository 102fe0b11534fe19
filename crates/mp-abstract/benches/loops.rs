//! Loop detection on 1k / 10k / 100k primitives (13 joints, 2D): a
//! repeating body of 3 with noise, interleaved with non-repeating stretches.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // bench code: failing loudly is the point

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use mp_abstract::DetPrim;
use mp_abstract::{detect_loops, LoopParams};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn prims(n: usize) -> Vec<DetPrim> {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let body: Vec<Vec<Vec<f64>>> = (0..3)
        .map(|_| {
            (0..13)
                .map(|_| (0..6).map(|_| rng.random_range(0.0..500.0)).collect())
                .collect()
        })
        .collect();
    (0..n)
        .map(|i| {
            let block = (i / 60) % 2 == 0;
            let points = if block {
                body[i % 3]
                    .iter()
                    .map(|v| v.iter().map(|x| x + rng.random_range(-2.0..2.0)).collect())
                    .collect()
            } else {
                (0..13)
                    .map(|_| (0..6).map(|_| rng.random_range(0.0..500.0)).collect())
                    .collect()
            };
            DetPrim {
                duration: 10,
                points,
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("detect_loops");
    g.sample_size(10);
    for n in [1_000, 10_000, 100_000] {
        let p = prims(n);
        g.bench_with_input(BenchmarkId::from_parameter(n), &p, |b, p| {
            b.iter(|| {
                detect_loops(p, &LoopParams::default())
                    .map(|l| l.len())
                    .unwrap_or(0)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
