//! Tests of the synthetic repetition cases (no shared data needed).

use super::*;
use crate::synth_select::{find_cycle, frame_dist, periodicity, sub_period_ratio, MAX_SUB_PERIOD};
use crate::synth_sources::{make_clip, source_of};
use std::f64::consts::TAU;

const FPS: f64 = 30.0;

/// `t` frames of 6 joints (2D, px) moving with period `period` frames
/// (`None`: a slow non-repeating drift and bend).
fn motion(t: usize, period: Option<f64>) -> SourceClip {
    let j = 6;
    let mut pos = Array3::zeros((t, j, 2));
    for ti in 0..t {
        for jj in 0..j {
            let (bx, by) = (300.0 + 20.0 * jj as f64, 100.0 + 60.0 * jj as f64);
            let (dx, dy) = match period {
                Some(p) => {
                    let ph = TAU * ti as f64 / p + 0.7 * jj as f64;
                    (60.0 * ph.sin(), 30.0 * (ph + 0.4).cos() * (jj % 3) as f64)
                }
                None => {
                    let u = ti as f64 / t as f64;
                    (
                        80.0 * u * u * jj as f64 / 5.0,
                        40.0 * (1.5 * u).sin() - 20.0 * u,
                    )
                }
            };
            pos[[ti, jj, 0]] = bx + dx;
            pos[[ti, jj, 1]] = by + dy;
        }
    }
    let name = period.map_or("drift".to_string(), |p| format!("sine{p}"));
    make_clip(&name, pos, Array2::ones((t, j)), FPS).expect("clip")
}

fn source(period: f64) -> Source {
    source_of(
        "test",
        vec![
            motion(400, Some(period)),
            motion(300, None),
            motion(200, None),
        ],
        Units::Pixels,
        Skeleton::generic(6),
    )
}

fn still() -> SynthOpts {
    SynthOpts {
        non_rep_share: 0.0,
        speed_jitter: 0.0,
        amp_jitter: 0.0,
        drift: 0.0,
        joint_amp_jitter: 0.0,
        phase_warp: 0.0,
        noise: 0.0,
        ..SynthOpts::default()
    }
}

fn pose(t: &Track, f: usize) -> ndarray::Array2<f64> {
    t.positions().slice(s![f, .., ..]).to_owned()
}

/// Without jitter, the cycle's first pose is at every declared repetition
/// start, each repetition is the cycle's length, and the length, fps and
/// truth are as declared.
#[test]
fn declared_reps_at_declared_frames() {
    let src = source(30.0);
    let opts = still();
    for id in 0..12 {
        let c = make_case(&src, id, 3, &opts).expect("case");
        let (_, cy) = c.cycle.as_ref().expect("cycle");
        let clip = &src.clips[cy.clip];
        let n = cy.b - cy.a;
        assert!(c.truth >= 2 && c.truth <= 20, "truth {}", c.truth);
        assert_eq!(c.boundaries.len(), c.truth + 1);
        assert_eq!(c.rep_end - c.rep_start, c.truth * n);
        assert!((c.track.fps() - FPS).abs() < 1e-12);
        assert!(c.track.n_frames() as f64 <= 60.0 * FPS);
        assert!(c.track.n_frames() >= c.rep_end);
        assert!(n as f64 >= 0.5 * FPS && n as f64 <= 3.0 * FPS);
        let first = clip.pos.slice(s![cy.a, .., ..]);
        let mid = clip.pos.slice(s![cy.a + n / 3, .., ..]);
        for k in 0..c.truth {
            let b = c.boundaries[k];
            assert_eq!(b, c.rep_start + k * n);
            assert!(
                (&pose(&c.track, b) - &first).iter().all(|v| v.abs() < 1e-9),
                "rep {k} of case {id}"
            );
            assert!((&pose(&c.track, b + n / 3) - &mid)
                .iter()
                .all(|v| v.abs() < 1e-9));
        }
        // The cycle of a 1 s sine is one period (not two): 30 frames ± the step.
        assert!((n as i64 - 30).abs() <= 2, "cycle of {n} frames");
        // No jump inside the repetitions: steps no larger than twice the clip's.
        let clip_step = (1..clip.pos.dim().0)
            .map(|t| frame_dist(clip, t - 1, t))
            .fold(0.0, f64::max);
        let tr = make_clip(
            "case",
            c.track.positions().to_owned(),
            c.track.confidence().to_owned(),
            FPS,
        )
        .expect("clip");
        for t in c.rep_start + 1..c.rep_end {
            let step = crate::synth_select::pose_dist(
                tr.pos.slice(s![t - 1, .., ..]),
                tr.pos.slice(s![t, .., ..]),
                &clip.joints,
                clip.scale,
            );
            assert!(
                step <= 2.0 * clip_step + 1e-9,
                "step {step} at {t} (clip {clip_step})"
            );
        }
    }
}

/// With speed, amplitude and drift jitter the cycle's first pose still
/// returns exactly N times inside the repetitions, near each declared start,
/// and each repetition lasts the cycle's length ±15 %.
#[test]
fn jittered_reps_return_n_times() {
    let src = source(36.0);
    let opts = SynthOpts {
        non_rep_share: 0.0,
        drift: 0.0,
        noise: 0.0,
        ..SynthOpts::default()
    };
    for id in 0..12 {
        let c = make_case(&src, id, 11, &opts).expect("case");
        let (_, cy) = c.cycle.as_ref().expect("cycle");
        let clip = &src.clips[cy.clip];
        let n = (cy.b - cy.a) as f64;
        let target = clip.pos.slice(s![cy.a, .., ..]);
        let d: Vec<f64> = (c.rep_start..c.rep_end)
            .map(|t| {
                crate::synth_select::pose_dist(
                    pose(&c.track, t).view(),
                    target,
                    &clip.joints,
                    clip.scale,
                )
            })
            .collect();
        let top = d.iter().cloned().fold(0.0, f64::max);
        // The last frames run back into the cycle's first pose (at `rep_end`, no start).
        let minima: Vec<usize> = (0..d.len() - 2)
            .filter(|&i| {
                d[i] < 0.25 * top
                    && (i == 0 || d[i] <= d[i - 1])
                    && (i + 1 == d.len() || d[i] < d[i + 1])
            })
            .map(|i| i + c.rep_start)
            .collect();
        assert_eq!(
            minima.len(),
            c.truth,
            "case {id}: minima {minima:?}, starts {:?}",
            c.boundaries
        );
        for (m, b) in minima.iter().zip(&c.boundaries) {
            assert!(
                (*m as i64 - *b as i64).abs() <= 2,
                "minimum {m} vs start {b}"
            );
        }
        for w in c.boundaries.windows(2) {
            let len = (w[1] - w[0]) as f64;
            assert!(
                len >= 0.85 * n - 1.0 && len <= 1.15 * n + 1.0,
                "rep of {len} frames, cycle {n}"
            );
        }
    }
}

#[test]
fn seeds_are_deterministic() {
    let srcs = vec![source(30.0), source(45.0)];
    let opts = SynthOpts::default();
    let a = generate(&srcs, 10, 5, &opts);
    let b = generate(&srcs, 10, 5, &opts);
    let c = generate(&srcs, 10, 6, &opts);
    assert_eq!(a.len(), 10);
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.id, y.id);
        assert_eq!(x.truth, y.truth);
        assert_eq!(x.boundaries, y.boundaries);
        assert_eq!(x.track, y.track);
    }
    assert!(a
        .iter()
        .zip(&c)
        .any(|(x, y)| x.track != y.track || x.truth != y.truth));
    assert!(a
        .iter()
        .enumerate()
        .all(|(i, x)| x.id == i && x.source == "test"));
}

/// N = 0 cases hold no repetition and 2–6 s of motion; N = 1 one cycle.
#[test]
fn non_repetitive_cases() {
    let src = source(30.0);
    let opts = SynthOpts {
        non_rep_share: 1.0,
        ..SynthOpts::default()
    };
    let cases: Vec<Case> = (0..16)
        .filter_map(|i| make_case(&src, i, 1, &opts))
        .collect();
    assert_eq!(cases.len(), 16);
    assert!(cases.iter().any(|c| c.truth == 0) && cases.iter().any(|c| c.truth == 1));
    for c in &cases {
        match c.truth {
            0 => {
                assert!(c.boundaries.is_empty() && c.rep_start == c.rep_end && c.cycle.is_none());
                let secs = c.track.n_frames() as f64 / FPS;
                assert!((1.9..=6.1).contains(&secs), "{secs} s");
            }
            1 => assert_eq!(c.boundaries, vec![c.rep_start, c.rep_end]),
            t => panic!("truth {t}"),
        }
    }
}

/// A cycle holding two periods of the motion is refused.
#[test]
fn sub_periods_are_refused() {
    let fast = source_of(
        "fast",
        vec![motion(300, Some(9.0))],
        Units::Pixels,
        Skeleton::generic(6),
    );
    let mut rng = Rng::for_case(0, 0);
    // 0.5 s is more than one 0.3 s period: every near-loop holds two or more.
    assert_eq!(find_cycle(&fast, &mut rng, 0.5, 1.0), None);
    let clip = motion(300, Some(20.0));
    assert!(sub_period_ratio(&clip, 10, 50) < MAX_SUB_PERIOD);
    assert!(sub_period_ratio(&clip, 10, 30) > 0.6);
}

#[test]
fn periodicity_separates_repeats_from_motion_once() {
    let rep = motion(90, Some(25.0));
    let once = motion(90, None);
    assert!(periodicity(&rep.pos, &rep.joints, rep.scale, FPS) > 0.7);
    assert!(periodicity(&once.pos, &once.joints, once.scale, FPS) < 0.2);
}

/// The keypoint noise is what it says: the same case with and without it
/// differs by a σ of at most `noise` body scales, and not by nothing.
#[test]
fn keypoint_noise_stays_within_its_scale() {
    let src = source(36.0);
    let quiet = SynthOpts {
        noise: 0.0,
        ..SynthOpts::default()
    };
    let mut seen = 0.0f64;
    for id in 0..8 {
        let a = make_case(&src, id, 5, &quiet).expect("case");
        let b = make_case(&src, id, 5, &SynthOpts::default()).expect("case");
        assert_eq!(a.track.n_frames(), b.track.n_frames());
        let (pa, pb) = (a.track.positions(), b.track.positions());
        let m = pa.len() as f64;
        let sd = ((&pa - &pb).mapv(|v| v * v).sum() / m).sqrt();
        let scale = src.clips[a.cycle.as_ref().map_or(0, |c| c.1.clip)].scale;
        assert!(sd <= 0.035 * scale, "case {id}: σ {sd} for scale {scale}");
        seen = seen.max(sd / scale);
    }
    assert!(seen > 0.003, "no noise was added: {seen}");
}
