//! Files as people expect, through the `mp` binary: every output is created
//! with the permissions of an ordinary new file (0666 less the umask), and a
//! folder `mp run` used before holds afterwards what the new run wrote, the
//! user's own files, and nothing the earlier run left.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use std::os::unix::fs::PermissionsExt;
use std::path::Path;

use common::ok;

fn mode(p: &Path) -> u32 {
    std::fs::metadata(p).unwrap().permissions().mode() & 0o777
}

#[test]
fn outputs_have_ordinary_permissions_and_a_reused_folder_is_cleaned() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name);
    let s = |name: &str| p(name).to_string_lossy().into_owned();
    // What a new file gets here (0666 less this process's umask).
    std::fs::write(p("reference"), b"").unwrap();
    let ordinary = mode(&p("reference"));

    ok(&["performer", "-o", &s("perf.npz")]);
    ok(&["fit", &s("perf.npz"), "-o", &s("prog.txt")]);
    ok(&["abstract", &s("perf.npz"), "-o", &s("abs.json"), "--quiet"]);
    ok(&["execute", &s("prog.txt"), "-o", &s("exec.csv")]);
    ok(&["run", &s("perf.npz"), "--out", &s("run"), "--quiet"]);
    for f in [
        "perf.npz",
        "prog.txt",
        "abs.json",
        "exec.csv",
        "run/loops.json",
        "run/report.html",
    ] {
        assert_eq!(mode(&p(f)), ordinary, "{f}: {:o}", mode(&p(f)));
    }

    // A reused folder: the user's file stays, the earlier run's files that
    // the new run does not write go.
    std::fs::write(p("run/notes.md"), b"mine").unwrap();
    let plots = |dir: &str| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(p(dir).join("plots"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    let first = plots("run");
    assert!(first.iter().any(|f| f.ends_with("_nose.svg")), "{first:?}");
    let Some(bvh) = mp_geom::test_support::data_file_or_skip(
        "cmu_salsa_bvh/60_01_scaled.bvh",
        "outputs_have_ordinary_permissions_and_a_reused_folder_is_cleaned",
    ) else {
        return;
    };
    ok(&[
        "run",
        bvh.to_str().unwrap(),
        "--out",
        &s("run"),
        "--quiet",
        "--max-frames",
        "240",
    ]);
    let second = plots("run");
    assert!(
        !second
            .iter()
            .any(|f| f.ends_with("_nose.svg") || f.ends_with("_nose.png")),
        "the performer's plots stayed beside the new ones: {second:?}"
    );
    assert!(!second.is_empty());
    assert_eq!(std::fs::read(p("run/notes.md")).unwrap(), b"mine");
    let listed = std::fs::read_to_string(p("run/mp-run-files.txt")).unwrap();
    for f in &second {
        assert!(
            listed.contains(&format!("plots/{f}")),
            "{f} not in the run's list"
        );
    }
}

#[test]
fn a_params_file_sets_every_setting_and_options_apply_on_top() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name);
    let s = |name: &str| p(name).to_string_lossy().into_owned();
    // `mp params` prints the defaults; a partial file comes back completed.
    let (defaults, _) = ok(&["params"]);
    let v: serde_json::Value = serde_json::from_str(&defaults).unwrap();
    assert_eq!(v["pose"]["model"], "full");
    assert_eq!(v["output"]["report"], true);
    std::fs::write(
        p("p.json"),
        r#"{"output": {"report": false}, "pose": {"model": "lite"}}"#,
    )
    .unwrap();
    let (completed, _) = ok(&["params", &s("p.json")]);
    let c: serde_json::Value = serde_json::from_str(&completed).unwrap();
    assert_eq!(c["pose"]["model"], "lite");
    assert_eq!(c["output"]["report"], false);
    assert_eq!(c["analysis"], v["analysis"]);
    std::fs::write(p("bad.json"), r#"{"output": {"reprot": false}}"#).unwrap();
    let err = common::refused(&["params", &s("bad.json")]);
    assert!(err.contains("reprot") && err.contains("bad.json"), "{err}");

    // The file's `report: false` holds for `mp run`; an option given on top wins.
    ok(&["performer", "-o", &s("perf.npz")]);
    ok(&[
        "run",
        &s("perf.npz"),
        "--out",
        &s("run"),
        "--params",
        &s("p.json"),
        "--quiet",
    ]);
    assert!(p("run/loops.json").is_file());
    assert!(!p("run/report.html").exists());
    let err = common::refused(&[
        "run",
        &s("perf.npz"),
        "--out",
        &s("run2"),
        "--params",
        &s("p.json"),
        "--pose-fps",
        "fast",
    ]);
    assert!(err.contains("fast"), "{err}");
}
