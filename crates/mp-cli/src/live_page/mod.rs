//! The live page of `mp live --serve`: a small web server that shows the
//! run while the stream plays.
//!
//! - `/`: the page (one self-contained document, [`PAGE`]);
//! - `/stream.mjpg`: the analysed frames with the people drawn on them, as
//!   MJPEG ([`video`]);
//! - `/events`: every event as Server-Sent Events, the state so far first
//!   ([`events`]).
//!
//! Anything else is 404, a method other than GET 405. The run only
//! hands over its events and its newest frame ([`PageSink`]); it never
//! waits on a browser. Every answer is written by a thread of its own,
//! and a browser that takes no bytes for [`WRITE_TIMEOUT`] is
//! disconnected, so a stalled browser cannot keep a place.

pub mod events;
pub mod video;

use std::net::{SocketAddr, TcpListener, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use anyhow::Context;
use mp_live::{Event, LiveFrame, Sink};

use events::EventHub;
use video::VideoHub;

/// The page, compiled into the binary.
pub const PAGE: &str = include_str!("page.html");

/// How long one write to a browser may wait for the browser to take
/// bytes before its connection is dropped.
pub const WRITE_TIMEOUT: Duration = Duration::from_secs(10);

/// The address of `--serve` without a value.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8000";

/// The address to serve at: a bare port binds the loopback address
/// (`8080` → `127.0.0.1:8080`; port 0: a free port), anything else is
/// `HOST:PORT` (`0.0.0.0:8080`, `[::1]:8080`, `localhost:8080`).
pub fn parse_addr(text: &str) -> anyhow::Result<SocketAddr> {
    let text = text.trim();
    if let Ok(port) = text.parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    let bad = || {
        format!("--serve: expected a port or HOST:PORT (e.g. 8080 or 127.0.0.1:8080), got {text:?}")
    };
    if let Ok(a) = text.parse::<SocketAddr>() {
        return Ok(a);
    }
    text.to_socket_addrs()
        .with_context(bad)?
        .next()
        .with_context(bad)
}

/// A listening socket whose connections time out writes after
/// `write_timeout`: the connections it accepts inherit the listening
/// socket's send timeout (it has no receive timeout, which would also end
/// waiting for the next connection).
fn listen(addr: SocketAddr, write_timeout: Duration) -> std::io::Result<TcpListener> {
    use socket2::{Domain, Protocol, Socket, Type};
    let socket = Socket::new(Domain::for_address(addr), Type::STREAM, Some(Protocol::TCP))?;
    socket.set_reuse_address(true)?;
    socket.set_write_timeout(Some(write_timeout))?;
    socket.bind(&addr.into())?;
    socket.listen(128)?;
    Ok(socket.into())
}

/// What the server's threads share.
struct Shared {
    events: EventHub,
    video: Arc<VideoHub>,
    stop: AtomicBool,
}

/// The running server. Dropping it stops it.
pub struct LivePage {
    shared: Arc<Shared>,
    addr: SocketAddr,
    threads: Vec<JoinHandle<()>>,
}

impl LivePage {
    /// Binds `addr` and starts serving.
    pub fn start(addr: SocketAddr) -> anyhow::Result<Self> {
        let listener = listen(addr, WRITE_TIMEOUT)
            .with_context(|| format!("--serve: cannot listen at {addr}"))?;
        let addr = listener.local_addr()?;
        let server = tiny_http::Server::from_listener(listener, None)
            .map_err(|e| anyhow::anyhow!("--serve: cannot serve at {addr}: {e}"))?;
        let shared = Arc::new(Shared {
            events: EventHub::default(),
            video: Arc::new(VideoHub::default()),
            stop: AtomicBool::new(false),
        });
        let s = shared.clone();
        let encoder = std::thread::Builder::new()
            .name("live-page-jpeg".into())
            .spawn(move || s.video.encode_loop(&s.stop))?;
        let s = shared.clone();
        let accept = std::thread::Builder::new()
            .name("live-page-http".into())
            .spawn(move || accept_loop(&server, &s))?;
        Ok(LivePage {
            shared,
            addr,
            threads: vec![encoder, accept],
        })
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// The sink that feeds the page, wrapping the run's own sink.
    pub fn sink<'a>(&'a self, inner: &'a mut dyn Sink) -> PageSink<'a> {
        PageSink {
            shared: &self.shared,
            inner,
        }
    }
}

impl Drop for LivePage {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

/// Passes every event and frame to the run's own sink, then to the page.
pub struct PageSink<'a> {
    shared: &'a Shared,
    inner: &'a mut dyn Sink,
}

impl Sink for PageSink<'_> {
    fn event(&mut self, event: &Event) {
        self.inner.event(event);
        if let Ok(line) = serde_json::to_string(event) {
            self.shared.events.publish(line);
        }
    }

    fn frame(&mut self, frame: &LiveFrame<'_>) {
        self.inner.frame(frame);
        self.shared
            .video
            .offer(frame.frame, frame.people, frame.totals);
    }
}

fn accept_loop(server: &tiny_http::Server, shared: &Arc<Shared>) {
    while !shared.stop.load(Ordering::SeqCst) {
        match server.recv_timeout(Duration::from_millis(200)) {
            Ok(Some(rq)) => route(rq, shared),
            Ok(None) => {}
            Err(_) => std::thread::sleep(Duration::from_millis(50)),
        }
    }
}

/// `r` with a header added (names and values here are plain ASCII).
fn with<R: std::io::Read>(
    mut r: tiny_http::Response<R>,
    name: &str,
    value: &str,
) -> tiny_http::Response<R> {
    if let Ok(h) = tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes()) {
        r.add_header(h);
    }
    r
}

fn text(status: u16, body: &str) -> tiny_http::Response<std::io::Cursor<Vec<u8>>> {
    with(
        tiny_http::Response::from_string(body).with_status_code(status),
        "Content-Type",
        "text/plain; charset=utf-8",
    )
}

/// Answers one request; the streams get a thread each.
fn route(rq: tiny_http::Request, shared: &Arc<Shared>) {
    use tiny_http::Method;
    let path = rq.url().split(['?', '#']).next().unwrap_or("").to_string();
    let known = matches!(path.as_str(), "/" | "/stream.mjpg" | "/events");
    let res = match rq.method() {
        Method::Get => match path.as_str() {
            "/" => {
                spawn("live-page-page", move || {
                    let _ = rq.respond(with(
                        with(
                            tiny_http::Response::from_string(PAGE),
                            "Content-Type",
                            "text/html; charset=utf-8",
                        ),
                        "Cache-Control",
                        "no-cache",
                    ));
                });
                Ok(())
            }
            "/stream.mjpg" => match shared.video.watch() {
                Some(watcher) => {
                    let s = shared.clone();
                    spawn("live-page-video", move || {
                        watcher.serve(rq.into_writer(), &s.stop)
                    });
                    Ok(())
                }
                None => rq.respond(text(
                    503,
                    &format!("{} browsers already watch the video\n", video::MAX_STREAMS),
                )),
            },
            "/events" => match shared.events.subscribe() {
                Some(queue) => {
                    let s = shared.clone();
                    spawn("live-page-events", move || {
                        events::serve_client(rq.into_writer(), queue, &s.stop)
                    });
                    Ok(())
                }
                None => rq.respond(text(
                    503,
                    &format!(
                        "{} browsers already follow the events\n",
                        events::MAX_CLIENTS
                    ),
                )),
            },
            _ => rq.respond(text(404, &format!("no page at {path}\n"))),
        },
        _ if known => rq.respond(with(text(405, "only GET\n"), "Allow", "GET")),
        _ => rq.respond(text(404, &format!("no page at {path}\n"))),
    };
    // A browser that went away before its answer: nothing to do.
    let _ = res;
}

fn spawn(name: &str, f: impl FnOnce() + Send + 'static) {
    // Without a thread the browser's connection closes: it retries.
    let _ = std::thread::Builder::new().name(name.into()).spawn(f);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses() {
        assert_eq!(parse_addr("8080").unwrap().to_string(), "127.0.0.1:8080");
        assert_eq!(parse_addr("0").unwrap().to_string(), "127.0.0.1:0");
        assert_eq!(
            parse_addr(DEFAULT_ADDR).unwrap().to_string(),
            "127.0.0.1:8000"
        );
        assert_eq!(
            parse_addr("0.0.0.0:9000").unwrap().to_string(),
            "0.0.0.0:9000"
        );
        assert_eq!(parse_addr("[::1]:80").unwrap().to_string(), "[::1]:80");
        let e = parse_addr("no port").unwrap_err().to_string();
        assert!(e.contains("--serve") && e.contains("no port"), "{e}");
        assert!(parse_addr("70000").is_err());
    }

    #[test]
    fn a_browser_that_takes_no_bytes_is_cut_off() {
        use std::io::Write;
        let timeout = Duration::from_millis(300);
        let listener = listen(SocketAddr::from(([127, 0, 0, 1], 0)), timeout).unwrap();
        let browser = std::net::TcpStream::connect(listener.local_addr().unwrap()).unwrap();
        let (mut conn, _) = listener.accept().unwrap();
        assert_eq!(conn.write_timeout().unwrap(), Some(timeout));
        // The browser never reads: once the buffers are full a write
        // fails instead of waiting for ever.
        let chunk = vec![0u8; 64 * 1024];
        let started = std::time::Instant::now();
        let err = loop {
            if let Err(e) = conn.write_all(&chunk) {
                break e;
            }
            assert!(started.elapsed() < Duration::from_secs(60), "never cut off");
        };
        assert!(
            matches!(
                err.kind(),
                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
            ),
            "{err}"
        );
        drop(browser);
    }
}
