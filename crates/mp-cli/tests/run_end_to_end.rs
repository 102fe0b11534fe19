//! End-to-end checks of `mp run` through the built binary: a real video clip
//! (the first 60 frames of the GolfDB swing), a real keypoint track file,
//! bad input, Ctrl-C, and the report opened in headless Chromium.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use mp_concrete::Program;
use mp_geom::read_track;
use mp_geom::Track;

const GOLF_FRAMES: usize = 60;

use common::{mp_command as mp, report_data, run_ok};

/// One run of `mp run` on the first 60 frames of the golf swing, shared by the tests below;
/// `None` (the skip recorded for the running test) where the shared video is absent.
fn golf_run() -> Option<&'static Path> {
    let video = mp_geom::test_support::data_file_or_skip(
        "golfdb/golf_swing.mp4",
        &mp_geom::test_support::current_test_name(),
    )?;
    static RUN: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, dir) = RUN.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("golf");
        run_ok(mp().arg("run").arg(&video).arg("--out").arg(&dir).args([
            "--max-frames",
            &GOLF_FRAMES.to_string(),
            "--quiet",
        ]));
        (tmp, dir)
    });
    Some(dir)
}

/// Names left in a folder that look like temporary or partial files.
fn leftovers(dir: &Path) -> Vec<String> {
    let mut bad = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with(".mp-") || name.ends_with(".tmp") || name.starts_with('.') {
                bad.push(e.path().display().to_string());
            }
            if e.path().is_dir() {
                stack.push(e.path());
            }
        }
    }
    bad
}

/// The content of one of the report's data files (`report/…`).
fn report_file(dir: &Path, rel: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"));
    mp_report::registered(&text)
        .unwrap_or_else(|| panic!("{rel} does not register its content"))
        .2
}

/// Every file under `dir`, relative to `base`.
fn files_under(base: &Path, dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(files_under(base, &p));
        } else {
            out.push(p.strip_prefix(base).unwrap().display().to_string());
        }
    }
    out
}

fn png_luma_variance(bytes: &[u8]) -> (u32, u32, f64) {
    let img = image::load_from_memory(bytes)
        .expect("not a PNG")
        .to_luma8();
    let (w, h) = img.dimensions();
    let n = img.as_raw().len() as f64;
    let mean = img.as_raw().iter().map(|&v| v as f64).sum::<f64>() / n;
    let var = img
        .as_raw()
        .iter()
        .map(|&v| (v as f64 - mean).powi(2))
        .sum::<f64>()
        / n;
    (w, h, var)
}

fn check_outputs(
    dir: &Path,
    frames: usize,
    joints: usize,
    video: bool,
    frame_px: f64,
) -> (Track, Program) {
    for f in [
        "track.npz",
        "program.txt",
        "program.json",
        "abstract.txt",
        "abstract.json",
        "loops.json",
        "timeline.svg",
        "timeline.png",
        "contact_sheet.png",
        "report.html",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing in {}", dir.display());
    }
    assert_eq!(
        dir.join("overlay.mp4").is_file(),
        video,
        "overlay.mp4 only for video input"
    );
    assert!(
        leftovers(dir).is_empty(),
        "temporary files left: {:?}",
        leftovers(dir)
    );

    // Frame counts agree across the track, the program, the loops and the report.
    let track = read_track(dir.join("track.npz")).unwrap();
    assert_eq!(track.n_frames(), frames);
    assert_eq!(track.n_joints(), joints);
    let program = Program::read(dir.join("program.json")).unwrap();
    assert_eq!(program.n_frames(), frames);
    assert_eq!(program.joints, track.skeleton().joints);
    let text = Program::read(dir.join("program.txt")).unwrap();
    assert_eq!(text, program, "program.txt and program.json differ");
    let abs = mp_abstract::AbstractProgram::read(dir.join("abstract.json")).unwrap();
    let abs_txt = mp_abstract::AbstractProgram::read(dir.join("abstract.txt")).unwrap();
    assert_eq!(abs.stmts.len(), abs_txt.stmts.len());
    let loops: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("loops.json")).unwrap()).unwrap();
    assert_eq!(loops["frames"], frames);
    let reps = &loops["repetitions"];
    let intervals = reps["intervals"].as_array().unwrap();
    let mut total = 0;
    for iv in intervals {
        let (first, last) = (
            iv["first_frame"].as_u64().unwrap() as usize,
            iv["last_frame"].as_u64().unwrap() as usize,
        );
        assert!(first <= last && last < frames);
        let count = iv["count"].as_u64().unwrap() as usize;
        total += count;
        // Every repetition's [first, last], inside the interval, in order.
        let r = iv["repetitions"].as_array().unwrap();
        assert_eq!(r.len(), count);
        assert_eq!(r[0][0].as_u64().unwrap() as usize, first);
        assert_eq!(r[count - 1][1].as_u64().unwrap() as usize, last);
    }
    assert_eq!(reps["total"].as_u64().unwrap() as usize, total);
    // The page is small; its frames and data lie in report/, every file of
    // which is in the run's list.
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(html.len() < 300_000, "report.html is {} B", html.len());
    let d = report_data(&html);
    assert_eq!(d["people"][0]["frames"], frames);
    assert_eq!(d["joints"].as_array().unwrap().len(), joints);
    assert_eq!(
        d["pictures"].as_array().unwrap().len(),
        if video { frames } else { 0 },
        "one picture per analysed frame of a short video"
    );
    let person = report_file(dir, "report/p0/person.js");
    assert_eq!(person["bounds"].as_array().unwrap().last().unwrap(), frames);
    assert_eq!(
        person["repetitions"].as_array().unwrap().len(),
        intervals.len()
    );
    let statements: usize = (0..joints)
        .map(|j| {
            report_file(dir, &format!("report/p0/joint-{j:02}.js"))["listing"]
                .as_array()
                .unwrap()
                .len()
        })
        .sum();
    assert_eq!(
        statements,
        program.n_segments() * program.n_joints(),
        "the listings hold every statement of every joint"
    );
    let listed = std::fs::read_to_string(dir.join("mp-run-files.txt")).unwrap();
    let listed: Vec<&str> = listed.lines().collect();
    let folder = files_under(dir, &dir.join("report"));
    assert!(!folder.is_empty());
    for f in &folder {
        assert!(
            listed.contains(&f.as_str()),
            "{f} is not in mp-run-files.txt"
        );
    }
    assert!(
        !html.contains("https://"),
        "the report must not load anything from the network"
    );
    assert!(
        !html.contains("data:image"),
        "the frames lie beside the page, not in it"
    );

    // The program reproduces the keypoints.
    let exec = program.execute().unwrap();
    let kd = mp_geom::kd(&track, &exec).unwrap();
    // 10 px at the 512-px reference frame.
    assert!(
        kd < 10.0 * frame_px / 512.0,
        "KD between program and keypoints is {kd:.2} px"
    );

    // One plot per joint, SVG and PNG, and pictures that are not blank.
    let plots: Vec<_> = std::fs::read_dir(dir.join("plots"))
        .unwrap()
        .flatten()
        .collect();
    assert_eq!(
        plots
            .iter()
            .filter(|e| e.path().extension().is_some_and(|x| x == "svg"))
            .count(),
        joints
    );
    assert_eq!(
        plots
            .iter()
            .filter(|e| e.path().extension().is_some_and(|x| x == "png"))
            .count(),
        joints
    );
    for f in ["timeline.png", "contact_sheet.png"] {
        let (w, h, var) = png_luma_variance(&std::fs::read(dir.join(f)).unwrap());
        assert!(
            w > 200 && h > 150 && var > 50.0,
            "{f}: {w}×{h}, variance {var:.1}"
        );
    }
    (track, program)
}

#[test]
fn run_on_golf_clip_writes_consistent_outputs() {
    let Some(dir) = golf_run() else {
        return;
    };
    let (track, _) = check_outputs(dir, GOLF_FRAMES, 17, true, 492.0);
    assert_eq!(track.skeleton().name, "coco17");
    assert!((track.fps() - 29.97).abs() < 0.01);
    // The overlay video has one frame per analysed frame, at the video's size.
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-count_frames", "-select_streams", "v:0"])
        .args([
            "-show_entries",
            "stream=width,height,nb_read_frames",
            "-of",
            "csv=p=0",
        ])
        .arg(dir.join("overlay.mp4"))
        .output()
        .expect("ffprobe missing (scripts/setup.sh installs FFmpeg)");
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        format!("354,492,{GOLF_FRAMES}")
    );
    // The frames lie beside the report, one per analysed frame.
    for f in 0..GOLF_FRAMES {
        let jpg = std::fs::read(dir.join(format!("report/frames/{f:06}.jpg"))).unwrap();
        assert_eq!(mp_report::jpeg_size(&jpg), Some((354, 492)));
    }
}

#[test]
fn fit_on_the_runs_track_reproduces_its_program() {
    let Some(dir) = golf_run() else {
        return;
    };
    // The track keeps the video frame it is in, so its program is fitted
    // at the same scale as `mp run`'s.
    let read = mp_geom::read_track_rated(dir.join("track.npz"), &Default::default()).unwrap();
    assert_eq!(read.frame_size, Some((354, 492)));
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("p.txt");
    run_ok(
        mp().arg("fit")
            .arg(dir.join("track.npz"))
            .arg("-o")
            .arg(&p)
            .arg("--quiet"),
    );
    assert_eq!(
        std::fs::read_to_string(&p).unwrap(),
        std::fs::read_to_string(dir.join("program.txt")).unwrap()
    );
}

#[test]
fn run_on_track_file() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    let input = mp_geom::data_or_return!("reference_keypoints/027_fitness.npz");
    let out = run_ok(mp().arg("run").arg(&input).arg("--out").arg(&dir).args([
        "--max-frames",
        "90",
        "--frame-size",
        "640",
    ]));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("report.html"), "{stdout}");
    assert!(
        stdout.contains("concrete") && stdout.contains("total"),
        "stage timings missing:\n{stdout}"
    );
    check_outputs(&dir, 90, 33, false, 640.0);
}

#[test]
fn corrupt_and_missing_inputs_fail_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    // Random bytes named .mp4.
    let bad = tmp.path().join("noise.mp4");
    let bytes: Vec<u8> = (0..20_000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    std::fs::write(&bad, bytes).unwrap();
    let out = mp()
        .arg("run")
        .arg(&bad)
        .arg("--out")
        .arg(tmp.path().join("o1"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert_ne!(out.status.code(), Some(0));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("error:") && err.contains("noise.mp4"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    // A missing file.
    let out = mp()
        .arg("run")
        .arg(tmp.path().join("absent.mp4"))
        .arg("--out")
        .arg(tmp.path().join("o2"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("absent.mp4") && err.contains("does not exist"),
        "{err}"
    );
    assert!(!tmp.path().join("o2").exists());
    assert!(
        !tmp.path().join("o1").exists(),
        "no output folder for an unreadable input"
    );
    // A track file that is not a track.
    let txt = tmp.path().join("notes.csv");
    std::fs::write(&txt, "hello\nworld\n").unwrap();
    let out = mp()
        .arg("run")
        .arg(&txt)
        .arg("--out")
        .arg(tmp.path().join("o3"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("notes.csv"), "{err}");
}

#[test]
fn interrupted_run_leaves_no_partial_files() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    let mut child = mp()
        .arg("run")
        .arg(mp_geom::data_or_return!("golfdb/golf_swing.mp4"))
        .arg("--out")
        .arg(&dir)
        .arg("--quiet")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the run is writing its files (the programs come first, then
    // the pictures and the overlay video), then interrupt it.
    let t0 = Instant::now();
    while !dir.join("loops.json").exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(600),
            "mp run wrote nothing in 10 minutes"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "mp run ended before it could be interrupted"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let t1 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        assert!(
            t1.elapsed() < Duration::from_secs(30),
            "mp did not stop after Ctrl-C"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut err = String::new();
    use std::io::Read;
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert_eq!(status.code(), Some(130), "stderr: {err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(
        leftovers(&dir).is_empty(),
        "left after Ctrl-C: {:?}",
        leftovers(&dir)
    );
    // What is there is complete; the report, written last, is not.
    assert!(!dir.join("report.html").exists());
    Program::read(dir.join("program.json")).unwrap();
    read_track(dir.join("track.npz")).unwrap();
    for e in std::fs::read_dir(dir.join("plots"))
        .into_iter()
        .flatten()
        .flatten()
    {
        if e.path().extension().is_some_and(|x| x == "png") {
            image::open(e.path()).unwrap_or_else(|err| panic!("{}: {err}", e.path().display()));
        }
    }
}

/// Runs headless Chromium on a page with the given extra arguments.
fn chromium(page: &Path, profile: &Path, extra: &[&str]) -> Output {
    common::browser::chromium_at(page, "", profile, extra)
}

#[test]
fn report_renders_in_headless_chromium() {
    let Some(dir) = golf_run() else {
        return;
    };
    let page = dir.join("report.html");
    let tmp = tempfile::tempdir().unwrap();

    // Screenshot: not blank.
    let shot = tmp.path().join("shot.png");
    let out = chromium(
        &page,
        &tmp.path().join("p1"),
        &[&format!("--screenshot={}", shot.display())],
    );
    assert!(
        shot.is_file(),
        "no screenshot; stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (w, h, var) = png_luma_variance(&std::fs::read(&shot).unwrap());
    assert_eq!((w, h), (1280, 900));
    assert!(
        var > 300.0,
        "screenshot looks blank (luma variance {var:.1})"
    );

    // The page opened at its first frame, and at a late one: the picture of
    // that frame and its keypoints (from the data file) are loaded and drawn.
    let dom = common::browser::check_opens_at(&page, "", &tmp.path().join("p2"), Some(0), Some(0));
    let late = GOLF_FRAMES - 5;
    common::browser::check_opens_at(
        &page,
        &format!("#frame={late}"),
        &tmp.path().join("p3"),
        Some(late),
        Some(late),
    );
    // The listing is there and the running statement is highlighted.
    assert!(dom.contains("class=\"listing\""));
    assert!(
        dom.matches(" active\"").count() >= 1,
        "no highlighted statement"
    );
    // The skeletons were drawn over the frame.
    let stage = common::browser::start_tag(&dom, "<canvas id=\"stage\"");
    let ink: usize = common::browser::attr(stage, "data-ink")
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("canvas not measured: {stage}"));
    assert!(ink > 500, "no skeleton on the stage ({ink} pixels painted)");
    // The timeline SVG was loaded and got its cursor.
    assert!(dom.contains("class=\"mp-timeline\""));
    assert!(dom.contains("fill=\"#facc15\""), "timeline cursor missing");
    // The counted repetitions and the program loops have their panels.
    assert!(dom.contains("id=\"repetitions-body\""));
    assert!(dom.contains("id=\"abstract-body\""));
}
