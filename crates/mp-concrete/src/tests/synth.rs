//! Synthesis: recovering known programs, invariances, execution, and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::{
    ConcreteError, ExecParams, Lambda, Program, Scale, Segment, SynthParams, Transition,
    UnobservedJoints,
};
use mp_geom::{Primitive, Skeleton, Track, Units};
use ndarray::{Array2, Array3};

fn line(x: f64, y: f64, vx: f64, vy: f64) -> Primitive {
    Primitive::Line {
        start: vec![x, y],
        velocity: vec![vx, vy],
    }
}
fn still(x: f64, y: f64) -> Primitive {
    Primitive::Stationary { point: vec![x, y] }
}
fn arc(cx: f64, cy: f64, r: f64, start: f64, vel: f64) -> Primitive {
    Primitive::Circle {
        center: vec![cx, cy],
        radius: r,
        angle_start: start,
        angle_vel: vel,
        angle_acc: 0.0,
        axes: vec![],
    }
}

/// A 3-joint program with segments of 15, 12 and 20 frames; the motion jumps
/// at each boundary so that every boundary is unambiguous.
fn known_program() -> Program {
    Program {
        fps: 30.0,
        units: Units::Pixels,
        dims: 2,
        skeleton: "generic".into(),
        joints: vec!["j0".into(), "j1".into(), "j2".into()],
        continuity: crate::Continuity::None,
        segments: vec![
            Segment {
                duration_frames: 15,
                primitives: vec![
                    line(100.0, 100.0, 6.0, 2.0),
                    still(300.0, 200.0),
                    arc(250.0, 250.0, 60.0, 0.0, 6.0),
                ],
            },
            Segment {
                duration_frames: 12,
                primitives: vec![
                    still(250.0, 180.0),
                    line(300.0, 150.0, -5.0, 7.0),
                    arc(250.0, 250.0, 60.0, 200.0, -8.0),
                ],
            },
            Segment {
                duration_frames: 20,
                primitives: vec![
                    arc(150.0, 300.0, 80.0, 90.0, 5.0),
                    line(180.0, 260.0, 4.0, -4.0),
                    still(320.0, 330.0),
                ],
            },
        ],
    }
}

/// Pixels at the reference scale; λ = 300 suits 3 joints (the default 1600
/// is meant for whole skeletons, where the cost sums over 13–17 joints).
/// Segments fitted independently: the known program jumps at every
/// boundary, which a C0 program cannot reproduce.
fn params_px() -> SynthParams {
    SynthParams {
        scale: Scale::UnitScale { unit_scale: 1.0 },
        lambda: Lambda::fixed(300.0),
        continuity: crate::Continuity::None,
        ..SynthParams::paper()
    }
}

#[test]
fn recovers_boundaries_of_a_known_program() {
    let truth = known_program();
    let track = truth.execute().unwrap();
    let syn = Program::synthesize_detailed(&track, &params_px()).unwrap();
    assert_eq!(syn.program.boundaries(), vec![0, 15, 27, 47]);
    assert_eq!(syn.unit_scale, 1.0);
    // The kinds are recovered too, and the program reproduces the track.
    for (s, t) in syn.program.segments.iter().zip(&truth.segments) {
        let got: Vec<_> = s.primitives.iter().map(Primitive::kind).collect();
        let want: Vec<_> = t.primitives.iter().map(Primitive::kind).collect();
        assert_eq!(got, want);
    }
    let st = syn.program.stats(&track).unwrap();
    assert!(st.kd < 1e-6, "kd {}", st.kd);
    assert_eq!(st.n_segments, 3);
    assert_eq!(st.params_raw, 47 * 3 * 2);
    assert_eq!(st.params_program, truth.n_params());
    assert_eq!(st.kinds["circle"], 3);
}

#[test]
fn recovers_boundaries_with_noise_and_gaps() {
    let truth = known_program();
    let clean = truth.execute().unwrap();
    let (mut pos, _, fps, units, skel) = clean.into_parts();
    // Deterministic ±1 px noise and a few missing entries.
    let mut conf = Array2::ones((47, 3));
    for t in 0..47 {
        for j in 0..3 {
            for k in 0..2 {
                let h = ((t * 31 + j * 17 + k * 7) % 13) as f64 / 6.0 - 1.0;
                pos[[t, j, k]] += h;
            }
        }
    }
    for (t, j) in [(3, 0), (20, 1), (21, 1), (40, 2)] {
        conf[[t, j]] = 0.0;
        pos[[t, j, 0]] = 9999.0; // garbage where missing: must be ignored
    }
    let track = Track::new(pos, Some(conf), fps, units, skel).unwrap();
    let p = Program::synthesize(&track, &params_px()).unwrap();
    assert_eq!(p.boundaries(), vec![0, 15, 27, 47]);
    let st = p.stats(&track).unwrap();
    assert!(st.kd < 1.5, "kd {}", st.kd);
}

#[test]
fn scaling_the_track_scales_nothing_else() {
    // With Scale::Auto thresholds and λ follow the track's size: a track
    // scaled by 3 gets the same segmentation.
    let track = known_program().execute().unwrap();
    let p1 = Program::synthesize(&track, &SynthParams::paper()).unwrap();
    let (pos, conf, fps, units, skel) = track.clone().into_parts();
    let big = Track::new(pos.mapv(|v| v * 3.0), Some(conf), fps, units, skel).unwrap();
    let p3 = Program::synthesize(&big, &SynthParams::paper()).unwrap();
    assert_eq!(p1.boundaries(), p3.boundaries());
}

#[test]
fn lambda_controls_the_number_of_segments() {
    let track = known_program().execute().unwrap();
    let few = Program::synthesize(
        &track,
        &SynthParams {
            lambda: Lambda::fixed(1e7),
            max_segment_frames: 100,
            ..params_px()
        },
    )
    .unwrap();
    assert_eq!(few.n_segments(), 1);
    let many = Program::synthesize(
        &track,
        &SynthParams {
            lambda: Lambda::fixed(0.0),
            ..params_px()
        },
    )
    .unwrap();
    assert!(many.n_segments() >= 3);
    // The window caps segment length.
    let capped = Program::synthesize(
        &track,
        &SynthParams {
            max_segment_frames: 10,
            ..params_px()
        },
    )
    .unwrap();
    assert!(capped.segments.iter().all(|s| s.duration_frames <= 10));
}

#[test]
fn adaptive_lambda_is_clamped_and_works() {
    let track = known_program().execute().unwrap();
    let syn = Program::synthesize_detailed(
        &track,
        &SynthParams {
            lambda: Lambda::Adaptive {
                window_frames: 31,
                min_ref: 50.0,
                max_ref: 300.0,
            },
            ..params_px()
        },
    )
    .unwrap();
    assert!(syn.lambda.iter().all(|&l| (50.0..=300.0).contains(&l)));
    // Big circles and lines move a lot: λ reaches the top of the range somewhere.
    assert!(syn.lambda.contains(&300.0));
    assert_eq!(syn.program.boundaries(), vec![0, 15, 27, 47]);
}

/// `Lambda::Spread` is the square root of the adaptive rule's covariance
/// norm held for `seconds · fps` frames, clamped: twice the seconds or twice
/// the frame rate, twice the λ; a longer hold, fewer segments.
#[test]
fn spread_lambda_is_the_local_spread_held_for_a_time() {
    let track = known_program().execute().unwrap();
    let open = |lambda| SynthParams {
        lambda,
        ..params_px()
    };
    let wide = |seconds| Lambda::Spread {
        seconds,
        window_frames: 31,
        min_ref: 0.0,
        max_ref: 1e12,
    };
    let lambda_of = |track: &Track, lambda| {
        Program::synthesize_detailed(track, &open(lambda))
            .unwrap()
            .lambda
    };
    let adaptive = lambda_of(
        &track,
        Lambda::Adaptive {
            window_frames: 31,
            min_ref: 0.0,
            max_ref: 1e12,
        },
    );
    let fps = track.fps();
    let spread = lambda_of(&track, wide(0.5));
    assert_eq!(spread.len(), track.n_frames());
    for (s, a) in spread.iter().zip(&adaptive) {
        let want = a.sqrt() * 0.5 * fps;
        assert!((s - want).abs() <= 1e-9 * want, "{s} vs {want}");
    }
    let fast = track.clone().with_fps(2.0 * fps).unwrap();
    let doubled = lambda_of(&fast, wide(0.5));
    let longer = lambda_of(&track, wide(1.0));
    for ((s, d), l) in spread.iter().zip(&doubled).zip(&longer) {
        assert!((d - 2.0 * s).abs() <= 1e-9 * d && (l - 2.0 * s).abs() <= 1e-9 * l);
    }
    // The default clamp, and the number of segments falling as the hold grows.
    let segments = |seconds: f64| {
        let syn = Program::synthesize_detailed(&track, &open(Lambda::spread(seconds))).unwrap();
        assert!(syn.lambda.iter().all(|&l| (100.0..=1600.0).contains(&l)));
        syn.program.n_segments()
    };
    assert!(
        segments(0.2) > segments(2.0),
        "{} vs {}",
        segments(0.2),
        segments(2.0)
    );
}

#[test]
fn a_parameter_budget_gives_the_finest_program_within_it() {
    let track = crate::synthetic::synthetic_track(400, 7).unwrap();
    let raw = (track.n_frames() * track.n_joints() * track.dims()) as f64;
    let base = SynthParams {
        continuity: crate::Continuity::C0,
        ..params_px()
    };
    let ratio_of = |p: &Program| p.n_params() as f64 / raw;
    for budget in [0.05, 0.1, 0.2] {
        let syn = Program::synthesize_detailed(
            &track,
            &SynthParams {
                lambda: Lambda::budget(budget),
                ..base.clone()
            },
        )
        .unwrap();
        let r = ratio_of(&syn.program);
        assert!(r <= budget, "budget {budget}: ratio {r}");
        // It is the program of the fixed λ it reports (unit scale 1: λ as is).
        let lambda = syn.lambda[0];
        assert!(syn.lambda.iter().all(|&l| l == lambda));
        let fixed = Program::synthesize(
            &track,
            &SynthParams {
                lambda: Lambda::fixed(lambda),
                ..base.clone()
            },
        )
        .unwrap();
        assert_eq!(fixed, syn.program);
        // `segment` with the budget gives the same segmentation.
        let seg = crate::Segmentation::search(
            &track,
            &SynthParams {
                lambda: Lambda::budget(budget),
                ..base.clone()
            },
        )
        .unwrap();
        assert_eq!(seg.boundaries, syn.segmentation.boundaries);
        // A 5 % smaller λ (past the bisection's 2 % bracket) no longer fits.
        let finer = Program::synthesize(
            &track,
            &SynthParams {
                lambda: Lambda::fixed(lambda / 1.05),
                ..base.clone()
            },
        )
        .unwrap();
        assert!(
            ratio_of(&finer) > budget * 0.98,
            "budget {budget}: λ {lambda} / 1.05 gives {}",
            ratio_of(&finer)
        );
    }
    // A budget that the finest program of the range (λ = 1) meets gives that
    // program: the noiseless known program, recovered exactly.
    let exact = known_program().execute().unwrap();
    let all = Program::synthesize_detailed(
        &exact,
        &SynthParams {
            lambda: Lambda::budget(0.5),
            ..base.clone()
        },
    )
    .unwrap();
    assert_eq!(all.lambda[0], 1.0);
    assert_eq!(all.program.boundaries(), vec![0, 15, 27, 47]);
    // A budget below the most compact program, and budgets out of range.
    for bad in [1e-6, 0.0, -0.1, 1.5, f64::NAN] {
        let e = Program::synthesize(
            &track,
            &SynthParams {
                lambda: Lambda::budget(bad),
                ..base.clone()
            },
        )
        .unwrap_err();
        assert!(
            matches!(e, ConcreteError::InvalidParam { .. })
                && e.to_string().contains("lambda.ratio"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn execution_at_other_rates() {
    let p = known_program();
    let native = p.execute().unwrap();
    assert_eq!(native.n_frames(), 47);
    assert_eq!(native.point(15, 1).to_vec(), vec![300.0, 150.0]);
    let double = p
        .execute_with(&ExecParams {
            fps_out: Some(60.0),
            transition: Transition::Blend,
        })
        .unwrap();
    assert_eq!(double.n_frames(), 93);
    assert_eq!(double.fps(), 60.0);
    for t in 0..47 {
        assert_eq!(double.point(2 * t, 0), native.point(t, 0));
    }
    // Between segments the default blends the two ends…
    let mid = double.point(29, 0).to_vec(); // program frame 14.5
    let a = native.point(14, 0);
    let b = native.point(15, 0);
    assert!((mid[0] - 0.5 * (a[0] + b[0])).abs() < 1e-9);
    // …and extrapolation continues the first primitive.
    let ex = p.sample_frames(&[14.5], Transition::Extrapolate).unwrap();
    assert!((ex[[0, 0, 0]] - (100.0 + 6.0 * 14.5)).abs() < 1e-9);
    // Inside a segment, fractional times follow the primitive.
    let f = p.sample_frames(&[3.25], Transition::Blend).unwrap();
    assert!((f[[0, 0, 1]] - (100.0 + 2.0 * 3.25)).abs() < 1e-9);
    // Outside the program: a typed error.
    assert!(matches!(
        p.sample_frames(&[46.5], Transition::Blend),
        Err(ConcreteError::InvalidParam { .. })
    ));
    assert!(p
        .execute_with(&ExecParams {
            fps_out: Some(0.0),
            ..Default::default()
        })
        .is_err());
    // Times in seconds.
    let s = p.sample_times_s(&[0.5], Transition::Blend).unwrap();
    assert_eq!(
        s.slice(ndarray::s![0, .., ..]),
        native.positions().slice(ndarray::s![15, .., ..])
    );
}

fn track_of(t: usize, j: usize) -> Track {
    let mut pos = Array3::zeros((t, j, 2));
    for ti in 0..t {
        for ji in 0..j {
            pos[[ti, ji, 0]] = ti as f64 * 3.0 + ji as f64;
            pos[[ti, ji, 1]] = 50.0;
        }
    }
    Track::new(pos, None, 30.0, Units::Pixels, Skeleton::generic(j)).unwrap()
}

#[test]
fn bad_input_is_a_typed_error() {
    let ok = SynthParams::paper();
    // Empty track and a single frame.
    assert!(matches!(
        Program::synthesize(&track_of(0, 2), &ok),
        Err(ConcreteError::Track(_))
    ));
    assert!(matches!(
        Program::synthesize(&track_of(1, 2), &ok),
        Err(ConcreteError::Track(_))
    ));
    // Two frames are enough.
    assert_eq!(
        Program::synthesize(&track_of(2, 2), &ok)
            .unwrap()
            .n_frames(),
        2
    );
    // An all-NaN joint is named.
    let (mut pos, _, fps, units, skel) = track_of(10, 3).into_parts();
    pos.slice_mut(ndarray::s![.., 1, ..]).fill(f64::NAN);
    let nan = Track::new(pos, None, fps, units, skel).unwrap();
    match Program::synthesize(&nan, &ok) {
        Err(ConcreteError::Track(m)) => assert!(m.contains("j1"), "{m}"),
        other => panic!("{other:?}"),
    }
    // …unless asked to ignore it.
    let ign = SynthParams {
        unobserved_joints: UnobservedJoints::Ignore,
        ..SynthParams::paper()
    };
    assert_eq!(Program::synthesize(&nan, &ign).unwrap().n_joints(), 3);
    // Zero confidence everywhere.
    let (pos, _, fps, units, skel) = track_of(10, 3).into_parts();
    let zero = Track::new(pos, Some(Array2::zeros((10, 3))), fps, units, skel).unwrap();
    match Program::synthesize(&zero, &ign) {
        Err(ConcreteError::Track(m)) => assert!(m.contains("every joint of every frame"), "{m}"),
        other => panic!("{other:?}"),
    }
    // Parameters.
    let tr = track_of(10, 2);
    let bad = |p: SynthParams, name: &str| match Program::synthesize(&tr, &p) {
        Err(ConcreteError::InvalidParam { name: n, .. }) => assert_eq!(n, name),
        other => panic!("{name}: {other:?}"),
    };
    bad(
        SynthParams {
            lambda: Lambda::fixed(-1.0),
            ..SynthParams::paper()
        },
        "lambda",
    );
    bad(
        SynthParams {
            lambda: Lambda::fixed(f64::NAN),
            ..SynthParams::paper()
        },
        "lambda",
    );
    bad(
        SynthParams {
            max_segment_frames: 0,
            ..SynthParams::paper()
        },
        "max_segment_frames",
    );
    bad(
        SynthParams {
            lambda: Lambda::Adaptive {
                window_frames: 31,
                min_ref: 2000.0,
                max_ref: 100.0,
            },
            ..SynthParams::paper()
        },
        "lambda.min_ref",
    );
    for seconds in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        bad(
            SynthParams {
                lambda: Lambda::spread(seconds),
                ..SynthParams::paper()
            },
            "lambda.seconds",
        );
    }
    bad(
        SynthParams {
            lambda: Lambda::Spread {
                seconds: 1.0,
                window_frames: 0,
                min_ref: 100.0,
                max_ref: 1600.0,
            },
            ..SynthParams::paper()
        },
        "lambda.window_frames",
    );
    bad(
        SynthParams {
            scale: Scale::FrameSize { frame_px: f64::NAN },
            ..SynthParams::paper()
        },
        "scale.frame_px",
    );
    bad(
        SynthParams {
            min_confidence: 1.5,
            ..SynthParams::paper()
        },
        "min_confidence",
    );
    let mut no_kinds = SynthParams::paper();
    no_kinds.fit.kinds.clear();
    bad(no_kinds, "fit.kinds");
}

#[test]
fn stats_require_matching_shapes() {
    let p = known_program();
    let tr = track_of(10, 3);
    assert!(matches!(p.stats(&tr), Err(ConcreteError::Program(_))));
}
