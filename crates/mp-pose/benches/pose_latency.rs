//! Per-frame latency of the pose models (ONNX Runtime, 2 intra-op threads):
//! detector, landmark full / lite, MoveNet, a BlazePose tracking frame
//! (crop from the previous frame's landmarks + landmark model + refinement),
//! and the several-people estimator at 30 fps on one person and on two (the
//! frame beside itself), its tile searches and detector checks included at
//! their rates; and four threads' crops through one shared landmark model
//! against a model each (`shared_landmarks`: one iteration is a frame of two
//! crops on every thread, so crops per second = 8 / its time).
//!
//! Needs `cargo xtask setup`; uses frame 0 of the shared golf video (a grey
//! frame when the shared data is absent).
//!
//! `cargo bench -p mp-pose --bench pose_latency`
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // bench code: failing loudly is the point

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::time::Duration;

use mp_pose::roi_from_points;
use mp_pose::{BlazePose, BlazePoseParams, LandmarkModel, LandmarkModelKind, SharedLandmarks};
use mp_pose::{Frame, VideoReader};
use mp_pose::{MoveNet, MoveNetParams, MultiPose, MultiPoseParams, PoseEstimator};

fn frame() -> Frame {
    mp_geom::data_file("golfdb/golf_swing.mp4")
        .and_then(|p| VideoReader::open(p).ok())
        .and_then(|mut r| r.next())
        .and_then(|f| f.ok())
        .unwrap_or_else(|| Frame::new(0, 0.0, 354, 492, vec![128; 354 * 492 * 3]).expect("frame"))
}

/// The frame and a copy of it side by side: two people.
fn beside_itself(f: &Frame) -> Frame {
    let row = f.width * 3;
    let mut rgb = Vec::with_capacity(2 * f.rgb.len());
    for y in 0..f.height {
        let line = &f.rgb[y * row..(y + 1) * row];
        rgb.extend_from_slice(line);
        rgb.extend_from_slice(line);
    }
    Frame::new(0, 0.0, 2 * f.width, f.height, rgb).expect("frame")
}

fn bench(c: &mut Criterion) {
    let frame = frame();
    let mut g = c.benchmark_group("pose_per_frame");
    g.sample_size(40)
        .measurement_time(Duration::from_secs(6))
        .warm_up_time(Duration::from_secs(2));

    let mut full = BlazePose::new(BlazePoseParams::default())
        .expect("BlazePose full (run `cargo xtask setup`)");
    g.bench_function("detector", |b| {
        b.iter(|| black_box(full.detector_mut().detect(frame.view()).expect("detect")))
    });
    let det = full.detector_mut().detect(frame.view()).expect("detect");
    let roi = det
        .first()
        .map(|d| roi_from_points(d.keypoints_px[0], d.keypoints_px[1], 1.25))
        .unwrap_or(mp_pose::Roi::letterbox(frame.width, frame.height));
    g.bench_function("landmark_full", |b| {
        b.iter(|| {
            black_box(
                full.landmarks_mut()
                    .run(frame.view(), &roi)
                    .expect("landmarks"),
            )
        })
    });
    // Tracking: after the first frame the crop comes from the previous landmarks.
    full.estimate(&frame).expect("first frame");
    let mut idx = 1usize;
    g.bench_function("tracking_frame_full", |b| {
        b.iter(|| {
            let f = Frame {
                index: idx,
                timestamp_s: idx as f64 / 30.0,
                ..frame.clone()
            };
            idx += 1;
            black_box(full.estimate(&f).expect("tracking"))
        })
    });
    drop(full);

    // Several people: steady state over many frames at 30 fps.
    let two = beside_itself(&frame);
    for (name, f0) in [("people_one_person", &frame), ("people_two_people", &two)] {
        let mut multi = MultiPose::new(MultiPoseParams::default()).expect("MultiPose");
        let mut k = 0usize;
        g.bench_function(name, |b| {
            b.iter(|| {
                let f = Frame {
                    index: k,
                    timestamp_s: k as f64 / 30.0,
                    ..f0.clone()
                };
                k += 1;
                black_box(multi.process(&f).expect("people"))
            })
        });
    }

    let mut lite = BlazePose::new(BlazePoseParams {
        model: LandmarkModelKind::Lite,
        ..Default::default()
    })
    .expect("BlazePose lite");
    g.bench_function("landmark_lite", |b| {
        b.iter(|| {
            black_box(
                lite.landmarks_mut()
                    .run(frame.view(), &roi)
                    .expect("landmarks"),
            )
        })
    });
    drop(lite);

    let mut mv = MoveNet::new(MoveNetParams::default()).expect("MoveNet");
    g.bench_function("movenet", |b| {
        b.iter(|| black_box(mv.estimate(&frame).expect("movenet")))
    });
    g.finish();
}

/// Four threads, each running the landmark model on two crops of the frame
/// per iteration, through `models` (one per thread).
fn four_threads(
    frame: &Frame,
    rois: &[mp_pose::Roi; 2],
    models: Vec<&mut LandmarkModel>,
) -> Duration {
    let start = std::time::Instant::now();
    std::thread::scope(|s| {
        for m in models {
            s.spawn(|| black_box(m.run_many(frame.view(), rois).expect("landmarks")));
        }
    });
    start.elapsed()
}

fn bench_shared(c: &mut Criterion) {
    let frame = frame();
    let (w, h) = (frame.width as f64, frame.height as f64);
    let side = w.min(h) * 0.8;
    let roi = |cx: f64| mp_pose::Roi {
        center_x_px: cx,
        center_y_px: h / 2.0,
        width_px: side,
        height_px: side,
        rotation_rad: 0.0,
    };
    let rois = [roi(w * 0.4), roi(w * 0.6)];
    let mut g = c.benchmark_group("shared_landmarks");
    g.sample_size(20)
        .measurement_time(Duration::from_secs(8))
        .warm_up_time(Duration::from_secs(2));
    let params = BlazePoseParams::default();
    let shared =
        SharedLandmarks::open(&params).expect("the landmark model (run `cargo xtask setup`)");
    let mut clients: Vec<LandmarkModel> = (0..4).map(|_| shared.model()).collect();
    g.bench_function("four_threads_one_model", |b| {
        b.iter_custom(|iters| {
            (0..iters)
                .map(|_| four_threads(&frame, &rois, clients.iter_mut().collect()))
                .sum()
        })
    });
    drop(clients);
    let mut own: Vec<BlazePose> = (0..4)
        .map(|_| BlazePose::new(params.clone()).expect("BlazePose"))
        .collect();
    g.bench_function("four_threads_a_model_each", |b| {
        b.iter_custom(|iters| {
            (0..iters)
                .map(|_| {
                    four_threads(
                        &frame,
                        &rois,
                        own.iter_mut().map(BlazePose::landmarks_mut).collect(),
                    )
                })
                .sum()
        })
    });
    g.finish();
}

criterion_group!(benches, bench, bench_shared);
criterion_main!(benches);
