//! Absurd output sizes of program execution are a typed error, never an allocation failure.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::{ConcreteError, ExecParams, Program, SynthParams};
use mp_geom::{Skeleton, Track, Units, MAX_FRAME_JOINTS};
use ndarray::Array3;

fn program() -> crate::Program {
    let mut pos = Array3::zeros((20, 2, 2));
    for t in 0..20 {
        pos[[t, 0, 0]] = 100.0 + 8.0 * (t.min(9) as f64);
        pos[[t, 1, 1]] = 50.0 + t as f64;
    }
    let track = Track::new(pos, None, 30.0, Units::Pixels, Skeleton::generic(2)).unwrap();
    Program::synthesize(&track, &SynthParams::paper()).unwrap()
}

#[test]
fn absurd_fps_out_is_too_large() {
    let p = program();
    let err = p
        .execute_with(&ExecParams {
            fps_out: Some(1e15),
            ..ExecParams::default()
        })
        .unwrap_err();
    match &err {
        ConcreteError::TooLarge { name, value, limit } => {
            assert_eq!(*name, "fps_out");
            assert_eq!(value, "1000000000000000");
            assert!(
                limit.contains(&ExecParams::max_output_frames(2).to_string()),
                "{limit}"
            );
        }
        e => panic!("expected TooLarge, got {e:?}"),
    }
    let msg = err.to_string();
    assert!(
        msg.contains("fps_out") && msg.contains("too large"),
        "{msg}"
    );
}

#[test]
fn fps_out_at_the_limit_edge() {
    let p = program();
    // 19 s of program frames at 30 fps → (19/30)·fps_out + 1 frames.
    assert_eq!(ExecParams::max_output_frames(2), MAX_FRAME_JOINTS / 2);
    let ok = p
        .execute_with(&ExecParams {
            fps_out: Some(3000.0),
            ..ExecParams::default()
        })
        .unwrap();
    assert_eq!(ok.n_frames(), 1901);
    let over = (ExecParams::max_output_frames(2) as f64) * 30.0 / 19.0 * 1.01;
    assert!(matches!(
        p.execute_with(&ExecParams {
            fps_out: Some(over),
            ..ExecParams::default()
        }),
        Err(ConcreteError::TooLarge {
            name: "fps_out",
            ..
        })
    ));
}
