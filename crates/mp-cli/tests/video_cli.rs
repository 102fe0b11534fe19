//! `mp predict VIDEO --seconds`, `mp interpolate` and `mp edit` through the
//! built binary on a short clip of a shared QUVA video, and their error
//! cases: clear messages, exit status 1, nothing written.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use mp_pose::VideoReader;

const CLIP_VIDEO: &str = "quva_repetition/videos/023_fitness.mp4";

fn mp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mp"))
}

mod common;

use common::run_ok;

fn run(cmd: &mut Command) -> Output {
    cmd.output().expect("cannot start the mp binary")
}

/// Runs `cmd`, expects exit status 1 and returns stderr.
fn run_err(cmd: &mut Command) -> String {
    let out = run(cmd);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(1),
        "expected a clean failure, got {}:\nstdout:\n{}\nstderr:\n{err}",
        out.status,
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// The first `seconds` of the shared QUVA video, re-encoded losslessly into
/// `dir`; `None` (the skip recorded) where the shared data are absent.
fn clip(seconds: f64, dir: &Path) -> Option<PathBuf> {
    let video = mp_geom::test_support::data_file_or_skip(
        CLIP_VIDEO,
        &mp_geom::test_support::current_test_name(),
    )?;
    let out = dir.join("clip.mkv");
    let st = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-y", "-i"])
        .arg(&video)
        .args(["-t", &seconds.to_string(), "-an", "-c:v", "ffv1"])
        .arg(&out)
        .status()
        .expect("ffmpeg");
    assert!(st.success());
    Some(out)
}

fn frames(p: &Path) -> usize {
    VideoReader::open(p).unwrap().count()
}

fn fps(p: &Path) -> f64 {
    mp_pose::probe(p).unwrap().fps
}

#[test]
fn predict_seconds_writes_the_expected_frame_count() {
    let dir = tempfile::tempdir().unwrap();
    let Some(input) = clip(3.0, dir.path()) else {
        return;
    };
    let (n, rate) = (frames(&input), fps(&input));
    let out = dir.path().join("continued.mp4");
    let o = run_ok(
        mp().arg("predict")
            .arg(&input)
            .args(["--seconds", "1.5", "-o"])
            .arg(&out),
    );
    let expect = (1.5 * rate).round() as usize;
    assert_eq!(frames(&out), n + expect);
    assert!((fps(&out) - rate).abs() < 0.01);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(&format!("{n} observed + {expect} predicted frames")),
        "{text}"
    );
}

#[test]
fn interpolate_doubles_the_frame_rate() {
    let dir = tempfile::tempdir().unwrap();
    let Some(input) = clip(1.5, dir.path()) else {
        return;
    };
    let (n, rate) = (frames(&input), fps(&input));
    let out = dir.path().join("x2.mp4");
    let o = run_ok(
        mp().arg("interpolate")
            .arg(&input)
            .args(["--factor", "2", "-o"])
            .arg(&out),
    );
    assert_eq!(frames(&out), (n - 1) * 2 + 1);
    assert!((fps(&out) - 2.0 * rate).abs() < 0.01, "{}", fps(&out));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("program"), "the default method: {text}");
}

#[test]
fn errors_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let Some(input) = clip(2.0, dir.path()) else {
        return;
    };
    let out = dir.path().join("x.mp4");

    // No interval 99: the message gives the intervals there are and the
    // numbering.
    let err = run_err(
        mp().arg("edit")
            .arg(&input)
            .args(["--interval", "99", "--add", "1", "-o"])
            .arg(&out),
    );
    assert!(err.contains("no interval 99"), "{err}");
    assert!(err.contains("numbered from 1"), "{err}");
    // Interval 0 does not exist either: intervals are numbered from 1.
    let err = run_err(
        mp().arg("edit")
            .arg(&input)
            .args(["--interval", "0", "--add", "1", "-o"])
            .arg(&out),
    );
    assert!(err.contains("no interval 0"), "{err}");

    // Factors below 2, and factors that are not 2, 4 or 8.
    for f in ["0", "1", "3", "16"] {
        let err = run_err(
            mp().arg("interpolate")
                .arg(&input)
                .args(["--factor", f, "-o"])
                .arg(&out),
        );
        assert!(
            err.contains(&format!("factor {f}")) && err.contains("2, 4, 8"),
            "{err}"
        );
    }

    // A video without --seconds: the error names the flag.
    let err = run_err(mp().arg("predict").arg(&input).arg("-o").arg(&out));
    assert!(err.contains("--seconds"), "{err}");
    // Nor without an output.
    let err = run_err(mp().arg("predict").arg(&input).args(["--seconds", "1"]));
    assert!(err.contains("-o OUT.mp4"), "{err}");
    // Seconds out of range.
    let err = run_err(
        mp().arg("predict")
            .arg(&input)
            .args(["--seconds", "0", "-o"])
            .arg(&out),
    );
    assert!(err.contains("--seconds 0"), "{err}");

    assert!(!out.exists(), "nothing is written on error");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "clip.mkv")
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn a_video_without_a_person_is_a_clear_error() {
    // The pose model is found through the shared data's workspace; skip with them.
    if mp_geom::test_support::data_file_or_skip(
        CLIP_VIDEO,
        &mp_geom::test_support::current_test_name(),
    )
    .is_none()
    {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("pattern.mp4");
    let st = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-y", "-f", "lavfi", "-i"])
        .arg("testsrc=size=160x120:rate=15:duration=2")
        .args(["-pix_fmt", "yuv420p"])
        .arg(&video)
        .status();
    if !st.is_ok_and(|s| s.success()) {
        mp_geom::test_support::skip_test(
            &mp_geom::test_support::current_test_name(),
            "ffmpeg's lavfi testsrc",
        );
        return;
    }
    let out = dir.path().join("x.mp4");
    let err = run_err(
        mp().arg("interpolate")
            .arg(&video)
            .args(["--factor", "2", "-o"])
            .arg(&out),
    );
    assert!(err.contains("no person found"), "{err}");
    let err = run_err(
        mp().arg("predict")
            .arg(&video)
            .args(["--seconds", "1", "-o"])
            .arg(&out),
    );
    assert!(err.contains("no person found"), "{err}");
    let err = run_err(
        mp().arg("edit")
            .arg(&video)
            .args(["--add", "1", "-o"])
            .arg(&out),
    );
    assert!(
        err.contains("no person found") || err.contains("has no repetitions"),
        "{err}"
    );
    assert!(!out.exists());
}
