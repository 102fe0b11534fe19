//! Absurd user-given sizes (iterations, loop parameters) are a typed error
//! naming the parameter, never an allocation failure.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::edit::MAX_ITERATIONS;
use crate::exec::output_frames_bound;
use crate::loops::{MAX_BODY, MAX_WINDOW};
use crate::AbstractError;
use crate::{AbstractExecParams, LoopParams, LoopReplay};
use crate::{AbstractProgram, DetPrim, FreqDist, Gaussian, Loop, ProbPrim, Stmt};
use mp_concrete::ConcreteError;

const JOINTS: usize = 4;

fn program(iterations: usize) -> AbstractProgram {
    let n = 6;
    let g = Gaussian {
        mean: vec![1.0; n],
        cov: (0..n * n)
            .map(|i| if i % (n + 1) == 0 { 1.0 } else { 0.0 })
            .collect(),
    };
    AbstractProgram {
        fps: 30.0,
        units: "px".into(),
        dims: 2,
        unit_scale: 1.0,
        joints: (0..JOINTS).map(|i| format!("j{i}")).collect(),
        stmts: vec![
            Stmt::Prim(DetPrim {
                duration: 10,
                points: vec![vec![0.0; n]; JOINTS],
            }),
            Stmt::Loop(Loop {
                iterations,
                body: vec![ProbPrim {
                    duration: FreqDist::from_values([10, 20, 30]),
                    joints: vec![g; JOINTS],
                }],
                observed: Vec::new(),
            }),
        ],
    }
}

fn assert_too_large(e: AbstractError, name: &str) {
    let msg = e.to_string();
    match e {
        AbstractError::Concrete(ConcreteError::TooLarge { name: n, .. }) => assert_eq!(n, name),
        AbstractError::InvalidParam { name: n, .. } => assert_eq!(n, name),
        e => panic!("expected a size error naming {name}, got {e:?}"),
    }
    assert!(msg.contains(name) && msg.contains("too large"), "{msg}");
}

#[test]
fn frames_bound_without_unrolling() {
    let p = program(1_000_000_000_000);
    assert_eq!(
        output_frames_bound(&p, LoopReplay::Mean, false),
        10.0 + 1e12 * 20.0
    );
    assert_eq!(
        output_frames_bound(&p, LoopReplay::Mean, true),
        10.0 + 1e12 * 30.0
    );
}

#[test]
fn absurd_iterations_in_a_program_are_an_error() {
    let p = program(1_000_000_000_000);
    assert_too_large(
        p.execute(&AbstractExecParams::default()).unwrap_err(),
        "iterations",
    );
    assert_too_large(
        p.sample(1, &AbstractExecParams::default()).unwrap_err(),
        "iterations",
    );
}

#[test]
fn set_iterations_is_bounded() {
    let mut p = program(3);
    let e = p.set_iterations(0, 1_000_000_000_000).unwrap_err();
    assert_too_large(e, "iterations");
    assert!(e_msg_has_limit(
        &mut p,
        MAX_ITERATIONS + 1,
        &MAX_ITERATIONS.to_string()
    ));
    // Below MAX_ITERATIONS but above the frame budget (30 frames × 4 joints per iteration).
    let over = mp_concrete::ExecParams::max_output_frames(JOINTS) / 30 + 1;
    assert!(over < MAX_ITERATIONS);
    assert_too_large(p.set_iterations(0, over).unwrap_err(), "iterations");
    let Stmt::Loop(l) = &p.stmts[1] else { panic!() };
    assert_eq!(
        l.iterations, 3,
        "a refused count leaves the program unchanged"
    );
    p.set_iterations(0, over - 1).unwrap();
    p.set_iterations(0, 5).unwrap();
    assert_eq!(
        p.execute(&AbstractExecParams::default())
            .unwrap()
            .n_frames(),
        110
    );
}

fn e_msg_has_limit(p: &mut AbstractProgram, it: usize, limit: &str) -> bool {
    p.set_iterations(0, it)
        .unwrap_err()
        .to_string()
        .contains(limit)
}

#[test]
fn loop_params_are_bounded() {
    let p = LoopParams {
        max_body: MAX_BODY + 1,
        ..LoopParams::default()
    };
    assert_too_large(p.validate().unwrap_err(), "max_body");
    let p = LoopParams {
        max_body: usize::MAX,
        ..LoopParams::default()
    };
    assert_too_large(p.validate().unwrap_err(), "max_body");
    let p = LoopParams {
        windows: vec![20, MAX_WINDOW + 1],
        ..LoopParams::default()
    };
    assert_too_large(p.validate().unwrap_err(), "windows");
    let p = LoopParams {
        short_window_iterations: Some(usize::MAX),
        ..LoopParams::default()
    };
    assert_too_large(p.validate().unwrap_err(), "short_window_iterations");
    LoopParams {
        max_body: MAX_BODY,
        ..LoopParams::default()
    }
    .validate()
    .unwrap();
}
