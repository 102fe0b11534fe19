//! The live page of `mp live --serve` through the built binary, on a real
//! QUVA video read at its own speed: headless Chromium shows the annotated
//! video while the stream plays, the page's totals after the end equal the
//! summary line, several browsers get the MJPEG stream at once (a ninth is
//! answered 503), unknown
//! routes are 404, and Ctrl-C ends the server cleanly.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::process::{Child, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::Duration;

/// `mp live VIDEO --realtime --json --serve 127.0.0.1:0`, its stderr lines
/// on a channel, its stdout collected by a thread.
struct Served {
    child: Child,
    stderr: Receiver<String>,
    stdout: std::thread::JoinHandle<String>,
    addr: SocketAddr,
}

fn serve(video: &Path) -> Served {
    let mut child = common::mp_command()
        .arg("live")
        .arg(video)
        .args(["--realtime", "--json", "--serve=127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (tx, stderr) = channel();
    let err = child.stderr.take().unwrap();
    std::thread::spawn(move || {
        for line in BufReader::new(err).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let mut out = child.stdout.take().unwrap();
    let stdout = std::thread::spawn(move || {
        let mut s = String::new();
        out.read_to_string(&mut s).unwrap();
        s
    });
    let first = stderr.recv_timeout(Duration::from_secs(60)).unwrap();
    let url = first
        .strip_prefix("serving the live page at http://")
        .unwrap_or_else(|| panic!("unexpected first line on stderr: {first}"));
    let addr: SocketAddr = url.trim_end_matches('/').parse().unwrap();
    assert_eq!(addr.ip().to_string(), "127.0.0.1", "{first}");
    assert_ne!(addr.port(), 0);
    Served {
        child,
        stderr,
        stdout,
        addr,
    }
}

impl Served {
    fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// Waits for the line saying the stream ended.
    fn wait_for_end(&self) {
        loop {
            let line = self
                .stderr
                .recv_timeout(Duration::from_secs(300))
                .expect("the stream did not end");
            assert!(!line.contains("panicked"), "{line}");
            if line.starts_with("the stream ended; the page stays at ") {
                assert!(line.contains(&self.url()), "{line}");
                return;
            }
        }
    }

    /// Ctrl-C: mp must exit with success; its stdout.
    fn interrupt(mut self) -> String {
        let st = std::process::Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status()
            .unwrap();
        assert!(st.success());
        let status = self.child.wait().unwrap();
        assert!(status.success(), "mp after Ctrl-C: {status}");
        self.stdout.join().unwrap()
    }
}

/// A raw HTTP request; the connection, its head read up to the blank line.
fn request(addr: SocketAddr, method: &str, path: &str) -> (TcpStream, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut head = Vec::new();
    let mut b = [0u8; 1];
    while !head.ends_with(b"\r\n\r\n") {
        assert_eq!(s.read(&mut b).unwrap(), 1, "connection closed in the head");
        head.push(b[0]);
    }
    (s, String::from_utf8(head).unwrap())
}

/// Reads `n` JPEG parts of an MJPEG stream; their decoded sizes.
fn jpeg_parts(s: &mut TcpStream, n: usize) -> Vec<(u32, u32)> {
    let mut buf = Vec::new();
    let mut sizes = Vec::new();
    let mut chunk = [0u8; 65536];
    while sizes.len() < n {
        let k = s.read(&mut chunk).unwrap();
        assert!(k > 0, "the stream closed after {} parts", sizes.len());
        buf.extend_from_slice(&chunk[..k]);
        // A part: its head, then Content-Length bytes.
        let key = b"Content-Type: image/jpeg\r\nContent-Length: ";
        let Some(h) = find(&buf, key) else {
            continue;
        };
        let Some(eol) = find(&buf[h + key.len()..], b"\r\n\r\n") else {
            continue;
        };
        let len: usize = std::str::from_utf8(&buf[h + key.len()..h + key.len() + eol])
            .unwrap()
            .trim()
            .parse()
            .unwrap();
        let start = h + key.len() + eol + 4;
        if buf.len() < start + len {
            continue;
        }
        let jpeg = &buf[start..start + len];
        assert_eq!(&jpeg[..2], [0xff, 0xd8], "not a JPEG");
        let img = image::load_from_memory(jpeg).unwrap();
        sizes.push((img.width(), img.height()));
        buf.drain(..start + len);
    }
    sizes
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// The summary line of `mp live --json` and each person's last `rep` count.
fn totals(stdout: &str) -> (BTreeMap<u64, u64>, BTreeMap<u64, u64>) {
    let events: Vec<serde_json::Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("not JSON ({e}): {l}")))
        .collect();
    let last = events.last().expect("no output");
    assert_eq!(last["type"], "summary", "{stdout}");
    let summary = last["people"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p["id"].as_u64().unwrap(),
                p["total_repetitions"].as_u64().unwrap(),
            )
        })
        .collect();
    let mut reps = BTreeMap::new();
    for e in events.iter().filter(|e| e["type"] == "rep") {
        reps.insert(e["person"].as_u64().unwrap(), e["count"].as_u64().unwrap());
    }
    (summary, reps)
}

/// The video's place on the page (left column, below the header): a picture
/// has many colours and varied brightness, an empty box one. Returns the
/// colours and the brightness's standard deviation there.
fn picture_in_video_place(png: &image::RgbImage) -> (usize, f64) {
    let mut colours = std::collections::HashSet::new();
    let mut lum = Vec::new();
    for y in (80..500).step_by(4) {
        for x in (30..640).step_by(4) {
            let p = png.get_pixel(x, y).0;
            colours.insert(p);
            lum.push(0.299 * p[0] as f64 + 0.587 * p[1] as f64 + 0.114 * p[2] as f64);
        }
    }
    let mean = lum.iter().sum::<f64>() / lum.len() as f64;
    let sd = (lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lum.len() as f64).sqrt();
    (colours.len(), sd)
}

/// The two tests run one after the other: each is a live run on a 2-core
/// machine, and the eight video streams of the second took the CPU the
/// first one's browser needs to receive the end in time.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[test]
fn the_page_shows_the_stream_and_the_final_totals() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let video = mp_geom::data_or_return!("quva_repetition/videos/000_rope_beach.mp4");
    let dir = tempfile::tempdir().unwrap();
    let served = serve(&video);
    let url = served.url();

    // While the stream plays: the video is on the page. Chromium may take
    // seconds to start on a busy machine, so a blank first look is taken
    // again, later.
    let mut seen = Vec::new();
    for (k, wait) in [3000, 4000, 6000].into_iter().enumerate() {
        let shot = dir.path().join(format!("live{k}.png"));
        let out = common::browser::chromium_live(
            &url,
            &dir.path().join(format!("profile{k}")),
            wait,
            &[&format!("--screenshot={}", shot.display())],
        );
        assert!(
            shot.exists(),
            "no screenshot: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let png = image::open(&shot).unwrap().to_rgb8();
        assert_eq!(png.dimensions(), (1280, 900));
        let (colours, sd) = picture_in_video_place(&png);
        seen.push((colours, sd));
        if colours > 500 && sd > 15.0 {
            break;
        }
    }
    let &(colours, sd) = seen.last().unwrap();
    assert!(
        colours > 500 && sd > 15.0,
        "(colours, brightness s.d.) in the video's place: {seen:?}"
    );

    // Routes: unknown paths are 404, other methods 405.
    let (_, head) = request(served.addr, "GET", "/nothing");
    assert!(head.starts_with("HTTP/1.1 404"), "{head}");
    let (_, head) = request(served.addr, "GET", "/../Cargo.toml");
    assert!(head.starts_with("HTTP/1.1 404"), "{head}");
    let (_, head) = request(served.addr, "POST", "/");
    assert!(head.starts_with("HTTP/1.1 405"), "{head}");
    let (_, head) = request(served.addr, "GET", "/");
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    assert!(head.contains("text/html"), "{head}");

    // After the end: the page's totals are the summary's.
    served.wait_for_end();
    // Chromium dumps the page after a wait in real time; on a loaded machine
    // its start can take most of it, so a page without the end yet is read
    // again with a longer wait.
    let mut dom = String::new();
    for (k, wait_ms) in [5000u32, 10000, 20000].into_iter().enumerate() {
        let profile = dir.path().join(format!("profile-end-{k}"));
        // The virtual-time budget keeps Chromium from dumping the page the
        // moment it has loaded, before its event stream has delivered the end.
        let budget = format!("--virtual-time-budget={wait_ms}");
        let out = common::browser::chromium_live(&url, &profile, wait_ms, &["--dump-dom", &budget]);
        dom = String::from_utf8_lossy(&out.stdout).into_owned();
        if dom.contains("data-ended=\"1\"") {
            break;
        }
    }
    let state = common::browser::start_tag(&dom, "<span id=\"state\"");
    assert_eq!(
        common::browser::attr(state, "data-ended"),
        Some("1"),
        "{state}"
    );
    let cell = regex::Regex::new(r#"<td data-person="(\d+)" class="reps">(\d+)</td>"#).unwrap();
    let page: BTreeMap<u64, u64> = cell
        .captures_iter(&dom)
        .map(|c| (c[1].parse().unwrap(), c[2].parse().unwrap()))
        .collect();
    let stdout = served.interrupt();
    let (summary, reps) = totals(&stdout);
    assert!(!summary.is_empty(), "nobody found: {stdout}");
    assert!(summary.values().any(|n| *n > 0), "no repetition: {stdout}");
    assert_eq!(page, summary, "the page's totals and the summary line");
    // The program as it grew: segments on the page, none on standard output
    // (that needs --segments).
    let program = &dom[dom.find("<ol id=\"program\"").expect("no program panel")..];
    let program = &program[..program.find("</ol>").unwrap()];
    assert!(
        program.matches("<li data-person=").count() > 0,
        "no segment on the page: {program}"
    );
    assert!(!stdout.contains("\"type\":\"segment\""), "{stdout}");
    for (person, n) in &summary {
        assert_eq!(
            reps.get(person).copied().unwrap_or(0),
            *n,
            "person {person}"
        );
    }
}

#[test]
fn several_browsers_get_the_video_at_once() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let served = serve(&video);
    let mut streams: Vec<TcpStream> = (0..3)
        .map(|_| {
            let (s, head) = request(served.addr, "GET", "/stream.mjpg");
            assert!(head.starts_with("HTTP/1.1 200"), "{head}");
            assert!(
                head.contains("Content-Type: multipart/x-mixed-replace; boundary="),
                "{head}"
            );
            s
        })
        .collect();
    let readers: Vec<_> = streams
        .iter_mut()
        .map(|s| s.try_clone().unwrap())
        .map(|mut s| std::thread::spawn(move || jpeg_parts(&mut s, 3)))
        .collect();
    for r in readers {
        let sizes = r.join().unwrap();
        assert_eq!(sizes.len(), 3);
        for (w, h) in sizes {
            // The QUVA video is 640 wide or less: sent at its size.
            assert!((100..=640).contains(&w) && h >= 100, "{w}×{h}");
        }
    }
    // Eight browsers at once is the most: a ninth is told so.
    let more: Vec<TcpStream> = (3..8)
        .map(|_| {
            let (s, head) = request(served.addr, "GET", "/stream.mjpg");
            assert!(head.starts_with("HTTP/1.1 200"), "{head}");
            s
        })
        .collect();
    let (mut ninth, head) = request(served.addr, "GET", "/stream.mjpg");
    assert!(head.starts_with("HTTP/1.1 503"), "{head}");
    let mut body = String::new();
    ninth.read_to_string(&mut body).unwrap();
    assert!(
        body.contains("8 browsers already watch the video"),
        "{body}"
    );
    drop(more);
    drop(streams);
    served.wait_for_end();
    let stdout = served.interrupt();
    let (summary, _) = totals(&stdout);
    assert!(!summary.is_empty(), "{stdout}");
}
