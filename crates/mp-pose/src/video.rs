//! Frames from videos (through the `ffmpeg`/`ffprobe` programs) and still images.
//!
//! [`probe`] reads a video's size, frame rate and frame count from `ffprobe`'s
//! JSON; [`VideoReader`] streams `rgb24` frames from an `ffmpeg` pipe one at a
//! time, so memory stays at one frame whatever the video's length.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::thread::JoinHandle;

use crate::error::{PoseError, Result};

/// One RGB frame (row-major, 3 bytes per pixel, no padding).
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Index of the frame in the video (0-based).
    pub index: usize,
    /// Time of the frame in seconds (`index / fps`).
    pub timestamp_s: f64,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `height × width × 3` bytes, RGB.
    pub rgb: Vec<u8>,
}

impl Frame {
    /// Builds a frame, checking that the buffer has `width × height × 3` bytes.
    pub fn new(
        index: usize,
        timestamp_s: f64,
        width: usize,
        height: usize,
        rgb: Vec<u8>,
    ) -> Result<Self> {
        let frame = Frame {
            index,
            timestamp_s,
            width,
            height,
            rgb,
        };
        frame.validate()?;
        Ok(frame)
    }

    /// Checks the buffer size and that the frame is not empty.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(PoseError::BadFrame {
                frame: self.index,
                reason: format!("empty frame ({}×{})", self.width, self.height),
            });
        }
        let need = self.width * self.height * 3;
        if self.rgb.len() != need {
            return Err(PoseError::BadFrame {
                frame: self.index,
                reason: format!(
                    "buffer has {} bytes, {}×{} RGB needs {need}",
                    self.rgb.len(),
                    self.width,
                    self.height
                ),
            });
        }
        Ok(())
    }

    /// A borrowed view of the pixels.
    pub fn view(&self) -> crate::imageops::RgbView<'_> {
        crate::imageops::RgbView {
            width: self.width,
            height: self.height,
            data: &self.rgb,
        }
    }
}

/// What `ffprobe` says about a video's first video stream.
#[derive(Debug, Clone, PartialEq)]
pub struct VideoInfo {
    /// The file.
    pub path: PathBuf,
    /// Width of the decoded frames (after display rotation).
    pub width: usize,
    /// Height of the decoded frames (after display rotation).
    pub height: usize,
    /// Average frame rate of the stream.
    pub fps: f64,
    /// Number of frames as stored in the container, when it says.
    pub frame_count: Option<usize>,
    /// Duration in seconds, when known.
    pub duration_s: Option<f64>,
    /// Codec name (e.g. `h264`).
    pub codec: String,
}

fn spawn_error(program: &str, path: &Path, e: std::io::Error) -> PoseError {
    if e.kind() == std::io::ErrorKind::NotFound {
        PoseError::FfmpegMissing {
            program: program.into(),
        }
    } else {
        PoseError::Video {
            path: path.to_path_buf(),
            reason: format!("cannot start {program}: {e}"),
        }
    }
}

fn check_file(path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(_) => Err(PoseError::Video {
            path: path.to_path_buf(),
            reason: "not a regular file".into(),
        }),
        Err(e) => Err(PoseError::io(path, e)),
    }
}

fn parse_rate(s: &str) -> Option<f64> {
    let v = match s.split_once('/') {
        Some((a, b)) => {
            let a: f64 = a.trim().parse().ok()?;
            let b: f64 = b.trim().parse().ok()?;
            if b == 0.0 {
                return None;
            }
            a / b
        }
        None => s.trim().parse().ok()?,
    };
    (v.is_finite() && v > 0.0).then_some(v)
}

fn json_num(v: &serde_json::Value) -> Option<f64> {
    match v {
        serde_json::Value::Number(n) => n.as_f64(),
        serde_json::Value::String(s) => s.trim().parse().ok(),
        _ => None,
    }
}

/// Parses `ffprobe -print_format json -show_streams -show_format` output.
pub(crate) fn parse_probe_json(path: &Path, json: &str) -> Result<VideoInfo> {
    let bad = |reason: String| PoseError::Video {
        path: path.to_path_buf(),
        reason,
    };
    let v: serde_json::Value =
        serde_json::from_str(json).map_err(|e| bad(format!("unreadable ffprobe output: {e}")))?;
    let streams = v
        .get("streams")
        .and_then(|s| s.as_array())
        .ok_or_else(|| bad("ffprobe found no streams".into()))?;
    let stream = streams
        .iter()
        .find(|s| s.get("codec_type").and_then(|c| c.as_str()) == Some("video"))
        .ok_or_else(|| bad("no video stream".into()))?;
    let dim = |k: &str| {
        stream
            .get(k)
            .and_then(json_num)
            .filter(|&x| x >= 1.0)
            .map(|x| x as usize)
    };
    let (mut width, mut height) = match (dim("width"), dim("height")) {
        (Some(w), Some(h)) => (w, h),
        _ => return Err(bad("video stream has no frame size".into())),
    };
    let rate = |k: &str| stream.get(k).and_then(|r| r.as_str()).and_then(parse_rate);
    let fps = rate("avg_frame_rate")
        .or_else(|| rate("r_frame_rate"))
        .ok_or_else(|| bad("video stream has no frame rate".into()))?;
    let frame_count = stream
        .get("nb_frames")
        .and_then(json_num)
        .filter(|&n| n >= 1.0)
        .map(|n| n as usize);
    let duration_s = stream
        .get("duration")
        .and_then(json_num)
        .or_else(|| {
            v.get("format")
                .and_then(|f| f.get("duration"))
                .and_then(json_num)
        })
        .filter(|d| d.is_finite() && *d > 0.0);
    // Display rotation (phones): ffmpeg rotates the decoded frames, so swap the size.
    let mut rotation = stream
        .get("tags")
        .and_then(|t| t.get("rotate"))
        .and_then(json_num)
        .unwrap_or(0.0);
    if let Some(list) = stream.get("side_data_list").and_then(|l| l.as_array()) {
        for sd in list {
            if let Some(r) = sd.get("rotation").and_then(json_num) {
                rotation = r;
            }
        }
    }
    let quarter_turns = ((rotation / 90.0).round() as i64).rem_euclid(4);
    if quarter_turns % 2 == 1 {
        std::mem::swap(&mut width, &mut height);
    }
    let codec = stream
        .get("codec_name")
        .and_then(|c| c.as_str())
        .unwrap_or("unknown")
        .to_string();
    Ok(VideoInfo {
        path: path.to_path_buf(),
        width,
        height,
        fps,
        frame_count,
        duration_s,
        codec,
    })
}

/// Reads a video's properties with `ffprobe`.
pub fn probe(path: impl AsRef<Path>) -> Result<VideoInfo> {
    let path = path.as_ref();
    check_file(path)?;
    let out = Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-print_format",
            "json",
            "-show_streams",
            "-show_format",
        ])
        .arg(path)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| spawn_error("ffprobe", path, e))?;
    probe_output(path, &out)
}

/// What `ffprobe` said: the video's properties, or its message.
fn probe_output(path: &Path, out: &std::process::Output) -> Result<VideoInfo> {
    if !out.status.success() {
        let msg = String::from_utf8_lossy(&out.stderr).trim().to_string();
        return Err(PoseError::Video {
            path: path.to_path_buf(),
            reason: if msg.is_empty() {
                format!("ffprobe failed ({})", out.status)
            } else {
                msg
            },
        });
    }
    parse_probe_json(path, &String::from_utf8_lossy(&out.stdout))
}

/// Reads a stream's properties with `ffprobe` from its first bytes (a
/// container that can be read from a pipe, such as MPEG-TS); `name` stands
/// for the stream in messages and in [`VideoInfo::path`].
pub fn probe_bytes(name: &Path, bytes: &[u8]) -> Result<VideoInfo> {
    use std::io::Write;
    let mut child = Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-print_format",
            "json",
            "-show_streams",
            "-i",
            "pipe:0",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| spawn_error("ffprobe", name, e))?;
    if let Some(mut stdin) = child.stdin.take() {
        let data = bytes.to_vec();
        // ffprobe may stop reading early: a closed pipe is not an error here.
        std::thread::spawn(move || {
            let _ = stdin.write_all(&data);
        });
    }
    let out = child
        .wait_with_output()
        .map_err(|e| spawn_error("ffprobe", name, e))?;
    probe_output(name, &out)
}

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

    fn spawn(info: VideoInfo, filter: Option<&str>) -> Result<Self> {
        Self::spawn_with(info, filter, filter.is_none(), VideoReadOptions::default())
    }

    /// `passthrough`: every decoded frame out as it is (no frame rate
    /// conversion, which a filter otherwise gets).
    fn spawn_with(
        info: VideoInfo,
        filter: Option<&str>,
        passthrough: bool,
        options: VideoReadOptions,
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
            .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
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
        let stderr = child.stderr.take().map(collect_stderr);
        Ok(VideoReader {
            info,
            child: Some(child),
            stdout,
            stderr,
            next_index: 0,
            done: false,
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

    fn read_frame(&mut self) -> Option<Result<Frame>> {
        let (w, h) = (self.info.width, self.info.height);
        let need = w * h * 3;
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
            let ts = index as f64 / self.info.fps;
            return Some(Frame::new(index, ts, w, h, buf));
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
        self.read_frame()
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

/// Reads a still image (PNG or JPEG) as frame 0.
pub fn read_image(path: impl AsRef<Path>) -> Result<Frame> {
    let path = path.as_ref();
    check_file(path).map_err(|e| match e {
        PoseError::Video { path, reason } => PoseError::Image { path, reason },
        other => other,
    })?;
    let img = image::ImageReader::open(path)
        .map_err(|e| PoseError::io(path, e))?
        .with_guessed_format()
        .map_err(|e| PoseError::io(path, e))?
        .decode()
        .map_err(|e| PoseError::Image {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?
        .to_rgb8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    Frame::new(0, 0.0, w, h, img.into_raw()).map_err(|e| PoseError::Image {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

/// Whether a path names a still image (by extension: png, jpg, jpeg).
pub(crate) fn is_image_path(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref(),
        Some("png" | "jpg" | "jpeg")
    )
}

/// Frames of a video or of a still image, with the frame rate
/// (still images get 1 fps and one frame).
pub struct FrameSource {
    /// Width of the frames.
    pub width: usize,
    /// Height of the frames.
    pub height: usize,
    /// Frames per second.
    pub fps: f64,
    /// Number of frames when known in advance.
    pub frame_count: Option<usize>,
    /// The frames.
    pub frames: Box<dyn Iterator<Item = Result<Frame>> + Send>,
}

/// Opens a video or a still image as a [`FrameSource`].
pub fn open_source(path: impl AsRef<Path>) -> Result<FrameSource> {
    let path = path.as_ref();
    if is_image_path(path) {
        let f = read_image(path)?;
        return Ok(FrameSource {
            width: f.width,
            height: f.height,
            fps: 1.0,
            frame_count: Some(1),
            frames: Box::new(std::iter::once(Ok(f))),
        });
    }
    let reader = VideoReader::open(path)?;
    let info = reader.info().clone();
    Ok(FrameSource {
        width: info.width,
        height: info.height,
        fps: info.fps,
        frame_count: info.frame_count,
        frames: Box::new(reader),
    })
}

/// Encodes RGB frames into a video file through an `ffmpeg` pipe (H.264,
/// yuv420p; odd sizes are padded by one pixel).
pub struct VideoWriter {
    path: PathBuf,
    width: usize,
    height: usize,
    /// Bytes a pixel: 3 (RGB) or 4 (RGBA).
    channels: usize,
    child: Option<Child>,
    stderr: Option<JoinHandle<String>>,
    frames: usize,
}

/// x264 speed presets, fastest first (`medium` is x264's default).
pub const X264_PRESETS: [&str; 9] = [
    "ultrafast",
    "superfast",
    "veryfast",
    "faster",
    "fast",
    "medium",
    "slow",
    "slower",
    "veryslow",
];

impl VideoWriter {
    /// Starts `ffmpeg` writing `path` at `fps` (x264's default preset, `medium`).
    pub fn create(path: impl AsRef<Path>, width: usize, height: usize, fps: f64) -> Result<Self> {
        Self::create_with_preset(path, width, height, fps, "medium")
    }

    /// Starts `ffmpeg` writing `path` at `fps` with an x264 speed preset
    /// (one of [`X264_PRESETS`]; faster presets trade file size for speed).
    pub fn create_with_preset(
        path: impl AsRef<Path>,
        width: usize,
        height: usize,
        fps: f64,
        preset: &str,
    ) -> Result<Self> {
        Self::spawn(path.as_ref(), width, height, fps, preset, false)
    }

    /// [`VideoWriter::create_with_preset`] for frames of opaque RGBA bytes
    /// (`height × width × 4`, the alpha ignored): a drawing surface such as a
    /// `tiny_skia::Pixmap` goes to the encoder as it is, without a copy to RGB.
    pub fn create_rgba_with_preset(
        path: impl AsRef<Path>,
        width: usize,
        height: usize,
        fps: f64,
        preset: &str,
    ) -> Result<Self> {
        Self::spawn(path.as_ref(), width, height, fps, preset, true)
    }

    fn spawn(
        path: &Path,
        width: usize,
        height: usize,
        fps: f64,
        preset: &str,
        rgba: bool,
    ) -> Result<Self> {
        let path = path.to_path_buf();
        if !X264_PRESETS.contains(&preset) {
            return Err(PoseError::param(
                "preset",
                format!(
                    "unknown x264 preset `{preset}` (expected one of {})",
                    X264_PRESETS.join(", ")
                ),
            ));
        }
        if width == 0 || height == 0 {
            return Err(PoseError::param(
                "size",
                format!("empty frame size {width}×{height}"),
            ));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(PoseError::param("fps", format!("must be > 0, got {fps}")));
        }
        let input = if rgba { "rgba" } else { "rgb24" };
        let mut child = Command::new("ffmpeg")
            .args([
                "-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", input, "-s",
            ])
            .arg(format!("{width}x{height}"))
            .arg("-r")
            .arg(format!("{fps}"))
            .args([
                "-i",
                "-",
                "-vf",
                "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                "-c:v",
                "libx264",
                "-preset",
                preset,
                "-pix_fmt",
                "yuv420p",
                "-movflags",
                "+faststart",
            ])
            .arg(&path)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| spawn_error("ffmpeg", &path, e))?;
        let stderr = child.stderr.take().map(collect_stderr);
        Ok(VideoWriter {
            path,
            width,
            height,
            channels: if rgba { 4 } else { 3 },
            child: Some(child),
            stderr,
            frames: 0,
        })
    }

    /// Appends one frame (`height × width × 3` bytes; × 4 for a writer made
    /// by [`VideoWriter::create_rgba_with_preset`]).
    pub fn write(&mut self, rgb: &[u8]) -> Result<()> {
        use std::io::Write;
        if rgb.len() != self.width * self.height * self.channels {
            return Err(PoseError::BadFrame {
                frame: self.frames,
                reason: format!(
                    "{} bytes, the video is {}×{} {}",
                    rgb.len(),
                    self.width,
                    self.height,
                    if self.channels == 4 { "RGBA" } else { "RGB" }
                ),
            });
        }
        let stdin = self
            .child
            .as_mut()
            .and_then(|c| c.stdin.as_mut())
            .ok_or_else(|| PoseError::Video {
                path: self.path.clone(),
                reason: "encoder already closed".into(),
            })?;
        if let Err(e) = stdin.write_all(rgb) {
            let (_, msg) = self.close_inner();
            return Err(PoseError::Video {
                path: self.path.clone(),
                reason: if msg.is_empty() { e.to_string() } else { msg },
            });
        }
        self.frames += 1;
        Ok(())
    }

    fn close_inner(&mut self) -> (bool, String) {
        let ok = match self.child.take() {
            Some(mut c) => {
                drop(c.stdin.take());
                c.wait().map(|s| s.success()).unwrap_or(false)
            }
            None => false,
        };
        let msg = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        (ok, msg.trim().to_string())
    }

    /// Finishes the file; returns the number of frames written.
    pub fn finish(mut self) -> Result<usize> {
        let (ok, msg) = self.close_inner();
        if !ok {
            return Err(PoseError::Video {
                path: self.path.clone(),
                reason: if msg.is_empty() {
                    "ffmpeg failed to encode".into()
                } else {
                    msg
                },
            });
        }
        Ok(self.frames)
    }
}

impl Drop for VideoWriter {
    fn drop(&mut self) {
        let _ = self.close_inner();
    }
}

/// Reads a child's standard error to its end on a thread of its own (so the
/// child never blocks on a full pipe); the text is its message on failure.
fn collect_stderr(mut s: std::process::ChildStderr) -> std::thread::JoinHandle<String> {
    std::thread::spawn(move || {
        let mut buf = String::new();
        let _ = s.read_to_string(&mut buf);
        buf
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_parse() {
        assert!((parse_rate("2997/100").unwrap() - 29.97).abs() < 1e-12);
        assert!((parse_rate("30000/1001").unwrap() - 29.97003).abs() < 1e-4);
        assert_eq!(parse_rate("0/0"), None);
        assert_eq!(parse_rate("25").unwrap(), 25.0);
        assert_eq!(parse_rate("x"), None);
    }

    #[test]
    fn probe_json_rotation_swaps_size() {
        let j = r#"{"streams":[{"codec_type":"video","codec_name":"h264","width":640,"height":360,
            "avg_frame_rate":"30/1","nb_frames":"10",
            "side_data_list":[{"rotation":-90}]}],"format":{"duration":"0.33"}}"#;
        let info = parse_probe_json(Path::new("x.mp4"), j).unwrap();
        assert_eq!((info.width, info.height), (360, 640));
        assert_eq!(info.frame_count, Some(10));
        assert_eq!(info.fps, 30.0);
        assert!((info.duration_s.unwrap() - 0.33).abs() < 1e-12);
    }

    #[test]
    fn probe_json_without_video_is_an_error() {
        let j = r#"{"streams":[{"codec_type":"audio"}]}"#;
        let e = parse_probe_json(Path::new("a.mp4"), j).unwrap_err();
        assert!(e.to_string().contains("no video stream"), "{e}");
    }

    /// RGB and RGBA frames give the same video; a frame of the other kind's
    /// size is refused with what the writer expects.
    #[test]
    fn rgba_frames_encode_as_their_rgb() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (64usize, 48usize);
        // Smooth colours (H.264 keeps them within a few grey levels).
        let rgb: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let (x, y) = (i % w, i / w);
                [(x * 4) as u8, (y * 5) as u8, 128u8]
            })
            .collect();
        let rgba: Vec<u8> = rgb
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect();
        let (a, b) = (dir.path().join("rgb.mp4"), dir.path().join("rgba.mp4"));
        let mut wa = VideoWriter::create_with_preset(&a, w, h, 10.0, "veryfast").unwrap();
        let mut wb = VideoWriter::create_rgba_with_preset(&b, w, h, 10.0, "veryfast").unwrap();
        let e = wb.write(&rgb).unwrap_err().to_string();
        assert!(e.contains("RGBA"), "{e}");
        for _ in 0..3 {
            wa.write(&rgb).unwrap();
            wb.write(&rgba).unwrap();
        }
        assert_eq!(wa.finish().unwrap(), 3);
        assert_eq!(wb.finish().unwrap(), 3);
        let read = |p: &Path| -> Vec<Vec<u8>> {
            VideoReader::open(p)
                .unwrap()
                .map(|f| f.unwrap().rgb)
                .collect()
        };
        let (fa, fb) = (read(&a), read(&b));
        assert_eq!((fa.len(), fb.len()), (3, 3));
        for (x, y) in fa.iter().zip(&fb) {
            let worst = x.iter().zip(y).map(|(p, q)| p.abs_diff(*q)).max().unwrap();
            assert!(worst <= 2, "RGB and RGBA frames differ by {worst} levels");
        }
        let truth = rgb.iter().zip(&fb[0]).map(|(p, q)| p.abs_diff(*q) as f64);
        let mean = truth.sum::<f64>() / rgb.len() as f64;
        assert!(mean < 3.0, "mean error {mean} levels");
    }

    /// Decoding from a frame gives the video's own frames from there on.
    #[test]
    fn decoding_from_a_frame_starts_there() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("levels.mp4");
        let (w, h) = (32usize, 32usize);
        let mut wr = VideoWriter::create_with_preset(&path, w, h, 25.0, "veryfast").unwrap();
        for k in 0..30u8 {
            wr.write(&vec![k * 8; w * h * 3]).unwrap();
        }
        wr.finish().unwrap();
        let mean = |f: &Frame| f.rgb.iter().map(|&v| v as f64).sum::<f64>() / f.rgb.len() as f64;
        let info = probe(&path).unwrap();
        for start in [0usize, 1, 13, 29] {
            let frames: Vec<Frame> = VideoReader::from_frame(info.clone(), start)
                .unwrap()
                .map(|f| f.unwrap())
                .collect();
            assert_eq!(frames.len(), 30 - start, "from {start}");
            for (i, f) in frames.iter().enumerate() {
                assert_eq!(f.index, i);
                let want = ((start + i) * 8) as f64;
                assert!(
                    (mean(f) - want).abs() < 3.0,
                    "frame {}: {} vs {want}",
                    start + i,
                    mean(f)
                );
            }
        }
        // Past the end: no frame (a clear error where FFmpeg gave none).
        let past: Vec<_> = VideoReader::from_frame(info, 40).unwrap().collect();
        assert!(
            past.iter().all(|f| f.is_err()),
            "{} frames past the end",
            past.len()
        );
    }

    #[test]
    fn frame_checks_buffer_size() {
        assert!(Frame::new(3, 0.0, 2, 2, vec![0; 11]).is_err());
        assert!(Frame::new(3, 0.0, 0, 2, vec![]).is_err());
        assert!(Frame::new(3, 0.0, 2, 2, vec![0; 12]).is_ok());
    }
}
