//! `mp edit`, `mp predict --seconds` and `mp interpolate` on short clips of
//! the shared QUVA videos, checked the product's way: the pipeline's count
//! on the edited video, frame counts, pose KD against the true frames; and
//! the typed errors.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::{Path, PathBuf};

use mp_pipeline::Params;
use mp_pose::VideoReader;
use mp_video::{
    edit_video, interpolate_video, predict_video, EditChange, EditParams, InterpMethod,
    InterpParams, VideoError, VideoMotion, VideoPredictMethod, VideoPredictParams,
};
use mp_video::{interpolate_frames, keep_every};

/// The first `seconds` of `video`, re-encoded losslessly into `dir`.
fn clip(video: &Path, seconds: f64, dir: &Path) -> PathBuf {
    let out = dir.join("clip.mkv");
    let st = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-y", "-i"])
        .arg(video)
        .args(["-t", &seconds.to_string(), "-an", "-c:v", "ffv1"])
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    out
}

fn frames(p: &Path) -> usize {
    VideoReader::open(p).unwrap().count()
}

#[test]
fn edit_adds_and_removes_one_repetition() {
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let dir = tempfile::tempdir().unwrap();
    let params = Params::default();
    let before = VideoMotion::analyse(&video, &params, None).unwrap();
    let iv = before.counts.intervals[0].clone();
    for (change, k) in [(EditChange::Add(1), 1i64), (EditChange::Remove(1), -1)] {
        let out = dir.path().join(format!("edit{k}.mp4"));
        let r = edit_video(&video, 1, change, &EditParams::default(), &params, &out).unwrap();
        assert_eq!(r.change, k);
        // Frame count: the repeated iteration's length, up to the seam adjustment.
        let n = frames(&out) as i64;
        let seg = (r.segment.1 - r.segment.0) as i64;
        let iter = (r.repetition.1 - r.repetition.0) as i64;
        assert_eq!(n, before.n_frames() as i64 + k * seg, "{r:?}");
        let slack = 2 * EditParams::default().seam_search as i64;
        assert!(
            (seg - iter).abs() <= slack,
            "segment {seg}, iteration {iter}"
        );
        // The pipeline counts K more (or fewer) in that interval.
        let after = VideoMotion::analyse(&out, &params, None).unwrap();
        let c = &after.counts.intervals[0];
        assert_eq!(
            c.count as i64,
            iv.count as i64 + k,
            "{:?} → {:?}",
            iv,
            after.counts.intervals
        );
        // No partial file is left next to the output.
        let leftovers: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".partial-"))
            .collect();
        assert!(leftovers.is_empty());
    }
}

#[test]
fn predict_writes_the_expected_length() {
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let dir = tempfile::tempdir().unwrap();
    let input = clip(&video, 3.0, dir.path());
    let n = frames(&input);
    let info = mp_pose::probe(&input).unwrap();
    let out = dir.path().join("pred.mp4");
    let r = predict_video(
        &input,
        1.5,
        VideoPredictMethod::Loop,
        &VideoPredictParams::default(),
        &Params::default(),
        &out,
    )
    .unwrap();
    let expect = (1.5 * info.fps).round() as usize;
    assert_eq!(r.predicted, expect);
    assert_eq!(
        r.used,
        VideoPredictMethod::Loop,
        "a loop is counted in the clip"
    );
    assert_eq!(frames(&out), n + expect);
}

#[test]
fn interpolation_beats_linear_blending_in_kd() {
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let dir = tempfile::tempdir().unwrap();
    let k = 2;
    let truth_clip = clip(&video, 2.0, dir.path());
    let kept = dir.path().join("kept.mkv");
    let m = keep_every(&truth_clip, k, None, &kept).unwrap();
    let n_out = (m - 1) * k + 1;
    let params = Params::default();
    // The pose of the true frames.
    let truth = VideoMotion::analyse(&truth_clip, &params, Some(n_out))
        .unwrap()
        .track;
    let info = mp_pose::probe(&truth_clip).unwrap();
    let kd_of = |method: InterpMethod| -> f64 {
        let out = dir.path().join(format!("{}.mkv", method.as_str()));
        // Lossless copy of the rebuilt frames for the pose model.
        let raw = dir.path().join(format!("{}.rgb", method.as_str()));
        let mut bytes = Vec::new();
        let r = interpolate_frames(&kept, k, method, &InterpParams::default(), &params, |rgb| {
            bytes.extend_from_slice(rgb);
            Ok(())
        })
        .unwrap();
        assert_eq!(r.frames_out, n_out);
        std::fs::write(&raw, &bytes).unwrap();
        let st = std::process::Command::new("ffmpeg")
            .args([
                "-v", "error", "-nostdin", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s",
            ])
            .arg(format!("{}x{}", info.width, info.height))
            .arg("-r")
            .arg(info.fps.to_string())
            .arg("-i")
            .arg(&raw)
            .args(["-c:v", "ffv1"])
            .arg(&out)
            .status()
            .unwrap();
        assert!(st.success());
        let rebuilt = VideoMotion::analyse(&out, &params, None).unwrap().track;
        let (mut s, mut c) = (0.0, 0usize);
        for t in (0..n_out).filter(|t| !t.is_multiple_of(k)) {
            for j in [7, 8, 9, 10] {
                if truth.is_valid(t, j, 0.3) && rebuilt.is_valid(t, j, 0.3) {
                    let (p, q) = (truth.point(t, j), rebuilt.point(t, j));
                    s += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                    c += 1;
                }
            }
        }
        assert!(c > 0);
        s / c as f64
    };
    let ours = kd_of(InterpMethod::Program);
    let linear = kd_of(InterpMethod::Linear);
    assert!(ours < linear, "program {ours:.2} px, linear {linear:.2} px");
}

#[test]
fn errors_are_typed() {
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let dir = tempfile::tempdir().unwrap();
    let input = clip(&video, 2.0, dir.path());
    let params = Params::default();
    let out = dir.path().join("x.mp4");
    // Factor below 2 (and any factor other than 2, 4, 8).
    for f in [0, 1, 3] {
        let e = interpolate_video(
            &input,
            f,
            InterpMethod::Program,
            &InterpParams::default(),
            &params,
            &out,
        )
        .unwrap_err();
        assert!(matches!(e, VideoError::Factor(x) if x == f), "{e}");
    }
    // Absurd seconds.
    for s in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e9] {
        let e = predict_video(
            &input,
            s,
            VideoPredictMethod::Loop,
            &VideoPredictParams::default(),
            &params,
            &out,
        )
        .unwrap_err();
        assert!(matches!(e, VideoError::Seconds { .. }), "{e}");
    }
    // No such loop.
    let e = edit_video(
        &input,
        7,
        EditChange::Add(1),
        &EditParams::default(),
        &params,
        &out,
    )
    .unwrap_err();
    assert!(matches!(e, VideoError::NoInterval { number: 7, .. }), "{e}");
    // Removing every repetition.
    let e = edit_video(
        &input,
        1,
        EditChange::Remove(50),
        &EditParams::default(),
        &params,
        &out,
    )
    .unwrap_err();
    assert!(matches!(e, VideoError::Edit(_)), "{e}");
    assert!(!out.exists(), "nothing is written on error");
}

#[test]
fn a_video_without_a_person_is_an_error() {
    // The pose model comes with the shared data sets.
    let _ = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let dir = tempfile::tempdir().unwrap();
    // Two seconds of a moving test pattern, no person in it.
    let video = dir.path().join("pattern.mp4");
    let st = std::process::Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-nostdin",
            "-y",
            "-f",
            "lavfi",
            "-i",
            "testsrc=size=160x120:rate=15:duration=2",
        ])
        .args(["-pix_fmt", "yuv420p"])
        .arg(&video)
        .status();
    if !st.is_ok_and(|s| s.success()) {
        eprintln!("skipped: ffmpeg cannot make a test pattern");
        return;
    }
    let params = Params::default();
    let out = dir.path().join("x.mp4");
    let e = interpolate_video(
        &video,
        2,
        InterpMethod::Program,
        &InterpParams::default(),
        &params,
        &out,
    )
    .unwrap_err();
    assert!(matches!(e, VideoError::NoPerson(_)), "{e}");
    let e = edit_video(
        &video,
        1,
        EditChange::Add(1),
        &EditParams::default(),
        &params,
        &out,
    )
    .unwrap_err();
    assert!(
        matches!(e, VideoError::NoPerson(_) | VideoError::NoInterval { .. }),
        "{e}"
    );
    let e = predict_video(
        &video,
        1.0,
        VideoPredictMethod::Loop,
        &VideoPredictParams::default(),
        &params,
        &out,
    )
    .unwrap_err();
    assert!(matches!(e, VideoError::NoPerson(_)), "{e}");
    assert!(!out.exists());
}
