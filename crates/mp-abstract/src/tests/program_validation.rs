//! Abstract programs read from JSON are validated: a wrong shape, a
//! non-finite value or a bad duration gives a typed error that names the
//! file and the field.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::{AbstractError, AbstractProgram};
use serde_json::{json, Value};
use std::path::PathBuf;

/// A valid 2-D program with one joint: a primitive and a one-body loop.
fn program() -> Value {
    let eye: Vec<f64> = (0..36)
        .map(|k| if k % 7 == 0 { 1.0 } else { 0.0 })
        .collect();
    json!({
        "fps": 30.0,
        "units": "px",
        "dims": 2,
        "joints": ["head"],
        "stmts": [
            {"kind": "prim", "duration": 5, "points": [[0.0, 0.0, 1.0, 1.0, 2.0, 2.0]]},
            {"kind": "loop", "iterations": 2, "body": [
                {"duration": [[4, 3], [5, 1]],
                 "joints": [{"mean": [0.0, 0.0, 1.0, 1.0, 2.0, 2.0], "cov": eye}]}
            ]}
        ]
    })
}

fn read(v: &Value, name: &str) -> (PathBuf, Result<(), AbstractError>) {
    let dir = std::env::temp_dir().join(format!(
        "mp-abstract-validation-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("program.json");
    std::fs::write(&p, v.to_string()).unwrap();
    let r = AbstractProgram::read(&p).map(|_| ());
    let _ = std::fs::remove_dir_all(&dir);
    (p, r)
}

#[test]
fn a_valid_program_loads() {
    let (_, r) = read(&program(), "valid");
    r.unwrap();
}

#[test]
fn invalid_programs_name_the_file_and_the_field() {
    type Edit = fn(&mut Value);
    let cases: [(&str, Edit, &str); 7] = [
        (
            "mean_len",
            |v| v["stmts"][1]["body"][0]["joints"][0]["mean"] = json!([0.0, 1.0]),
            "`mean` of dimension 2",
        ),
        (
            "cov_len",
            |v| v["stmts"][1]["body"][0]["joints"][0]["cov"] = json!([1.0, 0.0, 0.0, 1.0]),
            "covariance has 4 entries",
        ),
        (
            "duration_zero",
            |v| v["stmts"][0]["duration"] = json!(0),
            "must be ≥ 1",
        ),
        (
            "freq_empty",
            |v| v["stmts"][1]["body"][0]["duration"] = json!([]),
            "`duration` distribution is empty",
        ),
        (
            "freq_zero_value",
            |v| v["stmts"][1]["body"][0]["duration"] = json!([[0, 2]]),
            "`duration` distribution is empty or has 0",
        ),
        (
            "points_len",
            |v| v["stmts"][0]["points"][0] = json!([0.0, 1.0]),
            "2 values, expected 6",
        ),
        ("fps", |v| v["fps"] = json!(-30.0), "fps"),
    ];
    for (name, edit, needle) in cases {
        let mut v = program();
        edit(&mut v);
        let (p, r) = read(&v, name);
        let msg = r.expect_err(name).to_string();
        assert!(
            msg.contains(needle) && msg.contains(&p.display().to_string()),
            "{name}: {msg}"
        );
    }
}

#[test]
fn non_finite_and_negative_values_are_refused() {
    // JSON has no NaN: a null or a negative count fails to parse, naming the file.
    for (name, edit) in [
        (
            "nan_mean",
            (|v: &mut Value| v["stmts"][1]["body"][0]["joints"][0]["mean"][0] = Value::Null)
                as fn(&mut Value),
        ),
        ("negative_count", |v| {
            v["stmts"][1]["body"][0]["duration"] = json!([[4, -1]])
        }),
    ] {
        let mut v = program();
        edit(&mut v);
        let (p, r) = read(&v, name);
        let e = r.expect_err(name);
        assert!(
            matches!(e, AbstractError::Json { .. })
                && e.to_string().contains(&p.display().to_string()),
            "{name}: {e}"
        );
    }
    // A non-finite value given in memory is named as such.
    let mut prog: crate::AbstractProgram = serde_json::from_value(program()).unwrap();
    if let crate::Stmt::Loop(l) = &mut prog.stmts[1] {
        l.body[0].joints[0].mean[3] = f64::NAN;
    }
    let e = prog.validate().unwrap_err();
    assert!(
        matches!(&e, AbstractError::NonFinite(m) if m.contains("`mean`")),
        "{e}"
    );
}
