//! Decoding and set-up errors are typed and name what is wrong.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use std::io::Write;

use mp_pose::{probe, read_image, VideoReader};
use mp_pose::{BlazePose, BlazePoseParams, MoveNet, MoveNetParams, PoseError};

#[test]
fn golf_video_has_264_frames_at_29_97_fps() {
    let path = mp_geom::data_or_return!("golfdb/golf_swing.mp4");
    let info = probe(&path).unwrap();
    assert_eq!((info.width, info.height), (354, 492));
    assert!((info.fps - 29.97).abs() < 1e-9);
    assert_eq!(info.frame_count, Some(264));
    let mut n = 0;
    let mut last_ts = -1.0;
    for f in VideoReader::open(&path).unwrap() {
        let f = f.unwrap();
        assert_eq!(f.index, n);
        assert_eq!(f.rgb.len(), 354 * 492 * 3);
        assert!(f.timestamp_s > last_ts);
        last_ts = f.timestamp_s;
        n += 1;
    }
    assert_eq!(n, 264, "decoded frame count");
    assert!((last_ts - 263.0 / 29.97).abs() < 1e-9);
}

#[test]
fn quva_video_frame_count_and_rate() {
    // 020_fitness: 152 frames, 640×360, 29 fps (PyAV counts in the reference README).
    let path = mp_geom::data_or_return!("quva_repetition/videos/020_fitness.mp4");
    let info = probe(&path).unwrap();
    assert_eq!((info.width, info.height), (640, 360));
    assert!((info.fps - 29.0).abs() < 0.01, "{}", info.fps);
    let mut n = 0;
    for f in VideoReader::open(&path).unwrap() {
        assert_eq!(f.unwrap().rgb.len(), 640 * 360 * 3);
        n += 1;
    }
    assert_eq!(n, 152);
}

#[test]
fn missing_video_is_an_io_error_naming_the_file() {
    let err = VideoReader::open("/nonexistent/clip.mp4").err().unwrap();
    assert!(matches!(err, PoseError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("/nonexistent/clip.mp4"));
}

#[test]
fn corrupt_video_is_a_decoding_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("random.mp4");
    let mut f = std::fs::File::create(&path).unwrap();
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let bytes: Vec<u8> = (0..64 * 1024)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect();
    f.write_all(&bytes).unwrap();
    drop(f);
    let err = match VideoReader::open(&path) {
        Err(e) => e,
        Ok(mut r) => r
            .next()
            .expect("an error item")
            .expect_err("must not decode"),
    };
    assert!(
        matches!(err, PoseError::Video { .. } | PoseError::VideoFrame { .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("random.mp4"), "{err}");
}

#[test]
fn truncated_video_fails_or_stops_cleanly() {
    // The first 40% of a real video: frames decode, then the stream ends with
    // fewer frames than announced (never a panic, never a partial frame).
    let src = std::fs::read(mp_geom::data_or_return!("golfdb/golf_swing.mp4")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.mp4");
    std::fs::write(&path, &src[..src.len() * 2 / 5]).unwrap();
    match VideoReader::open(&path) {
        Err(e) => assert!(e.to_string().contains("cut.mp4"), "{e}"),
        Ok(r) => {
            let mut n = 0;
            for f in r {
                match f {
                    Ok(f) => {
                        assert_eq!(f.rgb.len(), 354 * 492 * 3);
                        n += 1
                    }
                    Err(e) => {
                        assert!(e.to_string().contains("cut.mp4"), "{e}");
                        break;
                    }
                }
            }
            assert!(n < 264);
        }
    }
}

#[test]
fn unreadable_image_is_an_image_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.png");
    std::fs::write(&path, b"not a png").unwrap();
    let err = read_image(&path).unwrap_err();
    assert!(matches!(err, PoseError::Image { .. }), "{err:?}");
    assert!(err.to_string().contains("broken.png"));
}

#[test]
fn missing_model_names_the_file_and_the_task() {
    let dir = tempfile::tempdir().unwrap();
    let err = BlazePose::new(BlazePoseParams {
        model_dir: Some(dir.path().to_path_buf()),
        ..Default::default()
    })
    .err()
    .unwrap();
    let msg = err.to_string();
    assert!(matches!(err, PoseError::ModelMissing { .. }), "{err:?}");
    assert!(
        msg.contains("pose_detection.onnx") && msg.contains("cargo xtask models"),
        "{msg}"
    );
    let err = MoveNet::new(MoveNetParams {
        model_dir: Some(dir.path().to_path_buf()),
        ..Default::default()
    })
    .err()
    .unwrap();
    assert!(err
        .to_string()
        .contains("movenet_singlepose_lightning_int8.onnx"));
}

#[test]
fn invalid_parameters_are_rejected() {
    let bad = BlazePoseParams {
        min_presence: 1.5,
        ..Default::default()
    };
    assert!(matches!(
        bad.validate(),
        Err(PoseError::InvalidParam {
            name: "min_presence",
            ..
        })
    ));
    let bad = BlazePoseParams {
        roi_scale: f64::NAN,
        ..Default::default()
    };
    assert!(bad.validate().is_err());
    let bad = MoveNetParams {
        min_pose_score: -0.1,
        ..Default::default()
    };
    assert!(bad.validate().is_err());
    let s = mp_pose::SessionParams {
        intra_threads: 0,
        ..Default::default()
    };
    assert!(s.validate().is_err());
}
