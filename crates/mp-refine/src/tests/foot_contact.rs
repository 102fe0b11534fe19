//! Foot contact in the refinement: slides of planted feet are held, refills
//! never add slide, and the learned refinement never increases the foot
//! slide of the evaluation's foot-slide cases.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::full_confidence;
use crate::learned::foot_contact::{guard_refills, hold_slides};
use crate::learned::{foot_legs, RepairedRun};
use crate::mpjpe_abs;
use crate::{foot_contacts, foot_slide, FootContactParams, NetRefineParams, NetRefiner};
use crate::{foot_joints, inject, Flaw, FootSlide};
use mp_geom::MsrAction3D;
use mp_geom::{Skeleton, Track, Units};
use ndarray::Array3;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// A person standing (1.6 m, MSR 20 joints, y up) for `t` frames at 15 fps,
/// swaying the arms, with 4 mm of seeded jitter on every coordinate.
fn standing(t: usize) -> Track {
    let base: [[f64; 3]; 20] = [
        [-0.18, 0.35, 0.0],  // right shoulder
        [0.18, 0.35, 0.0],   // left shoulder
        [0.0, 0.40, 0.0],    // neck
        [0.0, 0.15, 0.0],    // spine
        [-0.10, -0.10, 0.0], // right hip
        [0.10, -0.10, 0.0],  // left hip
        [0.0, -0.08, 0.0],   // hip centre
        [-0.25, 0.10, 0.0],  // right elbow
        [0.25, 0.10, 0.0],   // left elbow
        [-0.28, -0.12, 0.0], // right wrist
        [0.28, -0.12, 0.0],  // left wrist
        [-0.29, -0.18, 0.0], // right hand
        [0.29, -0.18, 0.0],  // left hand
        [-0.11, -0.50, 0.0], // right knee
        [0.11, -0.50, 0.0],  // left knee
        [-0.12, -0.92, 0.0], // right ankle
        [0.12, -0.92, 0.0],  // left ankle
        [-0.12, -0.98, 0.1], // right foot
        [0.12, -0.98, 0.1],  // left foot
        [0.0, 0.62, 0.0],    // head
    ];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let noise = Normal::new(0.0, 0.004).unwrap();
    let mut pos = Array3::<f64>::zeros((t, 20, 3));
    for f in 0..t {
        let sway = 0.15 * (f as f64 * 0.3).sin();
        for j in 0..20 {
            for k in 0..3 {
                let arm = if (7..=12).contains(&j) && k == 2 {
                    sway
                } else {
                    0.0
                };
                pos[[f, j, k]] = base[j][k] + arm + noise.sample(&mut rng);
            }
        }
    }
    Track::new(pos, None, 15.0, Units::Metres, Skeleton::msr20()).unwrap()
}

fn slide_of(track: &Track, clean: &Track) -> f64 {
    let feet = foot_joints(clean);
    let p = FootContactParams::default();
    let c = foot_contacts(clean.positions(), &feet, clean.fps(), &p).unwrap();
    foot_slide(track.positions(), &feet, &c, clean.fps(), 1).unwrap()
}

#[test]
fn a_planted_foot_that_slides_away_and_back_is_held() {
    let clean = standing(45);
    let legs = foot_legs(&clean.skeleton().joints);
    assert_eq!(legs, vec![vec![16, 18], vec![15, 17]]);
    let p = FootContactParams::default();
    // Every foot joint of the still person is in contact.
    let feet = foot_joints(&clean);
    let c = foot_contacts(clean.positions(), &feet, 15.0, &p).unwrap();
    assert!(c.iter().all(|&v| v));

    let flaw = Flaw::FootSlide(FootSlide {
        frames: 10,
        drift_m: 0.1,
        up_axis: 1,
    });
    let inj = inject(&clean, &flaw, 4).unwrap();
    let before_slide = slide_of(&inj.track, &clean);
    let clean_slide = slide_of(&clean, &clean);
    let before_err = mpjpe_abs(&inj.track, &clean).unwrap();
    let mut pos = inj.track.positions().to_owned();
    let held = hold_slides(&mut pos, &legs, 15.0, &p).unwrap();
    let mut out = inj.track.clone();
    out.positions_mut().assign(&pos);
    let after_slide = slide_of(&out, &clean);
    let after_err = mpjpe_abs(&out, &clean).unwrap();
    // Both legs slid (the flaw moves every foot joint): 4 runs, one per joint,
    // inside the flawed frames.
    assert_eq!(held.len(), 4, "{held:?}");
    let flawed: Vec<usize> = (0..45).filter(|&f| inj.mask[f]).collect();
    for r in &held {
        assert!(
            flawed.contains(&r.start) && flawed.contains(&r.end),
            "{r:?} vs {flawed:?}"
        );
    }
    // 10 cm out and back (0.2 m) over the 44 / 15 s of the clip: 0.068 m/s
    // on top of the jitter, partly overlapping it. Measured 0.139 m/s
    // before, clean 0.095.
    assert!(
        before_slide - clean_slide > 0.03 && before_slide < 0.2,
        "slide before {before_slide}, clean {clean_slide}"
    );
    assert!(clean_slide < 0.12, "clean slide {clean_slide}");
    assert!(
        after_slide < clean_slide + 0.02,
        "slide {before_slide} → {after_slide} (clean {clean_slide})"
    );
    // Measured 2.42 → 1.16 mm.
    assert!(
        after_err < 0.55 * before_err,
        "MPJPE {before_err} → {after_err}"
    );
    // Vertical coordinates and the other joints are untouched.
    for f in 0..45 {
        for j in 0..20 {
            assert_eq!(pos[[f, j, 1]], inj.track.positions()[[f, j, 1]]);
            if !feet.contains(&j) {
                assert_eq!(pos[[f, j, 0]], inj.track.positions()[[f, j, 0]]);
            }
        }
    }
    // The clean clip's jitter (4 mm) is no slide: nothing is held.
    let mut still = clean.positions().to_owned();
    assert!(hold_slides(&mut still, &legs, 15.0, &p).unwrap().is_empty());
    assert_eq!(&still, clean.positions());
    // A foot that moves to a new place and stays there is no slide.
    let mut step = clean.positions().to_owned();
    for f in 20..45 {
        for j in [16, 18] {
            step[[f, j, 0]] += 0.25 * ((f - 20) as f64 / 4.0).min(1.0);
        }
    }
    let stepped = step.clone();
    assert!(hold_slides(&mut step, &legs, 15.0, &p).unwrap().is_empty());
    assert_eq!(step, stepped);
    // Bad parameters are refused.
    let bad = FootContactParams {
        slide_tolerance: -1.0,
        ..FootContactParams::default()
    };
    assert!(hold_slides(&mut step, &legs, 15.0, &bad).is_err());
    assert!(foot_contacts(clean.positions(), &[25], 15.0, &p).is_err());
    assert!(foot_contacts(clean.positions(), &feet, 0.0, &p).is_err());
}

#[test]
fn a_refill_never_adds_horizontal_travel_to_a_planted_foot() {
    let clean = standing(30);
    let feet = foot_joints(&clean);
    let p = FootContactParams::default();
    let input = clean.positions().to_owned();
    assert!(foot_contacts(input.view(), &feet, 15.0, &p)
        .unwrap()
        .iter()
        .all(|&v| v));
    // A refill that swings the left foot 6 cm sideways over frames 10–13,
    // and one that moves the left hand (not a foot).
    let mut pos = input.clone();
    for f in 10..=13 {
        pos[[f, 18, 0]] += 0.06;
        pos[[f, 18, 1]] += 0.01;
        pos[[f, 12, 0]] += 0.06;
    }
    let runs = [
        RepairedRun {
            joint: 18,
            start: 10,
            end: 13,
        },
        RepairedRun {
            joint: 12,
            start: 10,
            end: 13,
        },
    ];
    assert_eq!(guard_refills(input.view(), &mut pos, &runs, &feet, 1), 1);
    for f in 10..=13 {
        assert_eq!(pos[[f, 18, 0]], input[[f, 18, 0]]);
        assert_eq!(pos[[f, 18, 2]], input[[f, 18, 2]]);
        // The vertical refill stays; the hand is no foot.
        assert!((pos[[f, 18, 1]] - input[[f, 18, 1]] - 0.01).abs() < 1e-12);
        assert!((pos[[f, 12, 0]] - input[[f, 12, 0]] - 0.06).abs() < 1e-12);
    }
    // A refill that removes travel (a straight line through the jitter) stays.
    let mut smooth = input.clone();
    for f in 10..=13 {
        let u = (f - 9) as f64 / 5.0;
        for k in [0, 2] {
            smooth[[f, 18, k]] = (1.0 - u) * input[[9, 18, k]] + u * input[[14, 18, k]];
        }
    }
    let want = smooth.clone();
    assert_eq!(
        guard_refills(input.view(), &mut smooth, &runs[..1], &feet, 1),
        0
    );
    assert_eq!(smooth, want);
}

#[test]
fn refinement_never_increases_the_foot_slide_of_the_evaluation_cases() {
    let path = mp_geom::data_or_return!(MsrAction3D::FILE);
    let data = MsrAction3D::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (nets, concepts) = super::shipped();
    let params = NetRefineParams::default();
    let off = NetRefineParams {
        foot_contact: None,
        ..NetRefineParams::default()
    };
    let refiner = NetRefiner::new(&nets, &concepts, &params).unwrap();
    let without = NetRefiner::new(&nets, &concepts, &off).unwrap();
    // The evaluation's foot slide (10 frames, 10 cm), seed = clip index, on
    // 24 clips of subjects 9 and 1.
    let flaw = Flaw::FootSlide(FootSlide {
        frames: 10,
        drift_m: 0.1,
        up_axis: 1,
    });
    let idx = data.clips_of_subjects(&[9, 1], 8, 180);
    let pick: Vec<usize> = (0..24).map(|i| idx[i * idx.len() / 24]).collect();
    let (mut b, mut a, mut a_off, mut e_b, mut e_a) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &i in &pick {
        let clean = full_confidence(&data.clip(i).unwrap()).unwrap();
        let action = data.clip_info(i).unwrap().action;
        let inj = inject(&clean, &flaw, i as u64).unwrap();
        let r = refiner.refine_track(&inj.track, Some(action)).unwrap();
        let r_off = without.refine_track(&inj.track, Some(action)).unwrap();
        let (sb, sa) = (slide_of(&inj.track, &clean), slide_of(&r.track, &clean));
        assert!(sa <= sb + 1e-9, "clip {i}: foot slide {sb} → {sa}");
        b += sb;
        a += sa;
        a_off += slide_of(&r_off.track, &clean);
        e_b += mpjpe_abs(&inj.track, &clean).unwrap();
        e_a += mpjpe_abs(&r.track, &clean).unwrap();
    }
    let n = pick.len() as f64;
    eprintln!(
        "foot slide {:.4} → {:.4} m/s (without contact handling {:.4}); MPJPE {:.2} → {:.2} mm",
        b / n,
        a / n,
        a_off / n,
        e_b / n * 1e3,
        e_a / n * 1e3
    );
    // Measured: foot slide 0.148 → 0.120 m/s (0.148 without the contact
    // handling), MPJPE 2.97 → 2.44 mm.
    assert!(a < 0.85 * b, "foot slide {b} → {a}");
    assert!(a < a_off, "with contact handling {a}, without {a_off}");
    assert!(e_a < e_b, "MPJPE {e_b} → {e_a}");
}
