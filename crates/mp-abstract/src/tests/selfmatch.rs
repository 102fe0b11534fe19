//! Self-match unrolling: synthetic tracks with about one observed cycle,
//! tracks that must not be replayed, and bad parameters.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::predict_constant;
use crate::{unroll, AbstractError, PredictMethod, PredictParams};
use crate::{SelfMatchFallback, SelfMatchKind};
use mp_geom::{Skeleton, Track, Units};
use ndarray::Array3;

/// A COCO-17 2D track at 30 fps whose limbs swing with a period of `period`
/// frames (fundamental plus a second harmonic, a different phase per joint).
fn swinging(frames: usize, period: f64) -> Track {
    let mut p = Array3::zeros((frames, 17, 2));
    for t in 0..frames {
        let ph = 2.0 * std::f64::consts::PI * t as f64 / period;
        for j in 0..17 {
            let a = j as f64 * 0.45;
            p[[t, j, 0]] = 300.0 + 8.0 * (j % 4) as f64 + 25.0 * (ph + a).sin();
            p[[t, j, 1]] = 100.0 + 12.0 * j as f64 + 18.0 * (ph + a).cos() + 6.0 * (2.0 * ph).sin();
        }
    }
    Track::new(p, None, 30.0, Units::Pixels, Skeleton::coco17()).unwrap()
}

/// Mean joint distance between two tracks of the same shape.
fn mean_err(a: &Track, b: &Track) -> f64 {
    let (t, j, _) = a.positions().dim();
    let mut s = 0.0;
    for f in 0..t {
        for k in 0..j {
            let dx = a.positions()[[f, k, 0]] - b.positions()[[f, k, 0]];
            let dy = a.positions()[[f, k, 1]] - b.positions()[[f, k, 1]];
            s += (dx * dx + dy * dy).sqrt();
        }
    }
    s / (t * j) as f64
}

#[test]
fn one_observed_cycle_and_a_third_is_replayed_with_the_true_period() {
    let period = 30.0;
    let track = swinging(100, period);
    let observe = 40; // 1.33 cycles
    let horizon = 30;
    let obs = track.slice_frames(0, observe).unwrap();
    let truth = track.slice_frames(observe, observe + horizon).unwrap();
    let sm = SelfMatchFallback::default();
    let m = sm.find_lag(&obs).unwrap().expect("a lag");
    assert_eq!(m.kind, SelfMatchKind::Lag);
    assert!(
        (m.lag_frames as f64 - period).abs() <= 1.0,
        "lag {} for a period of {period}",
        m.lag_frames
    );
    assert!(m.distance < 0.01, "distance {}", m.distance);
    let (pred, _) = sm.unroll(&obs, horizon).unwrap().unwrap();
    let constant = predict_constant(&obs, horizon).unwrap();
    let (e_sm, e_c) = (mean_err(&pred, &truth), mean_err(&constant, &truth));
    assert!(e_sm < 1.0, "self-match error {e_sm} px");
    assert!(e_c > 15.0, "constant error {e_c} px");
    // The whole predictor takes this path (no loop program, fewer than 3 cycles).
    let p = unroll(&track, observe, horizon, &PredictParams::default()).unwrap();
    assert_eq!(p.method(), PredictMethod::SelfMatch);
    assert!(mean_err(&p.track, &truth) < 0.2 * e_c);
}

/// A COCO-17 2D track at 30 fps of an out-and-back motion (every joint
/// leaves its start and returns with the same phase, as in a squat).
fn reciprocating(frames: usize, period: f64) -> Track {
    let mut p = Array3::zeros((frames, 17, 2));
    for t in 0..frames {
        let s = 0.5 * (1.0 - (2.0 * std::f64::consts::PI * t as f64 / period).cos());
        for j in 0..17 {
            p[[t, j, 0]] = 300.0 + 8.0 * (j % 4) as f64 + 10.0 * (j % 3) as f64 * s;
            p[[t, j, 1]] = 100.0 + 12.0 * j as f64 + 4.0 * j as f64 * s;
        }
    }
    Track::new(p, None, 30.0, Units::Pixels, Skeleton::coco17()).unwrap()
}

#[test]
fn half_a_cycle_is_continued_by_reflection_at_the_turning_point() {
    // Observe the way out and a little of the way back (turn at frame 40).
    let track = reciprocating(90, 80.0);
    let obs = track.slice_frames(0, 45).unwrap();
    let truth = track.slice_frames(45, 75).unwrap();
    let sm = SelfMatchFallback::default();
    assert!(
        sm.find_lag(&obs).unwrap().is_none(),
        "no full cycle observed"
    );
    let (pred, m) = sm.unroll(&obs, 30).unwrap().expect("a turning point");
    assert_eq!(m.kind, SelfMatchKind::Reflection);
    assert!(
        (m.lag_frames as i64 - 40).abs() <= 1,
        "turn at {}",
        m.lag_frames
    );
    let constant = predict_constant(&obs, 30).unwrap();
    let (e_sm, e_c) = (mean_err(&pred, &truth), mean_err(&constant, &truth));
    assert!(e_sm < 0.2 * e_c, "reflection {e_sm} vs constant {e_c}");
}

#[test]
fn a_still_track_holds_the_last_pose() {
    let mut p = Array3::zeros((60, 17, 2));
    for t in 0..60 {
        for j in 0..17 {
            p[[t, j, 0]] = 200.0 + 10.0 * j as f64;
            p[[t, j, 1]] = 100.0 + 12.0 * j as f64;
        }
    }
    let still = Track::new(p, None, 30.0, Units::Pixels, Skeleton::coco17()).unwrap();
    let sm = SelfMatchFallback::default();
    assert!(sm.unroll(&still, 20).unwrap().is_none());
    let pr = unroll(&still, 60, 20, &PredictParams::default()).unwrap();
    assert_eq!(pr.method(), PredictMethod::Constant);
}

#[test]
fn bad_parameters_are_typed_errors() {
    let obs = swinging(40, 30.0);
    let bad = [
        SelfMatchFallback {
            window_s: 0.0,
            ..Default::default()
        },
        SelfMatchFallback {
            max_distance: f64::NAN,
            ..Default::default()
        },
        SelfMatchFallback {
            max_lag_s: 0.1,
            min_lag_s: 0.5,
            ..Default::default()
        },
        SelfMatchFallback {
            max_return_ratio: 1.5,
            ..Default::default()
        },
        SelfMatchFallback {
            velocity_weight_s: -1.0,
            ..Default::default()
        },
    ];
    for b in bad {
        assert!(
            matches!(b.unroll(&obs, 5), Err(AbstractError::InvalidParam { .. })),
            "{b:?}"
        );
    }
    assert!(matches!(
        SelfMatchFallback::default().unroll(&obs, 0),
        Err(AbstractError::InvalidParam {
            name: "horizon",
            ..
        })
    ));
}
