//! A command interrupted at any moment leaves its output as it was or
//! complete, never part of one: `mp execute` writing a large track is sent
//! SIGINT (and, separately, SIGKILL) at delays spread over its whole run.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use mp_geom::read_track;

fn mp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mp"))
}

fn ok(cmd: &mut Command) {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Hidden temporary files left in `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

/// Runs `mp execute` to `out`, sends `signal` after `delay`, and returns
/// whether the process had already finished by then.
fn interrupt(program: &Path, out: &Path, fps: &str, signal: &str, delay: Duration) -> bool {
    let mut child = mp()
        .arg("execute")
        .arg(program)
        .args(["--fps", fps, "-o"])
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(delay);
    let finished = child.try_wait().unwrap().is_some();
    if !finished {
        let _ = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status();
    }
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(30),
            "mp did not stop after {signal}"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    if !finished && signal == "-INT" {
        assert!(
            matches!(status.code(), Some(0) | Some(130)),
            "after SIGINT: {status}"
        );
    }
    finished
}

#[test]
fn an_interrupted_write_leaves_the_old_file_or_the_new_one() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let perf = dir.join("performer.npz");
    let program = dir.join("program.json");
    ok(mp().arg("performer").arg("-o").arg(&perf));
    ok(mp().arg("fit").arg(&perf).arg("-o").arg(&program));

    let out_dir = dir.join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let out = out_dir.join("track.npz");
    ok(mp().arg("execute").arg(&program).arg("-o").arg(&out));
    let old = std::fs::read(&out).unwrap();
    let old_frames = read_track(&out).unwrap().n_frames();

    // A long write: the program at 100× its frame rate.
    let fps = "3000";
    let t0 = Instant::now();
    let calib = dir.join("calibration.npz");
    ok(mp()
        .arg("execute")
        .arg(&program)
        .args(["--fps", fps, "-o"])
        .arg(&calib));
    let full = t0.elapsed();
    let new_frames = read_track(&calib).unwrap().n_frames();
    assert!(new_frames > 50 * old_frames, "{new_frames} vs {old_frames}");
    std::fs::remove_file(&calib).unwrap();

    let (mut kept_old, mut got_new) = (0, 0);
    for signal in ["-INT", "-KILL"] {
        for i in 0..8 {
            // Delays from 5 % to 95 % of a whole run, then 5 whole runs (on a
            // shared machine a run can take several times the calibration's).
            let delay = if i < 7 {
                full.mul_f64(0.05 + 0.9 * i as f64 / 6.0)
            } else {
                full.mul_f64(5.0)
            };
            std::fs::write(&out, &old).unwrap();
            interrupt(&program, &out, fps, signal, delay);
            let now = std::fs::read(&out).unwrap();
            if now == old {
                kept_old += 1;
            } else {
                let t = read_track(&out)
                    .unwrap_or_else(|e| panic!("{signal} after {delay:?}: a partial file: {e}"));
                assert_eq!(t.n_frames(), new_frames, "{signal} after {delay:?}");
                got_new += 1;
            }
            if signal == "-INT" {
                // Ctrl-C also removes the file being written.
                assert_eq!(
                    temporaries(&out_dir),
                    Vec::<String>::new(),
                    "left after SIGINT at {delay:?}"
                );
            } else {
                for n in temporaries(&out_dir) {
                    std::fs::remove_file(out_dir.join(n)).unwrap();
                }
            }
        }
    }
    // Both outcomes happened: the delays covered the whole run.
    assert!(kept_old > 0 && got_new > 0, "old {kept_old}, new {got_new}");
}
