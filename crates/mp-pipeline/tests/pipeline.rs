//! The pipeline on real shared videos, as `mp run` runs it: counts from
//! keypoints and from frames, a single swing that must not count, the output
//! folder, and cancellation.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use mp_geom::CancelToken;
use mp_pipeline::{analyse_input, run, Input, Observer, Params, PipelineError, Silent, Stage};

/// A shared data file, or `None` (the running test's skip is recorded).
fn data(rel: &str) -> Option<PathBuf> {
    mp_geom::test_support::data_file_or_skip(rel, &mp_geom::test_support::current_test_name())
}

fn quva(name: &str) -> Option<(PathBuf, usize)> {
    let video = data(&format!("quva_repetition/videos/{name}.mp4"))?;
    let ann = data(&format!("quva_repetition/annotations/{name}.npy"))?;
    let truth = mp_geom::read_npy(ann).unwrap().to_i64().unwrap().len();
    Some((video, truth))
}

fn count_video(path: &Path) -> mp_pipeline::Outcome {
    let input = Input::open(path, None).unwrap();
    analyse_input(input, &Params::default(), &Silent, &CancelToken::new())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn quva_videos_count_within_one() {
    for name in ["020_fitness", "023_fitness", "007_pommel_practice"] {
        let Some((video, truth)) = quva(name) else {
            return;
        };
        let out = count_video(&video);
        let c = &out.counts;
        assert!(
            (c.total as i64 - truth as i64).abs() <= 1,
            "{name}: counted {} ({} / {}), labelled {truth}",
            c.total,
            c.signal.as_str(),
            c.method.as_str()
        );
        assert!(
            out.analysis.is_some(),
            "{name}: a person is found, so programs exist"
        );
        assert_eq!(c.frames, out.keypoints.track.n_frames());
    }
}

#[test]
fn a_bar_lift_in_the_dark_counts_from_the_frames() {
    let Some((video, truth)) = quva("028_bar_lift") else {
        return;
    };
    let out = count_video(&video);
    let c = &out.counts;
    assert_eq!(c.signal, mp_abstract::CountSignal::Frames, "{c:?}");
    assert!(
        (c.total as i64 - truth as i64).abs() <= 1,
        "counted {}, labelled {truth}",
        c.total
    );
    // The backlit performer's keypoints (found by the tiled detector, which
    // MediaPipe's single-person pipeline misses here) are less periodic than
    // the pixels of their own box: the frames decide.
}

#[test]
fn one_golf_swing_counts_zero() {
    let Some(video) = data("golfdb/golf_swing.mp4") else {
        return;
    };
    let out = count_video(&video);
    assert_eq!(out.counts.total, 0, "{:?}", out.counts);
    assert!(out.counts.intervals.is_empty());
}

/// Cancels the run once the pose model has done `after` frames.
struct CancelAfter {
    token: CancelToken,
    after: usize,
    fired: AtomicBool,
}

impl Observer for CancelAfter {
    fn progress(&self, stage: Stage, done: usize) {
        if stage == Stage::Pose && done >= self.after {
            self.fired.store(true, Ordering::SeqCst);
            self.token.cancel();
        }
    }
}

#[test]
fn run_writes_the_folder_and_a_cancelled_run_leaves_nothing() {
    let Some((video, _)) = quva("023_fitness") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    // A whole run (no overlay video, to keep it short), the report showing
    // every 21st of the 124 frames: as in a long video, few enough for the
    // decoding thread to make their copies.
    let mut params = Params::default();
    params.output.overlay_video = false;
    params.output.report_frames = 6;
    let dir = tmp.path().join("run");
    let s = run(
        Input::open(&video, None).unwrap(),
        &dir,
        &params,
        &Silent,
        &CancelToken::new(),
    )
    .unwrap();
    for f in [
        "track.npz",
        "program.txt",
        "abstract.json",
        "loops.json",
        "report.html",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let loops: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("loops.json")).unwrap()).unwrap();
    assert_eq!(
        loops["version"],
        mp_abstract::RepetitionsJson::LOOPS_VERSION
    );
    assert_eq!(loops["repetitions"]["total"], s.outcome.counts.total);
    assert_eq!(loops["repetitions"]["signal"], "keypoints");
    let mut shown: Vec<String> = std::fs::read_dir(dir.join("report/frames"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    shown.sort();
    let want: Vec<String> = (0..124)
        .step_by(21)
        .map(|i| format!("{i:06}.jpg"))
        .collect();
    assert_eq!(shown, want);
    let stages: Vec<&str> = s.outcome.stages.iter().map(|t| t.stage.name()).collect();
    for st in [
        "decode", "jpeg", "pose", "concrete", "abstract", "count", "pictures", "report",
    ] {
        assert!(stages.contains(&st), "stage {st} missing from {stages:?}");
    }
    // Cancelled during the pose pass: an error, and no folder at all.
    let token = CancelToken::new();
    let obs = CancelAfter {
        token: token.clone(),
        after: 20,
        fired: AtomicBool::new(false),
    };
    let dir2 = tmp.path().join("cancelled");
    let r = run(
        Input::open(&video, None).unwrap(),
        &dir2,
        &params,
        &obs,
        &token,
    );
    assert!(matches!(r, Err(PipelineError::Cancelled)), "{:?}", r.err());
    assert!(obs.fired.load(Ordering::SeqCst));
    assert!(!dir2.exists(), "a cancelled run created {}", dir2.display());
    // An unrelated run afterwards is not affected by that cancellation.
    let again = analyse_input(
        Input::open(&video, None).unwrap(),
        &params,
        &Silent,
        &CancelToken::new(),
    );
    assert!(again.is_ok());
}

#[test]
fn bad_input_gives_clear_errors() {
    let e = Input::open("/nonexistent/clip.mp4", None).unwrap_err();
    assert!(e.to_string().contains("does not exist"), "{e}");
    let tmp = tempfile::tempdir().unwrap();
    let junk = tmp.path().join("junk.npz");
    std::fs::write(&junk, b"not a zip").unwrap();
    let e = Input::open(&junk, None).unwrap_err();
    assert!(e.to_string().contains("junk.npz"), "{e}");
    let corrupt = tmp.path().join("corrupt.mp4");
    std::fs::write(&corrupt, b"\x00\x00\x00\x18ftypmp42 garbage").unwrap();
    let r = analyse_input(
        Input::open(&corrupt, None).unwrap(),
        &Params::default(),
        &Silent,
        &CancelToken::new(),
    );
    let e = r.err().expect("a corrupt video is an error");
    assert!(e.to_string().contains("corrupt.mp4"), "{e}");
    let mut p = Params::default();
    p.pose.threads = 0;
    assert!(p.validate().is_err());
    p = Params::default();
    p.count.min_strength = f64::NAN;
    assert!(p.validate().is_err());
}

#[test]
fn cmu_exercise_blocks_are_counted_one_by_one() {
    let Some(path) = data("cmu_mocap6_exercise/14_14_features10fps.npz") else {
        return;
    };
    let c = mp_geom::CmuFeatures::open(path).unwrap();
    // Labelled blocks: maximal runs of one label.
    let mut blocks = Vec::new();
    let mut s = 0;
    for i in 1..=c.labels.len() {
        if i == c.labels.len() || c.labels[i] != c.labels[s] {
            blocks.push((s, i));
            s = i;
        }
    }
    let counts = mp_pipeline::count(&c.track, None, &Params::default()).unwrap();
    assert_eq!(counts.method, mp_abstract::CountMethod::Intervals);
    assert_eq!(
        counts.intervals.len(),
        blocks.len(),
        "{:?} vs {blocks:?}",
        counts
            .intervals
            .iter()
            .map(|i| (i.start_frame, i.end_frame))
            .collect::<Vec<_>>()
    );
    for (iv, b) in counts.intervals.iter().zip(&blocks) {
        let m = mp_abstract::iom((iv.start_frame, iv.end_frame), *b);
        assert!(m > 0.5, "interval {iv:?} vs block {b:?}: IoM {m:.2}");
        assert!(iv.count >= 1);
    }
}

#[test]
fn an_analyser_reuses_its_model_and_gives_the_same_results() {
    let (Some((a, _)), Some((b, _))) = (quva("023_fitness"), quva("020_fitness")) else {
        return;
    };
    let mut analyser = mp_pipeline::Analyser::new(Params::default()).unwrap();
    let cancel = CancelToken::new();
    for video in [&a, &b, &a] {
        let reused = analyser
            .analyse(Input::open(video, None).unwrap(), &Silent, &cancel)
            .unwrap();
        let fresh = count_video(video);
        assert_eq!(reused.counts, fresh.counts, "{}", video.display());
        assert_eq!(
            reused.keypoints.track.positions(),
            fresh.keypoints.track.positions(),
            "the pose model's tracking state must not carry over between videos"
        );
    }
}
