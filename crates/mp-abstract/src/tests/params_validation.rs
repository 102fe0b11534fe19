//! Every params type of the pipeline rejects NaN and negative fields at its
//! public entry point with the parameter error naming the field.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::AbstractExecParams;
use crate::{analyse, unroll, AbstractError, AbstractParams, AbstractProgram, PredictParams};
use mp_geom::{Skeleton, Track, Units};
use ndarray::Array3;

fn track() -> Track {
    let mut p = Array3::zeros((40, 17, 2));
    for t in 0..40 {
        for j in 0..17 {
            p[[t, j, 0]] = 100.0 + j as f64 + t as f64;
            p[[t, j, 1]] = 50.0 + 3.0 * j as f64;
        }
    }
    Track::new(p, None, 30.0, Units::Pixels, Skeleton::coco17()).unwrap()
}

fn program() -> AbstractProgram {
    AbstractProgram {
        fps: 30.0,
        units: "px".into(),
        dims: 2,
        unit_scale: 1.0,
        joints: vec!["a".into()],
        stmts: Vec::new(),
    }
}

fn names(e: AbstractError) -> String {
    match e {
        AbstractError::InvalidParam { name, .. } => name.to_string(),
        AbstractError::Concrete(mp_concrete::ConcreteError::InvalidParam { name, .. }) => {
            name.to_string()
        }
        AbstractError::Geom(mp_geom::GeomError::InvalidParam { name, .. }) => name.to_string(),
        other => panic!("expected a parameter error, got {other:?}"),
    }
}

#[test]
fn abstract_params_reject_bad_fields() {
    assert!(AbstractParams::default().validate().is_ok());
    let mut p = AbstractParams::default();
    p.loops.threshold = f64::NAN;
    assert_eq!(names(p.validate().unwrap_err()), "threshold");
    assert_eq!(names(analyse(&track(), &p).unwrap_err()), "threshold");
    let mut p = AbstractParams::default();
    p.synth.min_confidence = -0.5;
    assert_eq!(names(analyse(&track(), &p).unwrap_err()), "min_confidence");
    // The loops' unit_scale is replaced by the analysis: not checked.
    let mut p = AbstractParams::default();
    p.loops.unit_scale = f64::NAN;
    assert!(p.validate().is_ok());
}

#[test]
fn predict_params_reject_bad_fields() {
    assert!(PredictParams::default().validate().is_ok());
    let t = track();
    let p = PredictParams {
        max_tail_periods: f64::NAN,
        ..PredictParams::default()
    };
    assert_eq!(
        names(unroll(&t, 30, 5, &p).unwrap_err()),
        "max_tail_periods"
    );
    let p = PredictParams {
        offset_decay_periods: -1.0,
        ..PredictParams::default()
    };
    assert_eq!(
        names(unroll(&t, 30, 5, &p).unwrap_err()),
        "offset_decay_periods"
    );
    let mut p = PredictParams::default();
    p.period_fallback.as_mut().unwrap().min_strength = f64::NAN;
    assert_eq!(names(unroll(&t, 30, 5, &p).unwrap_err()), "min_strength");
    let mut p = PredictParams::default();
    p.analysis.loops.threshold = -1.0;
    assert_eq!(names(unroll(&t, 30, 5, &p).unwrap_err()), "threshold");
}

#[test]
fn exec_params_reject_bad_fields() {
    assert!(AbstractExecParams::default().validate().is_ok());
    let prog = program();
    let p = AbstractExecParams {
        jitter: f64::NAN,
        ..AbstractExecParams::default()
    };
    assert_eq!(names(prog.execute(&p).unwrap_err()), "jitter");
    assert_eq!(names(prog.sample(1, &p).unwrap_err()), "jitter");
    let mut p = AbstractExecParams::default();
    p.fit.min_span_px = -1.0;
    assert_eq!(names(prog.execute(&p).unwrap_err()), "min_span_px");
    assert_eq!(names(prog.sample(1, &p).unwrap_err()), "min_span_px");
    // The fit's unit_scale is the program's: not checked.
    let mut p = AbstractExecParams::default();
    p.fit.unit_scale = f64::NAN;
    assert!(p.validate().is_ok());
}
