//! `mp live` on the sources other than a file or a pipe, through the built
//! binary and a real FFmpeg: a network stream (FFmpeg serving MPEG-TS on a
//! local TCP socket), a server that is not there yet or never comes, a
//! camera that does not exist, and a stream whose frame size changes.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::net::TcpListener;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

mod common;

use common::{json_lines as lines, mp_command as mp};

/// A port nothing listens on (bound once, then let go).
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// FFmpeg serving `video` as MPEG-TS, at half its own speed, to the first
/// client of `tcp://127.0.0.1:PORT`.
fn serve(video: &Path, port: u16) -> Child {
    common::mpegts_sender(video, 0.5)
        .arg(format!("tcp://127.0.0.1:{port}?listen=1"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("ffmpeg")
}

fn frame_count(video: &Path) -> u64 {
    let out = Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-count_frames",
            "-select_streams",
            "v:0",
            "-show_entries",
            "stream=nb_read_frames",
            "-of",
            "csv=p=0",
        ])
        .arg(video)
        .output()
        .unwrap();
    // One line per program of an MPEG-TS that was put together from parts.
    let text = String::from_utf8_lossy(&out.stdout);
    text.lines().next().unwrap().trim().parse().unwrap()
}

/// The summary of a run that succeeded: frames analysed and dropped.
fn summary(out: &Output) -> (u64, u64, serde_json::Value) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let events = lines(out);
    let last = events.last().expect("no output").clone();
    assert_eq!(last["type"], "summary", "{events:?}");
    assert!(events.iter().all(|e| e["type"] != "error"), "{events:?}");
    (
        last["frames"].as_u64().unwrap(),
        last["dropped"].as_u64().unwrap(),
        last,
    )
}

#[test]
fn network_stream_is_analysed_frame_by_frame() {
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let port = free_port();
    let mut server = serve(&video, port);
    std::thread::sleep(Duration::from_millis(500));
    let out = mp()
        .args(["live", &format!("tcp://127.0.0.1:{port}"), "--json"])
        .output()
        .unwrap();
    let _ = server.wait();
    let (frames, dropped, last) = summary(&out);
    // Every frame of the video came, analysed or dropped (the first ones
    // may pass while the stream is being recognised).
    let n = frame_count(&video);
    assert!(frames > n / 4, "{frames} of {n} frames analysed");
    assert!(frames + dropped <= n, "{frames} + {dropped} > {n}");
    assert!(frames + dropped + 15 >= n, "{frames} + {dropped} of {n}");
    let people = last["people"].as_array().unwrap();
    assert_eq!(people.len(), 1, "{last}");
    assert!(
        people[0]["total_repetitions"].as_u64().unwrap() >= 3,
        "{last}"
    );
}

#[test]
fn late_server_is_reached_on_a_new_try() {
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let port = free_port();
    let child = mp()
        .args(["live", &format!("tcp://127.0.0.1:{port}"), "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The first try finds nobody; the server comes before the last try.
    std::thread::sleep(Duration::from_millis(1200));
    let mut server = serve(&video, port);
    let out = child.wait_with_output().unwrap();
    let _ = server.kill();
    let _ = server.wait();
    let (frames, _, _) = summary(&out);
    assert!(frames > 0);
    let tries: Vec<_> = lines(&out)
        .into_iter()
        .filter(|e| e["type"] == "reconnect")
        .collect();
    assert!(!tries.is_empty(), "no new try reported");
    assert_eq!(tries[0]["attempt"], 1, "{tries:?}");
    assert!(
        tries[0]["reason"]
            .as_str()
            .unwrap()
            .contains("Connection refused"),
        "{tries:?}"
    );
}

#[test]
fn refused_stream_fails_after_its_tries() {
    let url = format!("tcp://127.0.0.1:{}", free_port());
    let out = mp().args(["live", &url, "--json"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains(&url), "{err}");
    assert!(err.contains("Connection refused"), "{err}");
    assert!(err.contains("tried 4 times"), "{err}");
    let events = lines(&out);
    let attempts: Vec<_> = events
        .iter()
        .filter(|e| e["type"] == "reconnect")
        .map(|e| e["attempt"].as_u64().unwrap())
        .collect();
    assert_eq!(attempts, [1, 2, 3]);
    let last = events.last().unwrap();
    assert_eq!(last["type"], "summary");
    assert_eq!(last["frames"], 0);
}

#[test]
fn missing_camera_fails_clearly() {
    let out = mp()
        .args(["live", "/dev/video-that-is-not-there", "--json"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("no camera at /dev/video-that-is-not-there"),
        "{err}"
    );
    assert_eq!(lines(&out).last().unwrap()["type"], "summary");
}

#[test]
fn frame_size_change_is_scaled_to_the_first() {
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let dir = tempfile::tempdir().unwrap();
    // Two parts of the video at two frame sizes, one stream after the other.
    let mut stream = Vec::new();
    for (i, (start, size)) in [(0.0, "320:240"), (2.0, "480:360")].iter().enumerate() {
        let part = dir.path().join(format!("{i}.ts"));
        let st = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-ss", &start.to_string(), "-i"])
            .arg(&video)
            .args(["-t", "2", "-an", "-vf", &format!("scale={size}")])
            .args(["-c:v", "libx264", "-f", "mpegts"])
            .arg(&part)
            .status()
            .unwrap();
        assert!(st.success());
        stream.extend(std::fs::read(&part).unwrap());
    }
    let both = dir.path().join("both.ts");
    std::fs::write(&both, &stream).unwrap();
    let n = frame_count(&both);
    let out = mp()
        .args(["live", "-", "--json"])
        .stdin(std::fs::File::open(&both).unwrap())
        .output()
        .unwrap();
    let (frames, dropped, _) = summary(&out);
    assert!(frames > 0);
    assert_eq!(frames + dropped, n, "every frame of both sizes came");
}

#[test]
fn stream_that_stalls_is_tried_again() {
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let port = free_port();
    let mut first = serve(&video, port);
    std::thread::sleep(Duration::from_millis(500));
    let child = mp()
        .args([
            "live",
            &format!("tcp://127.0.0.1:{port}"),
            "--json",
            "--stall-timeout",
            "2",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The first server stops sending mid-stream (its connection stays
    // open); a second one serves the video again on the same port.
    std::thread::sleep(Duration::from_millis(3000));
    let pid = first.id().to_string();
    assert!(Command::new("kill")
        .args(["-STOP", &pid])
        .status()
        .unwrap()
        .success());
    let mut second = serve(&video, port);
    let out = child.wait_with_output().unwrap();
    let _ = Command::new("kill").args(["-KILL", &pid]).status();
    let _ = first.wait();
    let _ = second.kill();
    let _ = second.wait();
    let (frames, dropped, _) = summary(&out);
    let events = lines(&out);
    let tries: Vec<_> = events.iter().filter(|e| e["type"] == "reconnect").collect();
    assert!(!tries.is_empty(), "{events:?}");
    // Frames of both connections, the second after the stream time of the gap.
    let n = frame_count(&video);
    assert!(
        frames + dropped > n,
        "{frames} + {dropped} of {n} per connection"
    );
    let t = events.last().unwrap()["t"].as_f64().unwrap();
    let length = n as f64 / 29.0;
    assert!(t > length + 1.0, "stream time {t} s");
}
