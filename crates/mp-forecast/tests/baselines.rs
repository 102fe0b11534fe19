//! The baselines on synthetic tracks, and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use common::*;
use mp_abstract::PredictParams;
use mp_forecast::{Constant, ForecastError, Forecaster, LoopUnroll, NearestNeighbour, NnParams};
use mp_geom::kd;
use mp_geom::{perform, Move, PerformerParams};
use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array2, Array3};

#[test]
fn constant_is_exact_on_a_still_track() {
    let t = still(50);
    let past = t.slice_frames(0, 15).unwrap();
    let p = Constant.predict(&past, 30).unwrap();
    assert_eq!(p.n_frames(), 30);
    let truth = t.slice_frames(15, 45).unwrap();
    assert_eq!(p.positions(), truth.positions());
    assert!(p.confidence().iter().all(|&c| c == 1.0));
}

#[test]
fn constant_holds_the_last_valid_position_of_a_missing_joint() {
    let t = periodic(20, 7.0);
    let mut conf = t.confidence().to_owned();
    conf[[19, 5]] = 0.0;
    conf[[18, 5]] = 0.0;
    let (p, _, fps, u, sk) = t.clone().into_parts();
    let t = Track::new(p, Some(conf), fps, u, sk).unwrap();
    let pred = Constant.predict(&t, 3).unwrap();
    assert_eq!(pred.point(2, 5), t.point(17, 5));
    assert_eq!(pred.point(0, 4), t.point(19, 4));
}

#[test]
fn nn_recovers_a_continuation_from_its_training_set() {
    // a non-periodic training track (chirp) so that every window is distinct
    let train = penn_track(120, |t| 0.02 * (t * t) as f64 / 10.0 + 0.1 * t as f64, 0.3);
    let other = periodic(90, 23.0);
    let nn = NearestNeighbour::build(&[other, train.clone()], NnParams::default()).unwrap();
    assert_eq!(nn.n_windows(), (90 - 45 + 1) + (120 - 45 + 1));
    // the query is window 40..55 of the training track, scaled by 0.5 and shifted
    let f = |_: usize, p: &[f64]| vec![0.5 * p[0] + 200.0, 0.5 * p[1] - 40.0];
    let query = map_positions(&train.slice_frames(40, 55).unwrap(), f);
    let pred = nn.predict(&query, 30).unwrap();
    let truth = map_positions(&train.slice_frames(55, 85).unwrap(), f);
    let err = kd(&pred, &truth).unwrap();
    assert!(err < 1e-6, "continuation error {err} px");
}

#[test]
fn nn_is_deterministic_and_parallel_batch_matches_single() {
    let train = vec![
        periodic(100, 13.0),
        penn_track(80, |t| (t as f64 * 0.05).powi(2), 0.1),
    ];
    let nn = NearestNeighbour::build(&train, NnParams::default()).unwrap();
    let q: Vec<Track> = (0..6)
        .map(|i| penn_track(15, move |t| 0.3 * (t + i) as f64, 0.0))
        .collect();
    let a = nn.predict_batch(&q, 10).unwrap();
    for (qi, p) in q.iter().zip(&a) {
        assert_eq!(&nn.predict(qi, 10).unwrap(), p);
    }
}

#[test]
fn loop_beats_constant_on_a_periodic_track() {
    let perf = perform(&PerformerParams {
        moves: vec![(Move::JumpingJack, 8)],
        variation: 0.0,
        noise_px: 0.5,
        ..PerformerParams::default()
    })
    .unwrap();
    let track = perf.track_2d;
    let observe = 5 * 36; // five repetitions of 1.2 s at 30 fps
    let past = track.slice_frames(0, observe).unwrap();
    let truth = track.slice_frames(observe, observe + 30).unwrap();
    let lp = LoopUnroll::new(PredictParams::default(), None).unwrap();
    let pl = lp.predict(&past, 30).unwrap();
    let pc = Constant.predict(&past, 30).unwrap();
    let (el, ec) = (kd(&pl, &truth).unwrap(), kd(&pc, &truth).unwrap());
    assert!(el < 0.5 * ec, "loop {el:.2} px vs constant {ec:.2} px");
}

#[test]
fn bad_input_gives_typed_errors() {
    let nn = NearestNeighbour::build(&[periodic(60, 10.0)], NnParams::default()).unwrap();
    // fewer frames than the context
    assert!(matches!(
        nn.predict(&periodic(10, 10.0), 5),
        Err(ForecastError::TooShort {
            needed: 15,
            got: 10,
            ..
        })
    ));
    // wrong joint count
    let coco = Track::new(
        Array3::zeros((20, 17, 2)),
        None,
        30.0,
        Units::Pixels,
        Skeleton::coco17(),
    )
    .unwrap();
    assert!(matches!(
        nn.predict(&coco, 5),
        Err(ForecastError::Mismatch { .. })
    ));
    // every joint missing
    let t = periodic(20, 10.0);
    let (p, _, fps, u, sk) = t.into_parts();
    let empty = Track::new(p, Some(Array2::zeros((20, 13))), fps, u, sk).unwrap();
    assert!(matches!(
        nn.predict(&empty, 5),
        Err(ForecastError::NoValidJoints(_))
    ));
    // horizon 0
    assert!(matches!(
        Constant.predict(&periodic(5, 3.0), 0),
        Err(ForecastError::InvalidParam { .. })
    ));
    // no training data
    assert!(matches!(
        NearestNeighbour::build(&[periodic(20, 5.0)], NnParams::default()),
        Err(ForecastError::NoTrainingData(_))
    ));
    assert!(matches!(
        NearestNeighbour::build(&[], NnParams::default()),
        Err(ForecastError::NoTrainingData(_))
    ));
    assert!(matches!(
        LoopUnroll::new(PredictParams::default(), Some(1)),
        Err(ForecastError::InvalidParam { .. })
    ));
}

#[test]
fn nn_with_missing_joints_in_the_query_still_predicts() {
    let train = periodic(100, 13.0);
    let nn = NearestNeighbour::build(std::slice::from_ref(&train), NnParams::default()).unwrap();
    let q = train.slice_frames(20, 35).unwrap();
    let mut conf = q.confidence().to_owned();
    for t in 0..15 {
        conf[[t, 5]] = 0.0;
        conf[[t, 12]] = 0.0;
    }
    let (p, _, fps, u, sk) = q.into_parts();
    let q = Track::new(p, Some(conf), fps, u, sk).unwrap();
    let pred = nn.predict(&q, 20).unwrap();
    let truth = train.slice_frames(35, 55).unwrap();
    assert!(kd(&pred, &truth).unwrap() < 1e-6);
}

#[test]
fn period_fallback_unrolls_the_last_cycle_of_a_periodic_track() {
    // integer period 20: the unrolled frames equal the true continuation
    let t = periodic(120, 20.0);
    let past = t.slice_frames(0, 80).unwrap();
    let truth = t.slice_frames(80, 110).unwrap();
    let fb = mp_abstract::PeriodFallback::default();
    let (u, est) = fb
        .unroll(&past, 30)
        .unwrap()
        .expect("a clearly periodic track");
    assert_eq!(est.period_frames, 20);
    assert_eq!(u.n_frames(), 30);
    let max_err = |a: &Track| {
        (&a.positions() - &truth.positions())
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
    };
    assert!(max_err(&u) < 1e-6, "max error {}", max_err(&u));
    // a still track is not periodic: no unrolling
    assert!(fb.unroll(&still(80), 30).unwrap().is_none());
    // an invalid strength threshold is a typed error
    let bad = mp_abstract::PeriodFallback {
        min_strength: 2.0,
        ..Default::default()
    };
    assert!(matches!(
        bad.unroll(&past, 5),
        Err(mp_abstract::AbstractError::InvalidParam { .. })
    ));
    // the loop baseline unrolls either a loop program or this period: close to the truth
    let lu = LoopUnroll::new(LoopUnroll::default_params(), None).unwrap();
    let p = lu.predict(&past, 30).unwrap();
    let c = Constant.predict(&past, 30).unwrap();
    // (Programs are continuous at segment boundaries by default (C0), and a
    // segment is worth the local spread held for a second: on this fast motion
    // (a wrist cusp every 10 frames) the program cuts some corners, so the
    // mean error is compared: 3.7 px against 9.2 px for Constant.)
    let (kp, kc) = (kd(&p, &truth).unwrap(), kd(&c, &truth).unwrap());
    assert!(kp < 0.5 * kc, "loop KD {kp} vs constant {kc}");
    assert!(
        max_err(&p) < 0.6 * max_err(&c),
        "loop {} vs constant {}",
        max_err(&p),
        max_err(&c)
    );
}
