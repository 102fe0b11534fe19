//! Metric test vectors pushed end-to-end through the forecasting evaluation
//! protocol, and the learned models against Constant on real clips.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

// The synthetic tracks of mp-forecast's own tests.
#[path = "../../mp-forecast/tests/common/mod.rs"]
mod common;

use common::*;
use std::sync::Arc;

use mp_eval::forecast::protocol::{evaluate, evaluate_clip, EvalParams, MethodReport};
use mp_forecast::Clip;
use mp_forecast::{ArForecaster, ArParams, Constant};
use mp_forecast::{ArSpace, ForecastModels};
use mp_geom::{Skeleton, Track, Units};
use mp_onnx::SessionParams;
use ndarray::Array3;

fn one_clip(track: Track) -> Vec<Clip> {
    vec![Clip {
        name: "synthetic".into(),
        action: "wave".into(),
        track,
        box_sizes: None,
    }]
}

fn overall(r: &MethodReport, metric: &str, h: usize) -> f64 {
    r.metrics[metric].overall[&format!("h{h}")]
}

#[test]
fn scaled_and_shifted_copy_scores_pck_100_with_and_without_dtw() {
    let clip = periodic(80, 17.0);
    let oracle = Oracle {
        clip: clip.clone(),
        map: |t: &Track| map_positions(t, |_, p| vec![1.7 * p[0] + 30.0, 1.7 * p[1] - 12.0]),
    };
    let params = EvalParams::default();
    let r = evaluate(&oracle, &one_clip(clip), &params, |_, _| {}).unwrap();
    for h in [1, 5, 10, 20, 30] {
        assert!((overall(&r, "pck", h) - 100.0).abs() < 1e-9, "pck h{h}");
        assert!(
            (overall(&r, "pck_dtw", h) - 100.0).abs() < 1e-9,
            "pck_dtw h{h}"
        );
    }
    // every start frame with at least one future frame was predicted
    assert_eq!(r.predictions, 80 - 15);
    assert_eq!(
        r.metrics["pck"].per_action["wave"],
        r.metrics["pck"].overall
    );
}

#[test]
fn a_wrong_prediction_scores_below_100() {
    let clip = periodic(60, 17.0);
    // a prediction of a different motion phase (shifted by half a period)
    let other = periodic(60 + 9, 17.0).slice_frames(9, 60 + 9).unwrap();
    let oracle = Oracle {
        clip: other,
        map: |t: &Track| t.clone(),
    };
    let r = evaluate(&oracle, &one_clip(clip), &EvalParams::default(), |_, _| {}).unwrap();
    assert!(overall(&r, "pck", 5) < 80.0, "{}", overall(&r, "pck", 5));
}

#[test]
fn time_stretched_copy_aligns_perfectly_with_dtw() {
    // The truth holds every distinct pose for 2 frames; the prediction shows the same
    // poses in the same order with other hold times (1 or 3 frames) and the same length.
    let distinct = periodic(40, 11.0);
    let truth_idx: Vec<usize> = (0..80).map(|i| i / 2).collect();
    let truth = pick_frames(&distinct, &truth_idx);
    // future of the (single) start: frames 15..45 of the truth = distinct poses 7 (second copy) .. 22
    let params = EvalParams {
        start_stride_frames: 1000,
        ..EvalParams::default()
    };
    let fut_idx: Vec<usize> = truth_idx[15..45].to_vec();
    // re-time: same first and last pose, same set of poses, different holds
    let mut distinct_fut: Vec<usize> = fut_idx.clone();
    distinct_fut.dedup();
    let mut warped: Vec<usize> = Vec::new();
    for (i, &p) in distinct_fut.iter().enumerate() {
        let hold = if i % 2 == 0 { 1 } else { 3 };
        for _ in 0..hold {
            warped.push(p);
        }
    }
    warped.truncate(30);
    while warped.len() < 30 {
        warped.push(*distinct_fut.last().unwrap());
    }
    assert_eq!(warped.first(), fut_idx.first());
    assert!(
        distinct_fut.iter().all(|p| warped.contains(p)),
        "warp must keep every pose"
    );
    let pred = pick_frames(&distinct, &warped);
    struct Fixed(Track);
    impl mp_forecast::Forecaster for Fixed {
        fn name(&self) -> &str {
            "fixed"
        }
        fn context_frames(&self) -> Option<usize> {
            None
        }
        fn predict(
            &self,
            _: &Track,
            h: usize,
        ) -> std::result::Result<Track, mp_forecast::ForecastError> {
            Ok(self.0.slice_frames(0, h)?)
        }
    }
    let (scores, n) = evaluate_clip(&Fixed(pred), &truth, &params).unwrap();
    assert_eq!(n, 1);
    for (hi, h) in params.horizons.iter().enumerate() {
        assert!(
            (scores["pck_dtw"][hi] - 100.0).abs() < 1e-9,
            "pck_dtw at h{h}: {}",
            scores["pck_dtw"][hi]
        );
    }
    // without DTW the re-timed prediction is wrong somewhere
    assert!(
        scores["pck"].iter().any(|&v| v < 100.0),
        "{:?}",
        scores["pck"]
    );
}

fn msr_like_clip(n: usize) -> Track {
    // 20 joints in 3D (metres) moving on circles
    let mut pos = Array3::zeros((n, 20, 3));
    for t in 0..n {
        for j in 0..20 {
            let a = 0.2 * t as f64 + j as f64;
            pos[[t, j, 0]] = (j as f64 * 0.37).sin() + 0.1 * a.cos();
            pos[[t, j, 1]] = (j as f64 * 0.71).cos() + 0.1 * a.sin();
            pos[[t, j, 2]] = 2.0 + 0.05 * (j as f64) + 0.02 * a.sin();
        }
    }
    Track::new(pos, None, 15.0, Units::Metres, Skeleton::msr20()).unwrap()
}

#[test]
fn pa_mpjpe_undoes_a_similarity_transform_in_3d() {
    let clip = msr_like_clip(70);
    let (c, s) = (0.6f64.cos(), 0.6f64.sin());
    let oracle = Oracle {
        clip: clip.clone(),
        // rotation about y, scale 1.3, translation
        map: move |t: &Track| {
            map_positions(t, |_, p| {
                vec![
                    1.3 * (c * p[0] + s * p[2]) + 0.5,
                    1.3 * p[1] - 0.2,
                    1.3 * (-s * p[0] + c * p[2]) + 1.0,
                ]
            })
        },
    };
    let params = EvalParams::for_track(&clip);
    assert_eq!(params.start_stride_frames, 25);
    assert_eq!(params.root_joint, Some(6));
    let r = evaluate(&oracle, &one_clip(clip), &params, |_, _| {}).unwrap();
    for h in [1, 5, 10, 20, 30] {
        assert!(overall(&r, "pa_mpjpe", h) < 1e-6, "pa_mpjpe h{h}");
        assert!(overall(&r, "pa_mpjpe_dtw", h) < 1e-6, "pa_mpjpe_dtw h{h}");
        assert!(
            overall(&r, "mpjpe", h) > 10.0,
            "mpjpe (mm) must see the transform"
        );
    }
    // 70 frames, starts every 25 frames with a future frame: 0, 25 and 50
    assert_eq!(r.predictions, 3);
}

#[test]
fn mpjpe_is_reported_in_millimetres_after_root_alignment() {
    let clip = msr_like_clip(40);
    // prediction = truth + 1 cm on joint 3 only, plus a global shift (removed by root alignment)
    let oracle = Oracle {
        clip: clip.clone(),
        map: |t: &Track| {
            let mut p = map_positions(t, |_, p| vec![p[0] + 0.3, p[1], p[2]]);
            let mut pos = p.positions().to_owned();
            for f in 0..pos.dim().0 {
                pos[[f, 3, 0]] += 0.01;
            }
            p = Track::new(pos, None, p.fps(), p.units(), p.skeleton().clone()).unwrap();
            p
        },
    };
    let r = evaluate(
        &oracle,
        &one_clip(clip),
        &EvalParams::for_track(&msr_like_clip(2)),
        |_, _| {},
    )
    .unwrap();
    // 10 mm on one of 20 joints = 0.5 mm mean
    assert!(
        (overall(&r, "mpjpe", 1) - 0.5).abs() < 1e-9,
        "{}",
        overall(&r, "mpjpe", 1)
    );
}

#[test]
fn frames_with_too_few_visible_joints_are_skipped() {
    let clip = periodic(40, 9.0);
    let mut conf = clip.confidence().to_owned();
    // the first future frame of start 0 (frame 15) has only 5 visible joints
    for j in 5..13 {
        conf[[15, j]] = 0.0;
    }
    let (p, _, fps, u, sk) = clip.clone().into_parts();
    let clip = Track::new(p, Some(conf), fps, u, sk).unwrap();
    let oracle = Oracle {
        clip: clip.clone(),
        map: |t: &Track| t.clone(),
    };
    let params = EvalParams {
        start_stride_frames: 1000,
        ..EvalParams::default()
    };
    let (scores, _) = evaluate_clip(&oracle, &clip, &params).unwrap();
    assert!(
        scores["pck"][0].is_nan(),
        "h1 must be skipped: {:?}",
        scores["pck"]
    );
    assert!((scores["pck"][1] - 100.0).abs() < 1e-9);
}

#[test]
fn bad_params_are_typed_errors() {
    let clip = periodic(40, 9.0);
    let p = EvalParams {
        horizons: vec![0],
        ..EvalParams::default()
    };
    let r = evaluate_clip(&mp_forecast::Constant, &clip, &p);
    assert!(matches!(
        r,
        Err(mp_forecast::ForecastError::InvalidParam { .. })
    ));
    let p = EvalParams {
        start_stride_frames: 0,
        ..EvalParams::default()
    };
    assert!(matches!(
        evaluate_clip(&mp_forecast::Constant, &clip, &p),
        Err(mp_forecast::ForecastError::InvalidParam { .. })
    ));
}

#[test]
fn action_groups_average_the_clips_of_their_classes() {
    // three clips of two classes, on which Constant scores differently
    let clip = |name: &str, action: &str, period: f64| Clip {
        name: name.into(),
        action: action.into(),
        track: periodic(60, period),
        box_sizes: None,
    };
    let clips = vec![
        clip("a1", "fast", 6.0),
        clip("a2", "fast", 9.0),
        clip("b1", "slow", 40.0),
    ];
    let mut params = EvalParams::default();
    params
        .action_groups
        .insert("fast_only".into(), vec!["fast".into()]);
    params
        .action_groups
        .insert("both".into(), vec!["fast".into(), "slow".into()]);
    params
        .action_groups
        .insert("none".into(), vec!["absent".into()]);
    let r = evaluate(&mp_forecast::Constant, &clips, &params, |_, _| {}).unwrap();
    let t = &r.metrics["pck"];
    for h in ["h5", "h10", "h30"] {
        assert_eq!(t.per_group["fast_only"][h], t.per_action["fast"][h]);
        assert_eq!(t.per_group["both"][h], t.overall[h]);
    }
    // the groups differ, so the checks above tell them apart
    assert!((t.per_group["both"]["h10"] - t.per_group["fast_only"]["h10"]).abs() > 1.0);
    assert!(!t.per_group.contains_key("none"));
}

/// `metric` averaged over the horizons 5, 10, 20 and 30 frames.
fn later_horizons(r: &MethodReport, metric: &str) -> f64 {
    ["h5", "h10", "h20", "h30"]
        .iter()
        .map(|h| r.metrics[metric].overall[*h])
        .sum::<f64>()
        / 4.0
}

/// The committed models of `dataset` (models/forecast/DATASET).
fn models_of(dataset: &str) -> Arc<ForecastModels> {
    let dir = ForecastModels::find_dir(dataset)
        .unwrap_or_else(|e| panic!("models/forecast/{dataset} is part of the repository: {e}"));
    Arc::new(
        ForecastModels::load(dir, &SessionParams::default())
            .expect("ONNX Runtime: run `cargo xtask setup`"),
    )
}

#[test]
fn learned_model_beats_constant_on_real_penn_action_clips() {
    // every 6th validation clip (21 clips, all 15 actions): AR on Φ vs Constant, PCK with
    // DTW averaged over the horizons 5–30
    let ds = mp_forecast::ForecastDataset::open(mp_geom::data_or_return!(
        "penn_action/penn_action_train.npz"
    ))
    .unwrap();
    let (_, val) = ds.split();
    let clips: Vec<Clip> = val.iter().step_by(6).map(|c| (*c).clone()).collect();
    let params = EvalParams {
        start_stride_frames: 5,
        ..EvalParams::default()
    };
    let ar = ArForecaster::new(
        models_of("penn_action"),
        ArSpace::Latent,
        ArParams::default(),
    )
    .unwrap();
    let a = evaluate(&ar, &clips, &params, |_, _| {}).unwrap();
    let c = evaluate(&Constant, &clips, &params, |_, _| {}).unwrap();
    let later = |r: &MethodReport| later_horizons(r, "pck_dtw");
    assert!(
        later(&a) > later(&c),
        "AR {:.1} vs constant {:.1}",
        later(&a),
        later(&c)
    );
}

#[test]
fn learned_3d_model_beats_constant_on_real_msr_action3d_clips() {
    // the 30 validation clips, a start every 25th frame (the 3D protocol of paper 002): PA-MPJPE with
    // DTW averaged over the horizons 5–30 (mm, lower is better)
    let ds = mp_forecast::ForecastDataset::open(mp_geom::data_or_return!(
        "msr_action3d/msr_action3d_odd_subjects.npz"
    ))
    .unwrap();
    let (_, val) = ds.split();
    let clips: Vec<Clip> = val.iter().map(|c| (*c).clone()).collect();
    let params = EvalParams::for_track(&clips[0].track);
    let ar = ArForecaster::new(
        models_of("msr_action3d"),
        ArSpace::Latent,
        ArParams::default(),
    )
    .unwrap();
    let a = evaluate(&ar, &clips, &params, |_, _| {}).unwrap();
    let c = evaluate(&Constant, &clips, &params, |_, _| {}).unwrap();
    let later = |r: &MethodReport| later_horizons(r, "pa_mpjpe_dtw");
    assert!(
        later(&a) < 0.9 * later(&c),
        "AR {:.1} mm vs constant {:.1} mm",
        later(&a),
        later(&c)
    );
}
