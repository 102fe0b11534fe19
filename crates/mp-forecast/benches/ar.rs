//! Throughput of the learned forecaster's autoregressive rollout (target: ≥ 1,000
//! predicted frames per second on 2 cores), single track and batched.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // bench code: failing loudly is the point

use std::sync::Arc;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mp_forecast::{ArForecaster, ArParams, Forecaster};
use mp_forecast::{ArSpace, ForecastModels};
use mp_geom::{Skeleton, Track, Units};
use mp_onnx::SessionParams;
use ndarray::Array3;

fn track(n: usize, phase: f64) -> Track {
    let mut pos = Array3::zeros((n, 13, 2));
    for t in 0..n {
        for j in 0..13 {
            let a = 0.3 * t as f64 + phase + j as f64;
            pos[[t, j, 0]] = 100.0 + 20.0 * (j % 2) as f64 + 10.0 * a.sin();
            pos[[t, j, 1]] = 20.0 + 14.0 * j as f64 + 5.0 * a.cos();
        }
    }
    Track::new(pos, None, 30.0, Units::Pixels, Skeleton::penn13()).unwrap()
}

fn bench(c: &mut Criterion) {
    let dir = match ForecastModels::find_dir("penn_action") {
        Ok(d) => d,
        Err(e) => {
            eprintln!("skipping the AR bench: {e}");
            return;
        }
    };
    let models = match ForecastModels::load(dir, &SessionParams::default()) {
        Ok(m) => Arc::new(m),
        Err(e) => {
            eprintln!("skipping the AR bench: {e}");
            return;
        }
    };
    let horizon = 30;
    let mut g = c.benchmark_group("ar_rollout");
    for (space, name) in [(ArSpace::Latent, "latent"), (ArSpace::Pose, "pose")] {
        let f = ArForecaster::new(models.clone(), space, ArParams::default()).unwrap();
        let past = track(15, 0.0);
        g.throughput(Throughput::Elements(horizon as u64));
        g.bench_function(format!("{name}_single_h30"), |b| {
            b.iter(|| f.predict(&past, horizon).unwrap())
        });
        let batch: Vec<Track> = (0..64).map(|i| track(15, i as f64 * 0.1)).collect();
        g.throughput(Throughput::Elements((horizon * batch.len()) as u64));
        g.bench_function(format!("{name}_batch64_h30"), |b| {
            b.iter(|| f.predict_batch(&batch, horizon).unwrap())
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(5));
    targets = bench
}
criterion_main!(benches);
