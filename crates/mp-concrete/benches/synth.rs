//! Full synthesis of a 13-joint track at T = 1k, 10k, 100k frames.
//!
//! The track is synthetic (seeded): each joint follows a random walk plus a
//! few sinusoids with random periods, with a pause now and then, so the
//! program has a realistic mix of stationary, linear and circular segments.
//! The 100k case is long, so it runs only when `MP_BENCH_100K=1`; the
//! `cargo xtask bench` harness times it once instead.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // bench code: failing loudly is the point

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode};
use mp_concrete::synthetic::synthetic_track;
use mp_concrete::{synthesize, Scale, SynthParams};
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let params = SynthParams {
        scale: Scale::UnitScale { unit_scale: 1.0 },
        ..SynthParams::default()
    };
    let mut g = c.benchmark_group("synthesize_13_joints");
    g.sampling_mode(SamplingMode::Flat);
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(100));
    let mut sizes = vec![1_000usize, 10_000];
    if std::env::var("MP_BENCH_100K").is_ok_and(|v| v == "1") {
        sizes.push(100_000);
    }
    for n in sizes {
        let track = synthetic_track(n, 7).expect("synthetic track");
        g.measurement_time(Duration::from_secs(if n >= 10_000 { 60 } else { 10 }));
        g.bench_with_input(BenchmarkId::from_parameter(n), &track, |b, tr| {
            b.iter(|| synthesize(tr, &params).expect("synthesis"))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
