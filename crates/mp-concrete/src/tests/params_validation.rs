//! Execution and synthesis parameters: NaN / negative fields give the
//! parameter error naming the field; the fit parameters are checked once.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::synthetic::*;
use crate::{ConcreteError, ExecParams, Program, SynthParams};

fn param_name(e: ConcreteError) -> String {
    match e {
        ConcreteError::InvalidParam { name, .. } => name.to_string(),
        ConcreteError::Geom(mp_geom::GeomError::InvalidParam { name, .. }) => name.to_string(),
        other => panic!("expected a parameter error, got {other:?}"),
    }
}

fn program() -> Program {
    let track = synthetic_track(60, 3).unwrap();
    Program::synthesize(&track, &SynthParams::paper()).unwrap()
}

#[test]
fn exec_params_reject_bad_fps_out() {
    assert!(ExecParams::default().validate().is_ok());
    let prog = program();
    for bad in [f64::NAN, -30.0, 0.0, f64::INFINITY] {
        let p = ExecParams {
            fps_out: Some(bad),
            ..ExecParams::default()
        };
        assert_eq!(param_name(p.validate().unwrap_err()), "fps_out");
        assert_eq!(param_name(prog.execute_with(&p).unwrap_err()), "fps_out");
    }
    let p = ExecParams {
        fps_out: Some(15.0),
        ..ExecParams::default()
    };
    assert!(prog.execute_with(&p).is_ok());
}

#[test]
fn bad_fit_params_are_rejected_once_at_synthesis() {
    let track = synthetic_track(40, 5).unwrap();
    let mut p = SynthParams::paper();
    p.fit.min_span_px = f64::NAN;
    assert_eq!(
        param_name(Program::synthesize(&track, &p).unwrap_err()),
        "min_span_px"
    );
    let mut p = SynthParams::paper();
    p.fit.radius_penalty = -1.0;
    assert_eq!(
        param_name(crate::Program::synthesize_detailed(&track, &p).unwrap_err()),
        "radius_penalty"
    );
}

#[test]
fn a_fit_with_checked_params_matches_the_checking_one() {
    use mp_geom::Validate;
    let track = synthetic_track(30, 7).unwrap();
    let fit = mp_geom::FitParams::default();
    let checked = fit.clone().check().unwrap();
    for j in 0..track.n_joints() {
        let pts = track.positions().slice(ndarray::s![.., j, ..]).to_owned();
        let a = mp_geom::fit_best(pts.view(), None, &fit).unwrap();
        let b = mp_geom::fit_best_checked(pts.view(), None, &checked).unwrap();
        assert_eq!(a, b);
    }
}

#[test]
fn bad_fit_params_never_become_checked() {
    use mp_geom::Validate;
    let fit = mp_geom::FitParams {
        unit_scale: f64::NAN,
        ..Default::default()
    };
    let e = fit.check().unwrap_err().to_string();
    assert!(e.contains("unit_scale"), "{e}");
}
