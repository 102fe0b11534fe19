//! The docs show what the tool does: every `mp` command of TUTORIAL.md and
//! VIDEO.md whose output the page shows is run on the shared data, and the
//! output shown must be what the command prints.
//!
//! What is checked, in each page, in order, in one scratch folder (so a later
//! block can read what an earlier command wrote):
//! * a ```` ```sh ```` block followed (blank lines aside) by a
//!   ```` ```text ```` block: the `mp` commands of the first are run, and the
//!   second must match their output (stdout, then stderr);
//! * a ```` ```text ```` block right after `<!-- output of: PATH -->`: it
//!   must match the file `PATH` (written by an earlier command).
//!
//! Matching: the shown lines must appear in that order, consecutively, where
//! a line holding only `…` stands for any number of lines and a `…` inside a
//! line for any text. Numbers may differ by what a different CPU, ONNX
//! Runtime build or FFmpeg can change: decimals by 5 % or 3 units of the last
//! digit shown, integers by 2 % or 1. Words, signs, units and the layout must
//! be the same.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use regex::Regex;

/// One checked block of a page.
#[derive(Debug)]
enum Check {
    /// Commands, and the output the page shows for them.
    Output {
        line: usize,
        commands: Vec<String>,
        shown: Vec<String>,
    },
    /// A file written by an earlier command, and the excerpt the page shows.
    File {
        line: usize,
        path: String,
        shown: Vec<String>,
    },
}

/// The checked blocks of a Markdown page.
fn checks(page: &str) -> Vec<Check> {
    let lines: Vec<&str> = page.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let block = |start: usize| -> (Vec<String>, usize) {
        // Lines of the fenced block opening at `start`, and the line after it.
        let mut j = start + 1;
        let mut body = Vec::new();
        while j < lines.len() && !lines[j].starts_with("```") {
            body.push(lines[j].to_string());
            j += 1;
        }
        (body, j + 1)
    };
    let next_text = |from: usize| -> Option<usize> {
        let mut k = from;
        while k < lines.len() && lines[k].trim().is_empty() {
            k += 1;
        }
        (k < lines.len() && lines[k].trim_end() == "```text").then_some(k)
    };
    while i < lines.len() {
        let l = lines[i].trim_end();
        if l == "```sh" {
            let (cmds, after) = block(i);
            if let Some(t) = next_text(after) {
                let (shown, after_text) = block(t);
                let commands: Vec<String> = cmds
                    .iter()
                    .map(|c| strip_comment(c))
                    .filter(|c| c.starts_with("mp "))
                    .collect();
                if !commands.is_empty() {
                    out.push(Check::Output {
                        line: i + 1,
                        commands,
                        shown,
                    });
                }
                i = after_text;
                continue;
            }
            i = after;
            continue;
        }
        if let Some(path) = l
            .strip_prefix("<!-- output of: ")
            .and_then(|r| r.strip_suffix(" -->"))
        {
            if let Some(t) = next_text(i + 1) {
                let (shown, after) = block(t);
                out.push(Check::File {
                    line: i + 1,
                    path: path.to_string(),
                    shown,
                });
                i = after;
                continue;
            }
        }
        i += 1;
    }
    out
}

/// A command line without its trailing `# comment`.
fn strip_comment(line: &str) -> String {
    let l = match line.find("  #") {
        Some(k) => &line[..k],
        None => line,
    };
    l.trim().to_string()
}

/// A shown line as a pattern: literal text (runs of spaces as one or more),
/// numbers captured, `…` as any text.
fn pattern(shown: &str) -> (Regex, Vec<String>) {
    let num = Regex::new(r"-?[0-9]+(?:\.[0-9]+)?").unwrap();
    let mut re = String::from("^");
    let mut numbers = Vec::new();
    let literal = |text: &str, re: &mut String| {
        for (k, part) in text.split('…').enumerate() {
            if k > 0 {
                re.push_str(".*?");
            }
            let mut words = part.split_whitespace().peekable();
            if part.starts_with(char::is_whitespace) && !part.trim().is_empty() {
                re.push_str(r"[ \t]+");
            }
            while let Some(w) = words.next() {
                re.push_str(&regex::escape(w));
                if words.peek().is_some() {
                    re.push_str(r"[ \t]+");
                }
            }
            if part.ends_with(char::is_whitespace) && !part.trim().is_empty() {
                re.push_str(r"[ \t]+");
            }
            if part.trim().is_empty() && !part.is_empty() {
                re.push_str(r"[ \t]*");
            }
        }
    };
    let mut last = 0;
    for m in num.find_iter(shown) {
        // A digit inside a word (`x264`, `H.264`, `01_nose`) is text.
        let before = shown[..m.start()].chars().next_back();
        let after = shown[m.end()..].chars().next();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_')
            || after.is_some_and(|c| c.is_alphabetic() || c == '_')
        {
            continue;
        }
        literal(&shown[last..m.start()], &mut re);
        re.push_str(r"(-?[0-9]+(?:\.[0-9]+)?)");
        numbers.push(m.as_str().to_string());
        last = m.end();
    }
    literal(&shown[last..], &mut re);
    re.push_str(r"[ \t]*$");
    (Regex::new(&re).unwrap(), numbers)
}

/// Whether `got` is `shown` within what another machine may change.
fn close(shown: &str, got: &str) -> bool {
    let (Ok(a), Ok(b)) = (shown.parse::<f64>(), got.parse::<f64>()) else {
        return false;
    };
    if shown.starts_with('-') != got.starts_with('-') && a != 0.0 && b != 0.0 {
        return false;
    }
    let unit = match shown.split_once('.') {
        Some((_, d)) => 3.0 * 10f64.powi(-(d.len() as i32)),
        None => return (a - b).abs() <= 1f64.max(0.02 * a.abs()),
    };
    (a - b).abs() <= unit.max(0.05 * a.abs())
}

/// Whether one actual line matches one shown line; `Err` says why not.
fn line_matches(shown: &str, actual: &str) -> Result<(), String> {
    let (re, numbers) = pattern(shown);
    let caps = re
        .captures(actual)
        .ok_or_else(|| "the text differs".to_string())?;
    for (k, want) in numbers.iter().enumerate() {
        let got = caps.get(k + 1).map_or("", |m| m.as_str());
        if !close(want, got) {
            return Err(format!("number {got} where the page shows {want}"));
        }
    }
    Ok(())
}

/// Whether `shown` (with `…` lines as gaps) matches consecutive lines of
/// `actual` at `at`.
fn matches_at(shown: &[String], actual: &[&str], at: usize) -> bool {
    let Some((first, rest)) = shown.split_first() else {
        return true;
    };
    if first.trim() == "…" {
        return (at..=actual.len()).any(|k| matches_at(rest, actual, k));
    }
    at < actual.len() && line_matches(first, actual[at]).is_ok() && matches_at(rest, actual, at + 1)
}

/// `Ok` when the shown lines appear in `actual`; else the best explanation.
fn compare(shown: &[String], actual: &str) -> Result<(), String> {
    let actual: Vec<&str> = actual.lines().collect();
    let shown: Vec<String> = shown.iter().map(|s| s.trim_end().to_string()).collect();
    if (0..=actual.len()).any(|k| matches_at(&shown, &actual, k)) {
        return Ok(());
    }
    // The first shown line that matches nowhere, and the closest reason.
    for s in shown.iter().filter(|s| s.trim() != "…") {
        let reasons: Vec<String> = actual
            .iter()
            .filter_map(|a| line_matches(s, a).err().map(|e| format!("{e}: {a}")))
            .filter(|e| e.starts_with("number"))
            .collect();
        if !actual.iter().any(|a| line_matches(s, a).is_ok()) {
            return Err(format!(
                "the page shows\n    {s}\nwhich is in no line of the output{}",
                reasons
                    .first()
                    .map(|r| format!(" (closest: {r})"))
                    .unwrap_or_default()
            ));
        }
    }
    Err("every shown line is there, but not in the order or the grouping the page shows".into())
}

/// The repository root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// Runs the checks of one page in a scratch folder; returns the failures.
fn check_page(rel: &str, shared: &Path) -> Vec<String> {
    let page = std::fs::read_to_string(root().join(rel)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let shared_s = format!("{}/", shared.display());
    let mut failures = Vec::new();
    for c in checks(&page) {
        match c {
            Check::Output {
                line,
                commands,
                shown,
            } => {
                let mut text = String::new();
                let mut err = String::new();
                for cmd in &commands {
                    let expanded = cmd.replace("../shared/", &shared_s);
                    let args: Vec<&str> = expanded.split_whitespace().skip(1).collect();
                    let out = Command::new(env!("CARGO_BIN_EXE_mp"))
                        .args(&args)
                        .current_dir(dir.path())
                        .output()
                        .expect("cannot start mp");
                    if !out.status.success() {
                        failures.push(format!(
                            "{rel}:{line}: `{cmd}` failed:\n{}",
                            String::from_utf8_lossy(&out.stderr)
                        ));
                    }
                    text.push_str(&String::from_utf8_lossy(&out.stdout));
                    err.push_str(&String::from_utf8_lossy(&out.stderr));
                }
                text.push_str(&err);
                if let Err(e) = compare(&shown, &text) {
                    failures.push(format!(
                        "{rel}:{line}: {}\n  {e}\n  the output was:\n{text}",
                        commands.join("; ")
                    ));
                }
            }
            Check::File { line, path, shown } => {
                match std::fs::read_to_string(dir.path().join(&path)) {
                    Ok(text) => {
                        if let Err(e) = compare(&shown, &text) {
                            failures.push(format!("{rel}:{line}: {path}: {e}"));
                        }
                    }
                    Err(e) => failures.push(format!("{rel}:{line}: cannot read {path}: {e}")),
                }
            }
        }
    }
    failures
}

#[test]
fn the_matching_can_fail() {
    let shown = |s: &str| vec![s.to_string()];
    assert!(compare(
        &shown("7 repetitions, period 0.59 s"),
        "7 repetitions, period 0.60 s"
    )
    .is_ok());
    // Another word, another unit, a number out of tolerance: refused.
    assert!(compare(
        &shown("7 repetitions, period 0.59 s"),
        "7 loops, period 0.59 s"
    )
    .is_err());
    assert!(compare(&shown("period 0.59 s"), "period 0.59 ms").is_err());
    assert!(compare(&shown("7 repetitions"), "9 repetitions").is_err());
    assert!(compare(&shown("frames 0–123"), "frames 0–124").is_ok());
    let e = compare(&shown("confidence 0.76"), "confidence 0.92").unwrap_err();
    assert!(e.contains("number 0.92"), "{e}");
    // `…` lines are gaps, `…` inside a line any text; order matters.
    let two = vec!["a 1".to_string(), "…".to_string(), "c 3".to_string()];
    assert!(compare(&two, "a 1\nb 2\nb 2\nc 3\n").is_ok());
    assert!(compare(&two, "c 3\na 1\n").is_err());
    assert!(compare(&shown("cov=[…])"), "cov=[[1.0, 2.0]])").is_ok());
    // Frame ranges and words with digits.
    assert!(compare(&shown("x264 preset"), "x265 preset").is_err());
    assert!(compare(&shown("frames 0–123"), "frames 0..124").is_err());
    assert!(compare(&shown("angle=-6.40*t - 81.51"), "angle=-6.40*t + -81.51").is_err());
}

#[test]
fn commands_of_the_docs_print_what_the_docs_show() {
    let Some(shared) = mp_geom::shared_dir() else {
        mp_geom::test_support::skip_test(
            "commands_of_the_docs_print_what_the_docs_show",
            "the shared data folder",
        );
        return;
    };
    let mut failures = Vec::new();
    let mut checked = 0;
    for page in ["docs/TUTORIAL.md", "docs/VIDEO.md"] {
        let text = std::fs::read_to_string(root().join(page)).unwrap();
        checked += checks(&text).len();
        failures.extend(check_page(page, &shared));
    }
    assert!(checked >= 6, "only {checked} checked blocks in the docs");
    assert!(
        failures.is_empty(),
        "{} block(s) of the docs do not match the tool:\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}
