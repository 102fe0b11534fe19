//! Frames from a file or from standard input, decoded by FFmpeg
//! ([`mp_pose::video::VideoReader`]) on a thread of their own.
//!
//! Standard input carries a video container that can be read from a pipe
//! (MPEG-TS, Matroska, …): its first bytes are read until `ffprobe` finds the
//! frame size and rate in them, then they and the rest of the stream are fed
//! to FFmpeg. The decoded frames wait in a [`Slot`] of one frame: for a live
//! source the newest frame replaces one not yet taken (which counts as
//! dropped), so nothing queues up when the pose model is slower than the
//! source; a file read as fast as possible waits for the pose model instead.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use mp_pose::video::{probe_bytes, Frame, ReadOptions, VideoInfo, VideoReader};

use crate::{LiveError, Result};

/// Where the frames come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LiveSource {
    /// A video file.
    File(PathBuf),
    /// A video stream on standard input.
    Stdin,
}

impl LiveSource {
    /// `-` is standard input, anything else a file.
    pub fn parse(s: &str) -> Self {
        if s == "-" {
            LiveSource::Stdin
        } else {
            LiveSource::File(PathBuf::from(s))
        }
    }

    /// Whether frames arrive at the source's own pace (and are dropped when late).
    pub fn is_live(&self, realtime: bool) -> bool {
        realtime || *self == LiveSource::Stdin
    }

    /// How the source is named in messages.
    pub fn name(&self) -> String {
        match self {
            LiveSource::File(p) => p.display().to_string(),
            LiveSource::Stdin => "standard input".into(),
        }
    }
}

/// How long [`Slot::stop`] waits for the decoding thread to end.
pub const STOP_WAIT: Duration = Duration::from_secs(2);

/// Bytes read from standard input at a time.
const CHUNK: usize = 64 << 10;
/// The most bytes of standard input read before giving up finding a video in them.
const MAX_PROBE_BYTES: usize = 8 << 20;

/// Bytes of standard input, read on a thread of their own (so that a
/// stalled stream can be noticed), and the bytes already taken.
struct ChannelReader {
    rx: Receiver<Vec<u8>>,
    buf: Vec<u8>,
    pos: usize,
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

fn read_stdin_chunks() -> Receiver<Vec<u8>> {
    let (tx, rx) = sync_channel::<Vec<u8>>(16);
    std::thread::spawn(move || {
        let mut stdin = std::io::stdin().lock();
        loop {
            let mut b = vec![0u8; CHUNK];
            match stdin.read(&mut b) {
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
        }
    });
    rx
}

/// Opens the source: probes it and starts FFmpeg decoding it.
pub fn open(source: &LiveSource, realtime: bool, stall: Duration) -> Result<VideoReader> {
    let err = |e: mp_pose::PoseError| LiveError::Source(e.to_string());
    match source {
        LiveSource::File(p) => {
            let info = mp_pose::probe(p).map_err(err)?;
            VideoReader::open_with(
                info,
                ReadOptions {
                    realtime,
                    feed: None,
                },
            )
            .map_err(err)
        }
        LiveSource::Stdin => {
            let rx = read_stdin_chunks();
            let (info, prefix) = probe_stdin(&rx, stall)?;
            VideoReader::open_with(
                info,
                ReadOptions {
                    realtime: false,
                    feed: Some(Box::new(ChannelReader {
                        rx,
                        buf: prefix,
                        pos: 0,
                    })),
                },
            )
            .map_err(err)
        }
    }
}

/// Reads standard input until `ffprobe` finds a video stream in its first
/// bytes; returns what it found and the bytes read.
fn probe_stdin(rx: &Receiver<Vec<u8>>, stall: Duration) -> Result<(VideoInfo, Vec<u8>)> {
    let name = Path::new("standard input");
    let mut bytes = Vec::new();
    let mut next_try = 16 << 10;
    let mut ended = false;
    loop {
        while !ended && bytes.len() < next_try {
            match rx.recv_timeout(stall) {
                Ok(b) => bytes.extend_from_slice(&b),
                Err(RecvTimeoutError::Disconnected) => ended = true,
                Err(RecvTimeoutError::Timeout) => {
                    return Err(LiveError::Source(format!(
                        "the stream stalled: no data on standard input for {:.1} s{}",
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
        if bytes.is_empty() {
            return Err(LiveError::Source(
                "standard input is empty: expected a video stream (e.g. MPEG-TS)".into(),
            ));
        }
        let found = probe_bytes(name, &bytes);
        match found {
            Ok(mut info) => {
                info.path = PathBuf::from("-");
                return Ok((info, bytes));
            }
            Err(e) if ended || bytes.len() >= MAX_PROBE_BYTES => {
                return Err(LiveError::Source(format!(
                    "standard input is not a video stream FFmpeg can read from a pipe (e.g. MPEG-TS): {e}"
                )));
            }
            Err(_) => next_try = bytes.len() * 4,
        }
    }
}

/// What the slot holds.
#[derive(Default)]
struct SlotState {
    frame: Option<Frame>,
    dropped: usize,
    newest_s: f64,
    ended: Option<std::result::Result<(), String>>,
    stop: bool,
    /// The decoding thread has ended and its FFmpeg process with it.
    decoder_done: bool,
}

/// The frame waiting for the pose model (see the module docs), shared
/// between the decoding thread and the analysis.
#[derive(Clone)]
pub struct Slot {
    inner: Arc<(Mutex<SlotState>, Condvar)>,
    drop_late: bool,
}

/// What [`Slot::take`] gives.
pub enum Taken {
    /// The next frame.
    Frame(Frame),
    /// The source ended (or failed, with the message).
    Ended(std::result::Result<(), String>),
    /// No frame for longer than the timeout.
    Stalled,
}

impl Slot {
    fn new(drop_late: bool) -> Self {
        Slot {
            inner: Arc::new((Mutex::new(SlotState::default()), Condvar::new())),
            drop_late,
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

    /// Asks the decoding thread to stop, and waits until it has ended (its
    /// FFmpeg process stopped) or [`STOP_WAIT`] has passed: it may be waiting
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
        while !self.drop_late && s.frame.is_some() && !s.stop {
            s = self.inner.1.wait(s).unwrap_or_else(|p| p.into_inner());
        }
        if s.stop {
            return false;
        }
        s.newest_s = frame.timestamp_s;
        if s.frame.replace(frame).is_some() {
            s.dropped += 1;
        }
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
            if let Some(f) = s.frame.take() {
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

/// Starts decoding `reader` into a [`Slot`] on a thread of its own; returns
/// the slot and the video's properties.
pub fn decode_into_slot(reader: VideoReader, drop_late: bool) -> Result<(Slot, VideoInfo)> {
    let info = reader.info().clone();
    let slot = Slot::new(drop_late);
    let s = slot.clone();
    std::thread::Builder::new()
        .name("live-decode".into())
        .spawn(move || {
            decode(reader, &s);
            // The reader (and its FFmpeg process) is gone by now.
            s.lock().decoder_done = true;
            s.inner.1.notify_all();
        })
        .map_err(|e| LiveError::Source(format!("cannot start the decoding thread: {e}")))?;
    Ok((slot, info))
}

/// Decodes `reader`'s frames into the slot until it ends or the slot stops;
/// the reader, and its FFmpeg process, end on return.
fn decode(reader: VideoReader, s: &Slot) {
    for frame in reader {
        match frame {
            Ok(f) => {
                if !s.put(f) {
                    return;
                }
            }
            Err(e) => {
                s.end(Err(e.to_string()));
                return;
            }
        }
    }
    s.end(Ok(()));
}
