//! Latency of the learned refinement of one 60-frame sequence (target:
//! < 5 ms on 2 cores): the defaults (flaw detector and repair) on a clean
//! held-out MSR Action3D clip and on the clip with 4 jittered frames; with
//! the anchor and transition steps, the clean clip and the same clip
//! with an implausible (upside-down) anchor pose blended in, which is
//! rejected and repaired — by a bridge (default) or by the anchor refinement
//! network followed by transition refinement (every network runs).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // bench code: failing loudly is the point

use criterion::{criterion_group, criterion_main, Criterion};
use mp_geom::MsrAction3D;
use mp_geom::{Skeleton, Track, Units};
use mp_onnx::SessionParams;
use mp_refine::full_confidence;
use mp_refine::Concepts;
use mp_refine::RefineNets;
use mp_refine::{inject, AnchorSource, Flaw};
use mp_refine::{resample, NET_FRAMES};
use mp_refine::{AnchorRepair, NetRefineParams, NetRefiner, RefineMode};

fn bench(c: &mut Criterion) {
    let dir = match RefineNets::find_dir() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("skipping the refinement bench: {e}");
            return;
        }
    };
    let nets = match RefineNets::load(&dir, &SessionParams::default()) {
        Ok(n) => n,
        Err(e) => {
            eprintln!("skipping the refinement bench: {e}");
            return;
        }
    };
    let concepts = match std::fs::read_to_string(dir.join("concepts.json"))
        .map_err(|e| e.to_string())
        .and_then(|t| Concepts::from_json(&t).map_err(|e| e.to_string()))
    {
        Ok(c) => c,
        Err(e) => {
            eprintln!("skipping the refinement bench: concepts.json: {e}");
            return;
        }
    };
    let data = match MsrAction3D::open_default() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("skipping the refinement bench: {e}");
            return;
        }
    };
    let Some(info) = data
        .clips()
        .iter()
        .find(|c| c.subject == 9 && c.rows.len() >= 30)
        .cloned()
    else {
        eprintln!("skipping the refinement bench: no clip of subject 9");
        return;
    };
    let clip = full_confidence(&data.clip(info.index).unwrap()).unwrap();
    let pos = resample(clip.positions(), NET_FRAMES).unwrap();
    let clean = Track::new(pos, None, 15.0, Units::Metres, Skeleton::msr20()).unwrap();
    let mut flipped = clean.positions().to_owned();
    for mut frame in flipped.outer_iter_mut() {
        let hip = frame[[6, 1]];
        for mut j in frame.outer_iter_mut() {
            j[1] = 2.0 * hip - j[1];
        }
    }
    let flipped = Track::new(flipped, None, 15.0, Units::Metres, Skeleton::msr20()).unwrap();
    let flaw = Flaw::WrongAnchor {
        half_width_frames: 1,
        source: AnchorSource::OtherClip(flipped),
    };
    // The first seed whose implausible pose is recognised as an anchor and repaired.
    let steps = NetRefineParams {
        mode: RefineMode::AnchorsAndTransitions,
        ..NetRefineParams::default()
    };
    let probe_params = steps.clone();
    let probe = NetRefiner::new(&nets, &concepts, &probe_params).unwrap();
    let flawed = (0..50)
        .map(|seed| inject(&clean, &flaw, seed).unwrap().track)
        .find(|t| {
            probe
                .refine_track(t, Some(info.action))
                .is_ok_and(|r| r.report.anchors.iter().any(|a| a.repaired))
        })
        .unwrap_or_else(|| inject(&clean, &flaw, 1).unwrap().track);
    let refiner = NetRefiner::new(&nets, &concepts, &steps).unwrap();
    let net_params = NetRefineParams {
        anchor_repair: AnchorRepair::Network,
        ..steps.clone()
    };
    // Defaults: the flaw detector and its repair only.
    let default_params = NetRefineParams::default();
    let detector = NetRefiner::new(&nets, &concepts, &default_params).unwrap();
    let jittered = inject(
        &clean,
        &Flaw::Jitter {
            frames: 4,
            std_m: 0.05,
        },
        3,
    )
    .unwrap()
    .track;
    let net_refiner = NetRefiner::new(&nets, &concepts, &net_params).unwrap();
    let r = net_refiner
        .refine_track(&flawed, Some(info.action))
        .unwrap();
    eprintln!(
        "implausible anchor: {} anchors repaired, {} transitions regenerated",
        r.report.anchors.iter().filter(|a| a.repaired).count(),
        r.report.refined_transitions().count()
    );
    let mut g = c.benchmark_group("refine_60_frames");
    g.bench_function("default_detector_clean", |b| {
        b.iter(|| detector.refine_track(&clean, Some(info.action)).unwrap())
    });
    g.bench_function("default_detector_jitter", |b| {
        b.iter(|| detector.refine_track(&jittered, Some(info.action)).unwrap())
    });
    g.bench_function("clean_action_given", |b| {
        b.iter(|| refiner.refine_track(&clean, Some(info.action)).unwrap())
    });
    g.bench_function("implausible_anchor_bridge", |b| {
        b.iter(|| refiner.refine_track(&flawed, Some(info.action)).unwrap())
    });
    g.bench_function("implausible_anchor_bridge_action_predicted", |b| {
        b.iter(|| refiner.refine_track(&flawed, None).unwrap())
    });
    g.bench_function("implausible_anchor_network_repair", |b| {
        b.iter(|| {
            net_refiner
                .refine_track(&flawed, Some(info.action))
                .unwrap()
        })
    });
    // The generated-motion preset on a generator sample of the same action.
    let gen_params = NetRefineParams::for_generated();
    let gen_refiner = NetRefiner::new(&nets, &concepts, &gen_params).unwrap();
    let (gen, labels) = mp_refine::generate_clips(&nets, 1, 0).unwrap();
    let row = labels.iter().position(|&a| a == info.action).unwrap_or(0);
    let sample = Track::new(
        mp_refine::from_features(gen.outer_iter().nth(row).unwrap()).unwrap(),
        None,
        15.0,
        Units::Metres,
        Skeleton::msr20(),
    )
    .unwrap();
    g.bench_function("generated_preset_sample", |b| {
        b.iter(|| {
            gen_refiner
                .refine_track(&sample, Some(labels[row]))
                .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
