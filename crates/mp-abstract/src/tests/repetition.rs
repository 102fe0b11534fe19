//! Repetition counting and the repetition segmenter: synthetic tracks with
//! known counts and intervals, bad input, and real data.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::AbstractError;
use crate::{
    estimate_period, iou, segment_repetitions, IntervalParams, JointSelection, PeriodParams,
};
use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array2, Array3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// A 2D track of `j` joints doing `k` cycles of `period` frames (a
/// non-sinusoidal cycle: fundamental plus second harmonic, a different phase
/// per joint), plus Gaussian noise.
fn cyclic_track(k: usize, period: usize, j: usize, noise_px: f64, seed: u64) -> Track {
    let n = k * period;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, noise_px).unwrap();
    let mut p = Array3::zeros((n, j, 2));
    for t in 0..n {
        let ph = 2.0 * std::f64::consts::PI * t as f64 / period as f64;
        for ji in 0..j {
            let a = ji as f64 * 0.7;
            p[[t, ji, 0]] = 200.0
                + 10.0 * ji as f64
                + 30.0 * (ph + a).sin()
                + 12.0 * (2.0 * ph + a).cos()
                + noise.sample(&mut rng);
            p[[t, ji, 1]] = 300.0 + 25.0 * (ph + 2.0 * a).cos() + noise.sample(&mut rng);
        }
    }
    Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(j)).unwrap()
}

/// A unitless feature track from per-frame channel values.
fn feature_track(rows: &[Vec<f64>], fps: f64) -> Track {
    let c = rows[0].len();
    let mut p = Array3::zeros((rows.len(), c, 1));
    for (t, r) in rows.iter().enumerate() {
        for (k, v) in r.iter().enumerate() {
            p[[t, k, 0]] = *v;
        }
    }
    Track::new(p, None, fps, Units::Unitless, Skeleton::generic(c)).unwrap()
}

/// `frames` frames of a periodic 4-channel pattern around `offset`.
fn block(frames: usize, period_frames: f64, offset: f64, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let noise = Normal::new(0.0, 1.0).unwrap();
    (0..frames)
        .map(|t| {
            let ph = 2.0 * std::f64::consts::PI * t as f64 / period_frames;
            vec![
                offset + 20.0 * ph.sin() + noise.sample(rng),
                offset * 0.5 + 15.0 * (ph + 1.0).sin() + 5.0 * (2.0 * ph).cos() + noise.sample(rng),
                -offset + 10.0 * (ph + 2.0).cos() + noise.sample(rng),
                30.0 + 8.0 * (ph + 0.3).sin() + noise.sample(rng),
            ]
        })
        .collect()
}

/// `frames` frames of a still pose with a little noise.
fn rest(frames: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let noise = Normal::new(0.0, 0.5).unwrap();
    (0..frames)
        .map(|_| {
            vec![
                noise.sample(rng),
                noise.sample(rng),
                noise.sample(rng),
                30.0 + noise.sample(rng),
            ]
        })
        .collect()
}

#[test]
fn period_counter_counts_k_noisy_repetitions() {
    for (k, period, seed) in [(5, 40, 1), (9, 23, 2), (14, 17, 3)] {
        let t = cyclic_track(k, period, 6, 3.0, seed);
        let p = estimate_period(&t, 0, t.n_frames(), &PeriodParams::default())
            .unwrap()
            .expect("a period");
        assert_eq!(p.count.round() as usize, k, "k={k} period={period}: {p:?}");
        assert!((p.period_frames as i64 - period as i64).abs() <= 1, "{p:?}");
    }
}

#[test]
fn segmenter_counts_one_repetitive_track() {
    let t = cyclic_track(8, 30, 6, 2.0, 7);
    let segs = segment_repetitions(&t, &IntervalParams::default()).unwrap();
    assert_eq!(segs.len(), 1, "{segs:?}");
    let s = &segs[0];
    assert!((s.period_frames as i64 - 30).abs() <= 1, "{s:?}");
    assert!((s.count - 8.0).abs() <= 0.5, "{s:?}");
    assert!(iou((s.start_frame, s.end_frame), (0, t.n_frames())) > 0.9);
    let iv = s.to_interval();
    assert_eq!(iv.count, 8);
    assert_eq!(iv.boundaries.len(), 9);
    assert_eq!(iv.boundaries.last(), Some(&s.end_frame));
}

#[test]
fn segmenter_finds_two_blocks_separated_by_rest() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let fps = 10.0;
    let mut rows = rest(25, &mut rng);
    rows.extend(block(66, 11.0, 0.0, &mut rng)); // 6 cycles of 1.1 s
    rows.extend(rest(40, &mut rng));
    rows.extend(block(92, 23.0, 40.0, &mut rng)); // 4 cycles of 2.3 s
    rows.extend(rest(20, &mut rng));
    let t = feature_track(&rows, fps);
    let segs = segment_repetitions(&t, &IntervalParams::default()).unwrap();
    assert_eq!(segs.len(), 2, "{segs:?}");
    let truth = [(25, 91, 11.0, 6.0), (131, 223, 23.0, 4.0)];
    for (s, (a, b, per, k)) in segs.iter().zip(truth) {
        let o = iou((s.start_frame, s.end_frame), (a, b));
        assert!(o >= 0.8, "{s:?} vs {a}..{b}: IoU {o}");
        assert!(
            (s.period_frames as f64 - per).abs() <= 0.1 * per,
            "{s:?}: period {per}"
        );
        assert!((s.count - k).abs() <= 1.0, "{s:?}: count {k}");
    }
}

#[test]
fn segmenter_splits_back_to_back_exercises() {
    // Two different exercises with no pause between them: two intervals.
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let mut rows = block(70, 10.0, 0.0, &mut rng);
    rows.extend(block(100, 25.0, 60.0, &mut rng));
    let t = feature_track(&rows, 10.0);
    let segs = segment_repetitions(&t, &IntervalParams::default()).unwrap();
    assert_eq!(segs.len(), 2, "{segs:?}");
    assert!(iou((segs[0].start_frame, segs[0].end_frame), (0, 70)) >= 0.8);
    assert!(iou((segs[1].start_frame, segs[1].end_frame), (70, 170)) >= 0.8);
}

#[test]
fn segmenter_finds_nothing_in_rest_or_drift() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let t = feature_track(&rest(120, &mut rng), 10.0);
    assert!(segment_repetitions(&t, &IntervalParams::default())
        .unwrap()
        .is_empty());
    // A slow monotonic drift is not a repetition.
    let drift: Vec<Vec<f64>> = (0..150)
        .map(|i| {
            let x = i as f64;
            vec![x, 0.5 * x, -0.2 * x, 0.01 * x * x]
        })
        .collect();
    let segs =
        segment_repetitions(&feature_track(&drift, 10.0), &IntervalParams::default()).unwrap();
    assert!(segs.is_empty(), "{segs:?}");
    // Shorter than the shortest interval.
    let short = feature_track(&block(8, 4.0, 0.0, &mut rng), 10.0);
    assert!(segment_repetitions(&short, &IntervalParams::default())
        .unwrap()
        .is_empty());
}

#[test]
fn bad_parameters_and_frames_give_typed_errors() {
    let t = cyclic_track(4, 20, 3, 1.0, 5);
    let bad_seg = [
        IntervalParams {
            threshold: f64::NAN,
            ..IntervalParams::default()
        },
        IntervalParams {
            min_period_s: 2.0,
            max_period_s: 1.0,
            ..IntervalParams::default()
        },
        IntervalParams {
            min_cycles: 0.5,
            ..IntervalParams::default()
        },
        IntervalParams {
            grid_s: 0.0,
            ..IntervalParams::default()
        },
        IntervalParams {
            interval_penalty_s: -1.0,
            ..IntervalParams::default()
        },
        IntervalParams {
            min_duration_s: 10.0,
            max_duration_s: 5.0,
            ..IntervalParams::default()
        },
    ];
    for p in bad_seg {
        let e = segment_repetitions(&t, &p).unwrap_err();
        assert!(
            matches!(e, AbstractError::InvalidParam { .. }),
            "{p:?}: {e}"
        );
    }
    let bad_period = [
        PeriodParams {
            min_cycles: 0.0,
            ..PeriodParams::default()
        },
        PeriodParams {
            peak_ratio: 1.5,
            ..PeriodParams::default()
        },
        PeriodParams {
            min_period_s: f64::INFINITY,
            ..PeriodParams::default()
        },
    ];
    for p in bad_period {
        let e = estimate_period(&t, 0, t.n_frames(), &p).unwrap_err();
        assert!(
            matches!(e, AbstractError::InvalidParam { .. }),
            "{p:?}: {e}"
        );
    }
    let e = estimate_period(&t, 10, 10_000, &PeriodParams::default()).unwrap_err();
    assert!(e.to_string().contains("10..10000"), "{e}");
}

#[test]
fn tracks_without_valid_joints_have_no_repetition() {
    let n = 60;
    let p = Array3::zeros((n, 3, 2));
    let conf = Array2::zeros((n, 3));
    let t = Track::new(p, Some(conf), 30.0, Units::Pixels, Skeleton::generic(3)).unwrap();
    assert!(segment_repetitions(&t, &IntervalParams::default())
        .unwrap()
        .is_empty());
    assert!(estimate_period(&t, 0, n, &PeriodParams::default())
        .unwrap()
        .is_none());
}

#[test]
fn limb_selection_picks_the_coco_limbs() {
    let b = Skeleton::blazepose33();
    let limbs = crate::repetition::selected_joints(&b, JointSelection::Limbs);
    assert_eq!(limbs, vec![11, 12, 13, 14, 15, 16, 23, 24, 25, 26, 27, 28]);
    let g = Skeleton::generic(5);
    assert_eq!(
        crate::repetition::selected_joints(&g, JointSelection::Limbs).len(),
        5
    );
}

#[test]
fn quva_reference_keypoints_count() {
    // Real data: MediaPipe keypoints of a QUVA video with 7 annotated cycles.
    let name = "023_fitness";
    let path = mp_geom::data_or_return!(format!("reference_keypoints/{name}.npz"));
    let ann = mp_geom::data_or_return!(format!("quva_repetition/annotations/{name}.npy"));
    let truth = mp_geom::read_npy(ann).unwrap().to_i64().unwrap().len();
    let t = mp_geom::read_track(&path).unwrap();
    let p = estimate_period(&t, 0, t.n_frames(), &PeriodParams::default())
        .unwrap()
        .expect("a period");
    assert_eq!(p.count.round() as usize, truth, "{p:?}");
}

#[test]
fn cmu_exercise_blocks_are_segmented() {
    // Real data: 6 labelled exercise blocks back to back, 12 joint angles at 10 fps.
    let path = mp_geom::data_or_return!("cmu_mocap6_exercise/14_14_features10fps.npz");
    let c = mp_geom::CmuFeatures::open(&path).unwrap();
    let mut blocks = Vec::new();
    let mut s = 0;
    for i in 1..=c.labels.len() {
        if i == c.labels.len() || c.labels[i] != c.labels[s] {
            blocks.push((s, i));
            s = i;
        }
    }
    assert_eq!(blocks.len(), 6);
    let segs = segment_repetitions(&c.track, &IntervalParams::default()).unwrap();
    let d: Vec<(usize, usize)> = segs.iter().map(|x| (x.start_frame, x.end_frame)).collect();
    let found = blocks
        .iter()
        .filter(|b| d.iter().any(|x| iou(*x, **b) >= 0.5))
        .count();
    assert!(found >= 5, "{found} of 6 blocks found: {d:?}");
    // No detection straddles two exercises.
    for x in &d {
        let best = blocks
            .iter()
            .map(|b| crate::iom(*x, *b))
            .fold(0.0, f64::max);
        assert!(best >= 0.9, "{x:?} straddles blocks {blocks:?}");
    }
}
