//! The counting API: synthetic recordings with known counts, the choice
//! between keypoints and frames, and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::{
    count_repetitions, count_signals, CountMethod, CountParams, CountSignal, PeriodParams,
};
use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array2, Array3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// `j` joints: `lead` still frames, then `k` cycles of `period` frames, plus noise.
fn exercise(lead: usize, k: usize, period: usize, j: usize, noise_px: f64, seed: u64) -> Track {
    let n = lead + k * period;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, noise_px).unwrap();
    let mut p = Array3::zeros((n, j, 2));
    for t in 0..n {
        let ph = if t < lead {
            0.0
        } else {
            2.0 * std::f64::consts::PI * (t - lead) as f64 / period as f64
        };
        for ji in 0..j {
            let a = ji as f64 * 0.7;
            p[[t, ji, 0]] = 200.0 + 10.0 * ji as f64 + 30.0 * (ph + a).sin() - 30.0 * a.sin()
                + noise.sample(&mut rng);
            p[[t, ji, 1]] = 300.0 + 25.0 * (ph + 2.0 * a).cos() + noise.sample(&mut rng);
        }
    }
    Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(j)).unwrap()
}

/// A unitless "thumbnail" track: `c` cells, a bright blob sweeping back and
/// forth with the given period, plus pixel noise.
fn thumbnails(n: usize, period: f64, c: usize, seed: u64) -> Track {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 2.0).unwrap();
    let mut p = Array3::zeros((n, c, 1));
    for t in 0..n {
        let centre =
            (c as f64 / 2.0) * (1.0 + 0.6 * (2.0 * std::f64::consts::PI * t as f64 / period).sin());
        for k in 0..c {
            let d = (k as f64 - centre) / 3.0;
            p[[t, k, 0]] = 40.0 + 120.0 * (-d * d).exp() + noise.sample(&mut rng);
        }
    }
    Track::new(p, None, 30.0, Units::Unitless, Skeleton::generic(c)).unwrap()
}

#[test]
fn counts_a_single_exercise() {
    for (k, period) in [(5, 40), (8, 25), (12, 18)] {
        let t = exercise(0, k, period, 12, 1.0, k as u64);
        let c = count_repetitions(&t, CountSignal::Keypoints, &CountParams::default()).unwrap();
        assert_eq!(c.total, k, "{k} cycles of {period}: {c:?}");
        assert_eq!(c.method, CountMethod::Period);
        assert_eq!(c.intervals.len(), 1);
        let iv = &c.intervals[0];
        assert!(
            (iv.period_frames as i64 - period as i64).abs() <= 1,
            "{iv:?}"
        );
        assert_eq!(iv.boundaries.len(), iv.count + 1);
        assert!(c.confidence > 0.5, "{}", c.confidence);
    }
}

#[test]
fn a_long_still_tail_is_not_counted() {
    // Seven cycles, then the person stands still for twice as long (a
    // performer who stops while the video goes on).
    let (k, period, tail) = (7usize, 18usize, 270usize);
    let active = exercise(0, k, period, 12, 1.0, 7);
    let n = k * period + tail;
    let mut p = Array3::zeros((n, 12, 2));
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let noise = Normal::new(0.0, 1.0).unwrap();
    for t in 0..n {
        let src = t.min(k * period - 1);
        for j in 0..12 {
            for d in 0..2 {
                let jitter = if t >= k * period {
                    noise.sample(&mut rng)
                } else {
                    0.0
                };
                p[[t, j, d]] = active.positions()[[src, j, d]] + jitter;
            }
        }
    }
    let t = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(12)).unwrap();
    let c = count_repetitions(&t, CountSignal::Keypoints, &CountParams::default()).unwrap();
    assert!((c.total as i64 - k as i64).abs() <= 1, "{c:?}");
}

#[test]
fn other_motion_around_the_repetitions_is_not_counted() {
    // Two seconds of a motion that does not repeat before and after seven
    // cycles: the count covers only the cycles (without the mismatch trim
    // it takes the whole active span).
    let (k, period, pad) = (7usize, 24usize, 60usize);
    let active = exercise(0, k, period, 12, 0.5, 11);
    let n = pad + k * period + pad;
    let mut p = Array3::zeros((n, 12, 2));
    for t in 0..n {
        for j in 0..12 {
            for d in 0..2 {
                p[[t, j, d]] = if t < pad || t >= pad + k * period {
                    // A one-off sweep away from the first pose and back,
                    // at the cycles' own amplitude.
                    let edge = if t < pad { 0 } else { k * period - 1 };
                    let u = if t < pad {
                        (pad - t) as f64 / pad as f64
                    } else {
                        (t - pad - k * period) as f64 / pad as f64
                    };
                    // Walking away from the first pose (and in from the
                    // last), faster and faster: nothing in it matches
                    // itself a period later.
                    let bend = u * u;
                    active.positions()[[edge, j, d]]
                        + 150.0 * bend * if d == 0 { 1.0 } else { -0.5 } * (1.0 + 0.1 * j as f64)
                } else {
                    active.positions()[[t - pad, j, d]]
                };
            }
        }
    }
    let t = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(12)).unwrap();
    let c = count_repetitions(&t, CountSignal::Keypoints, &CountParams::default()).unwrap();
    assert!((c.total as i64 - k as i64).abs() <= 1, "{c:?}");
    // Without the trim (mismatch_fraction 0) the padding is counted too.
    let loose = CountParams {
        mismatch_fraction: 0.0,
        ..CountParams::default()
    };
    let c0 = count_repetitions(&t, CountSignal::Keypoints, &loose).unwrap();
    assert!(c0.total > k + 1, "{c0:?}");
    // The count that reaches into the other motion is less certain: its
    // ends do not match themselves a period away.
    assert!(
        c0.features.end_mismatch > c.features.end_mismatch + 0.2,
        "{:?} vs {:?}",
        c0.features,
        c.features
    );
    assert!(c0.confidence < c.confidence, "{c0:?} vs {c:?}");
}

#[test]
fn confidence_is_high_for_repetitions_and_low_for_what_does_not_repeat() {
    let reps = exercise(0, 10, 24, 12, 0.5, 3);
    let c = count_repetitions(&reps, CountSignal::Keypoints, &CountParams::default()).unwrap();
    assert_eq!(c.total, 10);
    assert!(c.confidence > 0.8, "{c:?}");
    assert!(c.features.cycle_mismatch < 0.2, "{:?}", c.features);
    // A random walk (a person wandering about) does not repeat.
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let step = Normal::new(0.0, 3.0).unwrap();
    let n = 300;
    let mut p = Array3::zeros((n, 12, 2));
    for t in 1..n {
        for j in 0..12 {
            for d in 0..2 {
                p[[t, j, d]] = p[[t - 1, j, d]] + step.sample(&mut rng);
            }
        }
    }
    let walk = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(12)).unwrap();
    let w = count_repetitions(&walk, CountSignal::Keypoints, &CountParams::default()).unwrap();
    assert!(w.confidence < 0.5, "{w:?}");
    // A count from frames never carries more than its periodicity.
    let f = count_repetitions(
        &thumbnails(300, 30.0, 64, 4),
        CountSignal::Frames,
        &CountParams::default(),
    )
    .unwrap();
    assert!(
        f.total > 0 && f.confidence <= f.periodicity + 1e-12,
        "{f:?}"
    );
}

#[test]
fn a_person_who_walks_in_is_counted_over_their_own_frames() {
    // Nobody for 150 frames, then six cycles: the keypoints count the six
    // cycles, in the recording's frames, and no interval lies before the
    // person appears (their track holds no pose there).
    let (lead, k, period) = (150usize, 6usize, 24usize);
    let active = exercise(0, k, period, 12, 0.5, 21);
    let n = lead + k * period;
    let mut p = Array3::from_elem((n, 12, 2), f64::NAN);
    for t in lead..n {
        for j in 0..12 {
            for d in 0..2 {
                p[[t, j, d]] = active.positions()[[t - lead, j, d]];
            }
        }
    }
    let t = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(12)).unwrap();
    let params = CountParams {
        min_found_fraction: 0.3,
        ..CountParams::default()
    };
    let c = count_signals(Some(&t), None, &params).unwrap();
    assert!((c.total as i64 - k as i64).abs() <= 1, "{c:?}");
    assert_eq!(c.frames, n);
    assert!(
        c.intervals.iter().all(|iv| iv.start_frame + 2 >= lead),
        "{c:?}"
    );
}

#[test]
fn still_and_one_off_motion_count_zero() {
    let still = exercise(90, 0, 30, 12, 0.5, 1);
    let c = count_repetitions(&still, CountSignal::Keypoints, &CountParams::default()).unwrap();
    assert_eq!((c.total, c.method), (0, CountMethod::None), "{c:?}");
    // One smooth movement from one pose to another (a swing, not a repetition).
    let n = 150;
    let mut p = Array3::zeros((n, 12, 2));
    for t in 0..n {
        let s = (t as f64 / n as f64 * std::f64::consts::PI).sin().powi(2);
        for j in 0..12 {
            p[[t, j, 0]] = 100.0 + 5.0 * j as f64 + 80.0 * s;
            p[[t, j, 1]] = 200.0 - 40.0 * s * (j as f64 / 12.0);
        }
    }
    let swing = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(12)).unwrap();
    let c = count_repetitions(&swing, CountSignal::Keypoints, &CountParams::default()).unwrap();
    assert_eq!(c.total, 0, "{c:?}");
}

#[test]
fn frames_count_where_no_person_is_found() {
    let thumbs = thumbnails(300, 45.0, 64, 3);
    // Keypoints of an empty video: nobody found in any frame.
    let none = Track::new(
        Array3::zeros((300, 17, 2)),
        Some(Array2::zeros((300, 17))),
        30.0,
        Units::Pixels,
        Skeleton::coco17(),
    )
    .unwrap();
    let c = count_signals(Some(&none), Some(&thumbs), &CountParams::default()).unwrap();
    assert_eq!(c.signal, CountSignal::Frames);
    assert!((c.total as i64 - 7).abs() <= 1, "300 / 45 ≈ 6.7: {c:?}");
    // With a person repeating clearly, the keypoints decide.
    let kp = exercise(0, 6, 50, 12, 0.5, 4);
    let flat = thumbnails(300, 1e9, 64, 5);
    let c = count_signals(Some(&kp), Some(&flat), &CountParams::default()).unwrap();
    assert_eq!((c.signal, c.total), (CountSignal::Keypoints, 6), "{c:?}");
}

#[test]
fn frame_signal_counts_the_same_in_either_layout() {
    // A thumbnail as 64 channels of one value, or as 8 rows of 8 cells (how
    // `mp_pose::thumbnail_track` lays it out): the same channels in the
    // same order, so the same count, period and intervals. A lead-in of still
    // frames makes the active span (the speed per channel) matter.
    let moving = thumbnails(300, 45.0, 64, 3);
    let mut p = Array3::from_elem((360, 64, 1), 0.0);
    for t in 0..360 {
        for k in 0..64 {
            p[[t, k, 0]] = moving.positions()[[t.saturating_sub(60), k, 0]];
        }
    }
    let flat = Track::new(
        p.clone(),
        None,
        30.0,
        Units::Unitless,
        Skeleton::generic(64),
    )
    .unwrap();
    let grid = Track::new(
        p.into_shape_with_order((360, 8, 8)).unwrap(),
        None,
        30.0,
        Units::Unitless,
        Skeleton::generic(8),
    )
    .unwrap();
    let params = CountParams::default();
    let a = count_repetitions(&flat, CountSignal::Frames, &params).unwrap();
    let b = count_repetitions(&grid, CountSignal::Frames, &params).unwrap();
    assert!(a.total >= 6, "{a:?}");
    assert_eq!(a.total, b.total);
    assert_eq!(a.method, b.method);
    assert!((a.confidence - b.confidence).abs() < 1e-9);
    let spans = |c: &crate::Counts| {
        c.intervals
            .iter()
            .map(|i| (i.start_frame, i.end_frame, i.period_frames))
            .collect::<Vec<_>>()
    };
    assert_eq!(spans(&a), spans(&b));
    assert!(
        a.intervals[0].start_frame >= 30,
        "the still lead-in is trimmed: {a:?}"
    );
}

#[test]
fn bad_input_and_parameters() {
    assert!(count_signals(None, None, &CountParams::default()).is_err());
    let t = exercise(0, 3, 20, 4, 0.5, 1);
    for p in [
        CountParams {
            min_strength: f64::NAN,
            ..CountParams::default()
        },
        CountParams {
            min_found_fraction: 2.0,
            ..CountParams::default()
        },
        CountParams {
            period: PeriodParams {
                smooth_s: -1.0,
                ..PeriodParams::default()
            },
            ..CountParams::default()
        },
    ] {
        let e = count_repetitions(&t, CountSignal::Keypoints, &p).unwrap_err();
        assert!(e.to_string().contains("must be"), "{e}");
    }
    // Too short to hold a repetition: a count of 0, not an error.
    let short = exercise(0, 1, 3, 4, 0.5, 1);
    let c = count_repetitions(&short, CountSignal::Keypoints, &CountParams::default()).unwrap();
    assert_eq!(c.total, 0);
}

#[test]
fn a_tremor_on_motion_that_does_not_repeat_is_not_counted() {
    // A body wandering slowly (no repetition) with a small fast tremor of a
    // fixed period (9 frames): joint velocities correlate at the tremor's
    // period, but the poses are no nearer themselves a period later than
    // half a period later — the motion does not repeat at that period.
    let mut counted = Vec::new();
    for seed in 0..8u64 {
        let n = 450;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 3.0).unwrap();
        let mut p = Array3::zeros((n, 12, 2));
        let mut walk = [[0.0f64; 2]; 12];
        for t in 0..n {
            let tremor = 1.5 * (std::f64::consts::TAU * t as f64 / 9.0).sin();
            for (j, w) in walk.iter_mut().enumerate() {
                for (k, v) in w.iter_mut().enumerate() {
                    *v = 0.98 * *v + noise.sample(&mut rng);
                    p[[t, j, k]] = 200.0 + 10.0 * j as f64 * (k as f64 + 1.0) + *v + tremor;
                }
            }
        }
        let t = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(12)).unwrap();
        let c = count_repetitions(&t, CountSignal::Keypoints, &CountParams::default()).unwrap();
        if c.total > 0 {
            counted.push((seed, c.total, c.features.cycle_mismatch));
        }
    }
    assert!(counted.is_empty(), "counted: {counted:?}");
}

#[test]
fn a_cycle_of_several_similar_movements_is_counted_whole() {
    // Each 60-frame cycle holds five quick side-to-side movements (12 frames
    // each) on a slower, wider up-and-down sway: the joint velocities
    // correlate first at 12 frames, yet the pose comes back to itself only
    // after 60.
    // Five cycles are five repetitions, not 25.
    let (n, cycle, step) = (300, 60.0, 12.0);
    let mut p = Array3::zeros((n, 6, 2));
    for t in 0..n {
        let tt = t as f64;
        let quick = 10.0 * (std::f64::consts::TAU * tt / step).sin();
        let sway = 60.0 * (std::f64::consts::TAU * tt / cycle).sin();
        for j in 0..6 {
            p[[t, j, 0]] = 100.0 + 30.0 * j as f64 + quick;
            p[[t, j, 1]] = 200.0 + 10.0 * j as f64 + sway;
        }
    }
    let t = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(6)).unwrap();
    let params = CountParams::default();
    let e = mp_abstract_period(&t, &params);
    assert!(
        (e as i64 - 12).abs() <= 1,
        "the autocorrelation's period: {e}"
    );
    let c = count_repetitions(&t, CountSignal::Keypoints, &params).unwrap();
    assert_eq!(c.method, CountMethod::Period, "{c:?}");
    let iv = &c.intervals[0];
    assert!((iv.period_frames as i64 - 60).abs() <= 2, "{iv:?}");
    assert!((4..=5).contains(&c.total), "{c:?}");
    // A motion that repeats well at its period keeps it: the quick movement alone.
    let mut q = Array3::zeros((n, 6, 2));
    for t in 0..n {
        let quick = 20.0 * (std::f64::consts::TAU * t as f64 / step).sin();
        for j in 0..6 {
            q[[t, j, 0]] = 100.0 + 30.0 * j as f64 + quick;
            q[[t, j, 1]] = 200.0 + 10.0 * j as f64 + 0.5 * quick;
        }
    }
    let t = Track::new(q, None, 30.0, Units::Pixels, Skeleton::generic(6)).unwrap();
    let c = count_repetitions(&t, CountSignal::Keypoints, &params).unwrap();
    assert!(
        (c.intervals[0].period_frames as i64 - 12).abs() <= 1,
        "{c:?}"
    );
    assert!((24..=25).contains(&c.total), "{c:?}");
}

/// The period the autocorrelation of joint velocities picks.
fn mp_abstract_period(t: &Track, params: &CountParams) -> usize {
    crate::estimate_period(t, 0, t.n_frames(), &params.period)
        .unwrap()
        .unwrap()
        .period_frames
}

#[test]
fn repetitions_the_whole_recording_reads_too_weakly_are_counted_where_they_repeat() {
    // The whole-recording autocorrelation is held to be too weak for a period
    // (as when the pace changes from cycle to cycle); the segmenter's
    // interval of eight cycles still counts them.
    let params = CountParams {
        min_strength: 0.99,
        ..CountParams::default()
    };
    let t = exercise(20, 8, 24, 6, 1.0, 3);
    let c = count_repetitions(&t, CountSignal::Keypoints, &params).unwrap();
    assert_eq!(c.method, CountMethod::Intervals, "{c:?}");
    assert!((7..=9).contains(&c.total), "{c:?}");
    // Two cycles do not establish a period: no count.
    let t = exercise(20, 2, 24, 6, 1.0, 3);
    let c = count_repetitions(&t, CountSignal::Keypoints, &params).unwrap();
    assert_eq!(c.total, 0, "{c:?}");
}

/// `k` cycles of `period` frames (as [`exercise`], with keypoint noise),
/// then `tail` frames of slow motion that does not repeat: every joint
/// wanders off the last pose on two slow waves of periods unrelated to the
/// cycle's.
fn cycles_then_wandering(k: usize, period: usize, tail: usize, noise_px: f64) -> Track {
    let active = exercise(0, k, period, 12, noise_px, 21);
    let n = k * period + tail;
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    let noise = Normal::new(0.0, noise_px).unwrap();
    let mut p = Array3::zeros((n, 12, 2));
    let last = k * period - 1;
    for t in 0..n {
        for j in 0..12 {
            for d in 0..2 {
                p[[t, j, d]] = if t <= last {
                    active.positions()[[t, j, d]]
                } else {
                    let u = (t - last) as f64;
                    let phase = j as f64 * 0.4 + d as f64;
                    let tau = std::f64::consts::TAU;
                    active.positions()[[last, j, d]]
                        + 22.0 * ((tau * u / (2.9 * period as f64) + phase).sin() - phase.sin())
                        + 14.0 * ((tau * u / (4.3 * period as f64) - phase).sin() + phase.sin())
                        + noise.sample(&mut rng)
                };
            }
        }
    }
    Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(12)).unwrap()
}

#[test]
fn slow_motion_after_the_repetitions_is_not_counted() {
    // Slow wandering after the cycles stays near itself a period later (by
    // the recording's scale it "matches"), yet it is as near itself half a
    // period later: it does not come back, and is not counted.
    for (k, period, tail) in [(8usize, 30usize, 90usize), (12, 20, 60), (6, 40, 120)] {
        let t = cycles_then_wandering(k, period, tail, 2.0);
        let c = count_repetitions(&t, CountSignal::Keypoints, &CountParams::default()).unwrap();
        assert_eq!(
            c.total, k,
            "{k} cycles of {period}, {tail} frames after: {c:?}"
        );
        let iv = &c.intervals[0];
        assert!(
            iv.end_frame <= k * period + period / 2,
            "{k} cycles of {period} end at {}: {iv:?}",
            k * period
        );
    }
}

#[test]
fn long_runs_of_repetitions_are_counted_at_their_period_to_a_fraction_of_a_frame() {
    // Forty cycles of 30 and 31 frames in turn: counted at a whole number of
    // frames, 30 reads 40.7 cycles and 31 reads 39.4; the mean period (30.5)
    // is found between frames.
    let lengths: Vec<usize> = (0..40).map(|k| 30 + k % 2).collect();
    let n: usize = lengths.iter().sum();
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let noise = Normal::new(0.0, 1.0).unwrap();
    let mut p = Array3::zeros((n, 12, 2));
    let mut t = 0;
    for (k, &len) in lengths.iter().enumerate() {
        for i in 0..len {
            let ph = std::f64::consts::TAU * (k as f64 + i as f64 / len as f64);
            for j in 0..12 {
                let a = j as f64 * 0.7;
                p[[t, j, 0]] =
                    200.0 + 10.0 * j as f64 + 30.0 * (ph + a).sin() + noise.sample(&mut rng);
                p[[t, j, 1]] = 300.0 + 25.0 * (ph + 2.0 * a).cos() + noise.sample(&mut rng);
            }
            t += 1;
        }
    }
    let track = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(12)).unwrap();
    let c = count_repetitions(&track, CountSignal::Keypoints, &CountParams::default()).unwrap();
    assert_eq!(c.total, lengths.len(), "{c:?}");
    let iv = &c.intervals[0];
    let mean = n as f64 / lengths.len() as f64;
    assert!(
        (iv.cycles - lengths.len() as f64).abs() < 0.25,
        "mean period {mean}: {iv:?}"
    );
}

#[test]
fn repetitions_whose_pace_alternates_are_counted_one_by_one() {
    // Twenty cycles of 30 frames, every other one paced unevenly inside
    // (the same poses, reached earlier and later): the velocities of two
    // neighbouring cycles differ, those of every second cycle are the same,
    // and the autocorrelation peaks higher at two cycles than at one. The
    // pose comes back to itself every cycle, and that is the repetition.
    let (k, period) = (20usize, 30usize);
    let n = k * period;
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let noise = Normal::new(0.0, 0.5).unwrap();
    let mut p = Array3::zeros((n, 12, 2));
    for t in 0..n {
        let (cycle, i) = (t / period, t % period);
        let u = i as f64 / period as f64;
        let tau = std::f64::consts::TAU;
        let warped = if cycle % 2 == 1 {
            u + 0.2 * (tau * u).sin()
        } else {
            u
        };
        let ph = tau * warped;
        for j in 0..12 {
            let a = j as f64 * 0.7;
            p[[t, j, 0]] = 200.0 + 10.0 * j as f64 + 30.0 * (ph + a).sin() + noise.sample(&mut rng);
            p[[t, j, 1]] = 300.0 + 25.0 * (ph + 2.0 * a).cos() + noise.sample(&mut rng);
        }
    }
    let track = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(12)).unwrap();
    let c = count_repetitions(&track, CountSignal::Keypoints, &CountParams::default()).unwrap();
    assert_eq!(c.total, k, "{c:?}");
}
