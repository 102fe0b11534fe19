//! Decoding: frames out of an `ffmpeg` pipe, one at a time.

use std::io::Read;
use std::path::Path;
use std::process::{Child, ChildStdout, Command, Stdio};
use std::thread::JoinHandle;

use super::{
    collect_stderr, probe, spawn_error, widen_pipe, Frame, PixelFormat, VideoInfo, Yuv420Frame,
};
use crate::error::{PoseError, Result};

/// How [`VideoReader::open_with`] reads its input.
#[derive(Default)]
pub struct VideoReadOptions {
    /// Read at the video's own frame rate (FFmpeg's `-re`), as a camera would deliver it.
    pub realtime: bool,
    /// The bytes of the video, fed to FFmpeg's standard input, instead of the file.
    pub feed: Option<Box<dyn Read + Send>>,
}

/// Streams the frames of a video from an `ffmpeg` pipe, one at a time.
///
/// Yields `Result<Frame>`; stops after the last frame, or after the first
/// error (a corrupt or truncated stream).
pub struct VideoReader {
    info: VideoInfo,
    child: Option<Child>,
    stdout: Option<ChildStdout>,
    stderr: Option<JoinHandle<String>>,
    next_index: usize,
    done: bool,
    format: PixelFormat,
}

impl VideoReader {
    /// Probes the video and starts decoding it.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let info = probe(path.as_ref())?;
        Self::from_info(info)
    }

    /// Starts decoding a video already probed.
    pub fn from_info(info: VideoInfo) -> Result<Self> {
        Self::spawn(info, None)
    }

    /// Starts decoding a video through an FFmpeg filter graph (`-vf`), e.g.
    /// `minterpolate=fps=60`; `info` describes the filtered frames (the
    /// filter must keep the frame size; `info.fps` is their rate).
    pub fn with_filter(info: VideoInfo, filter: &str) -> Result<Self> {
        Self::spawn(info, Some(filter))
    }

    /// Starts decoding with [`VideoReadOptions`]: at the video's own speed, or
    /// from a byte stream (a container such as MPEG-TS) fed to FFmpeg's
    /// standard input on a thread of its own; `info` (the frame size and
    /// rate) then comes from the caller, e.g. [`probe_bytes`] on the
    /// stream's first bytes.
    pub fn open_with(info: VideoInfo, options: VideoReadOptions) -> Result<Self> {
        Self::spawn_with(info, None, true, options)
    }

    /// Starts decoding at frame `start`, counted as [`VideoReader::open`]
    /// counts them (the frames before are decoded and dropped, so the
    /// numbering is the video's own whatever its keyframes); the frames are
    /// then indexed from 0.
    pub fn from_frame(info: VideoInfo, start: usize) -> Result<Self> {
        if start == 0 {
            return Self::from_info(info);
        }
        let mut info = info;
        info.frame_count = info.frame_count.map(|n| n.saturating_sub(start));
        let select = format!("select=gte(n\\,{start})");
        Self::spawn_with(info, Some(&select), true, VideoReadOptions::default())
    }

    /// Starts decoding a video already probed into planar YUV 4:2:0
    /// ([`Yuv420Frame`]): the codec's own pixels for most videos, half the
    /// bytes of RGB and no colour conversion.
    pub fn yuv420(info: VideoInfo) -> Result<Yuv420Frames> {
        let reader = Self::spawn_format(
            info,
            None,
            true,
            VideoReadOptions::default(),
            PixelFormat::Yuv420p,
        )?;
        Ok(Yuv420Frames { reader })
    }

    fn spawn(info: VideoInfo, filter: Option<&str>) -> Result<Self> {
        Self::spawn_with(info, filter, filter.is_none(), VideoReadOptions::default())
    }

    fn spawn_with(
        info: VideoInfo,
        filter: Option<&str>,
        passthrough: bool,
        options: VideoReadOptions,
    ) -> Result<Self> {
        Self::spawn_format(info, filter, passthrough, options, PixelFormat::Rgb24)
    }

    /// `passthrough`: every decoded frame out as it is (no frame rate
    /// conversion, which a filter otherwise gets); `format`: the pixels'
    /// layout in the pipe.
    fn spawn_format(
        info: VideoInfo,
        filter: Option<&str>,
        passthrough: bool,
        options: VideoReadOptions,
        format: PixelFormat,
    ) -> Result<Self> {
        let path = info.path.clone();
        let mut cmd = Command::new("ffmpeg");
        cmd.args(["-v", "error", "-nostdin"]);
        if options.realtime {
            cmd.arg("-re");
        }
        match options.feed {
            // A stream: decode from its first packets instead of reading
            // seconds of it ahead to learn what it holds.
            Some(_) => cmd.args([
                "-probesize",
                "32768",
                "-analyzeduration",
                "0",
                "-i",
                "pipe:0",
            ]),
            None => cmd.arg("-i").arg(&path),
        };
        cmd.args(["-map", "0:v:0"]);
        if let Some(f) = filter {
            cmd.arg("-vf").arg(f);
        }
        if passthrough {
            cmd.args(["-fps_mode", "passthrough"]);
        }
        let mut child = cmd
            .args(["-f", "rawvideo", "-pix_fmt", format.ffmpeg_name(), "-"])
            .stdin(if options.feed.is_some() {
                Stdio::piped()
            } else {
                Stdio::null()
            })
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| spawn_error("ffmpeg", &path, e))?;
        if let (Some(mut feed), Some(mut stdin)) = (options.feed, child.stdin.take()) {
            // Ends with the feed, or when FFmpeg closes its input (it ended or was stopped).
            std::thread::spawn(move || {
                let _ = std::io::copy(&mut feed, &mut stdin);
            });
        }
        let stdout = child.stdout.take();
        if let Some(out) = &stdout {
            widen_pipe(out);
        }
        let stderr = child.stderr.take().map(collect_stderr);
        Ok(VideoReader {
            info,
            child: Some(child),
            stdout,
            stderr,
            next_index: 0,
            done: false,
            format,
        })
    }

    /// The probed properties.
    pub fn info(&self) -> &VideoInfo {
        &self.info
    }

    fn finish(&mut self) -> (Option<std::process::ExitStatus>, String) {
        self.done = true;
        self.stdout = None;
        let status = self.child.take().and_then(|mut c| c.wait().ok());
        let msg = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        (status, msg.trim().to_string())
    }

    /// The next frame's index and bytes in the reader's pixel format.
    fn read_frame(&mut self) -> Option<Result<(usize, Vec<u8>)>> {
        let (w, h) = (self.info.width, self.info.height);
        let need = self.format.frame_bytes(w, h);
        let mut buf = vec![0u8; need];
        let mut filled = 0;
        let stdout = self.stdout.as_mut()?;
        while filled < need {
            match stdout.read(&mut buf[filled..]) {
                Ok(0) => break,
                Ok(n) => filled += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    let index = self.next_index;
                    self.finish();
                    return Some(Err(PoseError::VideoFrame {
                        path: self.info.path.clone(),
                        frame: index,
                        reason: e.to_string(),
                    }));
                }
            }
        }
        let index = self.next_index;
        if filled == need {
            self.next_index += 1;
            return Some(Ok((index, buf)));
        }
        // End of stream (or a partial last frame).
        let (status, msg) = self.finish();
        let failed = status.map(|s| !s.success()).unwrap_or(true);
        if filled > 0 || (failed && index == 0) || (failed && !msg.is_empty()) {
            let reason = if !msg.is_empty() {
                msg
            } else if filled > 0 {
                format!("stream ended inside a frame ({filled} of {need} bytes)")
            } else {
                "ffmpeg produced no frames".into()
            };
            if index == 0 {
                return Some(Err(PoseError::Video {
                    path: self.info.path.clone(),
                    reason,
                }));
            }
            return Some(Err(PoseError::VideoFrame {
                path: self.info.path.clone(),
                frame: index,
                reason,
            }));
        }
        if index == 0 {
            return Some(Err(PoseError::Video {
                path: self.info.path.clone(),
                reason: "the video has no decodable frames".into(),
            }));
        }
        None
    }
}

impl Iterator for VideoReader {
    type Item = Result<Frame>;
    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let (w, h, fps) = (self.info.width, self.info.height, self.info.fps);
        self.read_frame()
            .map(|r| r.and_then(|(index, rgb)| Frame::new(index, index as f64 / fps, w, h, rgb)))
    }
}

/// The frames of a video in planar YUV 4:2:0 ([`VideoReader::yuv420`]);
/// stops after the last frame, or after the first error.
pub struct Yuv420Frames {
    reader: VideoReader,
}

impl Iterator for Yuv420Frames {
    type Item = Result<Yuv420Frame>;
    fn next(&mut self) -> Option<Self::Item> {
        if self.reader.done {
            return None;
        }
        let (w, h) = (self.reader.info.width, self.reader.info.height);
        self.reader
            .read_frame()
            .map(|r| r.and_then(|(index, data)| Yuv420Frame::new(index, w, h, data)))
    }
}

impl Drop for VideoReader {
    fn drop(&mut self) {
        self.stdout = None;
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
        if let Some(h) = self.stderr.take() {
            let _ = h.join();
        }
    }
}
