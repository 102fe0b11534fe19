//! Tensor contracts of the ONNX models: names, shapes, element types, value
//! ranges, and the outputs for a fixed input against values computed once
//! with Python onnxruntime (`tools/make_pose_fixtures.py`).
//!
//! Needs ONNX Runtime (`cargo xtask setup`) and the models (`cargo xtask models`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::blazepose::detector::{self, PoseDetector};
use crate::blazepose::landmarks::{LandmarkModel, LandmarkModelKind, RefineParams};
use crate::blazepose::DetectorParams;
use crate::imageops::{RgbView, Roi};
use crate::movenet::{MoveNet, MoveNetParams};
use crate::runtime::{self, ModelFile, SessionParams};
use mp_onnx::TensorInfo;
use serde_json::Value;

fn fixtures() -> Value {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/model_fixtures.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// value(y, x, c) = (3x + 5y + 50c) mod 256, as in the fixture script.
fn pattern(n: usize) -> Vec<u8> {
    let mut v = Vec::with_capacity(n * n * 3);
    for y in 0..n {
        for x in 0..n {
            for c in 0..3 {
                v.push(((3 * x + 5 * y + 50 * c) % 256) as u8);
            }
        }
    }
    v
}

fn assert_close(what: &str, got: &[f64], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len(), "{what}: length");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        let lim = tol * w.abs().max(1.0);
        assert!(
            (g - w).abs() <= lim,
            "{what}[{i}]: got {g}, Python onnxruntime gave {w}"
        );
    }
}

fn info<'a>(infos: &'a [TensorInfo], name: &str) -> &'a TensorInfo {
    infos
        .iter()
        .find(|i| i.name == name)
        .unwrap_or_else(|| panic!("no tensor {name}: {infos:?}"))
}

fn session(file: ModelFile) -> ort::session::Session {
    let path = runtime::model_path(file).unwrap_or_else(|e| panic!("{e}"));
    runtime::open_session(&path, &SessionParams::default()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn detector_contract_and_fixed_output() {
    let s = session(ModelFile::PoseDetection);
    let ins = runtime::TensorInfo::inputs_of(&s);
    let outs = runtime::TensorInfo::outputs_of(&s);
    assert_eq!(ins.len(), 1);
    assert_eq!(info(&ins, "input_1").shape, vec![1, 224, 224, 3]);
    assert_eq!(info(&ins, "input_1").dtype, "f32");
    assert_eq!(info(&outs, "Identity").shape, vec![1, 2254, 12]);
    assert_eq!(info(&outs, "Identity_1").shape, vec![1, 2254, 1]);
    drop(s);

    let fx = &fixtures()["detector"];
    let path = runtime::model_path(ModelFile::PoseDetection).unwrap();
    let mut det = PoseDetector::open(
        &path,
        // Keep every anchor so that decoding can be compared with the raw fixture.
        DetectorParams {
            min_score: 0.0,
            nms_iou: 1.0,
            ..Default::default()
        },
        &SessionParams::default(),
    )
    .unwrap();
    let input: Vec<f32> = pattern(224)
        .iter()
        .map(|&v| v as f32 / 127.5 - 1.0)
        .collect();
    assert!(input.iter().all(|v| (-1.0..=1.0).contains(v)));
    let dets = det.run_tensor(&input).unwrap();
    // nms_iou = 1.0 merges only identical boxes, so (almost) every anchor survives;
    // the best one must be the fixture's best anchor, decoded.
    let best = &dets[0];
    let bi = fx["best_index"].as_u64().unwrap() as usize;
    let anchors = detector::ssd_anchors();
    let raw = floats(&fx["best_boxes"]);
    let want_kp0 = [
        raw[4] / 224.0 + anchors[bi][0] as f64,
        raw[5] / 224.0 + anchors[bi][1] as f64,
    ];
    assert!(
        (best.keypoints[0][0] as f64 - want_kp0[0]).abs() < 1e-3,
        "{:?} vs {want_kp0:?}",
        best.keypoints[0]
    );
    assert!((best.keypoints[0][1] as f64 - want_kp0[1]).abs() < 1e-3);
    let best_logit = floats(&fx["scores"])[6];
    let want_score = 1.0 / (1.0 + (-best_logit).exp());
    assert!((best.score as f64 - want_score).abs() < 1e-4);
    assert!(dets.iter().all(|d| (0.0..=1.0).contains(&d.score)));
}

#[test]
fn detector_raw_outputs_match_python() {
    let fx = &fixtures()["detector"];
    let mut s = session(ModelFile::PoseDetection);
    let input: Vec<f32> = pattern(224)
        .iter()
        .map(|&v| v as f32 / 127.5 - 1.0)
        .collect();
    let t =
        ort::value::TensorRef::from_array_view(([1usize, 224, 224, 3], input.as_slice())).unwrap();
    let out = s.run(ort::inputs!["input_1" => t]).unwrap();
    let (_, boxes) = out["Identity"].try_extract_tensor::<f32>().unwrap();
    let (_, scores) = out["Identity_1"].try_extract_tensor::<f32>().unwrap();
    let got: Vec<f64> = boxes[..36].iter().map(|&v| v as f64).collect();
    assert_close("detector boxes", &got, &floats(&fx["boxes_first_36"]), 1e-3);
    let idx: Vec<usize> = fx["score_idx"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    let got: Vec<f64> = idx.iter().map(|&i| scores[i] as f64).collect();
    assert_close("detector scores", &got, &floats(&fx["scores"]), 1e-3);
}

fn check_landmark(kind: LandmarkModelKind, file: ModelFile, key: &str) {
    let s = session(file);
    let ins = runtime::TensorInfo::inputs_of(&s);
    let outs = runtime::TensorInfo::outputs_of(&s);
    assert_eq!(info(&ins, "input_1").shape, vec![1, 256, 256, 3]);
    for (name, shape) in [
        ("Identity", vec![1, 195]),
        ("Identity_1", vec![1, 1]),
        ("Identity_2", vec![1, 256, 256, 1]),
        ("Identity_3", vec![1, 64, 64, 39]),
        ("Identity_4", vec![1, 117]),
    ] {
        assert_eq!(info(&outs, name).shape, shape, "{key} {name}");
        assert_eq!(info(&outs, name).dtype, "f32");
    }
    drop(s);
    let fx = &fixtures()[key];
    let path = runtime::model_path(file).unwrap();
    let mut m = LandmarkModel::open(
        &path,
        kind,
        RefineParams {
            enabled: false,
            ..Default::default()
        },
        &SessionParams::default(),
    )
    .unwrap();
    let input: Vec<f32> = pattern(256).iter().map(|&v| v as f32 / 255.0).collect();
    let out = m.run_tensor(&input).unwrap();
    // Presence is a probability; visibility/presence are sigmoids.
    assert!((0.0..=1.0).contains(&out.pose_presence));
    assert!((out.pose_presence as f64 - fx["presence"].as_f64().unwrap()).abs() < 1e-4);
    assert_eq!(out.landmarks.len(), 39);
    let raw = floats(&fx["landmarks"]);
    let mut got = Vec::new();
    let mut want = Vec::new();
    for (k, lm) in out.landmarks.iter().enumerate() {
        assert!((0.0..=1.0).contains(&lm.visibility) && (0.0..=1.0).contains(&lm.presence));
        // Coordinates in 256-pixel units against the raw fixture.
        got.extend([
            lm.x as f64 * 256.0,
            lm.y as f64 * 256.0,
            lm.z as f64 * 256.0,
        ]);
        want.extend([raw[5 * k], raw[5 * k + 1], raw[5 * k + 2]]);
        let v = 1.0 / (1.0 + (-raw[5 * k + 3]).exp());
        assert!(
            (lm.visibility as f64 - v).abs() < 1e-4,
            "{key} visibility {k}"
        );
    }
    assert_close(&format!("{key} landmarks"), &got, &want, 1e-3);
    let world: Vec<f64> = out.world.iter().flat_map(|w| w.map(|v| v as f64)).collect();
    assert_close(&format!("{key} world"), &world, &floats(&fx["world"]), 1e-3);
    assert!(
        world.iter().all(|v| v.abs() < 5.0),
        "world coordinates are metres"
    );
}

#[test]
fn landmark_full_contract_and_fixed_output() {
    check_landmark(
        LandmarkModelKind::Full,
        ModelFile::LandmarkFull,
        "landmark_full",
    );
}

#[test]
fn landmark_lite_contract_and_fixed_output() {
    check_landmark(
        LandmarkModelKind::Lite,
        ModelFile::LandmarkLite,
        "landmark_lite",
    );
}

/// The estimators open the landmark model without its mask head (made by
/// `cargo xtask models`); it must give the values of the model as converted.
fn check_without_mask(kind: LandmarkModelKind, file: ModelFile) {
    let cut = runtime::run_model_path(file).unwrap();
    let want = file.without_mask().unwrap();
    assert!(
        cut.ends_with(want),
        "the estimators open {}, not {want} (run `cargo xtask models`)",
        cut.display()
    );
    let s = runtime::open_session(&cut, &SessionParams::default()).unwrap();
    let outs = runtime::TensorInfo::outputs_of(&s);
    assert!(outs.iter().all(|o| o.name != "Identity_2"), "{outs:?}");
    assert_eq!(outs.len(), 4, "{outs:?}");
    drop(s);
    let orig = runtime::model_path(file).unwrap();
    let open = |p: &std::path::Path| {
        LandmarkModel::open(p, kind, RefineParams::default(), &SessionParams::default()).unwrap()
    };
    let (mut a, mut b) = (open(&orig), open(&cut));
    for seed in [0u8, 91] {
        let input: Vec<f32> = pattern(256)
            .iter()
            .map(|&v| v.wrapping_add(seed) as f32 / 255.0)
            .collect();
        let (x, y) = (a.run_tensor(&input).unwrap(), b.run_tensor(&input).unwrap());
        assert!((x.pose_presence - y.pose_presence).abs() < 1e-5);
        for (p, q) in x.landmarks.iter().zip(&y.landmarks) {
            // Pixels of the 256-pixel crop.
            assert!(
                ((p.x - q.x) * 256.0).abs() < 1e-3 && ((p.y - q.y) * 256.0).abs() < 1e-3,
                "{kind:?}: {p:?} vs {q:?}"
            );
        }
        for (p, q) in x.world.iter().zip(&y.world) {
            assert!((0..3).all(|k| (p[k] - q[k]).abs() < 1e-5), "{p:?} vs {q:?}");
        }
    }
}

#[test]
fn landmark_models_without_mask_give_the_same_values() {
    check_without_mask(LandmarkModelKind::Full, ModelFile::LandmarkFull);
    check_without_mask(LandmarkModelKind::Lite, ModelFile::LandmarkLite);
}

/// An RGB image of `w × h` whose value at (x, y, c) is
/// `(a·x + b·y + k·c + x·y / d) mod 256`, for `[a, b, k, d]`: no two crops alike.
fn busy_image(w: usize, h: usize, [a, b, k, d]: [usize; 4]) -> Vec<u8> {
    (0..w * h * 3)
        .map(|i| {
            let (p, c) = (i / 3, i % 3);
            let (x, y) = (p % w, p / w);
            ((a * x + b * y + k * c + (x * y) / d) % 256) as u8
        })
        .collect()
}

/// Several crops in one run of the landmark model (the cut model's batch is
/// open) give each crop's values from a run of its own, and a model whose
/// batch is closed runs them one by one.
#[test]
fn several_crops_in_one_run_give_each_crops_values() {
    let (w, h) = (512usize, 384usize);
    let data = busy_image(w, h, [7, 3, 60, 97]);
    let image = RgbView {
        width: w,
        height: h,
        data: &data,
    };
    let rois = [
        Roi::letterbox(w, h),
        Roi {
            center_x_px: 150.0,
            center_y_px: 200.0,
            width_px: 180.0,
            height_px: 180.0,
            rotation_rad: 0.4,
        },
        Roi {
            center_x_px: 400.0,
            center_y_px: 120.0,
            width_px: 260.0,
            height_px: 260.0,
            rotation_rad: -1.2,
        },
    ];
    let cut = runtime::run_model_path(ModelFile::LandmarkFull).unwrap();
    let orig = runtime::model_path(ModelFile::LandmarkFull).unwrap();
    let open = |p: &std::path::Path| {
        LandmarkModel::open(
            p,
            LandmarkModelKind::Full,
            RefineParams::default(),
            &SessionParams::default(),
        )
        .unwrap()
    };
    let mut batched = open(&cut);
    assert!(
        batched.batch_open(),
        "{} takes one crop a run (run `cargo xtask models`)",
        cut.display()
    );
    let mut single = open(&orig);
    assert!(!single.batch_open());
    let together = batched.run_many(image, &rois).unwrap();
    let apart = single.run_many(image, &rois).unwrap();
    assert_eq!(together.len(), 3);
    assert_eq!(apart.len(), 3);
    for (i, (x, y)) in together.iter().zip(&apart).enumerate() {
        assert!((x.pose_presence - y.pose_presence).abs() < 1e-4, "crop {i}");
        for (p, q) in x.landmarks.iter().zip(&y.landmarks) {
            // Pixels of the 256-pixel crop.
            assert!(
                ((p.x - q.x) * 256.0).abs() < 1e-2 && ((p.y - q.y) * 256.0).abs() < 1e-2,
                "crop {i}: {p:?} vs {q:?}"
            );
        }
    }
    // The crops differ, so a mix-up of the batch's order would show.
    assert!((together[0].landmarks[0].x - together[2].landmarks[0].x).abs() > 1e-4);
    assert!(batched.run_many(image, &[]).unwrap().is_empty());
}

#[test]
fn movenet_contract_and_fixed_output() {
    if super::movenet_model().is_none() {
        return;
    }
    let s = session(ModelFile::MoveNetLightning);
    let ins = runtime::TensorInfo::inputs_of(&s);
    let outs = runtime::TensorInfo::outputs_of(&s);
    assert_eq!(
        info(&ins, "serving_default_input:0").shape,
        vec![1, 192, 192, 3]
    );
    assert_eq!(info(&ins, "serving_default_input:0").dtype, "u8");
    assert_eq!(
        info(&outs, "StatefulPartitionedCall:0").shape,
        vec![1, 1, 17, 3]
    );
    drop(s);
    let mut m = MoveNet::new(MoveNetParams::default()).unwrap();
    let kps = m.run_tensor(&pattern(192)).unwrap();
    assert_eq!(kps.len(), 17);
    let got: Vec<f64> = kps.iter().flat_map(|k| k.map(|v| v as f64)).collect();
    for k in &kps {
        assert!(
            k.iter().all(|v| (0.0..=1.0).contains(v)),
            "(y, x, score) are normalised: {k:?}"
        );
    }
    // The int8 graph runs different kernels per instruction set (AVX2,
    // AVX-512, VNNI): on this synthetic pattern, which shows no person, the
    // outputs of two CPUs differ by up to 0.4, so no fixture made on one CPU
    // is compared here. What holds everywhere: the same input gives the same
    // output on one machine. MoveNet's accuracy is checked on a real image
    // against its annotation (PCK, tests/pipeline.rs).
    let again: Vec<f64> = m
        .run_tensor(&pattern(192))
        .unwrap()
        .iter()
        .flat_map(|k| k.map(|v| v as f64))
        .collect();
    assert_eq!(got, again, "MoveNet is deterministic on one machine");
    assert_eq!(floats(&fixtures()["movenet"]["keypoints"]).len(), got.len());
}

#[test]
fn wrong_model_file_breaks_the_contract() {
    // Opening the MoveNet file as a landmark model must be refused with a clear message.
    let Some(path) = super::movenet_model() else {
        return;
    };
    let err = LandmarkModel::open(
        &path,
        LandmarkModelKind::Full,
        RefineParams::default(),
        &SessionParams::default(),
    )
    .err()
    .expect("must fail");
    let msg = err.to_string();
    assert!(
        msg.contains("tensor contract") && msg.contains("input_1"),
        "{msg}"
    );
}

/// A landmark model shared by estimators on several threads gives each
/// crop the values of a model of its own, runs crops that arrive together
/// in one run, and refuses an estimator that asks for another model.
#[test]
fn shared_model_gives_each_thread_its_own_crops_values() {
    use crate::blazepose::{BlazePose, BlazePoseParams, SharedLandmarks};
    use std::time::Duration;

    let (w, h) = (320usize, 240usize);
    let data = busy_image(w, h, [5, 11, 70, 53]);
    let image = RgbView {
        width: w,
        height: h,
        data: &data,
    };
    let roi = |k: usize| Roi {
        center_x_px: 80.0 + 20.0 * k as f64,
        center_y_px: 120.0,
        width_px: 150.0,
        height_px: 150.0,
        rotation_rad: 0.3 * k as f64 - 0.5,
    };
    let cut = runtime::run_model_path(ModelFile::LandmarkFull).unwrap();
    let open = || {
        LandmarkModel::open(
            &cut,
            LandmarkModelKind::Full,
            RefineParams::default(),
            &SessionParams::default(),
        )
        .unwrap()
    };
    let mut own = open();
    let expected: Vec<_> = (0..6).map(|k| own.run(image, &roi(k)).unwrap()).collect();
    // A batch of all six crops, run as soon as they are there; the long
    // wait only matters on a machine too busy to start the threads at once.
    let shared = SharedLandmarks::start(open(), 6, Duration::from_secs(2)).unwrap();
    let got: Vec<Vec<_>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..3)
            .map(|t| {
                let mut m = shared.model();
                s.spawn(move || m.run_many(image, &[roi(2 * t), roi(2 * t + 1)]).unwrap())
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (t, outs) in got.iter().enumerate() {
        assert_eq!(outs.len(), 2, "thread {t}");
        for (j, x) in outs.iter().enumerate() {
            let y = &expected[2 * t + j];
            assert!(
                (x.pose_presence - y.pose_presence).abs() < 1e-4,
                "crop {t}/{j}"
            );
            for (p, q) in x.landmarks.iter().zip(&y.landmarks) {
                assert!(
                    ((p.x - q.x) * 256.0).abs() < 1e-2 && ((p.y - q.y) * 256.0).abs() < 1e-2,
                    "crop {t}/{j}: {p:?} vs {q:?}"
                );
            }
        }
    }
    let stats = shared.stats();
    assert_eq!((stats.requests, stats.crops), (3, 6));
    assert!(
        stats.runs < 3,
        "the three requests ran in {} runs",
        stats.runs
    );
    // An estimator asking for another model is refused by name.
    let lite = BlazePose::new(BlazePoseParams {
        model: LandmarkModelKind::Lite,
        shared: Some(shared.clone()),
        ..Default::default()
    });
    let err = lite.err().expect("a lite estimator on a full shared model");
    assert!(err.to_string().contains("full"), "{err}");
}
