#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point
use crate::synth::synthesize;
use crate::AbstractError;
use crate::LoopParams;
use crate::PrintOptions;
use crate::{AbstractExecParams, LoopReplay};
use crate::{AbstractProgram, DetPrim, FreqDist, Gaussian, Loop, ProbPrim, Stmt};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn det(rng: &mut ChaCha8Rng, joints: usize, dims: usize) -> DetPrim {
    DetPrim {
        duration: rng.random_range(1..30),
        points: (0..joints)
            .map(|_| (0..3 * dims).map(|_| rng.random_range(-1e3..1e3)).collect())
            .collect(),
    }
}

fn random_program(seed: u64, dims: usize) -> AbstractProgram {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let joints = rng.random_range(1..4);
    let n = 3 * dims;
    let mut stmts = Vec::new();
    for _ in 0..rng.random_range(1..5) {
        if rng.random_bool(0.5) {
            stmts.push(Stmt::Prim(det(&mut rng, joints, dims)));
        } else {
            let k = rng.random_range(1..3);
            let iterations = rng.random_range(2..5);
            let body = (0..k)
                .map(|_| ProbPrim {
                    duration: FreqDist::from_values((0..3).map(|_| rng.random_range(1..20))),
                    joints: (0..joints)
                        .map(|_| Gaussian {
                            mean: (0..n).map(|_| rng.random_range(-500.0..500.0)).collect(),
                            cov: (0..n * n).map(|_| rng.random_range(-2.0..2.0)).collect(),
                        })
                        .collect(),
                })
                .collect();
            let observed = (0..iterations)
                .map(|_| (0..k).map(|_| det(&mut rng, joints, dims)).collect())
                .collect();
            stmts.push(Stmt::Loop(Loop {
                iterations,
                body,
                observed,
            }));
        }
    }
    AbstractProgram {
        fps: 29.97,
        units: if dims == 3 { "m".into() } else { "px".into() },
        dims,
        unit_scale: 0.5 + seed as f64 / 7.0,
        joints: (0..joints).map(|i| format!("joint_{i}")).collect(),
        stmts,
    }
}

proptest! {
    #[test]
    fn print_parse_round_trip(seed in 0u64..10_000, three in any::<bool>()) {
        let p = random_program(seed, if three { 3 } else { 2 });
        let text = p.to_dsl();
        let q = AbstractProgram::from_dsl(&text).unwrap();
        prop_assert_eq!(&p, &q);
        let json = serde_json::to_string(&p).unwrap();
        let r: AbstractProgram = serde_json::from_str(&json).unwrap();
        prop_assert_eq!(&p, &r);
    }
}

#[test]
fn summary_mentions_loops() {
    let p = random_program(3, 2);
    let s = p.to_dsl_with(&PrintOptions::summary());
    assert!(s.starts_with("abstract_program(fps=29.97, units=px, dims=2, unit_scale="));
}

#[test]
fn malformed_text_is_located() {
    let bad = "abstract_program(fps=30, units=px, dims=2)\njoints(a)\nmotion(duration=3) {\n  a: start=(1, 2), mid=(3), end=(5, 6)\n}\n";
    match AbstractProgram::from_dsl(bad) {
        Err(AbstractError::Parse {
            line,
            column,
            message,
        }) => {
            assert_eq!(line, 4);
            assert!(column > 10, "{column}");
            assert!(message.contains("coordinates"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        AbstractProgram::from_dsl(""),
        Err(AbstractError::Parse { line: 1, .. })
    ));
    assert!(matches!(
        AbstractProgram::from_dsl(
            "abstract_program(fps=30, units=px, dims=2)\njoints(a)\nfor i in range(3) {\n}\n"
        ),
        Err(AbstractError::Parse { line: 4, .. })
    ));
    // NaN covariance is rejected by validation.
    let mut p = random_program(1, 2);
    for s in &mut p.stmts {
        if let Stmt::Loop(l) = s {
            l.body[0].joints[0].cov[0] = f64::NAN;
        }
    }
    if p.loop_indices().is_empty() {
        return;
    }
    assert!(matches!(p.validate(), Err(AbstractError::NonFinite(_))));
}

/// 2-D squat-like motion: each joint moves down then up; `reps` repetitions.
fn repetitive_prims(reps: usize, seed: u64) -> Vec<DetPrim> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    for _ in 0..reps {
        for dir in [1.0, -1.0] {
            let points = (0..3)
                .map(|j| {
                    let x = 100.0 + 50.0 * j as f64 + rng.random_range(-1.0..1.0);
                    let (y0, y1) = if dir > 0.0 {
                        (100.0, 220.0)
                    } else {
                        (220.0, 100.0)
                    };
                    vec![
                        x,
                        y0 + rng.random_range(-1.0..1.0),
                        x + 10.0,
                        (y0 + y1) / 2.0,
                        x,
                        y1 + rng.random_range(-1.0..1.0),
                    ]
                })
                .collect();
            out.push(DetPrim {
                duration: 12 + rng.random_range(0..2),
                points,
            });
        }
    }
    out
}

fn program(reps: usize) -> AbstractProgram {
    let prims = repetitive_prims(reps, 9);
    let (p, loops) = synthesize(
        &prims,
        &LoopParams::default(),
        30.0,
        "px",
        vec!["a".into(), "b".into(), "c".into()],
    )
    .unwrap();
    assert_eq!(loops.len(), 1);
    assert_eq!(loops[0].iterations, reps);
    p
}

#[test]
fn deterministic_execution_length_and_shape() {
    let p = program(6);
    let t = p.execute(&AbstractExecParams::default()).unwrap();
    assert_eq!(t.n_frames(), p.expected_frames());
    assert_eq!(t.n_joints(), 3);
    // The first frame of the loop is the mean start of the body's first primitive.
    let Stmt::Loop(l) = &p.stmts[0] else { panic!() };
    let m = &l.body[0].joints[0].mean;
    assert!(
        (t.point(0, 0)[1] - m[1]).abs() < 1.0,
        "{} vs {}",
        t.point(0, 0)[1],
        m[1]
    );
    // Replaying the observed iterations reproduces their total length.
    let obs = p
        .execute(&AbstractExecParams {
            replay: LoopReplay::Observed,
            ..AbstractExecParams::default()
        })
        .unwrap();
    let observed_frames: usize = l.observed.iter().flatten().map(|d| d.duration).sum();
    assert_eq!(obs.n_frames(), observed_frames);
}

#[test]
fn stochastic_execution_is_seeded_and_within_support() {
    let p = program(8);
    let a = p.sample(42, &AbstractExecParams::default()).unwrap();
    let b = p.sample(42, &AbstractExecParams::default()).unwrap();
    let c = p.sample(43, &AbstractExecParams::default()).unwrap();
    assert_eq!(a, b);
    assert_ne!(a.positions(), c.positions());
    // Every sampled start point lies within 6 standard deviations of its Gaussian.
    let Stmt::Loop(l) = &p.stmts[0] else { panic!() };
    let flat = crate::exec::flatten_sampled(&p, 42, 1e-9).unwrap();
    for (i, d) in flat.iter().enumerate() {
        let b = &l.body[i % l.body.len()];
        assert!(b.duration.counts.contains_key(&d.duration));
        for (j, g) in b.joints.iter().enumerate() {
            let n = g.dim();
            for a in 0..n {
                let sd = g.cov[a * n + a].max(0.0).sqrt();
                assert!(
                    (d.points[j][a] - g.mean[a]).abs() <= 6.0 * sd + 1e-3,
                    "value {a} of joint {j}"
                );
            }
        }
    }
}

#[test]
fn editing_changes_length_as_expected() {
    let mut p = program(6);
    let Stmt::Loop(l) = &p.stmts[0] else { panic!() };
    let per_iter: usize = l
        .body
        .iter()
        .map(|b| b.duration.mean_rounded().unwrap())
        .sum();
    let base = p
        .execute(&AbstractExecParams::default())
        .unwrap()
        .n_frames();
    p.set_iterations(0, 10).unwrap();
    let t = p.execute(&AbstractExecParams::default()).unwrap();
    assert_eq!(t.n_frames(), base + 4 * per_iter);
    p.set_iterations(0, 3).unwrap();
    assert_eq!(
        p.execute(&AbstractExecParams::default())
            .unwrap()
            .n_frames(),
        base - 3 * per_iter
    );
    p.drop_iteration(0, 1).unwrap();
    p.repeat_iteration(0, 0).unwrap();
    p.repeat_iteration(0, 0).unwrap();
    let Stmt::Loop(l) = &p.stmts[0] else { panic!() };
    assert_eq!(l.iterations, 4);
    assert_eq!(l.observed.len(), 4);
    assert!(matches!(
        p.set_iterations(3, 2),
        Err(AbstractError::NotFound(_))
    ));
    assert!(matches!(
        p.drop_iteration(0, 9),
        Err(AbstractError::NotFound(_))
    ));
}
