//! Encoding: frames into an H.264 file through an `ffmpeg` pipe.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::thread::JoinHandle;

use super::{collect_stderr, spawn_error, widen_pipe, PixelFormat};
use crate::error::{PoseError, Result};

/// Encodes RGB frames into a video file through an `ffmpeg` pipe (H.264,
/// yuv420p; odd sizes are padded by one pixel).
pub struct VideoWriter {
    path: PathBuf,
    width: usize,
    height: usize,
    /// How the frames handed to [`VideoWriter::write`] are laid out.
    format: PixelFormat,
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

/// How x264 encodes: a speed preset (one of [`X264_PRESETS`]) and, over it,
/// x264's own options (FFmpeg's `-x264-params`: `key=value` pairs joined by
/// `:`, e.g. `subme=1:me=dia`; empty for none).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct X264<'a> {
    /// The speed preset.
    pub preset: &'a str,
    /// Options over the preset.
    pub params: &'a str,
}

impl<'a> X264<'a> {
    /// A preset alone.
    pub fn preset(preset: &'a str) -> Self {
        X264 { preset, params: "" }
    }

    /// Checks the preset's name and the options' form.
    pub fn validate(&self) -> Result<()> {
        if !X264_PRESETS.contains(&self.preset) {
            return Err(PoseError::param(
                "preset",
                format!(
                    "unknown x264 preset `{}` (expected one of {})",
                    self.preset,
                    X264_PRESETS.join(", ")
                ),
            ));
        }
        let option = |o: &str| {
            o.split_once('=').is_some_and(|(k, v)| {
                !k.is_empty()
                    && k.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
                    && !v.is_empty()
                    && v.chars().all(|c| c.is_ascii_graphic() && c != '=')
            })
        };
        if !self.params.is_empty() && !self.params.split(':').all(option) {
            return Err(PoseError::param(
                "x264 params",
                format!("`{}` is not key=value pairs joined by `:`", self.params),
            ));
        }
        Ok(())
    }
}

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
        Self::with_format(
            path,
            width,
            height,
            fps,
            X264::preset(preset),
            PixelFormat::Rgb24,
        )
    }

    /// [`VideoWriter::create_with_preset`] with x264's own options over the
    /// preset, for frames in a given layout, e.g. planar YUV 4:2:0
    /// ([`super::Yuv420Frame`]), which x264 encodes without a conversion.
    pub fn with_format(
        path: impl AsRef<Path>,
        width: usize,
        height: usize,
        fps: f64,
        x264: X264<'_>,
        format: PixelFormat,
    ) -> Result<Self> {
        Self::spawn(path.as_ref(), width, height, fps, x264, format)
    }

    fn spawn(
        path: &Path,
        width: usize,
        height: usize,
        fps: f64,
        x264: X264<'_>,
        format: PixelFormat,
    ) -> Result<Self> {
        let path = path.to_path_buf();
        x264.validate()?;
        if width == 0 || height == 0 {
            return Err(PoseError::param(
                "size",
                format!("empty frame size {width}×{height}"),
            ));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(PoseError::param("fps", format!("must be > 0, got {fps}")));
        }
        let input = format.ffmpeg_name();
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
                x264.preset,
                "-pix_fmt",
                "yuv420p",
                "-movflags",
                "+faststart",
            ])
            .args(if x264.params.is_empty() {
                vec![]
            } else {
                vec!["-x264-params", x264.params]
            })
            .arg(&path)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| spawn_error("ffmpeg", &path, e))?;
        if let Some(input) = &child.stdin {
            widen_pipe(input);
        }
        let stderr = child.stderr.take().map(collect_stderr);
        Ok(VideoWriter {
            path,
            width,
            height,
            format,
            child: Some(child),
            stderr,
            frames: 0,
        })
    }

    /// Appends one frame (`height × width × 3` RGB bytes, or the layout the
    /// writer was made for: [`VideoWriter::with_format`]).
    pub fn write(&mut self, rgb: &[u8]) -> Result<()> {
        use std::io::Write;
        if rgb.len() != self.format.frame_bytes(self.width, self.height) {
            return Err(PoseError::BadFrame {
                frame: self.frames,
                reason: format!(
                    "{} bytes, the video is {}×{} {}",
                    rgb.len(),
                    self.width,
                    self.height,
                    self.format.label()
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
