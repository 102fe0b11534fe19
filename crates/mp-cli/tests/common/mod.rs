//! Running the `mp` binary from the command-line tests.
#![allow(dead_code)] // each test file uses the helpers it needs

use std::process::{Command, Output};

pub mod browser;

/// `mp ARGS`, its output captured.
pub fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mp"))
        .args(args)
        .output()
        .expect("cannot start mp")
}

/// `mp ARGS`, which must succeed: its stdout and stderr.
pub fn ok(args: &[&str]) -> (String, String) {
    let out = run(args);
    assert!(
        out.status.success(),
        "mp {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `mp ARGS`, which must fail with exit code 1 (an error, not a signal):
/// its stderr.
pub fn refused(args: &[&str]) -> String {
    let out = run(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(1),
        "mp {args:?} should fail with exit code 1 (status {:?}):\n{stderr}",
        out.status
    );
    stderr
}

/// The JSON lines of a command's standard output (`mp live --json`).
pub fn json_lines(out: &Output) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("not JSON ({e}): {l}")))
        .collect()
}

/// FFmpeg sending `video` as MPEG-TS (H.264, zerolatency) at `speed` times
/// its own rate; the caller adds where to (`pipe:1`, `tcp://…?listen=1`).
pub fn mpegts_sender(video: &std::path::Path, speed: f64) -> Command {
    let mut cmd = Command::new("ffmpeg");
    cmd.args([
        "-v",
        "error",
        "-nostdin",
        "-readrate",
        &speed.to_string(),
        "-i",
    ])
    .arg(video)
    .args([
        "-an",
        "-c:v",
        "libx264",
        "-tune",
        "zerolatency",
        "-f",
        "mpegts",
    ]);
    cmd
}

/// The `mp` binary as a command to build on.
pub fn mp_command() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mp"))
}

/// Runs a command of the `mp` binary, which must succeed; its output.
pub fn run_ok(cmd: &mut Command) -> Output {
    let out = cmd.output().expect("cannot start the mp binary");
    assert!(
        out.status.success(),
        "mp failed ({}):\nstdout:\n{}\nstderr:\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The JSON data block of a report page.
pub fn report_data(html: &str) -> serde_json::Value {
    let key = "id=\"mp-data\">";
    let start = html.find(key).expect("report has no data block") + key.len();
    let end = start
        + html[start..]
            .find("</script>")
            .expect("unterminated data block");
    serde_json::from_str(&html[start..end]).expect("report data block is not JSON")
}
