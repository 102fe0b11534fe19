//! Loops are numbered from 1 on the command line: `mp loops` lists them so,
//! and `mp extend --loop N` takes the same numbers.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use common::refused;

fn ok(args: &[&str]) -> String {
    common::ok(args).0
}

/// Iteration counts of the loops of an abstract program in JSON, in order.
fn iterations(json: &str) -> Vec<u64> {
    let v: serde_json::Value = serde_json::from_str(json).unwrap();
    v["stmts"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|s| s.get("iterations").and_then(|i| i.as_u64()))
        .collect()
}

#[test]
fn loops_are_numbered_from_one() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name).to_string_lossy().into_owned();
    ok(&["performer", "-o", &p("perf.npz")]);
    ok(&["abstract", &p("perf.npz"), "-o", &p("abs.json"), "--quiet"]);
    let before = iterations(&std::fs::read_to_string(p("abs.json")).unwrap());
    assert!(before.len() >= 2, "the performer has loops: {before:?}");

    // `mp loops`: the first row of the table is interval 1.
    let table = ok(&["loops", &p("perf.npz")]);
    let first = table.lines().nth(2).unwrap();
    assert_eq!(first.split_whitespace().next(), Some("1"), "{table}");

    // Its program-loop section follows the options it names: one loop body
    // at most one primitive long finds other loops than the default.
    let loops_part = |t: &str| {
        t.split("program loops (the abstract program's `for` statements")
            .nth(1)
            .unwrap()
            .to_string()
    };
    let default = loops_part(&table);
    assert_eq!(
        default
            .lines()
            .filter(|l| l.trim_start().starts_with(char::is_numeric))
            .count(),
        before.len(),
        "{table}"
    );
    let short = loops_part(&ok(&["loops", &p("perf.npz"), "--max-body", "1"]));
    assert_ne!(default, short);
    assert!(short.contains("--max-body 1"), "{short}");

    // `mp extend --loop 2` edits the second loop and nothing else.
    ok(&[
        "extend",
        &p("abs.json"),
        "--loop",
        "2",
        "--iters",
        "9",
        "-o",
        &p("ext.json"),
    ]);
    let after = iterations(&std::fs::read_to_string(p("ext.json")).unwrap());
    assert_eq!(after.len(), before.len());
    assert_eq!(after[1], 9);
    assert_eq!(after[0], before[0]);

    let zero = refused(&[
        "extend",
        &p("abs.json"),
        "--loop",
        "0",
        "--iters",
        "2",
        "-o",
        &p("x.npz"),
    ]);
    assert!(zero.contains("numbered from 1"), "{zero}");
    let missing = refused(&[
        "extend",
        &p("abs.json"),
        "--loop",
        "99",
        "--iters",
        "2",
        "-o",
        &p("x.npz"),
    ]);
    assert!(
        missing.contains("no loop 99") && missing.contains(&format!("{} loop(s)", before.len())),
        "{missing}"
    );
    assert!(!tmp.path().join("x.npz").exists());
}
