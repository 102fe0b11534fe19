//! [`refine_default`] on a real MSR Action3D clip with an injected jump: the
//! same result as the refiner built by hand with the same defaults, and
//! closer to the clean clip than the flawed input. Skipped, with a message,
//! where the shared data are absent.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_geom::MsrAction3D;
use mp_refine::full_confidence;
use mp_refine::RefineNets;
use mp_refine::{inject, Flaw};
use mp_refine::{mpjpe_abs, refine_default, Concepts, RefineError, RefineOptions};
use mp_refine::{NetRefineParams, NetRefiner, RefineMode};

#[test]
fn refine_default_repairs_an_injected_jump_as_the_hand_built_refiner_does() {
    let path = mp_geom::data_or_return!(MsrAction3D::FILE);
    let data = MsrAction3D::open(&path).unwrap();
    let i = (0..data.len())
        .find(|&i| {
            let c = data.clip_info(i).unwrap();
            c.subject == 9 && (30..=120).contains(&c.rows.len())
        })
        .expect("a subject-9 clip of 30–120 frames");
    let clean = full_confidence(&data.clip(i).unwrap()).unwrap();
    let flawed = inject(
        &clean,
        &Flaw::Jump {
            frames: 4,
            skip_frames: 8,
        },
        i as u64,
    )
    .unwrap()
    .track;

    let r = refine_default(&flawed, &RefineOptions::default()).unwrap();
    assert!(r.map.is_none());
    assert_eq!(r.track.n_frames(), clean.n_frames());
    assert!(!r.msr.report.repaired_runs.is_empty());
    let before = mpjpe_abs(&flawed, &clean).unwrap();
    let after = mpjpe_abs(&r.track, &clean).unwrap();
    println!(
        "injected jump: {:.1} mm before, {:.1} mm after refinement",
        before * 1e3,
        after * 1e3
    );
    assert!(after < 0.8 * before);

    // the same networks, concepts and parameters assembled by hand
    let dir = RefineNets::find_dir().unwrap();
    let nets = RefineNets::load(&dir, &Default::default()).unwrap();
    let concepts =
        Concepts::from_json(&std::fs::read_to_string(dir.join("concepts.json")).unwrap()).unwrap();
    let params = NetRefineParams::default();
    let by_hand = NetRefiner::new(&nets, &concepts, &params)
        .unwrap()
        .refine_track(&flawed, None)
        .unwrap();
    assert_eq!(r.track, by_hand.track);

    // the anchor step with a given action
    let mut opts = RefineOptions {
        action: Some(data.clip_info(i).unwrap().action),
        ..RefineOptions::default()
    };
    opts.params.mode = RefineMode::AnchorsOnly;
    let r = refine_default(&flawed, &opts).unwrap();
    assert!(!r.msr.report.action_predicted);
    assert!(!r.msr.report.anchors.is_empty());

    // a model folder that does not exist is named
    let opts = RefineOptions {
        models: Some("/nonexistent/refine".into()),
        ..RefineOptions::default()
    };
    let e = refine_default(&flawed, &opts).unwrap_err();
    assert!(matches!(e, RefineError::ModelMissing { .. }), "{e}");
    assert!(e.to_string().contains("/nonexistent/refine"), "{e}");
}
