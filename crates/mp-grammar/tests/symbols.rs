//! Symbol identification: determinism, bad input, and a synthetic motion
//! whose repeated motifs must be recovered.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_grammar::{identify_symbols, GrammarError, PoseFeatures, SymbolParams};
use ndarray::Array2;

/// A 1-D feature signal made of three motifs (ramp up, ramp down, flat) of
/// 30 frames, in a fixed pattern.
fn motif_signal(pattern: &str) -> Array2<f64> {
    let mut v = Vec::new();
    for c in pattern.chars() {
        for t in 0..30 {
            let x = t as f64 / 29.0;
            v.push(match c {
                'u' => x,
                'd' => 1.0 - x,
                _ => 0.5,
            });
        }
    }
    Array2::from_shape_fn(
        (v.len(), 2),
        |(t, k)| if k == 0 { v[t] } else { 0.3 * v[t] },
    )
}

fn small_params(k: usize, seed: u64) -> SymbolParams {
    let mut p = SymbolParams {
        k,
        seed,
        ..Default::default()
    };
    p.ga.population = 30;
    p.ga.generations = 40;
    p.sa.iterations = 200;
    p.sa.max_iterations = 600;
    p
}

#[test]
fn same_seed_same_symbols() {
    let x = motif_signal("udfudfffudud");
    let f = PoseFeatures::from_rows(x.view(), 30.0).unwrap();
    let a = identify_symbols(&f, &small_params(3, 5)).unwrap();
    let b = identify_symbols(&f, &small_params(3, 5)).unwrap();
    assert_eq!(a.segments, b.segments);
    assert_eq!(a.quality, b.quality);
    // Segments tile the motion and respect the length bounds.
    assert_eq!(a.segments[0].start, 0);
    assert_eq!(a.segments.last().unwrap().end, x.nrows());
    for w in a.segments.windows(2) {
        assert_eq!(w[0].end, w[1].start);
    }
    let p = small_params(3, 5);
    for s in &a.segments {
        let len = s.end - s.start;
        assert!(len >= p.min_segment_frames && len <= p.max_segment_frames);
    }
    assert!(a.segments.len() >= 3);
    assert!(a.quality.f.is_finite() && a.quality.f > 0.0);
    // SA never ends below the GA result.
    assert!(a.quality.f >= a.stats.ga_best_f * (1.0 - 1e-9));
}

#[test]
fn bad_input_is_a_typed_error() {
    let x = motif_signal("udfudf");
    let f = PoseFeatures::from_rows(x.view(), 30.0).unwrap();
    let k0 = identify_symbols(&f, &small_params(0, 0));
    assert!(matches!(
        k0,
        Err(GrammarError::InvalidParam { name: "k", .. })
    ));
    // 180 frames, candidates every 30 frames: at most 6 segments.
    let too_many = identify_symbols(&f, &small_params(7, 0));
    assert!(
        matches!(too_many, Err(GrammarError::TooShort { .. })),
        "{too_many:?}"
    );
    let short = PoseFeatures::from_rows(Array2::zeros((5, 2)).view(), 30.0).unwrap();
    assert!(matches!(
        identify_symbols(&short, &small_params(1, 0)),
        Err(GrammarError::TooShort { .. })
    ));
    let mut p = small_params(2, 0);
    p.omega = 1.5;
    assert!(identify_symbols(&f, &p).is_err());
    let mut p = small_params(2, 0);
    p.max_segment_frames = 40;
    assert!(identify_symbols(&f, &p).is_err());
    assert!(PoseFeatures::from_rows(Array2::zeros((0, 2)).view(), 30.0).is_err());
}

/// Real data: 60 s of CMU mocap exercise features; symbols are found and
/// they agree with the hand labels better than chance (purity).
#[test]
fn cmu_exercise_features() {
    let path = mp_geom::data_or_return!("cmu_mocap6_exercise/13_29_features10fps.npz");
    let data = mp_geom::CmuFeatures::open(path).unwrap();
    let f = PoseFeatures::from_track(&data.track, &Default::default()).unwrap();
    let mut p = small_params(6, 1);
    p.candidate_step_frames = 5;
    p.min_segment_frames = 3;
    p.max_segment_frames = 40;
    p.sa.initial_step_frames = Some(2);
    let s = identify_symbols(&f, &p).unwrap();
    let frames = s.frame_symbols();
    // Purity: each symbol votes for its majority label.
    let mut counts = std::collections::HashMap::new();
    for (t, &sym) in frames.iter().enumerate() {
        *counts.entry((sym, data.labels[t])).or_insert(0usize) += 1;
    }
    let mut purity = 0;
    for sym in 0..p.k {
        purity += counts
            .iter()
            .filter(|((s, _), _)| *s == sym)
            .map(|(_, &c)| c)
            .max()
            .unwrap_or(0);
    }
    let purity = purity as f64 / frames.len() as f64;
    // Majority label alone covers 92/382 frames (0.24).
    assert!(purity > 0.3, "purity {purity}");
}
