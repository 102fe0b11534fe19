//! Absurd sizes on the command line end with exit code 1 and a message
//! naming the parameter, never an allocation abort (a signal).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

fn ok(args: &[&str]) {
    common::ok(args);
}

/// Exit code 1 (an error, not a signal) and stderr naming `param`.
fn refused(args: &[&str], param: &str) {
    let stderr = common::refused(args);
    assert!(
        stderr.contains(param),
        "mp {args:?}: the message should name `{param}`:\n{stderr}"
    );
}

#[test]
fn absurd_sizes_are_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name).to_string_lossy().into_owned();
    ok(&["performer", "-o", &p("perf.npz")]);
    ok(&["fit", &p("perf.npz"), "-o", &p("fit.json"), "--quiet"]);
    ok(&["abstract", &p("perf.npz"), "-o", &p("abs.json"), "--quiet"]);

    // A parameter budget outside (0, 1], or below the most compact program.
    refused(
        &["fit", &p("perf.npz"), "-o", &p("b.json"), "--budget", "2"],
        "lambda.ratio",
    );
    refused(
        &[
            "fit",
            &p("perf.npz"),
            "-o",
            &p("b.json"),
            "--budget",
            "1e-9",
        ],
        "most compact program",
    );
    // A spread λ held for no time, or given with another λ rule.
    refused(
        &[
            "fit",
            &p("perf.npz"),
            "-o",
            &p("s.json"),
            "--lambda-spread",
            "0",
        ],
        "lambda.seconds",
    );
    let both = common::run(&[
        "fit",
        &p("perf.npz"),
        "-o",
        &p("s.json"),
        "--lambda-spread",
        "1",
        "--budget",
        "0.1",
    ]);
    let stderr = String::from_utf8_lossy(&both.stderr);
    assert_eq!(both.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("cannot be used with"), "{stderr}");
    refused(
        &[
            "execute",
            &p("fit.json"),
            "--fps",
            "1e15",
            "-o",
            &p("x.npz"),
        ],
        "fps_out",
    );
    refused(
        &[
            "extend",
            &p("abs.json"),
            "--iters",
            "1000000000000",
            "-o",
            &p("x.npz"),
        ],
        "iterations",
    );
    refused(
        &[
            "predict",
            &p("perf.npz"),
            "--observe",
            "30",
            "--horizon",
            "1000000000000",
        ],
        "horizon",
    );

    ok(&[
        "grammar",
        "symbols",
        &p("perf.npz"),
        "--k",
        "4",
        "--seed",
        "1",
        "-o",
        &p("sym.json"),
    ]);
    for (flag, param) in [
        ("--population", "ga.population"),
        ("--sa-iterations", "sa.iterations"),
    ] {
        refused(
            &[
                "grammar",
                "symbols",
                &p("perf.npz"),
                "--k",
                "4",
                flag,
                "1000000000000",
                "-o",
                &p("x.json"),
            ],
            param,
        );
    }
    ok(&["grammar", "learn", &p("sym.json"), "-o", &p("gram.json")]);
    refused(
        &[
            "grammar",
            "synth",
            &p("gram.json"),
            "--segments",
            "1000000000000",
            "-o",
            &p("x.npz"),
        ],
        "segments",
    );
}

#[test]
fn a_negative_or_endless_recovery_time_is_an_error() {
    let video = mp_geom::data_or_return!("golfdb/golf_swing.mp4");
    let video = video.to_string_lossy().into_owned();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("t.npz").to_string_lossy().into_owned();
    for bad in ["--recover=-1", "--recover=NaN", "--recover=inf"] {
        refused(
            &["extract", &video, "-o", &out, bad, "--quiet"],
            "recover_s",
        );
    }
    assert!(!tmp.path().join("t.npz").exists());
}
