//! `mp fit`, `mp abstract`, `mp loops` and `mp run` give the same concrete
//! program, abstract program and counts for the same track and defaults.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::process::Command;

fn mp(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_mp"))
        .args(args)
        .output()
        .expect("cannot start mp");
    assert!(
        out.status.success(),
        "mp {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn fit_abstract_loops_and_run_agree() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name).to_string_lossy().into_owned();
    mp(&["performer", "-o", &p("perf.npz")]);
    mp(&["fit", &p("perf.npz"), "-o", &p("fit.json"), "--quiet"]);
    mp(&[
        "abstract",
        &p("perf.npz"),
        "-o",
        &p("abstract.json"),
        "--quiet",
    ]);
    let loops = mp(&["loops", &p("perf.npz"), "--json"]);
    mp(&["run", &p("perf.npz"), "--out", &p("run"), "--quiet"]);

    let fit = mp_concrete::Program::read(p("fit.json")).unwrap();
    let run = mp_concrete::Program::read(tmp.path().join("run/program.json")).unwrap();
    assert_eq!(fit, run, "mp fit and mp run wrote different programs");
    assert!(fit.n_segments() > 10);

    let a = mp_abstract::AbstractProgram::read(p("abstract.json")).unwrap();
    let b = mp_abstract::AbstractProgram::read(tmp.path().join("run/abstract.json")).unwrap();
    assert_eq!(
        a, b,
        "mp abstract and mp run wrote different abstract programs"
    );

    let printed: serde_json::Value = serde_json::from_str(&loops).unwrap();
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("run/loops.json")).unwrap())
            .unwrap();
    assert_eq!(printed["repetitions"], written["repetitions"]);
    assert_eq!(printed["program_loops"], written["program_loops"]);
    // The performer does 4 jumping jacks, 3 squats and 3 arm circles in a row.
    assert_eq!(written["repetitions"]["total"], 10, "{written}");

    // A fixed λ is a different program: the option is honoured.
    mp(&[
        "fit",
        &p("perf.npz"),
        "-o",
        &p("fixed.json"),
        "--lambda",
        "400",
        "--quiet",
    ]);
    let fixed = mp_concrete::Program::read(p("fixed.json")).unwrap();
    assert_ne!(fixed.n_segments(), fit.n_segments());
}
