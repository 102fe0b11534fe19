//! The report page of `mp run` opened in headless Chromium from disk: a
//! whole clip whose data spans several files (scrubbed to late frames), a
//! video with nobody in it, and two people with a link that picks one.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use std::path::Path;
use std::process::Command;

use common::browser::{attr, check_opens_at, chromium_at, start_tag, status};

use common::{mp_command as mp, report_data, run_ok};

fn loops_json(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("loops.json")).unwrap()).unwrap()
}

/// The value of the summary card captioned `label`.
fn card(html: &str, label: &str) -> String {
    let key = format!(r#"<div class="l">{label}</div><div class="v">"#);
    let start = html.find(&key).unwrap_or_else(|| panic!("no {label} card")) + key.len();
    html[start..start + html[start..].find('<').unwrap()].to_string()
}

/// The terminal, `loops.json` and the report show the same repetitions and
/// the same program loops (numbers, frames and iterations).
fn counts_agree(stdout: &str, dir: &Path, html: &str) {
    let loops = loops_json(dir);
    let reps = loops["repetitions"]["total"].as_u64().unwrap();
    let ploops = loops["program_loops"].as_array().unwrap();
    // Terminal.
    assert!(
        stdout.contains(&format!("\n{reps} repetition"))
            || stdout.starts_with(&format!("{reps} repetition")),
        "{stdout}"
    );
    let n = ploops.len();
    assert!(
        stdout.contains(&format!(
            "the abstract program has {n} program loop{}",
            if n == 1 { "" } else { "s" }
        )),
        "{stdout}"
    );
    assert!(
        stdout.contains(&format!(
            "(main): frames 0–263 (0.0–8.8 s, found in 264) · {reps} repetition"
        )),
        "{stdout}"
    );
    // The report's cards.
    assert_eq!(card(html, "repetitions"), reps.to_string());
    assert_eq!(card(html, "program loops"), n.to_string());
    // The person's panels: every program loop with its frames and iterations,
    // and as many counted intervals as loops.json has.
    let person = std::fs::read_to_string(dir.join("report/p0/person.js")).unwrap();
    let row =
        regex::Regex::new(r"<tr><td>([0-9]+)</td><td>([^<]*)</td><td>[^<]*</td><td>×([0-9]+)</td>")
            .unwrap();
    let shown: Vec<(String, String)> = row
        .captures_iter(&person)
        .map(|c| (c[2].to_string(), c[3].to_string()))
        .collect();
    let written: Vec<(String, String)> = ploops
        .iter()
        .map(|l| {
            (
                format!("{}–{}", l["first_frame"], l["last_frame"]),
                l["iterations"].to_string(),
            )
        })
        .collect();
    assert_eq!(shown, written, "program loops: report vs loops.json");
    let count = regex::Regex::new(r#"<td class=\\?"count\\?">×([0-9]+)</td>"#).unwrap();
    let shown: Vec<u64> = count
        .captures_iter(&person)
        .map(|c| c[1].parse().unwrap())
        .collect();
    let written: Vec<u64> = loops["repetitions"]["intervals"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["count"].as_u64().unwrap())
        .collect();
    assert_eq!(shown, written, "counted intervals: report vs loops.json");
    assert_eq!(written.iter().sum::<u64>(), reps);
}

/// The whole golf swing (264 frames: two data files of 256 frames): the page
/// opens at frames in either, with their pictures and keypoints.
#[test]
fn a_whole_clip_loads_the_frames_and_data_it_scrubs_to() {
    let video = mp_geom::data_or_return!("golfdb/golf_swing.mp4");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("golf");
    let out = run_ok(
        mp().arg("run")
            .arg(&video)
            .arg("--out")
            .arg(&dir)
            .arg("--no-video"),
    );
    let page = dir.join("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    counts_agree(&String::from_utf8_lossy(&out.stdout), &dir, &html);
    let d = report_data(&html);
    assert_eq!(d["people"][0]["frames"], 264);
    assert_eq!(d["people"][0]["chunks"], 2);
    assert!(dir.join("report/p0/data-0001.js").is_file());
    for (k, f) in [10usize, 200, 260, 263].into_iter().enumerate() {
        check_opens_at(
            &page,
            &format!("#frame={f}&joint=right_wrist"),
            &tmp.path().join(format!("p{k}")),
            Some(f),
            Some(f),
        );
    }
}

/// A video in which nobody appears: `mp run` succeeds and says where the
/// report is; the page plays the frames, says that nobody was found and
/// shows the repetitions counted from the frames (none here), without
/// program panels.
#[test]
fn a_video_with_nobody_gets_a_report() {
    let tmp = tempfile::tempdir().unwrap();
    let video = tmp.path().join("pattern.mp4");
    let st = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-y", "-f", "lavfi", "-i"])
        .arg("testsrc2=size=320x240:rate=25")
        .args(["-t", "3", "-pix_fmt", "yuv420p"])
        .arg(&video)
        .status();
    if !st.is_ok_and(|s| s.success()) {
        mp_geom::test_support::skip_test(
            &mp_geom::test_support::current_test_name(),
            "ffmpeg's lavfi testsrc2",
        );
        return;
    }
    let dir = tmp.path().join("out");
    let out = run_ok(mp().arg("run").arg(&video).arg("--out").arg(&dir));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let page = dir.join("report.html");
    assert!(
        stdout.contains(&format!("Report: {}", page.display())),
        "{stdout}"
    );
    let loops = loops_json(&dir);
    assert_eq!(loops["repetitions"]["total"], 0);
    assert_eq!(loops["program_loops"].as_array().unwrap().len(), 0);
    assert_eq!(loops["frames"], 75);
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        html.contains("No person was found in this video"),
        "no notice"
    );
    assert!(
        html.contains("blazepose"),
        "the notice names the pose model"
    );
    assert!(
        html.contains("its 75 frames"),
        "the notice names the frames examined"
    );
    for absent in [
        "id=\"program\"",
        "id=\"timeline\"",
        "id=\"trajectory\"",
        "id=\"abstract\"",
    ] {
        assert!(
            !html.contains(absent),
            "{absent} on a page without a program"
        );
    }
    assert!(html.contains("<div class=\"l\">repetitions</div><div class=\"v\">0</div>"));
    assert!(!dir.join("program.txt").exists());
    let listed = std::fs::read_to_string(dir.join("mp-run-files.txt")).unwrap();
    assert!(
        listed.lines().any(|l| l == "report/frames/000074.jpg"),
        "{listed}"
    );
    assert!(listed.lines().any(|l| l == "report.html"));
    for f in [0usize, 70] {
        let dom = check_opens_at(
            &page,
            &format!("#frame={f}"),
            &tmp.path().join(format!("p{f}")),
            Some(f),
            None,
        );
        assert!(
            dom.contains("No repetition was counted"),
            "the repetitions panel"
        );
    }
}

/// Two exercising people side by side (020_fitness and 027_fitness, 3 s):
/// the report's people strip has a row each, and a link that names the
/// other person opens the page on their analysis.
#[test]
fn report_picks_the_person_a_link_names() {
    let test = mp_geom::test_support::current_test_name();
    let Some(a) =
        mp_geom::test_support::data_file_or_skip("quva_repetition/videos/020_fitness.mp4", &test)
    else {
        return;
    };
    let Some(b) =
        mp_geom::test_support::data_file_or_skip("quva_repetition/videos/027_fitness.mp4", &test)
    else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let video = tmp.path().join("two.mp4");
    let status_ok = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(&a)
        .arg("-i")
        .arg(&b)
        .args([
            "-filter_complex",
            "[0:v]fps=30,scale=-2:360,setsar=1[a];[1:v]fps=30,scale=-2:360,setsar=1[b];[a][b]hstack=inputs=2[v]",
            "-map",
            "[v]",
            "-t",
            "3",
            "-c:v",
            "libx264",
            "-preset",
            "veryfast",
            "-pix_fmt",
            "yuv420p",
        ])
        .arg(&video)
        .status()
        .expect("ffmpeg runs");
    assert!(status_ok.success());
    let dir = tmp.path().join("out");
    run_ok(
        mp().arg("run")
            .arg(&video)
            .arg("--out")
            .arg(&dir)
            .args(["--no-video", "--quiet"]),
    );
    let loops = loops_json(&dir);
    let people = loops["people"].as_array().unwrap();
    assert_eq!(people.len(), 2, "{people:?}");
    let other = people
        .iter()
        .find(|p| p["main"] == false)
        .expect("a person besides the main one");
    let (id, first) = (
        other["id"].as_u64().unwrap(),
        other["first_frame"].as_u64().unwrap(),
    );
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert_eq!(html.matches("<g class=\"row\"").count(), 2);
    assert_eq!(report_data(&html)["people"].as_array().unwrap().len(), 2);
    assert_eq!(html.matches("<div class=\"l\">people</div>").count(), 1);
    assert!(dir.join("report/p1/person.js").is_file());

    let out = chromium_at(
        &dir.join("report.html"),
        &format!("#person={id}&frame=45"),
        &tmp.path().join("p"),
        &["--dump-dom"],
    );
    let dom = String::from_utf8_lossy(&out.stdout);
    let st = status(&dom);
    assert!(st.contains("data-errors=\"0\""), "{st}");
    assert!(st.contains("data-ready=\"1\""), "{st}");
    assert!(
        st.contains(&format!("data-person=\"{id}\"")),
        "the page shows person {id}: {st}"
    );
    assert!(st.contains("data-frame=\"45\""), "{st}");
    // The picture of frame 45, and the other person's keypoints there.
    let stage = start_tag(&dom, "<canvas id=\"stage\"");
    assert_eq!(attr(stage, "data-picture"), Some("45"), "{stage}");
    assert_eq!(attr(stage, "data-drawn"), Some("45"), "{stage}");
    // Their listing is shown, its frames in frames of the video from theirs.
    assert!(
        dom.contains(&format!("<span class=\"fr\">{first}–")),
        "the listing starts at frame {first} of the video"
    );
}
