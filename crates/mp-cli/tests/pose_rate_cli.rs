//! `--pose-fps`: the pose model on a subset of the frames, the frames between
//! filled from the motion. On the shared golf swing (29.97 fps) the model
//! runs on every second frame at 15 poses a second (`auto` too), every frame is still
//! written, and the filled keypoints stay within a few pixels of those of
//! the every-frame run; bad rates are refused with a message naming them.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use common::{ok, refused};
use mp_geom::Track;

const FRAMES: usize = 61;

fn golf() -> String {
    mp_geom::data_file("golfdb/golf_swing.mp4")
        .expect("the shared golf swing")
        .display()
        .to_string()
}

/// `mp extract` of the first frames with extra arguments: the track and stdout.
fn extract(dir: &std::path::Path, name: &str, extra: &[&str]) -> (Track, String) {
    let out = dir.join(name);
    let frames = FRAMES.to_string();
    let video = golf();
    let mut args = vec![
        "extract",
        video.as_str(),
        "-o",
        out.to_str().unwrap(),
        "--max-frames",
        frames.as_str(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let (stdout, _) = ok(&args);
    (
        mp_geom::read_track(&out).expect("the written track"),
        stdout,
    )
}

fn median(mut v: Vec<f64>) -> f64 {
    assert!(!v.is_empty());
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Distances between the joints valid in both tracks on the frames `which` accepts.
fn distances(a: &Track, b: &Track, which: impl Fn(usize) -> bool) -> Vec<f64> {
    let mut d = Vec::new();
    for t in (0..a.n_frames()).filter(|&t| which(t)) {
        for j in 0..a.n_joints() {
            if a.is_valid(t, j, 0.0) && b.is_valid(t, j, 0.0) {
                let (p, q) = (a.point(t, j), b.point(t, j));
                d.push((p[0] - q[0]).hypot(p[1] - q[1]));
            }
        }
    }
    d
}

#[test]
fn half_the_poses_fill_every_frame_close_to_the_full_run() {
    let dir = tempfile::tempdir().unwrap();
    let (full, _) = extract(dir.path(), "full.npz", &[]);
    let (half, _) = extract(dir.path(), "half.npz", &["--pose-fps", "15"]);
    assert_eq!(full.n_frames(), FRAMES);
    assert_eq!(half.n_frames(), FRAMES);
    // Every frame has the golfer, the skipped ones too.
    for t in 0..FRAMES {
        assert!(
            (0..half.n_joints()).any(|j| half.is_valid(t, j, 0.0)),
            "frame {t} has no pose"
        );
    }
    let filled = distances(&half, &full, |t| t % 2 == 1);
    let posed = distances(&half, &full, |t| t % 2 == 0);
    let (mf, mp) = (median(filled), median(posed));
    assert!(
        mf < 4.0,
        "filled frames {mf:.2} px from the every-frame run"
    );
    assert!(mp < 3.0, "posed frames {mp:.2} px from the every-frame run");
}

#[test]
fn the_summary_says_how_many_frames_were_posed() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("third.json");
    let frames = FRAMES.to_string();
    let video = golf();
    let (stdout, _) = ok(&[
        "extract",
        &video,
        "-o",
        out.to_str().unwrap(),
        "--max-frames",
        &frames,
        "--pose-fps",
        "10",
        "--single-person",
    ]);
    // Every third frame from 0 to 60: 21 frames, the last (60) among them.
    assert!(
        stdout.contains("(pose model on 21 of 61 frames)"),
        "summary: {stdout}"
    );
    let t = mp_geom::read_track(&out).unwrap();
    assert_eq!(t.n_frames(), FRAMES);
}

#[test]
fn bad_rates_are_refused_by_name() {
    let video = golf();
    for bad in ["0", "-2", "fast", "nan"] {
        let arg = format!("--pose-fps={bad}");
        let err = refused(&["extract", &video, "-o", "/nonexistent/x.npz", &arg]);
        assert!(err.contains("pose_fps"), "{bad}: {err}");
    }
    let err = refused(&[
        "run",
        &video,
        "--out",
        "/nonexistent/out",
        "--pose-fps",
        "0",
    ]);
    assert!(err.contains("pose_fps"), "{err}");
}
