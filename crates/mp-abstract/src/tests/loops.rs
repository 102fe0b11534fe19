#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point
use crate::loops::window_score;
use crate::synth::{fit_loop, synthesize};
use crate::AbstractError;
use crate::DetPrim;
use crate::{detect_loops, LoopParams};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A body of `k` distinct 2-D motions for `j` joints, repeated `reps` times with noise,
/// between a lead-in and a lead-out of non-repeating primitives.
fn synthetic(k: usize, reps: usize, joints: usize, noise: f64, seed: u64) -> (Vec<DetPrim>, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let body: Vec<Vec<Vec<f64>>> = (0..k)
        .map(|i| {
            (0..joints)
                .map(|j| {
                    let a = i as f64 * 2.0 * std::f64::consts::PI / k as f64 + j as f64;
                    let (s, e) = (
                        (a.cos() * 80.0, a.sin() * 80.0),
                        ((a + 1.0).cos() * 80.0, (a + 1.0).sin() * 80.0),
                    );
                    vec![
                        200.0 + s.0,
                        200.0 + s.1,
                        200.0 + (s.0 + e.0) * 0.6,
                        200.0 + (s.1 + e.1) * 0.6,
                        200.0 + e.0,
                        200.0 + e.1,
                    ]
                })
                .collect()
        })
        .collect();
    let mut prims = Vec::new();
    // Lead-in: primitives that drift far apart (no repetition).
    let lead = 3;
    for i in 0..lead {
        let p: Vec<Vec<f64>> = (0..joints)
            .map(|_| {
                (0..6)
                    .map(|_| 50.0 * i as f64 * i as f64 + rng.random::<f64>() * 300.0)
                    .collect()
            })
            .collect();
        prims.push(DetPrim {
            duration: 5 + i,
            points: p,
        });
    }
    for _ in 0..reps {
        for b in &body {
            let p = b
                .iter()
                .map(|v| {
                    v.iter()
                        .map(|x| x + noise * (rng.random::<f64>() - 0.5))
                        .collect()
                })
                .collect();
            prims.push(DetPrim {
                duration: 10 + rng.random_range(0..2),
                points: p,
            });
        }
    }
    for i in 0..2 {
        let p: Vec<Vec<f64>> = (0..joints)
            .map(|_| {
                (0..6)
                    .map(|_| 900.0 + 300.0 * i as f64 + rng.random::<f64>() * 300.0)
                    .collect()
            })
            .collect();
        prims.push(DetPrim {
            duration: 7,
            points: p,
        });
    }
    (prims, lead)
}

#[test]
fn finds_one_loop_with_known_iterations_and_body() {
    for (k, reps) in [(1, 20), (2, 12), (3, 8), (4, 6)] {
        let (prims, lead) = synthetic(k, reps, 5, 2.0, 7 + k as u64);
        let loops = detect_loops(&prims, &LoopParams::default()).unwrap();
        assert_eq!(loops.len(), 1, "k={k}: {loops:?}");
        let l = &loops[0];
        assert_eq!(l.body, k, "k={k}: {l:?}");
        assert_eq!(l.iterations, reps, "k={k}: {l:?}");
        assert_eq!(l.start, lead);
        assert!(l.score < 8.0);
    }
}

#[test]
fn no_loop_in_random_motion() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let prims: Vec<DetPrim> = (0..60)
        .map(|_| DetPrim {
            duration: 8,
            points: (0..4)
                .map(|_| (0..6).map(|_| rng.random::<f64>() * 500.0).collect())
                .collect(),
        })
        .collect();
    assert!(detect_loops(&prims, &LoopParams::default())
        .unwrap()
        .is_empty());
}

#[test]
fn threshold_is_unit_free() {
    // The same motion in metres (1 reference px = 0.004 m) is found when unit_scale says so.
    let (prims, _) = synthetic(2, 12, 3, 2.0, 11);
    let s = 0.004;
    let metres: Vec<DetPrim> = prims
        .iter()
        .map(|p| DetPrim {
            duration: p.duration,
            points: p
                .points
                .iter()
                .map(|v| v.iter().map(|x| x * s).collect())
                .collect(),
        })
        .collect();
    let a = window_score(&prims, 3, 13, 2, 1.0).unwrap();
    let b = window_score(&metres, 3, 13, 2, s).unwrap();
    assert!((a - b).abs() < 1e-9 * a.max(1.0), "{a} vs {b}");
    let params = LoopParams {
        unit_scale: s,
        ..LoopParams::default()
    };
    let loops = detect_loops(&metres, &params).unwrap();
    assert_eq!(loops.len(), 1);
    assert_eq!(loops[0].iterations, 12);
}

#[test]
fn standing_still_is_not_a_loop() {
    let prims: Vec<DetPrim> = (0..40)
        .map(|_| DetPrim {
            duration: 10,
            points: vec![vec![100.0; 6]; 3],
        })
        .collect();
    assert!(detect_loops(&prims, &LoopParams::default())
        .unwrap()
        .is_empty());
}

#[test]
fn bad_input_is_typed() {
    assert!(matches!(
        detect_loops(&[], &LoopParams::default()),
        Err(AbstractError::Empty(_))
    ));
    let mut prims = synthetic(1, 5, 2, 0.0, 1).0;
    prims[4].points[1][2] = f64::NAN;
    assert!(matches!(
        detect_loops(&prims, &LoopParams::default()),
        Err(AbstractError::NonFinite(_))
    ));
    let p = LoopParams {
        threshold: -1.0,
        ..LoopParams::default()
    };
    assert!(matches!(
        detect_loops(&prims, &p),
        Err(AbstractError::InvalidParam { .. })
    ));
    let one = crate::DetectedLoop {
        start: 0,
        end: 1,
        body: 1,
        iterations: 1,
        score: 0.0,
    };
    assert!(matches!(
        fit_loop(&prims, &one),
        Err(AbstractError::InvalidLoop(_))
    ));
}

#[test]
fn synthesis_rolls_up_the_loop() {
    let (prims, lead) = synthetic(2, 10, 3, 2.0, 5);
    let names: Vec<String> = (0..3).map(|i| format!("j{i}")).collect();
    let (prog, loops) = synthesize(&prims, &LoopParams::default(), 30.0, "px", names).unwrap();
    assert_eq!(loops.len(), 1);
    assert_eq!(prog.loop_indices(), vec![lead]);
    assert_eq!(prog.stmts.len(), lead + 1 + 2);
    assert!(prog.expected_frames() > 0);
}

#[test]
fn relative_score_is_scale_free() {
    let (prims, lead) = synthetic(3, 8, 4, 2.0, 21);
    let params = LoopParams {
        relative_threshold: Some(0.3),
        ..LoopParams::default()
    };
    let scaled: Vec<DetPrim> = prims
        .iter()
        .map(|p| DetPrim {
            duration: p.duration,
            points: p
                .points
                .iter()
                .map(|v| v.iter().map(|x| x * 1e-3).collect())
                .collect(),
        })
        .collect();
    // The motion check stays in reference pixels: give the scaled data its unit scale.
    for (ps, unit_scale) in [(&prims, 1.0), (&scaled, 1e-3)] {
        let loops = detect_loops(
            ps,
            &LoopParams {
                unit_scale,
                ..params.clone()
            },
        )
        .unwrap();
        assert_eq!(loops.len(), 1, "{loops:?}");
        assert_eq!(
            (loops[0].start, loops[0].body, loops[0].iterations),
            (lead, 3, 8)
        );
    }
    let (a, _) = crate::loops::window_score_with(&prims, lead, lead + 12, 3, &params).unwrap();
    let (b, _) = crate::loops::window_score_with(&scaled, lead, lead + 12, 3, &params).unwrap();
    assert!((a - b).abs() < 1e-9 && a < 0.3, "{a} {b}");
    assert!(detect_loops(
        &prims,
        &LoopParams {
            relative_threshold: Some(f64::NAN),
            ..LoopParams::default()
        }
    )
    .is_err());
}
