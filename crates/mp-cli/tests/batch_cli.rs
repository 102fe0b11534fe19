//! `mp batch` through the built binary on a small folder of procedural
//! performer tracks (written by `mp performer -o`) and a corrupt file: the
//! manifest, the exit status, the summary and a re-run that skips.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::Path;
use std::process::{Command, Output};

fn mp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mp"))
}

fn text(out: &Output) -> String {
    format!(
        "status {}\nstdout:\n{}\nstderr:\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

fn performer(path: &Path, seed: u64) {
    let out = mp()
        .args(["performer", "--seed", &seed.to_string(), "-o"])
        .arg(path)
        .output()
        .expect("cannot start the mp binary");
    assert!(out.status.success(), "{}", text(&out));
}

fn manifest(out: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(out.join("manifest.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

fn status_of(lines: &[serde_json::Value], file: &str) -> String {
    lines
        .iter()
        .find(|l| l["input"].as_str().unwrap().ends_with(file))
        .unwrap_or_else(|| panic!("no line for {file}: {lines:?}"))["status"]
        .as_str()
        .unwrap()
        .to_string()
}

#[test]
fn a_folder_with_a_corrupt_item_fails_and_a_rerun_skips() {
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("tracks");
    std::fs::create_dir_all(&input).unwrap();
    performer(&input.join("one.npz"), 1);
    performer(&input.join("two.json"), 2);
    std::fs::write(input.join("broken.csv"), "frame,joint\nnot,numbers\n").unwrap();
    let out = tmp.path().join("out");

    let first = mp()
        .arg("batch")
        .arg(&input)
        .arg("--out")
        .arg(&out)
        .args(["--jobs", "2"])
        .output()
        .unwrap();
    let t = text(&first);
    assert_eq!(first.status.code(), Some(1), "{t}");
    assert!(t.contains("1 of 3 items failed"), "{t}");
    assert!(t.contains("failed: ") && t.contains("broken.csv"), "{t}");
    assert!(t.contains("3 items: 2 ok, 1 failed, 0 skipped"), "{t}");
    assert!(t.contains("frames/s"), "{t}");
    let lines = manifest(&out);
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert_eq!(status_of(&lines, "one.npz"), "ok");
    assert_eq!(status_of(&lines, "two.json"), "ok");
    assert_eq!(status_of(&lines, "broken.csv"), "failed");
    for l in &lines {
        for key in [
            "output", "error", "frames", "seconds", "counts", "signal", "method",
        ] {
            assert!(l.get(key).is_some(), "{key} missing: {l}");
        }
        if l["status"] == "ok" {
            assert!(l["total_repetitions"].as_u64().unwrap() > 0, "{l}");
            assert!(l["error"].is_null());
            let folder = Path::new(l["output"].as_str().unwrap());
            assert!(folder.join("loops.json").is_file());
            assert!(folder.join("report.html").is_file());
        } else {
            assert!(l["error"].as_str().unwrap().contains("broken.csv"), "{l}");
        }
    }
    assert!(out.join("one").is_dir() && out.join("two").is_dir());

    // Again, quietly: the two complete items are skipped, the corrupt one fails again.
    let second = mp()
        .arg("batch")
        .arg(&input)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .output()
        .unwrap();
    let t = text(&second);
    assert_eq!(second.status.code(), Some(1), "{t}");
    assert!(String::from_utf8_lossy(&second.stdout).is_empty(), "{t}");
    let lines = manifest(&out);
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert_eq!(status_of(&lines, "one.npz"), "skipped");
    assert_eq!(status_of(&lines, "two.json"), "skipped");
    assert_eq!(status_of(&lines, "broken.csv"), "failed");

    // Without the corrupt file the batch succeeds.
    std::fs::remove_file(input.join("broken.csv")).unwrap();
    let third = mp()
        .arg("batch")
        .arg(&input)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let t = text(&third);
    assert!(third.status.success(), "{t}");
    assert!(t.contains("2 items: 0 ok, 0 failed, 2 skipped"), "{t}");
}

#[test]
fn bad_arguments_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = mp()
        .arg("batch")
        .arg(tmp.path().join("nothing-here"))
        .arg("--out")
        .arg(tmp.path().join("out"))
        .output()
        .unwrap();
    let t = text(&out);
    assert!(!out.status.success(), "{t}");
    assert!(t.contains("does not exist"), "{t}");
    let out = mp()
        .arg("batch")
        .arg(tmp.path())
        .arg("--out")
        .arg(tmp.path().join("out"))
        .args(["--jobs", "0"])
        .output()
        .unwrap();
    let t = text(&out);
    assert!(!out.status.success(), "{t}");
    assert!(t.contains("jobs"), "{t}");
}
