//! Frames from videos (through the `ffmpeg`/`ffprobe` programs) and still images.
//!
//! [`probe`] reads a video's size, frame rate and frame count from `ffprobe`'s
//! JSON; [`VideoReader`] streams `rgb24` frames (or planar YUV 4:2:0,
//! [`VideoReader::yuv420`]) from an `ffmpeg` pipe one at a time, so memory
//! stays at one frame whatever the video's length; [`VideoWriter`] encodes
//! H.264 from frames handed to another `ffmpeg` pipe.

mod reader;
mod writer;
mod yuv;

pub use reader::{VideoReadOptions, VideoReader, Yuv420Frames};
pub use writer::{VideoWriter, X264, X264_PRESETS};
pub use yuv::{PixelFormat, Yuv420Frame};

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

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

/// Bytes of a pipe to or from FFmpeg: a megabyte (Linux's most for an
/// unprivileged process by default) instead of 64 KiB, so a frame of video
/// passes in one or a few writes rather than dozens, each a switch between
/// the two processes.
const PIPE_BYTES: i32 = 1 << 20;

/// Widens a pipe to [`PIPE_BYTES`] where the system allows (a failure
/// leaves it as it was: only slower).
#[cfg(target_os = "linux")]
fn widen_pipe(pipe: &impl std::os::fd::AsRawFd) {
    // SAFETY: `fcntl` on a descriptor the caller owns for the call's length;
    // F_SETPIPE_SZ changes only the pipe's capacity.
    unsafe {
        libc::fcntl(pipe.as_raw_fd(), libc::F_SETPIPE_SZ, PIPE_BYTES);
    }
}

#[cfg(not(target_os = "linux"))]
fn widen_pipe<T>(_pipe: &T) {}

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
pub(crate) mod tests;
