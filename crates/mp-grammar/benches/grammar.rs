//! Hot paths of `mp-grammar`.
//!
//! * `identify_symbols/salsa_8677_frames_k20`: the paper's break-dance
//!   setting (8,677 frames, K = 20; paper: ≈ 0.5 s per GA generation × 500
//!   generations + ≈ 4 min of annealing ≈ 8 min) on the CMU salsa takes
//!   joined to 8,677 frames at 120 fps, default parameters.
//! * `identify_symbols/salsa_1731_frames_k12`: one performer's three takes at
//!   30 fps (the evaluation's setting).
//! * `search_partition/…`, `stitch/…`: grammar learning and synthesis on the
//!   symbols of that motion.
//!
//! `cargo bench -p mp-grammar` (or `cargo xtask bench --packages mp-grammar`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // bench code: failing loudly is the point

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use mp_grammar::read_motions;
use mp_grammar::{find_symbols, learn_grammar};
use mp_grammar::{
    identify_symbols, symbol_name, DeriveParams, PoseFeatures, StitchParams, SymbolParams,
};
use mp_grammar::{search_partition, PartitionParams};

fn salsa_dir() -> std::path::PathBuf {
    mp_geom::data_file("cmu_salsa_bvh").expect("shared data cmu_salsa_bvh is missing")
}

fn symbols(c: &mut Criterion) {
    let track = mp_grammar::salsa_track(salsa_dir(), 8677).unwrap();
    let feat = PoseFeatures::from_track(&track, &Default::default()).unwrap();
    let mut g = c.benchmark_group("identify_symbols");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(60));
    g.warm_up_time(Duration::from_secs(1));
    let p = SymbolParams {
        k: 20,
        ..Default::default()
    };
    g.bench_function("salsa_8677_frames_k20", |b| {
        b.iter(|| identify_symbols(&feat, &p).unwrap())
    });
    let files: Vec<_> = ["60_01_scaled.bvh", "60_02_scaled.bvh", "60_09_scaled.bvh"]
        .iter()
        .map(|f| salsa_dir().join(f))
        .collect();
    let m = read_motions(&files, 4).unwrap();
    let feat30 = PoseFeatures::from_track(&m.track, &Default::default()).unwrap();
    let p12 = SymbolParams {
        k: 12,
        ..Default::default()
    };
    g.measurement_time(Duration::from_secs(20));
    g.bench_function("salsa_1731_frames_k12", |b| {
        b.iter(|| identify_symbols(&feat30, &p12).unwrap())
    });
    g.finish();

    // Grammar learning and synthesis on those symbols.
    let sym = find_symbols(&m, &Default::default(), &p12).unwrap();
    let string = sym.string();
    let names: Vec<String> = (0..12).map(symbol_name).collect();
    let mut g = c.benchmark_group("search_partition");
    g.sample_size(10);
    g.bench_function("salsa_string_200_candidates", |b| {
        b.iter(|| search_partition(&string, &names, &PartitionParams::default()).unwrap())
    });
    g.finish();
    let model = learn_grammar(&sym, &PartitionParams::default()).unwrap();
    let st = model.stitcher(&m, &StitchParams::default()).unwrap();
    let mut g = c.benchmark_group("stitch");
    g.bench_function("salsa_grammar_50_segments_bvh", |b| {
        b.iter(|| {
            st.synthesize(&model.grammar, &DeriveParams::default(), 50, 3)
                .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, symbols);
criterion_main!(benches);
