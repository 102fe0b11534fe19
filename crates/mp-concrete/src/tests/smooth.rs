//! Smooth (C0) programs: consecutive segments share their boundary pose.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::synthetic::synthetic_track;
use crate::{Continuity, Lambda, Program, RefitNorm, Scale, SynthParams, UnobservedJoints};
use mp_geom::PennAction;
use mp_geom::{Primitive, PrimitiveKind, Skeleton, Track, Units};
use ndarray::{Array2, Array3};

fn with(continuity: Continuity, base: &SynthParams) -> SynthParams {
    SynthParams {
        continuity,
        ..base.clone()
    }
}

/// Every boundary of a C0 program is shared within `1e-9` (track units;
/// coordinates are up to `scale`, so this is about 1e-12 relative).
fn assert_c0(p: &Program, scale: f64) {
    assert_eq!(p.continuity, Continuity::C0);
    let gap = p.max_boundary_gap();
    assert!(
        gap <= 1e-9,
        "boundary gap {gap} (coordinates up to {scale})"
    );
}

#[test]
fn default_is_c0_and_none_is_independent() {
    assert_eq!(SynthParams::paper().continuity, Continuity::C0);
    let track = synthetic_track(400, 3).unwrap();
    let smooth = Program::synthesize(&track, &SynthParams::paper()).unwrap();
    assert_c0(&smooth, 1000.0);
    let free = Program::synthesize(&track, &with(Continuity::None, &SynthParams::paper())).unwrap();
    assert_eq!(free.continuity, Continuity::None);
    // Same segmentation, independent fits jump at boundaries.
    assert_eq!(free.boundaries(), smooth.boundaries());
    assert!(free.max_boundary_gap() > 1e-3);
    let (sf, ss) = (free.stats(&track).unwrap(), smooth.stats(&track).unwrap());
    eprintln!(
        "synthetic: KD {:.3} → {:.3}, jump raw {:.2} free {:.2} C0 {:.2}, params {} → {}",
        sf.kd,
        ss.kd,
        sf.max_jump_raw,
        sf.max_jump_program,
        ss.max_jump_program,
        sf.params_program,
        ss.params_program
    );
    assert!(ss.max_jump_program <= ss.max_jump_raw + 1e-9);
    assert!(ss.kd <= 1.5 * sf.kd + 0.5, "KD {} vs {}", ss.kd, sf.kd);
}

/// 2D and 3D tracks, every primitive kind allowed, missing frames and a
/// joint missing everywhere: still C0, and executing gives no jump at a
/// boundary larger than the primitives' own steps.
#[test]
fn c0_with_all_kinds_missing_frames_and_3d() {
    for d in [2usize, 3] {
        let (t, j) = (240usize, 4usize);
        let mut pos = Array3::zeros((t, j, d));
        let mut conf = Array2::ones((t, j));
        for ti in 0..t {
            let x = ti as f64;
            for ji in 0..j {
                let ph = 0.05 * x + ji as f64;
                let base = [
                    200.0 + 60.0 * ph.cos(),
                    200.0 + 60.0 * ph.sin(),
                    50.0 + 0.3 * x,
                ];
                for k in 0..d {
                    // Steps and holds on joint 1, noise everywhere.
                    let hold = if ji == 1 {
                        ((ti / 30) as f64) * 15.0
                    } else {
                        0.0
                    };
                    pos[[ti, ji, k]] = base[k] + hold + ((ti * 31 + ji * 7 + k) % 5) as f64 * 0.4;
                }
                if (ti * 13 + ji) % 11 == 0 {
                    conf[[ti, ji]] = 0.0;
                }
            }
            conf[[ti, 3]] = 0.0; // never observed
        }
        let track = Track::new(pos, Some(conf), 30.0, Units::Pixels, Skeleton::generic(j)).unwrap();
        let params = SynthParams {
            lambda: Lambda::fixed(400.0),
            scale: Scale::UnitScale { unit_scale: 1.0 },
            unobserved_joints: UnobservedJoints::Ignore,
            fit: mp_geom::FitParams {
                kinds: PrimitiveKind::ALL.to_vec(),
                ..Default::default()
            },
            ..SynthParams::paper()
        };
        let p = Program::synthesize(&track, &params).unwrap();
        assert!(p.n_segments() > 3, "{} segments", p.n_segments());
        assert_c0(&p, 1000.0);
        let st = p.stats(&track).unwrap();
        eprintln!(
            "{d}D: {} segments, KD {:.3}, jump raw {:.2} program {:.2}",
            p.n_segments(),
            st.kd,
            st.max_jump_raw,
            st.max_jump_program
        );
        assert!(st.kd < 6.0, "KD {}", st.kd);
        // The executed program steps at most as far as the input (the hold on
        // joint 1 steps 15 px at once).
        assert!(st.max_jump_program <= st.max_jump_raw + 1e-9);
    }
}

/// A C0 program's free parameters leave out every segment's start pose (the
/// previous segment's end): `D` numbers per joint and boundary. Independent
/// programs, and a boundary that a C0-labelled program does not share, count
/// every number.
#[test]
fn c0_start_poses_are_not_free_parameters() {
    let track = synthetic_track(400, 3).unwrap();
    let c0 = Program::synthesize(&track, &SynthParams::paper()).unwrap();
    let (s, j, d) = (c0.n_segments(), c0.n_joints(), c0.dims);
    assert!(s > 3);
    assert_eq!(c0.n_shared_params(), d * j * (s - 1));
    assert_eq!(c0.n_params() + d * j * (s - 1), c0.n_numbers());
    let free = Program::synthesize(&track, &with(Continuity::None, &SynthParams::paper())).unwrap();
    assert_eq!(free.n_shared_params(), 0);
    assert_eq!(free.n_params(), free.n_numbers());
    // The same primitives labelled independent: every number counts.
    let mut relabelled = c0.clone();
    relabelled.continuity = Continuity::None;
    assert_eq!(relabelled.n_params(), c0.n_numbers());
    // One joint moved off the shared pose at the first boundary.
    let mut broken = c0.clone();
    if let Some(p) = broken.segments[1].primitives.get_mut(0) {
        *p = p.translated(&vec![5.0; d]);
    }
    assert_eq!(broken.n_shared_params(), d * j * (s - 1) - 2 * d);
    // A program that does not validate is not evaluated: every number counts.
    let mut invalid = c0.clone();
    invalid.segments[1].duration_frames = 0;
    assert_eq!(invalid.n_params(), invalid.n_numbers());
    let st = c0.stats(&track).unwrap();
    assert_eq!(st.params_program, c0.n_params());
    assert_eq!(st.numbers_program, c0.n_numbers());
}

#[test]
fn continuity_survives_json_dsl_and_binary_and_old_files_load() {
    let track = synthetic_track(200, 5).unwrap();
    let p = Program::synthesize(&track, &SynthParams::paper()).unwrap();
    assert_eq!(p.continuity, Continuity::C0);
    assert_eq!(Program::from_json(&p.to_json().unwrap()).unwrap(), p);
    assert!(p.to_dsl().starts_with("program(") && p.to_dsl().contains("continuity=c0"));
    assert_eq!(Program::from_dsl(&p.to_dsl()).unwrap(), p);
    assert_eq!(Program::from_bincode(&p.to_bincode().unwrap()).unwrap(), p);

    // A program written before the field existed (JSON without it, DSL header
    // without it) reads as independently fitted.
    let mut v: serde_json::Value = serde_json::from_str(&p.to_json().unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("continuity");
    let old = Program::from_json(&v.to_string()).unwrap();
    assert_eq!(old.continuity, Continuity::None);
    assert_eq!(old.segments, p.segments);
    let text = p.to_dsl().replace(", continuity=c0", "");
    assert_eq!(
        Program::from_dsl(&text).unwrap().continuity,
        Continuity::None
    );
    let free = Program {
        continuity: Continuity::None,
        ..p.clone()
    };
    assert!(!free.to_dsl().contains("continuity"));
    assert!(Program::from_dsl(&p.to_dsl().replace("continuity=c0", "continuity=c1")).is_err());
}

/// A version-1 `.mpb` (no continuity) still decodes, as `Continuity::None`.
#[test]
fn binary_version_1_reads_as_independent() {
    // A one-joint, one-segment program in the version-1 layout, built by hand:
    // magic, version 1, then the bincode record without `continuity`.
    #[derive(serde::Serialize)]
    struct V1 {
        fps: f64,
        units: Units,
        dims: u64,
        skeleton: String,
        joints: Vec<String>,
        segments: Vec<(u64, Vec<P>)>,
    }
    #[derive(serde::Serialize)]
    enum P {
        #[allow(dead_code)]
        Stationary {
            point: Vec<f64>,
        },
        Line {
            start: Vec<f64>,
            velocity: Vec<f64>,
        },
    }
    let rec = V1 {
        fps: 30.0,
        units: Units::Pixels,
        dims: 2,
        skeleton: "generic".into(),
        joints: vec!["a".into()],
        segments: vec![(
            4,
            vec![P::Line {
                start: vec![1.0, 2.0],
                velocity: vec![0.5, -0.25],
            }],
        )],
    };
    let bytes = mp_geom::binary::encode(b"mp-program", 1, &rec).unwrap();
    let p = Program::from_bincode(&bytes).unwrap();
    assert_eq!(p.continuity, Continuity::None);
    assert_eq!(
        p.segments[0].primitives[0],
        Primitive::Line {
            start: vec![1.0, 2.0],
            velocity: vec![0.5, -0.25]
        }
    );
}

/// Penn Action golf swings (the first 8 of the train split) with the
/// product's parameters: C0 programs are continuous, their executed poses
/// jump no more than the input's, and their KD stays close to the
/// independent fits'.
#[test]
fn penn_action_golf_swings_c0() {
    let Some(path) = mp_geom::test_support::data_file_or_skip(
        PennAction::TRAIN_FILE,
        &mp_geom::test_support::current_test_name(),
    ) else {
        return;
    };
    let pa = PennAction::open(&path).unwrap();
    let clips: Vec<usize> = pa
        .clips_of_action("golf_swing")
        .into_iter()
        .take(8)
        .collect();
    let base = SynthParams {
        lambda: Lambda::adaptive(),
        unobserved_joints: UnobservedJoints::Ignore,
        ..SynthParams::paper()
    };
    let (mut kd_free, mut kd_c0, mut jr, mut jf, mut jc) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut pf, mut pc, mut raw) = (0usize, 0usize, 0usize);
    for &i in &clips {
        let info = pa.clip_info(i).unwrap();
        let frame_px = info.height_px.max(info.width_px) as f64;
        let to512 = 512.0 / frame_px;
        let track = pa.clip(i).unwrap();
        let params = SynthParams {
            scale: Scale::FrameSize { frame_px },
            ..base.clone()
        };
        let free = Program::synthesize(&track, &with(Continuity::None, &params)).unwrap();
        let c0 = Program::synthesize(&track, &params).unwrap();
        assert_c0(&c0, frame_px);
        let (sf, sc) = (free.stats(&track).unwrap(), c0.stats(&track).unwrap());
        eprintln!(
            "clip {}: KD {:.2} → {:.2} px@512, jump raw {:.1} free {:.1} C0 {:.1}, params {} → {} / {}",
            info.clip_id,
            sf.kd * to512,
            sc.kd * to512,
            sf.max_jump_raw * to512,
            sf.max_jump_program * to512,
            sc.max_jump_program * to512,
            sf.params_program,
            sc.params_program,
            sf.params_raw
        );
        kd_free += sf.kd * to512;
        kd_c0 += sc.kd * to512;
        jr += sf.max_jump_raw * to512;
        jf += sf.max_jump_program * to512;
        jc += sc.max_jump_program * to512;
        pf += sf.params_program;
        pc += sc.params_program;
        raw += sf.params_raw;
    }
    let n = clips.len() as f64;
    eprintln!(
        "mean KD {:.2} → {:.2} px@512; max jump raw {:.1}, free {:.1}, C0 {:.1}; params {:.3} → {:.3}",
        kd_free / n,
        kd_c0 / n,
        jr / n,
        jf / n,
        jc / n,
        pf as f64 / raw as f64,
        pc as f64 / raw as f64
    );
    // Measured 1.97 → 3.81 px@512 (max jump raw 29.4, independent 111.9, C0
    // 16.3; parameter ratio 0.120 → 0.133). Bounds: the target for
    // golf swings (KD ≤ 6.25 px, ≤ 1/6 of the raw parameters) and the
    // measurement with ~20 % margin.
    assert!(kd_c0 / n < 4.5, "C0 KD {:.2}", kd_c0 / n);
    assert!((pc as f64) < raw as f64 / 6.0, "params {pc} / {raw}");
    assert!(jc <= jr, "C0 jump {jc:.1} vs raw {jr:.1}");
}

mod random_tracks {
    use super::*;
    use proptest::prelude::*;

    /// A random walk of velocity per joint (2D or 3D) with noise, some frames missing.
    fn walk(t: usize, j: usize, d: usize, seed: &[f64], missing_every: usize) -> Track {
        let mut pos = Array3::zeros((t, j, d));
        let mut conf = Array2::ones((t, j));
        for ji in 0..j {
            let mut p = vec![200.0 + 15.0 * ji as f64; d];
            let mut v = vec![0.0; d];
            for ti in 0..t {
                for k in 0..d {
                    let s = |o: usize| seed[(ti * 7 + ji * 5 + k * 3 + o) % seed.len()];
                    v[k] = 0.9 * v[k] + 3.0 * (s(0) - 0.5);
                    p[k] += v[k];
                    pos[[ti, ji, k]] = p[k] + 2.0 * (s(1) - 0.5);
                }
                if missing_every > 0 && (ti * 3 + ji) % missing_every == 0 {
                    conf[[ti, ji]] = 0.0;
                }
            }
        }
        Track::new(pos, Some(conf), 30.0, Units::Pixels, Skeleton::generic(j)).unwrap()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// Any track, any λ, both kind sets, both refit norms: the C0 program is
        /// valid, keeps the segmentation of the independent fits and shares every
        /// boundary within 1e-9.
        #[test]
        fn c0_shares_every_boundary(
            t in 12usize..150,
            j in 1usize..4,
            three_d in any::<bool>(),
            lambda in 20.0f64..1000.0,
            all_kinds in any::<bool>(),
            euclidean in any::<bool>(),
            missing_every in prop_oneof![Just(0usize), 4usize..13],
            seed in proptest::collection::vec(0.0f64..1.0, 16..64),
        ) {
            let track = walk(t, j, if three_d { 3 } else { 2 }, &seed, missing_every);
            let mut params = SynthParams {
                lambda: Lambda::fixed(lambda),
                scale: Scale::UnitScale { unit_scale: 1.0 },
                unobserved_joints: UnobservedJoints::Ignore,
                refit_norm: if euclidean { RefitNorm::Euclidean } else { RefitNorm::Squared },
                ..SynthParams::paper()
            };
            if all_kinds {
                params.fit.kinds = PrimitiveKind::ALL.to_vec();
            }
            let c0 = Program::synthesize(&track, &params).unwrap();
            let free = Program::synthesize(&track, &with(Continuity::None, &params)).unwrap();
            c0.validate().unwrap();
            prop_assert_eq!(c0.boundaries(), free.boundaries());
            let gap = c0.max_boundary_gap();
            prop_assert!(gap <= 1e-9, "boundary gap {}", gap);
        }
    }
}
