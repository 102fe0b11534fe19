//! The learned models on what `mp extract` writes, through the built binary:
//! the first 60 frames of the shared golf swing extracted as BlazePose-33
//! (2D pixels and 3D world landmarks) and COCO-17, then `mp predict --method
//! ar` (through the Penn Action or MSR Action3D model and back), `mp statue`
//! and `mp refine` (through the 20 MSR joints and back). The output tracks
//! must have the input's skeleton, the requested frames and finite values
//! near the observed motion. Skipped where the shared video is absent (the
//! skip recorded through the shared-data helper), and with a message where
//! ONNX Runtime and the pose models are absent.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use mp_geom::read_track;
use mp_geom::Track;

const FRAMES: usize = 60;
const OBSERVE: usize = 45;
const HORIZON: usize = 12;

fn mp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mp"))
}

fn text(out: &Output) -> String {
    format!(
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

fn run_ok(cmd: &mut Command) -> String {
    let out = cmd.output().expect("cannot start the mp binary");
    assert!(
        out.status.success(),
        "mp failed ({}):\n{}",
        out.status,
        text(&out)
    );
    text(&out)
}

/// The shared golf swing video (`golfdb/golf_swing.mp4`); where it is absent
/// the test records its skip and returns.
macro_rules! video_or_return {
    () => {
        mp_geom::data_or_return!("golfdb/golf_swing.mp4")
    };
}

/// The first 60 frames of `video` (the golf swing) as `(BlazePose 2D,
/// BlazePose world, COCO-17 2D)` track files, or why they cannot be made here.
fn extracted(video: &Path) -> Result<&'static (tempfile::TempDir, [PathBuf; 3]), &'static str> {
    static TRACKS: OnceLock<Result<(tempfile::TempDir, [PathBuf; 3]), String>> = OnceLock::new();
    TRACKS
        .get_or_init(|| {
            let dir = tempfile::tempdir().unwrap();
            let names = ["blazepose.npz", "world.npz", "coco.npz"];
            let extra: [&[&str]; 3] = [&["--all-joints"], &["--world"], &[]];
            for (name, extra) in names.iter().zip(extra) {
                let out = mp()
                    .arg("extract")
                    .arg(video)
                    .arg("-o")
                    .arg(dir.path().join(name))
                    .args(["--max-frames", &FRAMES.to_string(), "--quiet"])
                    .args(extra)
                    .output()
                    .expect("cannot start the mp binary");
                if !out.status.success() {
                    let msg = text(&out);
                    if msg.contains("ONNX Runtime") || msg.contains("not found (looked in") {
                        return Err(format!(
                            "ONNX Runtime or the pose models are missing (`cargo xtask setup`, `cargo xtask models`): {}",
                            String::from_utf8_lossy(&out.stderr).trim()
                        ));
                    }
                    panic!("mp extract {extra:?} failed:\n{msg}");
                }
            }
            let paths = names.map(|n| dir.path().join(n));
            Ok((dir, paths))
        })
        .as_ref()
        .map_err(String::as_str)
}

/// Vertical extent of the valid joints in `frame` (y is the vertical axis
/// of image pixels and of BlazePose's world landmarks).
fn body_height(t: &Track, frame: usize) -> f64 {
    let ys: Vec<f64> = (0..t.n_joints())
        .filter(|&j| t.is_valid(frame, j, 0.0))
        .map(|j| t.point(frame, j)[1])
        .collect();
    let (lo, hi) = ys
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
    hi - lo
}

/// Mean distance of every predicted joint from its last observed position.
fn mean_offset(pred: &Track, input: &Track, last: usize) -> f64 {
    let mut sum = 0.0;
    for h in 0..pred.n_frames() {
        for j in 0..pred.n_joints() {
            let d = &pred.point(h, j) - &input.point(last, j);
            sum += d.dot(&d).sqrt();
        }
    }
    sum / (pred.n_frames() * pred.n_joints()) as f64
}

fn predict(input: &Path, out: &Path) -> String {
    run_ok(
        mp().arg("predict")
            .arg(input)
            .args(["--method", "ar", "--observe"])
            .arg(OBSERVE.to_string())
            .arg("--horizon")
            .arg(HORIZON.to_string())
            .arg("-o")
            .arg(out),
    )
}

#[test]
fn extracted_tracks_are_forecast_on_their_own_skeleton() {
    let video = video_or_return!();
    let (dir, tracks) = match extracted(&video) {
        Ok(t) => t,
        Err(why) => {
            println!("skipped: {why}");
            return;
        }
    };
    for (input, model) in tracks
        .iter()
        .zip(["penn_action", "msr_action3d", "penn_action"])
    {
        let track = read_track(input).unwrap();
        assert_eq!(track.n_frames(), FRAMES);
        let out = dir.path().join(format!(
            "pred_{}",
            input.file_name().unwrap().to_string_lossy()
        ));
        let log = predict(input, &out);
        assert!(log.contains(model), "{}: {log}", input.display());
        let pred = read_track(&out).unwrap();
        assert_eq!(pred.skeleton(), track.skeleton(), "{}", input.display());
        assert_eq!(pred.n_frames(), HORIZON);
        assert_eq!(pred.dims(), track.dims());
        assert!(pred.positions().iter().all(|v| v.is_finite()));
        let height = body_height(&track, OBSERVE - 1);
        let offset = mean_offset(&pred, &track, OBSERVE - 1);
        assert!(
            height > 0.0 && offset < height,
            "{}: predicted joints {offset:.3} from the last observed pose, body height {height:.3}",
            input.display()
        );
    }
    // the statue moment of a COCO-17 track runs through the same mapping
    let log = run_ok(mp().arg("statue").arg(&tracks[2]));
    assert!(log.contains("statue frame"), "{log}");
}

#[test]
fn extracted_world_landmarks_are_refined_on_their_own_skeleton() {
    let video = video_or_return!();
    let (dir, tracks) = match extracted(&video) {
        Ok(t) => t,
        Err(why) => {
            println!("skipped: {why}");
            return;
        }
    };
    let world = read_track(&tracks[1]).unwrap();
    assert_eq!(
        (world.skeleton().name.as_str(), world.dims()),
        ("blazepose33", 3)
    );
    let out = dir.path().join("refined.npz");
    let log = run_ok(mp().arg("refine").arg(&tracks[1]).arg("-o").arg(&out));
    assert!(
        log.contains("mapped onto the 20 MSR Action3D joints"),
        "{log}"
    );
    let refined = read_track(&out).unwrap();
    assert_eq!(refined.skeleton(), world.skeleton());
    assert_eq!(refined.n_frames(), world.n_frames());
    assert!(refined.positions().iter().all(|v| v.is_finite()));
    let offset = (0..world.n_frames())
        .map(|f| {
            let one = refined.slice_frames(f, f + 1).unwrap();
            mean_offset(&one, &world, f)
        })
        .sum::<f64>()
        / world.n_frames() as f64;
    assert!(
        offset < 0.1,
        "refinement moved the landmarks by {offset:.3} m"
    );

    // 2D pixels are refused with what is needed
    let out = mp()
        .arg("refine")
        .arg(&tracks[0])
        .arg("-o")
        .arg(dir.path().join("no.npz"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--world"), "{err}");
}
