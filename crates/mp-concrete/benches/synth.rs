//! Full synthesis of a 13-joint track at T = 1k, 10k, 100k frames, and the
//! segmentation of the procedural performer (17 joints) repeated to 10,206
//! frames, against the exhaustive reference DP at 1,134 frames.
//!
//! The 13-joint track is synthetic (seeded): each joint follows a random walk
//! plus a few sinusoids with random periods, with a pause now and then, so
//! the program has a realistic mix of stationary, linear and circular
//! segments. The 100k case is long, so it runs only when `MP_BENCH_100K=1`;
//! the `cargo xtask bench` harness times it once instead. Single-core figures:
//! `RAYON_NUM_THREADS=1` (the search itself is sequential).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // bench code

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode};
use mp_concrete::synthetic_track;
use mp_concrete::{Program, Scale, Segmentation, SynthParams};
use mp_geom::Track;
use mp_geom::{perform, PerformerParams};
use ndarray::{concatenate, Axis};
use std::time::Duration;

/// The default performer (COCO-17, 567 frames) repeated `reps` times.
fn repeated_performer(reps: usize) -> Track {
    let tr = perform(&PerformerParams::default()).unwrap().track_2d;
    let pos: Vec<_> = (0..reps).map(|_| tr.positions()).collect();
    let conf: Vec<_> = (0..reps).map(|_| tr.confidence()).collect();
    Track::new(
        concatenate(Axis(0), &pos).unwrap(),
        Some(concatenate(Axis(0), &conf).unwrap()),
        tr.fps(),
        tr.units(),
        tr.skeleton().clone(),
    )
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let params = SynthParams {
        scale: Scale::UnitScale { unit_scale: 1.0 },
        ..SynthParams::paper()
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
        g.measurement_time(Duration::from_secs(if n >= 10_000 { 30 } else { 10 }));
        g.bench_with_input(BenchmarkId::from_parameter(n), &track, |b, tr| {
            b.iter(|| Program::synthesize(tr, &params).expect("synthesis"))
        });
    }
    g.finish();

    let mut g = c.benchmark_group("segment_performer_17_joints");
    g.sampling_mode(SamplingMode::Flat);
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(100));
    g.measurement_time(Duration::from_secs(20));
    let defaults = SynthParams::paper();
    let long = repeated_performer(18);
    g.bench_with_input(
        BenchmarkId::new("search", long.n_frames()),
        &long,
        |b, tr| b.iter(|| Segmentation::search(tr, &defaults).expect("segment")),
    );
    let short = repeated_performer(2);
    g.bench_with_input(
        BenchmarkId::new("search", short.n_frames()),
        &short,
        |b, tr| b.iter(|| Segmentation::search(tr, &defaults).expect("segment")),
    );
    g.bench_with_input(
        BenchmarkId::new("exhaustive", short.n_frames()),
        &short,
        |b, tr| b.iter(|| Segmentation::exhaustive(tr, &defaults).expect("segment")),
    );
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
