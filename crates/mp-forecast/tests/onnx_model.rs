//! The learned forecaster through ONNX Runtime (needs `cargo xtask setup` for the
//! library and the committed models in models/forecast/penn_action).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use std::path::PathBuf;
use std::sync::Arc;

use common::*;
use mp_forecast::{
    find_statue, ArForecaster, ArParams, Constant, ForecastError, Forecaster, StatueParams,
};
use mp_forecast::{ArSpace, ForecastModels};
use mp_geom::{Skeleton, Track, Units};
use mp_onnx::SessionParams;
use ndarray::{Array2, Array3};
use serde_json::Value;

fn models_of(dataset: &str) -> Arc<ForecastModels> {
    let dir = ForecastModels::find_dir(dataset)
        .unwrap_or_else(|e| panic!("models/forecast/{dataset} is part of the repository: {e}"));
    Arc::new(
        ForecastModels::load(dir, &SessionParams::default())
            .expect("ONNX Runtime: run `cargo xtask setup`"),
    )
}

fn models() -> Arc<ForecastModels> {
    models_of("penn_action")
}

fn fixture(dataset: &str) -> Value {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join(format!("../../testdata/forecast/{dataset}_parity.json"));
    serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap()
}

fn flat(v: &Value) -> Vec<f32> {
    v.as_array()
        .unwrap()
        .iter()
        .flat_map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap() as f32)
        })
        .collect()
}

fn max_diff(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

#[test]
fn onnx_matches_the_pytorch_export_within_1e4() {
    for dataset in ["penn_action", "msr_action3d"] {
        parity(dataset);
    }
}

fn parity(dataset: &str) {
    let m = models_of(dataset);
    let fx = fixture(dataset);
    let input = flat(&fx["input"]);
    let frames = fx["context_frames"].as_u64().unwrap() as usize;
    let horizon = fx["horizon"].as_u64().unwrap() as usize;
    let (_, pose) = m.encode(1, frames, &input).unwrap();
    let d = max_diff(&pose, &flat(&fx["encoder_pose"]));
    assert!(d < 1e-4, "{dataset}: encoder pose differs by {d}");
    let roll = m
        .rollout_normalised(ArSpace::Latent, 1, frames, &input, horizon)
        .unwrap();
    let d = max_diff(&roll, &flat(&fx["latent_rollout"]));
    assert!(d < 1e-4, "{dataset}: latent rollout differs by {d}");
    let roll = m
        .rollout_normalised(ArSpace::Pose, 1, frames, &input, horizon)
        .unwrap();
    let d = max_diff(&roll, &flat(&fx["pose_rollout"]));
    assert!(d < 1e-4, "{dataset}: pose rollout differs by {d}");
}

#[test]
fn batched_and_single_predictions_agree() {
    let f = ArForecaster::new(models(), ArSpace::Latent, ArParams::default()).unwrap();
    let pasts: Vec<Track> = (0..5).map(|i| periodic(15 + i, 12.0)).collect();
    let batch = f.predict_batch(&pasts, 12).unwrap();
    for (p, b) in pasts.iter().zip(&batch) {
        let s = f.predict(p, 12).unwrap();
        let d = s
            .positions()
            .iter()
            .zip(b.positions().iter())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(d < 1e-3, "batch vs single: {d} px");
        assert_eq!(s.n_frames(), 12);
    }
}

#[test]
fn predictions_follow_the_track_position_and_scale() {
    // normalisation: predicting a shifted, scaled copy gives the shifted, scaled prediction
    let f = ArForecaster::new(models(), ArSpace::Pose, ArParams::default()).unwrap();
    let past = periodic(15, 12.0);
    let moved = map_positions(&past, |_, p| vec![2.0 * p[0] + 300.0, 2.0 * p[1] + 50.0]);
    let a = f.predict(&past, 10).unwrap();
    let b = f.predict(&moved, 10).unwrap();
    let a2 = map_positions(&a, |_, p| vec![2.0 * p[0] + 300.0, 2.0 * p[1] + 50.0]);
    let d = mp_geom::kd(&a2, &b).unwrap();
    assert!(d < 1e-2, "{d} px");
}

#[test]
fn bad_input_to_the_model_gives_typed_errors() {
    let f = ArForecaster::new(models(), ArSpace::Latent, ArParams::default()).unwrap();
    // fewer frames than the receptive field (13)
    assert!(matches!(
        f.predict(&periodic(12, 9.0), 5),
        Err(ForecastError::TooShort {
            needed: 13,
            got: 12,
            ..
        })
    ));
    // wrong joint count for the model
    let coco = Track::new(
        Array3::zeros((20, 17, 2)),
        None,
        30.0,
        Units::Pixels,
        Skeleton::coco17(),
    )
    .unwrap();
    assert!(matches!(
        f.predict(&coco, 5),
        Err(ForecastError::Mismatch { .. })
    ));
    // 3D track for a 2D model
    let msr = Track::new(
        Array3::zeros((20, 20, 3)),
        None,
        15.0,
        Units::Metres,
        Skeleton::msr20(),
    )
    .unwrap();
    assert!(matches!(
        f.predict(&msr, 5),
        Err(ForecastError::Mismatch { .. })
    ));
    // every joint missing
    let (p, _, fps, u, sk) = periodic(15, 9.0).into_parts();
    let empty = Track::new(p, Some(Array2::zeros((15, 13))), fps, u, sk).unwrap();
    assert!(matches!(
        f.predict(&empty, 5),
        Err(ForecastError::NoValidJoints(_))
    ));
    // context shorter than the receptive field
    assert!(matches!(
        ArForecaster::new(
            models(),
            ArSpace::Latent,
            ArParams {
                context_frames: 10,
                ..ArParams::default()
            }
        ),
        Err(ForecastError::InvalidParam { .. })
    ));
}

#[test]
fn mirror_average_is_the_mean_of_a_prediction_and_its_mirrored_twin() {
    let single = ArForecaster::new(
        models(),
        ArSpace::Latent,
        ArParams {
            mirror_average: false,
            ..ArParams::default()
        },
    )
    .unwrap();
    let averaged = ArForecaster::new(models(), ArSpace::Latent, ArParams::default()).unwrap();
    let t = periodic(20, 9.0);
    // the mirror image of the context: x negated, left and right joints swapped
    let swap = [0usize, 2, 1, 4, 3, 6, 5, 8, 7, 10, 9, 12, 11];
    let (p, c, fps, u, sk) = t.clone().into_parts();
    let mut mp = p.clone();
    for f in 0..20 {
        for j in 0..13 {
            mp[[f, j, 0]] = -p[[f, swap[j], 0]];
            mp[[f, j, 1]] = p[[f, swap[j], 1]];
        }
    }
    let mirrored = Track::new(mp, Some(c), fps, u, sk).unwrap();
    let a = single.predict(&t, 10).unwrap();
    let b = single.predict(&mirrored, 10).unwrap();
    let m = averaged.predict(&t, 10).unwrap();
    let mut max_err = 0.0f64;
    let mut max_gap = 0.0f64;
    for f in 0..10 {
        for (j, &sj) in swap.iter().enumerate().take(13) {
            let bx = -b.positions()[[f, sj, 0]];
            let by = b.positions()[[f, sj, 1]];
            let ex = 0.5 * (a.positions()[[f, j, 0]] + bx);
            let ey = 0.5 * (a.positions()[[f, j, 1]] + by);
            max_err = max_err
                .max((m.positions()[[f, j, 0]] - ex).abs())
                .max((m.positions()[[f, j, 1]] - ey).abs());
            max_gap = max_gap.max((a.positions()[[f, j, 0]] - bx).abs());
        }
    }
    assert!(max_err < 1e-3, "mirror average differs by {max_err} px");
    // the two passes are not identical, so the average is not a no-op
    assert!(
        max_gap > 1e-3,
        "mirrored pass equals the direct one ({max_gap})"
    );
}

#[test]
fn missing_joints_are_masked_not_fatal() {
    let f = ArForecaster::new(models(), ArSpace::Latent, ArParams::default()).unwrap();
    let t = periodic(15, 9.0);
    let mut conf = t.confidence().to_owned();
    for fr in 0..15 {
        conf[[fr, 11]] = 0.0;
        conf[[fr, 3]] = 0.0;
    }
    let (p, _, fps, u, sk) = t.into_parts();
    let t = Track::new(p, Some(conf), fps, u, sk).unwrap();
    let pred = f.predict(&t, 20).unwrap();
    assert!(pred.positions().iter().all(|v| v.is_finite()));
    assert_eq!(pred.n_frames(), 20);
}

#[test]
fn statue_frame_is_where_the_error_drops_most() {
    // a forecaster that is right only once frame 25 has been observed
    struct Late(Track);
    impl Forecaster for Late {
        fn name(&self) -> &str {
            "late"
        }
        fn context_frames(&self) -> Option<usize> {
            None
        }
        fn predict(
            &self,
            past: &Track,
            h: usize,
        ) -> std::result::Result<Track, mp_forecast::ForecastError> {
            // past = 15 frames ending at frame e; find e by matching the last frame
            let last = past.n_frames() - 1;
            let e = (0..self.0.n_frames())
                .find(|&f| {
                    self.0.point(f, 0) == past.point(last, 0)
                        && self.0.point(f, 5) == past.point(last, 5)
                })
                .unwrap();
            if e >= 25 {
                Ok(self.0.slice_frames(e + 1, e + 1 + h)?)
            } else {
                Constant.predict(past, h)
            }
        }
    }
    let t = penn_track(60, |f| 0.05 * f as f64 + 0.002 * (f * f) as f64, 0.5);
    let params = StatueParams {
        filter_frames: 1,
        ..StatueParams::default()
    };
    let s = find_statue(&Late(t.clone()), &t, &params).unwrap();
    assert_eq!(s.frame, 25);
    assert!(s.improvement > 0.0);
    assert_eq!(s.window_end_frames.len(), 60 - 15 - 15 + 1);
    // too short
    assert!(matches!(
        find_statue(
            &Constant,
            &t.slice_frames(0, 30).unwrap(),
            &StatueParams::default()
        ),
        Err(ForecastError::TooShort { .. })
    ));
    // and the learned model runs on a real-sized track
    let f = ArForecaster::new(models(), ArSpace::Latent, ArParams::default()).unwrap();
    let s = find_statue(&f, &t, &StatueParams::default()).unwrap();
    assert!(s.frame >= 15 && s.frame < 45);
}
