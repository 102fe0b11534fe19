//! Frames from a file, standard input, a camera or a network stream,
//! decoded by FFmpeg ([`mp_pose::VideoReader`]) on a thread of their
//! own.
//!
//! Standard input carries a video container that can be read from a pipe
//! (MPEG-TS, Matroska, …): its first bytes are read until `ffprobe` finds the
//! frame size and rate in them, then they and the rest of the stream are fed
//! to FFmpeg. A camera (`/dev/video0`, FFmpeg's `v4l2` input) or a network
//! stream (`rtsp://`, `http://`, `udp://`, `srt://`, `tcp://`, …) is read
//! the same way from a first FFmpeg that copies its video, unchanged, into
//! a NUT stream on a pipe: one connection to the source serves both the
//! probing and the decoding. A network source that cannot be reached, or
//! that breaks off with an error, is tried again a few times
//! ([`RECONNECTS`], [`RECONNECT_PAUSE`]); the stream time goes on across the
//! gap. A stream whose frame size changes is scaled by FFmpeg to its first
//! size.
//!
//! The decoded frames wait in a [`Slot`], a queue of at most
//! `LiveParams::queue_s` seconds of frames (at least one frame, at most
//! [`MAX_QUEUE_BYTES`]): a frame that costs the pose model more than the
//! rest (a search of the detector, the counting of a window) delays the next
//! ones instead of losing them. For a live source, a new frame that finds
//! the queue full pushes out the oldest one waiting (which counts as
//! dropped), so nothing queues up without bound when the pose model is
//! slower than the source; a file read as fast as possible waits for the
//! pose model instead.

use std::collections::VecDeque;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use mp_pose::{probe_bytes, Frame, VideoInfo, VideoReadOptions, VideoReader};

use crate::{LiveError, Result};

/// How many times a network source is tried again after it could not be
/// reached or broke off with an error.
pub const RECONNECTS: u32 = 3;
/// The pause before each new try.
pub const RECONNECT_PAUSE: Duration = Duration::from_secs(1);

/// Where the frames come from.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum LiveSource {
    /// A video file.
    File(PathBuf),
    /// A video stream on standard input.
    Stdin,
    /// A camera: a video device read through FFmpeg's `v4l2` input.
    Device(PathBuf),
    /// A stream FFmpeg reads from the network (`rtsp://…`, `udp://…`, …).
    Url(String),
}

impl LiveSource {
    /// `-` is standard input, `scheme://…` a network stream, `/dev/…` a
    /// camera, anything else a file.
    pub fn parse(s: &str) -> Self {
        if s == "-" {
            return LiveSource::Stdin;
        }
        if let Some((scheme, rest)) = s.split_once("://") {
            let is_scheme = !scheme.is_empty()
                && scheme
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c));
            if is_scheme && scheme != "file" {
                return LiveSource::Url(s.to_string());
            }
            if scheme == "file" {
                return LiveSource::File(PathBuf::from(rest));
            }
        }
        if s.starts_with("/dev/") {
            return LiveSource::Device(PathBuf::from(s));
        }
        LiveSource::File(PathBuf::from(s))
    }

    /// Whether frames arrive at the source's own pace (and are dropped when late).
    pub fn is_live(&self, realtime: bool) -> bool {
        realtime || !matches!(self, LiveSource::File(_))
    }

    /// How the source is named in messages.
    pub fn name(&self) -> String {
        match self {
            LiveSource::File(p) | LiveSource::Device(p) => p.display().to_string(),
            LiveSource::Stdin => "standard input".into(),
            LiveSource::Url(u) => u.clone(),
        }
    }

    /// Whether the source is tried again when it cannot be reached or breaks off.
    fn reconnects(&self) -> bool {
        matches!(self, LiveSource::Url(_))
    }
}

/// How long [`Slot::stop`] waits for the decoding thread to end.
pub const STOP_WAIT: Duration = Duration::from_secs(2);

/// Bytes read from standard input at a time.
const CHUNK: usize = 64 << 10;
/// The longest wait for more bytes before the first bytes of a stream are probed.
const PROBE_PAUSE: Duration = Duration::from_millis(300);
/// The most bytes of a stream read before giving up finding a video in them.
const MAX_PROBE_BYTES: usize = 8 << 20;

/// Bytes of a stream (standard input, or the pipe of the FFmpeg that reads
/// a camera or the network), read on a thread of their own (so that a
/// stalled stream can be noticed), and the bytes already taken. Owns that
/// FFmpeg, which is stopped when the bytes are no longer wanted.
struct ChannelReader {
    rx: Receiver<Vec<u8>>,
    buf: Vec<u8>,
    pos: usize,
    child: Option<Arc<Mutex<Child>>>,
}

impl Read for ChannelReader {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        while self.pos >= self.buf.len() {
            match self.rx.recv() {
                Ok(b) => {
                    self.buf = b;
                    self.pos = 0;
                }
                Err(_) => return Ok(0),
            }
        }
        let n = out.len().min(self.buf.len() - self.pos);
        out[..n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

impl Drop for ChannelReader {
    fn drop(&mut self) {
        if let Some(c) = &self.child {
            let mut c = c.lock().unwrap_or_else(|p| p.into_inner());
            let _ = c.kill();
        }
    }
}

fn read_chunks(mut input: impl Read + Send + 'static) -> Receiver<Vec<u8>> {
    let (tx, rx) = sync_channel::<Vec<u8>>(16);
    std::thread::spawn(move || loop {
        let mut b = vec![0u8; CHUNK];
        match input.read(&mut b) {
            Ok(0) => break,
            Ok(n) => {
                b.truncate(n);
                if tx.send(b).is_err() {
                    break;
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(_) => break,
        }
    });
    rx
}

/// Why the FFmpeg reading a camera or the network stopped: its message, or
/// `None` when it ended cleanly (or is still running).
#[derive(Clone, Default)]
struct Outcome(Arc<Mutex<Option<std::result::Result<(), String>>>>);

impl Outcome {
    fn set(&self, r: std::result::Result<(), String>) {
        *self.0.lock().unwrap_or_else(|p| p.into_inner()) = Some(r);
    }
    fn failure(&self) -> Option<String> {
        match &*self.0.lock().unwrap_or_else(|p| p.into_inner()) {
            Some(Err(m)) => Some(m.clone()),
            _ => None,
        }
    }
}

/// Starts the FFmpeg that copies the video of a camera or a network stream
/// into a NUT stream on its standard output.
fn start_remux(source: &LiveSource, stall: Duration) -> Result<(ChannelReader, Outcome)> {
    let mut cmd = Command::new("ffmpeg");
    // Copied from its first packets on, not after seconds of probing.
    cmd.args([
        "-v",
        "error",
        "-nostdin",
        "-probesize",
        "32768",
        "-analyzeduration",
        "0",
    ]);
    // Half the stall timeout: a stream that stalls is tried again before the
    // analysis would give up on it.
    let micros = (stall.as_secs_f64() * 0.5e6).round().to_string();
    match source {
        LiveSource::Device(p) => {
            if !p.exists() {
                return Err(LiveError::Source(format!(
                    "no camera at {}: the device does not exist",
                    p.display()
                )));
            }
            cmd.args(["-f", "v4l2"]).arg("-i").arg(p);
        }
        LiveSource::Url(u) => {
            if u.starts_with("rtsp") {
                cmd.args(["-timeout", &micros]);
            } else if !u.starts_with("udp") && !u.starts_with("srt") && !u.starts_with("rtp") {
                cmd.args(["-rw_timeout", &micros]);
            }
            cmd.args(["-i", u]);
        }
        LiveSource::File(_) | LiveSource::Stdin => {
            return Err(LiveError::Source(format!(
                "{} is not a camera or a network stream",
                source.name()
            )))
        }
    }
    let mut child = cmd
        .args([
            "-map",
            "0:v:0",
            "-c:v",
            "copy",
            "-flush_packets",
            "1",
            "-f",
            "nut",
            "pipe:1",
        ])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| LiveError::Source(format!("cannot run ffmpeg (is FFmpeg installed?): {e}")))?;
    let stdout = child.stdout.take();
    let mut stderr = child.stderr.take();
    let child = Arc::new(Mutex::new(child));
    let outcome = Outcome::default();
    let rx = match stdout {
        Some(out) => {
            let (c, o) = (child.clone(), outcome.clone());
            let (tx, rx) = sync_channel::<Vec<u8>>(16);
            let inner = read_chunks(out);
            std::thread::spawn(move || {
                for b in inner {
                    if tx.send(b).is_err() {
                        break;
                    }
                }
                let mut msg = String::new();
                if let Some(e) = stderr.as_mut() {
                    let _ = e.read_to_string(&mut msg);
                }
                let status = c.lock().unwrap_or_else(|p| p.into_inner()).wait();
                // FFmpeg's last line says what failed, naming the source.
                let msg = msg.trim().lines().last().unwrap_or_default().to_string();
                // A timed-out connection ends with success and a message.
                o.set(match status {
                    Ok(s) if s.success() && msg.is_empty() => Ok(()),
                    Ok(s) if msg.is_empty() => Err(format!("ffmpeg stopped ({s})")),
                    _ => Err(msg),
                });
                drop(tx);
            });
            rx
        }
        None => return Err(LiveError::Source("cannot read the output of ffmpeg".into())),
    };
    Ok((
        ChannelReader {
            rx,
            buf: Vec::new(),
            pos: 0,
            child: Some(child),
        },
        outcome,
    ))
}

/// An opened source: the reader of its frames, and for a camera or a
/// network stream, how the FFmpeg that reads it ended.
pub struct Opened {
    reader: VideoReader,
    outcome: Option<Outcome>,
}

/// Opens the source: probes it and starts FFmpeg decoding it.
pub fn open(source: &LiveSource, realtime: bool, stall: Duration) -> Result<Opened> {
    let err = |e: mp_pose::PoseError| LiveError::Source(e.to_string());
    let from_stream = |feed: ChannelReader, outcome: Option<Outcome>| -> Result<Opened> {
        let mut feed = feed;
        let (mut info, prefix) = match probe_stream(&feed.rx, stall, source) {
            Ok(x) => x,
            Err(e) => {
                // The reason the reading FFmpeg gave, rather than "no video".
                drop(feed);
                return Err(outcome
                    .and_then(|o| wait_failure(&o))
                    .map(LiveError::Source)
                    .unwrap_or(e));
            }
        };
        info.path = PathBuf::from(source.name());
        feed.buf = prefix;
        let reader = VideoReader::open_with(
            info,
            VideoReadOptions {
                realtime: false,
                feed: Some(Box::new(feed)),
            },
        )
        .map_err(err)?;
        Ok(Opened { reader, outcome })
    };
    match source {
        LiveSource::File(p) => {
            let info = mp_pose::probe(p).map_err(err)?;
            let reader = VideoReader::open_with(
                info,
                VideoReadOptions {
                    realtime,
                    feed: None,
                },
            )
            .map_err(err)?;
            Ok(Opened {
                reader,
                outcome: None,
            })
        }
        LiveSource::Stdin => {
            let feed = ChannelReader {
                rx: read_chunks(std::io::stdin()),
                buf: Vec::new(),
                pos: 0,
                child: None,
            };
            from_stream(feed, None)
        }
        LiveSource::Device(_) | LiveSource::Url(_) => {
            let (feed, outcome) = start_remux(source, stall)?;
            from_stream(feed, Some(outcome))
        }
    }
}

/// The failure of the reading FFmpeg, once it has stopped (waits briefly for it).
fn wait_failure(outcome: &Outcome) -> Option<String> {
    let deadline = Instant::now() + Duration::from_secs(2);
    loop {
        if outcome
            .0
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .is_some()
            || Instant::now() > deadline
        {
            return outcome.failure();
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Opens a network source, trying again up to [`RECONNECTS`] times.
fn open_retrying(
    source: &LiveSource,
    realtime: bool,
    stall: Duration,
    on_retry: &mut dyn FnMut(u32, &str),
) -> Result<Opened> {
    let mut attempt = 0;
    loop {
        match open(source, realtime, stall) {
            Ok(o) => return Ok(o),
            Err(e) if source.reconnects() && attempt < RECONNECTS => {
                attempt += 1;
                on_retry(attempt, &e.to_string());
                std::thread::sleep(RECONNECT_PAUSE);
            }
            Err(e) if attempt > 0 => {
                return Err(LiveError::Source(format!(
                    "{e} (tried {} times)",
                    attempt + 1
                )))
            }
            Err(e) => return Err(e),
        }
    }
}

/// Reads a stream until `ffprobe` finds a video in its first bytes;
/// returns what it found and the bytes read.
fn probe_stream(
    rx: &Receiver<Vec<u8>>,
    stall: Duration,
    source: &LiveSource,
) -> Result<(VideoInfo, Vec<u8>)> {
    let name = source.name();
    let mut bytes = Vec::new();
    let mut next_try = 16 << 10;
    let mut ended = false;
    let mut quiet = Duration::ZERO;
    loop {
        // Tried as soon as enough bytes came, or after a pause in a slow
        // stream (a few kilobytes can hold its first frames).
        let mut since_try = Instant::now();
        while !ended && bytes.len() < next_try {
            match rx.recv_timeout(PROBE_PAUSE) {
                Ok(b) => {
                    bytes.extend_from_slice(&b);
                    quiet = Duration::ZERO;
                }
                Err(RecvTimeoutError::Disconnected) => ended = true,
                Err(RecvTimeoutError::Timeout) => {
                    quiet += PROBE_PAUSE;
                    if quiet >= stall {
                        return Err(LiveError::Source(format!(
                            "the stream stalled: no data from {name} for {:.1} s{}",
                            stall.as_secs_f64(),
                            if bytes.is_empty() {
                                ""
                            } else {
                                " (no video stream found in what came)"
                            }
                        )));
                    }
                }
            }
            if !bytes.is_empty() && since_try.elapsed() >= PROBE_PAUSE {
                since_try = Instant::now();
                if let Ok(info) = probe_bytes(Path::new(&name), &bytes) {
                    return Ok((info, bytes));
                }
            }
        }
        if bytes.is_empty() {
            return Err(LiveError::Source(format!(
                "{name} is empty: expected a video stream (e.g. MPEG-TS)"
            )));
        }
        match probe_bytes(Path::new(&name), &bytes) {
            Ok(info) => return Ok((info, bytes)),
            Err(e) if ended || bytes.len() >= MAX_PROBE_BYTES => {
                return Err(LiveError::Source(format!(
                    "{name} is not a video stream FFmpeg can read from a pipe (e.g. MPEG-TS): {e}"
                )));
            }
            Err(_) => next_try = bytes.len() * 4,
        }
    }
}

/// What the slot holds.
#[derive(Default)]
struct SlotState {
    frames: VecDeque<Frame>,
    dropped: usize,
    newest_s: f64,
    ended: Option<std::result::Result<(), String>>,
    stop: bool,
    reconnects: Vec<Reconnect>,
    reconnecting: bool,
    /// The decoding thread has ended and its FFmpeg processes with it.
    decoder_done: bool,
}

/// A new try at a network source that could not be reached or broke off.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Reconnect {
    /// 1 for the first new try.
    pub attempt: u32,
    /// Why the source is tried again.
    pub reason: String,
}

/// The frame waiting for the pose model (see the module docs), shared
/// between the decoding thread and the analysis.
#[derive(Clone)]
pub struct Slot {
    inner: Arc<(Mutex<SlotState>, Condvar)>,
    drop_late: bool,
    /// Frames that may wait at once (at least one).
    capacity: usize,
}

/// What [`Slot::take`] gives.
#[non_exhaustive]
pub enum Taken {
    /// The next frame.
    Frame(Frame),
    /// The source ended (or failed, with the message).
    Ended(std::result::Result<(), String>),
    /// No frame for longer than the timeout.
    Stalled,
}

impl Slot {
    fn new(drop_late: bool, capacity: usize) -> Self {
        Slot {
            inner: Arc::new((Mutex::new(SlotState::default()), Condvar::new())),
            drop_late,
            capacity: capacity.max(1),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, SlotState> {
        self.inner.0.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Frames dropped so far.
    pub fn dropped(&self) -> usize {
        self.lock().dropped
    }

    /// Stream time of the newest frame decoded, seconds.
    pub fn newest_s(&self) -> f64 {
        self.lock().newest_s
    }

    /// The new tries at the source since the last call.
    pub fn take_reconnects(&self) -> Vec<Reconnect> {
        std::mem::take(&mut self.lock().reconnects)
    }

    fn reconnecting(&self, attempt: u32, reason: &str) {
        let mut s = self.lock();
        s.reconnecting = true;
        s.reconnects.push(Reconnect {
            attempt,
            reason: reason.to_string(),
        });
    }

    /// Whether the source is being tried again now (no frame is expected
    /// meanwhile: the wait does not count as a stall).
    pub fn is_reconnecting(&self) -> bool {
        self.lock().reconnecting
    }

    fn stopped(&self) -> bool {
        self.lock().stop
    }

    /// Asks the decoding thread to stop, and waits until it has ended (its
    /// FFmpeg process stopped) or `STOP_WAIT` has passed: it may be waiting
    /// for bytes of a stalled stream, and then ends with the stream.
    pub fn stop(&self) {
        let mut s = self.lock();
        s.stop = true;
        self.inner.1.notify_all();
        let deadline = Instant::now() + STOP_WAIT;
        while !s.decoder_done {
            let now = Instant::now();
            if now >= deadline {
                break;
            }
            s = self
                .inner
                .1
                .wait_timeout(s, deadline - now)
                .map(|(g, _)| g)
                .unwrap_or_else(|p| p.into_inner().0);
        }
    }

    /// Puts a decoded frame; false when the decoding should stop.
    fn put(&self, frame: Frame) -> bool {
        let mut s = self.lock();
        while !self.drop_late && s.frames.len() >= self.capacity && !s.stop {
            s = self.inner.1.wait(s).unwrap_or_else(|p| p.into_inner());
        }
        if s.stop {
            return false;
        }
        s.newest_s = frame.timestamp_s;
        s.reconnecting = false;
        // Only a live source's queue can be full here (a file's waited).
        if s.frames.len() >= self.capacity {
            s.frames.pop_front();
            s.dropped += 1;
        }
        s.frames.push_back(frame);
        self.inner.1.notify_all();
        true
    }

    fn end(&self, r: std::result::Result<(), String>) {
        self.lock().ended = Some(r);
        self.inner.1.notify_all();
    }

    /// The next frame, waiting at most `timeout` (or until `stop`).
    pub fn take(&self, timeout: Duration) -> Taken {
        let deadline = Instant::now() + timeout;
        let mut s = self.lock();
        loop {
            if let Some(f) = s.frames.pop_front() {
                self.inner.1.notify_all();
                return Taken::Frame(f);
            }
            if let Some(r) = &s.ended {
                return Taken::Ended(r.clone());
            }
            let now = Instant::now();
            if now >= deadline {
                return Taken::Stalled;
            }
            s = self
                .inner
                .1
                .wait_timeout(s, deadline - now)
                .map(|(g, _)| g)
                .unwrap_or_else(|p| p.into_inner().0);
        }
    }
}

/// The most bytes of frames a [`Slot`] holds: 256 MiB (a second of 1080p
/// RGB frames at 30 fps is about 187 MB).
pub const MAX_QUEUE_BYTES: usize = 256 << 20;

/// How many frames of `info`'s size `queue_s` seconds hold, within
/// [`MAX_QUEUE_BYTES`] and at least one.
fn queue_frames(info: &VideoInfo, queue_s: f64) -> usize {
    let frame_bytes = (info.width * info.height * 3).max(1);
    let by_time = (queue_s * info.fps).floor();
    let by_time = if by_time.is_finite() && by_time > 0.0 {
        by_time as usize
    } else {
        1
    };
    by_time.min(MAX_QUEUE_BYTES / frame_bytes).max(1)
}

/// Opens `source` and starts decoding it into a [`Slot`] of `queue_s`
/// seconds of frames on a thread of its own; returns the slot and the
/// video's properties. A network source is
/// tried again (each new try at opening it reported to `on_retry`, later ones
/// by [`Slot::take_reconnects`]) when it cannot be reached or breaks off with an error (see
/// the module docs); its frames go on with the stream time that passed.
pub fn start(
    source: &LiveSource,
    realtime: bool,
    stall: Duration,
    drop_late: bool,
    queue_s: f64,
    on_retry: &mut dyn FnMut(Reconnect),
) -> Result<(Slot, VideoInfo)> {
    let first = open_retrying(source, realtime, stall, &mut |attempt, reason| {
        on_retry(Reconnect {
            attempt,
            reason: reason.to_string(),
        })
    })?;
    let info = first.reader.info().clone();
    let slot = Slot::new(drop_late, queue_frames(&info, queue_s));
    let s = slot.clone();
    let source = source.clone();
    std::thread::Builder::new()
        .name("live-decode".into())
        .spawn(move || {
            decode(first, &source, realtime, stall, &s);
            // The readers (and their FFmpeg processes) are gone by now.
            s.lock().decoder_done = true;
            s.inner.1.notify_all();
        })
        .map_err(|e| LiveError::Source(format!("cannot start the decoding thread: {e}")))?;
    Ok((slot, info))
}

/// The decoding thread: every frame of the source into the slot, through
/// new connections to a network source that breaks off.
fn decode(first: Opened, source: &LiveSource, realtime: bool, stall: Duration, s: &Slot) {
    let (fps, size) = {
        let i = first.reader.info();
        (i.fps, (i.width, i.height))
    };
    let mut opened = first;
    // Stream frames before this connection's first.
    let mut offset = 0usize;
    loop {
        let mut next = offset;
        let mut failure = None;
        for frame in opened.reader.by_ref() {
            match frame {
                Ok(mut f) => {
                    f.index += offset;
                    f.timestamp_s = f.index as f64 / fps;
                    next = f.index + 1;
                    if !s.put(f) {
                        return;
                    }
                }
                Err(e) => {
                    failure = Some(e.to_string());
                    break;
                }
            }
        }
        let failure = failure.or_else(|| opened.outcome.as_ref().and_then(wait_failure));
        let Some(reason) = failure.filter(|_| source.reconnects() && !s.stopped()) else {
            s.end(Ok(()));
            return;
        };
        let lost = Instant::now();
        s.reconnecting(1, &reason);
        let again = open_retrying(source, realtime, stall, &mut |a, r| {
            s.reconnecting(a + 1, r)
        })
        .and_then(|o| {
            let i = o.reader.info();
            if (i.width, i.height) == size {
                Ok(o)
            } else {
                Err(LiveError::Source(format!(
                    "{} came back with frames of {}×{} instead of {}×{}",
                    source.name(),
                    i.width,
                    i.height,
                    size.0,
                    size.1
                )))
            }
        });
        match again {
            Ok(o) => {
                opened = o;
                // The stream time that passed while the source was away.
                offset = next + (lost.elapsed().as_secs_f64() * fps).round() as usize;
            }
            Err(e) => {
                s.end(Err(format!("{reason}; then {e}")));
                return;
            }
        }
    }
}

#[cfg(test)]
#[path = "source_tests.rs"]
mod tests;
