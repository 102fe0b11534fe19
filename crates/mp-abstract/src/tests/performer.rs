//! End-to-end on the procedural performer: track → concrete → abstract, loops, prediction.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::predict_constant;
use crate::{analyse, unroll, AbstractParams, PredictParams};
use mp_geom::{perform, Move, PerformerParams};

fn kd(a: &mp_geom::Track, b: &mp_geom::Track) -> f64 {
    let (t, j, d) = a.positions().dim();
    let mut s = 0.0;
    for ti in 0..t {
        for ji in 0..j {
            let mut e = 0.0;
            for k in 0..d {
                e += (a.positions()[[ti, ji, k]] - b.positions()[[ti, ji, k]]).powi(2);
            }
            s += e.sqrt();
        }
    }
    s / (t * j) as f64
}

#[test]
fn finds_jumping_jacks_and_squats_with_their_counts() {
    let perf = perform(&PerformerParams::default()).unwrap();
    let a = analyse(&perf.track_2d, &AbstractParams::default()).unwrap();
    for (mv, reps) in [(Move::JumpingJack, 4), (Move::Squat, 3)] {
        let gt = perf.segments.iter().find(|s| s.kind == mv).unwrap();
        let hit = a
            .intervals
            .iter()
            .find(|i| {
                crate::iom(
                    (i.start_frame, i.end_frame),
                    (gt.frames.start, gt.frames.end),
                ) > 0.5
            })
            .unwrap_or_else(|| panic!("no loop for {mv:?}: {:?}", a.intervals));
        assert_eq!(hit.count, reps, "{mv:?}");
        assert_eq!(hit.boundaries.len(), reps + 1);
    }
    // The abstract program executes back to the same number of frames when loops replay as observed.
    let t = a
        .program
        .execute(&crate::AbstractExecParams {
            replay: crate::LoopReplay::Observed,
            ..Default::default()
        })
        .unwrap();
    assert_eq!(t.n_frames(), perf.track_2d.n_frames());
}

#[test]
fn unrolling_beats_constant_on_repetitive_motion() {
    let params = PerformerParams {
        moves: vec![(Move::JumpingJack, 8)],
        transition_seconds: 0.0,
        ..PerformerParams::default()
    };
    let perf = perform(&params).unwrap();
    let track = &perf.track_2d;
    let observe = track.n_frames() / 2 + 7;
    let horizon = 30;
    let p = unroll(track, observe, horizon, &PredictParams::default()).unwrap();
    assert!(p.used.is_some(), "a loop should be unrolled");
    assert_eq!(p.track.n_frames(), horizon);
    let truth = track.slice_frames(observe, observe + horizon).unwrap();
    let c = predict_constant(&track.slice_frames(0, observe).unwrap(), horizon).unwrap();
    let (kl, kc) = (kd(&p.track, &truth), kd(&c, &truth));
    assert!(kl < 0.6 * kc, "loop KD {kl:.2} vs constant {kc:.2}");
}

#[test]
fn prediction_rejects_bad_arguments() {
    let perf = perform(&PerformerParams::default()).unwrap();
    assert!(unroll(&perf.track_2d, 1, 10, &PredictParams::default()).is_err());
    assert!(unroll(&perf.track_2d, 100, 0, &PredictParams::default()).is_err());
    assert!(unroll(&perf.track_2d, 10_000, 10, &PredictParams::default()).is_err());
}

#[test]
fn period_counter_counts_performer_repetitions() {
    use crate::{estimate_period, PeriodParams};
    for (mv, reps) in [(Move::JumpingJack, 8), (Move::Squat, 6)] {
        let params = PerformerParams {
            moves: vec![(mv, reps)],
            transition_seconds: 0.0,
            ..PerformerParams::default()
        };
        let perf = perform(&params).unwrap();
        let t = &perf.track_2d;
        let p = estimate_period(t, 0, t.n_frames(), &PeriodParams::default())
            .unwrap()
            .expect("a period");
        assert!((p.count - reps as f64).abs() <= 1.0, "{mv:?}: {p:?}");
        // Limb joints only (the default): squats give about 0.29.
        assert!(p.strength > 0.25, "{mv:?}: {p:?}");
        let legacy = estimate_period(t, 0, t.n_frames(), &PeriodParams::legacy())
            .unwrap()
            .expect("a period");
        assert!(
            (legacy.count - reps as f64).abs() <= 1.0,
            "{mv:?}: {legacy:?}"
        );
    }
    // A still track has no period.
    let perf = perform(&PerformerParams {
        noise_px: 0.0,
        ..PerformerParams::default()
    })
    .unwrap();
    let still = perf.track_2d.slice_frames(0, 1).unwrap();
    assert!(estimate_period(&still, 0, 1, &PeriodParams::default())
        .unwrap()
        .is_none());
    assert!(estimate_period(&perf.track_2d, 5, 3, &PeriodParams::default()).is_err());
}
