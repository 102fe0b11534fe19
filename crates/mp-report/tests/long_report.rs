//! The report of an hour: a synthetic hour-long recording (108,000 frames at
//! 30 fps) with the frame store at its cap, hundreds of counted intervals
//! and several people, written as `mp run` writes it
//! ([`mp_report::write_report`], then the page last). The page stays small,
//! the folder within its budget, and every card one line.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod hour_input;

use std::path::Path;

use hour_input::*;
use mp_abstract::{AbstractProgram, RepetitiveInterval};
use mp_concrete::Program;
use mp_geom::Track;

use mp_report::{OutputDir, PersonPage, PersonRow, ProgramView, ReportInput};

/// A person's analysis: program, executed program, keypoints, abstract
/// program and its loops as frame intervals.
struct Person {
    program: Program,
    executed: Track,
    track: Track,
    abstract_program: AbstractProgram,
    loops: Vec<RepetitiveInterval>,
}

fn person(frames: usize, shift: usize) -> Person {
    let program = program(frames, shift);
    let executed = program.execute().unwrap();
    let track = track(&executed);
    let (abstract_program, loops, prims) =
        mp_abstract::AbstractProgram::from_concrete(&program, &mp_abstract::LoopParams::default())
            .unwrap();
    let loops = mp_abstract::intervals(&prims, &loops, 0);
    Person {
        program,
        executed,
        track,
        abstract_program,
        loops,
    }
}

fn folder_bytes(dir: &Path) -> (u64, usize) {
    let (mut bytes, mut files) = (0, 0);
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            let (b, f) = folder_bytes(&p);
            bytes += b;
            files += f;
        } else {
            bytes += e.metadata().unwrap().len();
            files += 1;
        }
    }
    (bytes, files)
}

/// What a written report measured.
struct Written {
    tmp: tempfile::TempDir,
    page: mp_report::ReportPage,
    html_bytes: u64,
    folder: u64,
    frames_bytes: u64,
    data_bytes: u64,
}

fn write(input: &ReportInput<'_>) -> Written {
    let tmp = tempfile::tempdir().unwrap();
    let out = OutputDir::create(tmp.path()).unwrap();
    let t1 = std::time::Instant::now();
    let page = mp_report::write_report(&out, input).unwrap();
    page.write(&out).unwrap();
    drop(out);
    let html_bytes = std::fs::metadata(tmp.path().join("report.html"))
        .unwrap()
        .len();
    let (folder, files) = folder_bytes(&tmp.path().join("report"));
    assert_eq!(files, page.files.len(), "every file is listed for the run");
    let bytes_of = |pick: &dyn Fn(&str) -> bool| -> u64 {
        page.files
            .iter()
            .filter(|f| pick(f))
            .map(|f| std::fs::metadata(tmp.path().join(f)).unwrap().len())
            .sum()
    };
    let frames_bytes = bytes_of(&|f| f.ends_with(".jpg"));
    let data_bytes = bytes_of(&|f| f.contains("/data-"));
    eprintln!(
        "{} people: report.html {html_bytes} B; report/ {folder} B in {files} files: frames {frames_bytes} B, per-frame data {data_bytes} B; written in {:.1} s",
        input.people.len(),
        t1.elapsed().as_secs_f64()
    );
    Written {
        tmp,
        page,
        html_bytes,
        folder,
        frames_bytes,
        data_bytes,
    }
}

#[test]
fn an_hour_makes_a_small_page_and_a_bounded_folder() {
    let t0 = std::time::Instant::now();
    let main = person(HOUR, 0);
    // Five others, ten minutes each, one after the other.
    let others: Vec<(usize, Person)> = (0..5)
        .map(|k| (k * 18_000 + 900, person(18_000, k + 1)))
        .collect();
    let counts = counts(HOUR, 30);
    let store = frame_store();
    eprintln!("inputs built in {:.1} s", t0.elapsed().as_secs_f64());

    let mut people = vec![PersonPage {
        id: Some(1),
        label: "person 1 (main) · 3000 repetitions".into(),
        colour: None,
        offset: 0,
        track: &main.track,
        program: Some(ProgramView {
            concrete: &main.program,
            executed: &main.executed,
            abstract_program: &main.abstract_program,
            loops: &main.loops,
        }),
        repetitions: counts.intervals.clone(),
    }];
    for (k, (offset, p)) in others.iter().enumerate() {
        people.push(PersonPage {
            id: Some(k as u32 + 2),
            label: format!("person {} · 500 repetitions", k + 2),
            colour: Some([0, 158, 115]),
            offset: *offset,
            track: &p.track,
            program: Some(ProgramView {
                concrete: &p.program,
                executed: &p.executed,
                abstract_program: &p.abstract_program,
                loops: &p.loops,
            }),
            repetitions: hour_input::counts(18_000, 0).intervals,
        });
    }
    // The strip: the six analysed, and forty people seen briefly here and there.
    let mut strip: Vec<PersonRow> = (0..6)
        .map(|k| PersonRow {
            id: k as u32 + 1,
            label: format!("person {}", k + 1),
            colour: [0, 158, 115],
            found: (0..3600).map(|s| [s * 30, s * 30 + 25]).collect(),
            repetitions: (0..HOUR / 30).map(|r| [r * 30, r * 30 + 30]).collect(),
            pick: Some(k),
        })
        .collect();
    strip.extend((0..40).map(|k| PersonRow {
        id: k + 7,
        label: format!("person {} · seen briefly", k + 7),
        colour: [204, 121, 167],
        found: vec![[k as usize * 2500, k as usize * 2500 + 40]],
        repetitions: Vec::new(),
        pick: None,
    }));

    let mut input = ReportInput {
        title: "hour.mp4",
        subtitle: "a synthetic hour",
        people,
        counts: &counts,
        frames: Some(&store),
        notice: None,
        cards: Vec::new(),
        files: &["loops.json".into()],
        strip: None,
    };
    // One person: every frame's data (stride 1), within the folder's budget.
    let everyone = std::mem::take(&mut input.people);
    input.people = everyone[..1].to_vec();
    let one = write(&input);
    assert!(
        one.html_bytes <= 2 << 20,
        "report.html is {} B",
        one.html_bytes
    );
    assert!(one.frames_bytes <= mp_report::FRAMES_BUDGET_BYTES as u64);
    // The frame store's 1,200 frames are all there (they fit the budget).
    assert_eq!(
        one.page
            .files
            .iter()
            .filter(|f| f.ends_with(".jpg"))
            .count(),
        1200
    );
    assert_eq!(
        one.page
            .files
            .iter()
            .filter(|f| f.contains("/data-"))
            .count(),
        HOUR.div_ceil(mp_report::CHUNK_FRAMES)
    );
    assert!(
        one.folder <= mp_report::FOLDER_BUDGET_BYTES as u64,
        "report/ is {} B, over its budget of {} B",
        one.folder,
        mp_report::FOLDER_BUDGET_BYTES
    );
    // Six people and a strip of forty-six: the data keeps every second
    // frame, and the folder stays within the budget.
    input.people = everyone;
    input.strip = Some(strip);
    let all = write(&input);
    assert!(
        all.html_bytes <= 2 << 20,
        "report.html is {} B",
        all.html_bytes
    );
    assert!(
        all.data_bytes <= one.data_bytes * 3 / 2,
        "{} B of data",
        all.data_bytes
    );
    assert!(
        all.folder <= mp_report::FOLDER_BUDGET_BYTES as u64,
        "report/ is {} B, over its budget of {} B",
        all.folder,
        mp_report::FOLDER_BUDGET_BYTES
    );
    if let Some(keep) = std::env::var_os("MP_KEEP_HOUR") {
        let keep = std::path::PathBuf::from(keep);
        let _ = std::fs::remove_dir_all(&keep);
        std::fs::create_dir_all(&keep).unwrap();
        std::fs::rename(one.tmp.path(), keep.join("one")).unwrap();
        std::fs::rename(all.tmp.path(), keep.join("all")).unwrap();
        return;
    }
    let tmp = all.tmp;

    // Every card is one line of bounded length.
    let html = std::fs::read_to_string(tmp.path().join("report.html")).unwrap();
    let cards: Vec<&str> = html
        .split(r#"<div class="card">"#)
        .skip(1)
        .map(|c| c.split(r#"<div class="card">"#).next().unwrap())
        .collect();
    assert!(cards.len() >= 8, "{} cards", cards.len());
    for c in &cards {
        let sub = c
            .split(r#"<div class="s">"#)
            .nth(1)
            .and_then(|s| s.split("</div>").next())
            .unwrap();
        assert!(
            !sub.contains('\n') && sub.chars().count() <= 100,
            "card line: {sub}"
        );
    }
    let reps = cards
        .iter()
        .find(|c| c.contains(r#"<div class="l">repetitions</div>"#))
        .unwrap();
    assert!(reps.contains("<div class=\"v\">3000</div>"), "{reps}");
    assert!(reps.contains("from the keypoints (intervals, confidence 0.87) · in 300 intervals: ×10, ×10, ×10 and 297 more"), "{reps}");
    // The people strip stays small for an hour of many people.
    let strip = html.split("<svg class=\"mp-people\"").nth(1).unwrap();
    let strip = strip.split("</svg>").next().unwrap();
    assert!(strip.len() < 200_000, "people strip of {} B", strip.len());

    // In a browser, from disk: late in the hour the picture of the nearest
    // kept frame and the keypoints of the frame itself are loaded and drawn,
    // for the main person and for another.
    let page = tmp.path().join("report.html");
    let step = store.step;
    for (fragment, picture, drawn) in [
        ("#frame=100000", 100_000 / step * step, 100_000),
        ("#person=4&frame=40000", 40_000 / step * step, 40_000),
    ] {
        let Some(stage) = open_in_chromium(&page, fragment, &tmp.path().join("profile")) else {
            return;
        };
        assert_eq!(
            attr(&stage, "data-picture"),
            Some(picture.to_string()),
            "{fragment}: {stage}"
        );
        assert_eq!(
            attr(&stage, "data-drawn"),
            Some(drawn.to_string()),
            "{fragment}: {stage}"
        );
    }
}

/// An attribute's value in a start tag.
fn attr(tag: &str, name: &str) -> Option<String> {
    Some(
        tag.split(&format!(" {name}=\""))
            .nth(1)?
            .split('"')
            .next()?
            .to_string(),
    )
}

/// Opens `page` at `fragment` in headless Chromium; checks that it got
/// ready without an error and returns the stage's start tag. `None` (the
/// test's skip recorded) where Chromium is not installed.
fn open_in_chromium(page: &Path, fragment: &str, profile: &Path) -> Option<String> {
    let Some(exe) = ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .find(|p| Path::new(p).exists())
    else {
        mp_geom::test_support::skip_test(&mp_geom::test_support::current_test_name(), "Chromium");
        return None;
    };
    let out = std::process::Command::new(exe)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--window-size=1280,900",
            "--virtual-time-budget=5000",
            "--dump-dom",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("file://{}{fragment}", page.display()))
        .output()
        .expect("cannot start Chromium");
    let dom = String::from_utf8_lossy(&out.stdout);
    let status = dom
        .split("<div id=\"mp-status\"")
        .nth(1)
        .and_then(|s| s.split("</div>").next())
        .unwrap_or_else(|| panic!("no status in the DOM: {}", &dom[..dom.len().min(2000)]));
    eprintln!("{fragment}: {status}");
    assert!(status.contains("data-errors=\"0\""), "{fragment}: {status}");
    assert!(status.contains("data-ready=\"1\""), "{fragment}: {status}");
    let stage = dom
        .split("<canvas id=\"stage\"")
        .nth(1)
        .and_then(|s| s.split('>').next())
        .unwrap();
    Some(stage.to_string())
}
