//! Absurd user-given sizes (segments, derivation depth and length, K,
//! segment windows, GA population, iteration counts) are an error naming the parameter, never an allocation
//! failure.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::derive::{MAX_DEPTH, MAX_TERMINALS};
use crate::derive_at_least;
use crate::symbols::{MAX_ITERATIONS, MAX_POPULATION, MAX_SEGMENT_FRAMES, MAX_SYMBOLS};
use crate::synth::{MAX_FRAME_JOINTS, MAX_SEGMENTS};
use crate::ClusterQuality;
use crate::{DeriveParams, Fsm, FsmWeighting, Grammar, GrammarError, StitchParams, Stitcher};
use crate::{GaParams, SaParams, SymbolParams, SymbolSearchStats, SymbolSegment, SymbolString};
use mp_geom::{Skeleton, Track, Units};
use ndarray::Array3;

const SEG: usize = 15;
const FRAMES: usize = 120;
const JOINTS: usize = 3;

fn stitcher() -> Stitcher {
    let mut pos = Array3::zeros((FRAMES, JOINTS, 3));
    for t in 0..FRAMES {
        for j in 0..JOINTS {
            pos[[t, j, 0]] = (t as f64 * 0.1).sin() + j as f64;
            pos[[t, j, 1]] = 1.0 + 0.1 * j as f64;
            pos[[t, j, 2]] = (t as f64 * 0.1).cos();
        }
    }
    let track = Track::new(pos, None, 30.0, Units::Metres, Skeleton::generic(JOINTS)).unwrap();
    let k = 4;
    let symbols = SymbolString {
        k,
        n_frames: FRAMES,
        fps: 30.0,
        medoids: (0..k).collect(),
        segments: (0..FRAMES / SEG)
            .map(|i| SymbolSegment {
                start: i * SEG,
                end: (i + 1) * SEG,
                symbol: i % k,
            })
            .collect(),
        quality: ClusterQuality::from_terms(0.5, 0.5, 0.5),
        d_max: 1.0,
        stats: SymbolSearchStats::default(),
    };
    Stitcher::new(&track, None, &symbols, &StitchParams::default()).unwrap()
}

fn grammar() -> Grammar {
    Grammar::from_text("S -> a X d\nX -> b X | c | b c", None).unwrap()
}

fn assert_param(e: GrammarError, name: &str) {
    let msg = e.to_string();
    match e {
        GrammarError::InvalidParam { name: n, .. } => assert_eq!(n, name),
        e => panic!("expected a parameter error naming {name}, got {e:?}"),
    }
    assert!(msg.contains(name) && msg.contains("too large"), "{msg}");
}

#[test]
fn absurd_segments_are_an_error() {
    let s = stitcher();
    let g = grammar();
    let d = DeriveParams::default();
    let limit = (MAX_FRAME_JOINTS / JOINTS / SEG).min(MAX_SEGMENTS);
    let e = s.synthesize(&g, &d, 1_000_000_000_000, 0).unwrap_err();
    assert!(e.to_string().contains(&limit.to_string()), "{e}");
    assert_param(e, "segments");
    assert_param(s.synthesize(&g, &d, limit + 1, 0).unwrap_err(), "segments");
    assert_param(s.synthesize(&g, &d, usize::MAX, 0).unwrap_err(), "segments");
    let fsm = Fsm::from_symbols(&[0, 1, 2, 3, 0, 1, 2, 3], 4, FsmWeighting::Counts).unwrap();
    assert_param(
        s.synthesize_fsm(&fsm, 1_000_000_000_000, 0).unwrap_err(),
        "segments",
    );
    assert!(s.synthesize(&g, &d, 20, 0).unwrap().n_frames() >= 20 * SEG / 2);
}

#[test]
fn derivation_sizes_are_bounded() {
    let g = grammar();
    let p = DeriveParams {
        max_depth: MAX_DEPTH + 1,
        ..DeriveParams::default()
    };
    assert_param(p.validate().unwrap_err(), "max_depth");
    let p = DeriveParams {
        max_terminals: usize::MAX,
        ..DeriveParams::default()
    };
    assert_param(p.validate().unwrap_err(), "max_terminals");
    assert_param(
        derive_at_least(&g, &DeriveParams::default(), MAX_TERMINALS + 1, 0).unwrap_err(),
        "min_terminals",
    );
    DeriveParams {
        max_depth: MAX_DEPTH,
        ..DeriveParams::default()
    }
    .validate()
    .unwrap();
}

#[test]
fn symbol_params_are_bounded() {
    let p = SymbolParams {
        k: MAX_SYMBOLS + 1,
        ..SymbolParams::default()
    };
    assert_param(p.validate().unwrap_err(), "k");
    let p = SymbolParams {
        max_segment_frames: usize::MAX,
        ..SymbolParams::default()
    };
    assert_param(p.validate().unwrap_err(), "max_segment_frames");
    let p = SymbolParams {
        candidate_step_frames: usize::MAX / 2 + 1,
        max_segment_frames: MAX_SEGMENT_FRAMES,
        ..SymbolParams::default()
    };
    assert_param(p.validate().unwrap_err(), "candidate_step_frames");
    // The GA's population (an allocation per genome) and the iteration counts.
    let p = SymbolParams {
        ga: GaParams {
            population: 1_000_000_000_000,
            ..GaParams::default()
        },
        ..SymbolParams::default()
    };
    assert_param(p.validate().unwrap_err(), "ga.population");
    let p = SymbolParams {
        ga: GaParams {
            generations: MAX_ITERATIONS + 1,
            ..GaParams::default()
        },
        ..SymbolParams::default()
    };
    assert_param(p.validate().unwrap_err(), "ga.generations");
    let p = SymbolParams {
        sa: SaParams {
            iterations: usize::MAX,
            ..SaParams::default()
        },
        ..SymbolParams::default()
    };
    assert_param(p.validate().unwrap_err(), "sa.iterations");
    SymbolParams {
        ga: GaParams {
            population: MAX_POPULATION,
            generations: MAX_ITERATIONS,
            ..GaParams::default()
        },
        ..SymbolParams::default()
    }
    .validate()
    .unwrap();
}
