//! The procedural performer: determinism, rigid bones, ground truth.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::performer::{perform, Move, PerformerParams, Projection, RIGID_BONES};
use crate::{GeomError, Units};

fn bone_len(t: &crate::Track, f: usize, a: usize, b: usize) -> f64 {
    (0..t.dims())
        .map(|k| (t.point(f, a)[k] - t.point(f, b)[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

#[test]
fn default_routine_shapes_and_ground_truth() {
    let p = PerformerParams::default();
    let perf = perform(&p).unwrap();
    let (t3, t2) = (&perf.track_3d, &perf.track_2d);
    assert_eq!(
        (t3.n_joints(), t3.dims(), t3.units()),
        (17, 3, Units::Metres)
    );
    assert_eq!(
        (t2.n_joints(), t2.dims(), t2.units()),
        (17, 2, Units::Pixels)
    );
    assert_eq!(t3.n_frames(), t2.n_frames());
    assert_eq!(t3.fps(), 30.0);
    let kinds: Vec<Move> = perf.segments.iter().map(|s| s.kind).collect();
    assert_eq!(
        kinds,
        vec![
            Move::JumpingJack,
            Move::Squat,
            Move::ArmCircle,
            Move::GolfSwing
        ]
    );
    let reps: Vec<usize> = perf.segments.iter().map(|s| s.reps.len()).collect();
    assert_eq!(reps, vec![4, 3, 3, 1]);
    // Repetitions tile their move; moves are separated by 15-frame transitions.
    for s in &perf.segments {
        assert_eq!(s.reps.first().unwrap().start, s.frames.start);
        assert_eq!(s.reps.last().unwrap().end, s.frames.end);
        for w in s.reps.windows(2) {
            assert_eq!(w[0].end, w[1].start);
        }
        // 1.2 s × tempo × (1 ± ≤ 12.5 %) at 30 fps.
        let base = 36.0 * s.kind.tempo_factor();
        for r in &s.reps {
            let n = r.len() as f64;
            assert!(
                n > 0.85 * base && n < 1.15 * base,
                "{:?} rep of {n} frames",
                s.kind
            );
        }
    }
    assert_eq!(perf.segments[0].frames.start, 0);
    for w in perf.segments.windows(2) {
        assert_eq!(w[1].frames.start - w[0].frames.end, 15);
    }
    assert_eq!(perf.segments.last().unwrap().frames.end, t3.n_frames());
    // Everything is inside the 512×512 frame.
    let (lo, hi) = t2.bounds().unwrap();
    assert!(
        lo[0] > 0.0 && lo[1] > 0.0 && hi[0] < 512.0 && hi[1] < 512.0,
        "{lo:?} {hi:?}"
    );
    // Feet on the ground when the squats start: ankles at 8 cm for a 1.75 m body
    // (and within 2 mm of it while the legs are 3° apart at the first jumping jack).
    assert!((t3.point(perf.segments[1].frames.start, 15)[1] - 0.08).abs() < 1e-9);
    assert!((t3.point(0, 15)[1] - 0.08).abs() < 2e-3);
}

#[test]
fn same_seed_same_output_other_seed_differs() {
    let p = PerformerParams::default();
    let a = perform(&p).unwrap();
    let b = perform(&p).unwrap();
    assert_eq!(a.track_3d, b.track_3d);
    assert_eq!(a.track_2d, b.track_2d);
    assert_eq!(a.segments, b.segments);
    let c = perform(&PerformerParams {
        seed: 1,
        ..p.clone()
    })
    .unwrap();
    assert_ne!(a.track_2d, c.track_2d);
    let q = PerformerParams {
        variation: 0.0,
        noise_px: 0.0,
        ..p
    };
    let d = perform(&q).unwrap();
    let e = perform(&PerformerParams { seed: 99, ..q }).unwrap();
    assert_eq!(
        d.track_2d, e.track_2d,
        "without randomness the seed does not matter"
    );
}

#[test]
fn rigid_bones_keep_their_length() {
    let perf = perform(&PerformerParams {
        variation: 0.2,
        ..Default::default()
    })
    .unwrap();
    let t = &perf.track_3d;
    for &(a, b) in &RIGID_BONES {
        let l0 = bone_len(t, 0, a, b);
        assert!(l0 > 0.03, "bone {a}-{b} has length {l0}");
        for f in 0..t.n_frames() {
            let l = bone_len(t, f, a, b);
            assert!((l - l0).abs() < 1e-9, "bone {a}-{b} frame {f}: {l} vs {l0}");
        }
    }
    // Upper arm 0.30 m and shin 0.42 m for the default 1.75 m body.
    assert!((bone_len(t, 0, 5, 7) - 0.30).abs() < 1e-12);
    assert!((bone_len(t, 0, 13, 15) - 0.42).abs() < 1e-12);
}

#[test]
fn moves_do_what_they_say() {
    let p = PerformerParams {
        variation: 0.0,
        noise_px: 0.0,
        ..Default::default()
    };
    let perf = perform(&p).unwrap();
    let t = &perf.track_3d;
    let seg = |m: Move| perf.segments.iter().find(|s| s.kind == m).unwrap().clone();
    // Jumping jack: at mid-repetition the wrists are above the head.
    let jj = seg(Move::JumpingJack);
    let mid = jj.reps[0].start + jj.reps[0].len() / 2;
    assert!(t.point(mid, 9)[1] > t.point(mid, 0)[1] + 0.2);
    assert!(t.point(jj.reps[0].start, 9)[1] < t.point(jj.reps[0].start, 11)[1]);
    // Squat: the hips drop more than 30 cm at mid-repetition, ankles stay put.
    let sq = seg(Move::Squat);
    let (s0, sm) = (sq.reps[1].start, sq.reps[1].start + sq.reps[1].len() / 2);
    assert!(t.point(s0, 11)[1] - t.point(sm, 11)[1] > 0.3);
    assert!((t.point(s0, 15)[1] - t.point(sm, 15)[1]).abs() < 1e-9);
    // Arm circle: in the image the left wrist goes round the shoulder at
    // about constant distance (a circle of radius ≈ arm length).
    let ac = seg(Move::ArmCircle);
    let t2 = &perf.track_2d;
    let r = ac.reps[0].clone();
    let dists: Vec<f64> = r.clone().map(|f| bone_len(t2, f, 5, 9)).collect();
    let (mn, mx) = dists
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &d| (a.min(d), b.max(d)));
    assert!(mx / mn < 1.15, "wrist–shoulder distance {mn}..{mx} px");
    let angle = |f: usize| {
        let (s, w) = (t2.point(f, 5), t2.point(f, 9));
        (w[1] - s[1]).atan2(w[0] - s[0])
    };
    let mut total = 0.0;
    for f in r.start + 1..r.end {
        let mut d = angle(f) - angle(f - 1);
        if d > std::f64::consts::PI {
            d -= 2.0 * std::f64::consts::PI;
        } else if d < -std::f64::consts::PI {
            d += 2.0 * std::f64::consts::PI;
        }
        total += d;
    }
    assert!(
        total.abs() > 5.5,
        "one repetition sweeps about a full turn, got {total} rad"
    );
    // Golf swing: shoulders turn by more than 60° at the top of the backswing.
    let g = seg(Move::GolfSwing);
    let top = g.frames.start + (0.40 * g.frames.len() as f64) as usize;
    let line = |f: usize| {
        let (l, rr) = (t.point(f, 5), t.point(f, 6));
        (l[2] - rr[2]).atan2(l[0] - rr[0]).to_degrees().abs()
    };
    assert!(line(top) > 60.0, "shoulder turn {}", line(top));
    assert!(line(g.frames.start) < 5.0);
}

#[test]
fn perspective_and_frame_size() {
    let p = PerformerParams {
        frame_size_px: (640, 360),
        projection: Projection::Perspective {
            camera_distance_m: 4.0,
        },
        moves: vec![(Move::Squat, 2)],
        ..Default::default()
    };
    let perf = perform(&p).unwrap();
    let (lo, hi) = perf.track_2d.bounds().unwrap();
    assert!(
        lo[0] > 0.0 && lo[1] > 0.0 && hi[0] < 640.0 && hi[1] < 360.0,
        "{lo:?} {hi:?}"
    );
    assert_eq!(perf.segments.len(), 1);
    assert_eq!(perf.segments[0].reps.len(), 2);
}

#[test]
fn invalid_parameters_are_typed_errors() {
    let d = PerformerParams::default();
    let bad = [
        PerformerParams {
            moves: vec![],
            ..d.clone()
        },
        PerformerParams {
            moves: vec![(Move::Squat, 0)],
            ..d.clone()
        },
        PerformerParams {
            fps: 0.0,
            ..d.clone()
        },
        PerformerParams {
            rep_seconds: f64::NAN,
            ..d.clone()
        },
        PerformerParams {
            rep_seconds: 0.05,
            ..d.clone()
        },
        PerformerParams {
            variation: 0.5,
            ..d.clone()
        },
        PerformerParams {
            noise_px: -1.0,
            ..d.clone()
        },
        PerformerParams {
            frame_size_px: (8, 512),
            ..d.clone()
        },
        PerformerParams {
            projection: Projection::Perspective {
                camera_distance_m: 1.0,
            },
            ..d.clone()
        },
    ];
    for p in bad {
        assert!(
            matches!(perform(&p), Err(GeomError::InvalidParam { .. })),
            "{p:?}"
        );
    }
}
