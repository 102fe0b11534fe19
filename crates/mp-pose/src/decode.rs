//! Decoding alongside the pose model.
//!
//! * [`decode_ahead`]: a thread decodes frames ahead of the pose model
//!   through a bounded channel, keeping full-size copies (for an overlay
//!   video), grey thumbnails ([`crate::thumbs`]) and copies of every
//!   `step`-th frame made by the caller's function ([`FrameCopies`]) on the
//!   way.
//! * [`MjpegStream`]: a second FFmpeg process writing reduced (scaled,
//!   subsampled) frames as JPEG files back to back, much faster than
//!   encoding them here when most frames are kept; when few are, copies on
//!   the decoding thread spare the second decoding of the whole video.
//!
//! Both stop when their [`CancelToken`] is cancelled.

use std::io::{BufReader, Read};
use std::path::PathBuf;
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::mpsc::sync_channel;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use mp_geom::CancelToken;

use crate::error::{PoseError, Result};
use crate::thumbs::grey_thumbnail;
use crate::video::{Frame, FrameSource, VideoInfo, VideoReader, Yuv420Frame};

/// Options of [`decode_ahead`].
#[derive(Debug, Clone, PartialEq)]
pub struct DecodeOptions {
    /// Stop after this many frames.
    pub limit: Option<usize>,
    /// Keep every frame's full-size RGB copy.
    pub keep_full: bool,
    /// Grey thumbnail side in cells; `None`: no thumbnails.
    pub thumbnail_size: Option<usize>,
    /// Frames decoded ahead of the consumer. Default 8.
    pub ahead: usize,
    /// Copies of every `step`-th frame (e.g. reduced JPEG files); `None`: none.
    pub copies: Option<FrameCopies>,
}

/// What makes a copy of a frame (its bytes, e.g. a reduced JPEG file) from
/// its index in the video and its pixels, or says why it could not.
pub type CopyFn = dyn Fn(usize, &Frame) -> std::result::Result<Vec<u8>, String> + Send + Sync;

/// Copies of every `step`-th frame made on the decoding thread by `copy`.
#[derive(Clone)]
pub struct FrameCopies {
    /// Frames whose index in the video is a multiple of `step` (≥ 1) are copied.
    pub step: usize,
    /// Index in the video of the reader's first frame (a reader started at
    /// a frame, [`VideoReader::from_frame`], counts its frames from 0).
    pub first: usize,
    /// Makes one copy.
    pub copy: Arc<CopyFn>,
}

impl std::fmt::Debug for FrameCopies {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrameCopies")
            .field("step", &self.step)
            .field("first", &self.first)
            .finish_non_exhaustive()
    }
}

impl PartialEq for FrameCopies {
    fn eq(&self, other: &Self) -> bool {
        self.step == other.step && self.first == other.first && Arc::ptr_eq(&self.copy, &other.copy)
    }
}

impl Default for DecodeOptions {
    fn default() -> Self {
        DecodeOptions {
            limit: None,
            keep_full: false,
            thumbnail_size: Some(crate::thumbs::DEFAULT_THUMBNAIL_SIZE),
            ahead: 8,
            copies: None,
        }
    }
}

/// What the decoding thread hands back when its frames are consumed.
#[derive(Debug, Default)]
pub struct Decoded {
    /// Full-size frames in YUV 4:2:0 (half the bytes of RGB), when asked for.
    pub kept: Option<Vec<Yuv420Frame>>,
    /// Grey thumbnails of every decoded frame, when asked for: the
    /// `thumbnail_size²` cells of each frame one after the other (one
    /// buffer for a whole video, not one allocation a frame).
    pub thumbnails: Vec<f32>,
    /// The copies asked for ([`DecodeOptions::copies`]): (frame index,
    /// bytes), in frame order.
    pub copies: Vec<(usize, Vec<u8>)>,
    /// Time spent decoding (waiting on FFmpeg's pipe).
    pub decode: Duration,
    /// Time spent making the copies.
    pub copying: Duration,
}

/// Starts decoding `reader` on its own thread. Returns the frames as a
/// [`FrameSource`] for the pose model and the thread, which ends (and hands
/// back what it kept) when the video ends, after `limit` frames, at the first
/// decoding error (passed on to the source), when `cancel` is cancelled, or
/// when the source is dropped.
pub fn decode_ahead(
    reader: VideoReader,
    options: &DecodeOptions,
    cancel: CancelToken,
) -> Result<(FrameSource, JoinHandle<Decoded>)> {
    if let Some(0) = options.thumbnail_size {
        return Err(PoseError::param("thumbnail_size", "must be at least 1"));
    }
    if options.copies.as_ref().is_some_and(|c| c.step == 0) {
        return Err(PoseError::param("copies.step", "must be at least 1"));
    }
    let info = reader.info().clone();
    let (tx, rx) = sync_channel::<Result<Frame>>(options.ahead.max(1));
    let opts = options.clone();
    let handle = std::thread::Builder::new()
        .name("decode".into())
        .spawn(move || {
            let mut out = Decoded {
                kept: opts.keep_full.then(Vec::new),
                ..Decoded::default()
            };
            let mut frames = reader.take(opts.limit.unwrap_or(usize::MAX));
            loop {
                if cancel.is_cancelled() {
                    break;
                }
                let t0 = Instant::now();
                let Some(f) = frames.next() else { break };
                out.decode += t0.elapsed();
                if let Ok(frame) = &f {
                    if let Some(k) = out.kept.as_mut() {
                        match Yuv420Frame::from_rgb(
                            frame.index,
                            frame.width,
                            frame.height,
                            &frame.rgb,
                        ) {
                            Ok(y) => k.push(y),
                            Err(e) => {
                                let _ = tx.send(Err(e));
                                break;
                            }
                        }
                    }
                    if let Some(size) = opts.thumbnail_size {
                        match grey_thumbnail(frame, size) {
                            Ok(t) => out.thumbnails.extend_from_slice(&t),
                            Err(e) => {
                                let _ = tx.send(Err(e));
                                break;
                            }
                        }
                    }
                    if let Some(c) = opts.copies.as_ref() {
                        let at = c.first + frame.index;
                        if at.is_multiple_of(c.step) {
                            let t1 = Instant::now();
                            match (c.copy)(at, frame) {
                                Ok(bytes) => out.copies.push((at, bytes)),
                                Err(reason) => {
                                    let _ = tx.send(Err(PoseError::BadFrame {
                                        frame: at,
                                        reason: format!("copying the frame: {reason}"),
                                    }));
                                    break;
                                }
                            }
                            out.copying += t1.elapsed();
                        }
                    }
                }
                let failed = f.is_err();
                if tx.send(f).is_err() || failed {
                    break;
                }
            }
            out
        })
        .map_err(|e| PoseError::io("(decoding thread)", e))?;
    let source = FrameSource {
        width: info.width,
        height: info.height,
        fps: info.fps,
        frame_count: info.frame_count,
        frames: Box::new(rx.into_iter()),
    };
    Ok((source, handle))
}

/// Options of [`MjpegStream::start`].
#[derive(Debug, Clone, PartialEq)]
pub struct MjpegOptions {
    /// Keep every `step`-th frame (≥ 1).
    pub step: usize,
    /// Output size; `None`: the video's own.
    pub size: Option<(usize, usize)>,
    /// Stop after the frames of this many source frames.
    pub limit: Option<usize>,
    /// Quality on FFmpeg's `-q:v` scale (2 best … 31 worst).
    pub qscale: u32,
}

/// An FFmpeg process writing reduced frames of a video as JPEG files back to
/// back on its standard output (read them with a JPEG splitter such as
/// `mp_report::read_jpeg`).
pub struct MjpegStream {
    path: PathBuf,
    child: Child,
    stdout: Option<BufReader<ChildStdout>>,
    stderr: Option<JoinHandle<String>>,
}

impl MjpegStream {
    /// Starts FFmpeg on the video.
    pub fn start(info: &VideoInfo, options: &MjpegOptions) -> Result<Self> {
        if options.step == 0 {
            return Err(PoseError::param("step", "must be at least 1"));
        }
        if !(2..=31).contains(&options.qscale) {
            return Err(PoseError::param(
                "qscale",
                format!("must be in 2..=31, got {}", options.qscale),
            ));
        }
        let mut filters = Vec::new();
        if options.step > 1 {
            filters.push(format!("select=not(mod(n\\,{}))", options.step));
        }
        if let Some((w, h)) = options.size {
            if (w, h) != (info.width, info.height) {
                filters.push(format!("scale={w}:{h}:flags=area"));
            }
        }
        let mut cmd = Command::new("ffmpeg");
        cmd.args(["-v", "error", "-nostdin", "-i"])
            .arg(&info.path)
            .args(["-map", "0:v:0", "-fps_mode", "passthrough"]);
        if !filters.is_empty() {
            cmd.arg("-vf").arg(filters.join(","));
        }
        if let Some(n) = options.limit {
            cmd.arg("-frames:v")
                .arg(n.div_ceil(options.step).max(1).to_string());
        }
        cmd.args(["-c:v", "mjpeg", "-q:v"])
            .arg(options.qscale.to_string())
            .args(["-f", "image2pipe", "-"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = cmd.spawn().map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                PoseError::FfmpegMissing {
                    program: "ffmpeg".into(),
                }
            } else {
                PoseError::io(&info.path, e)
            }
        })?;
        let stdout = child
            .stdout
            .take()
            .map(|o| BufReader::with_capacity(1 << 16, o));
        let stderr = child.stderr.take().map(|mut e| {
            std::thread::spawn(move || {
                let mut s = String::new();
                let _ = e.read_to_string(&mut s);
                s
            })
        });
        Ok(MjpegStream {
            path: info.path.clone(),
            child,
            stdout,
            stderr,
        })
    }

    /// The stream of JPEG files.
    pub fn reader(&mut self) -> Option<&mut BufReader<ChildStdout>> {
        self.stdout.as_mut()
    }

    /// Stops FFmpeg if it still runs and returns what it said on its error
    /// output (empty when nothing), with its exit status.
    pub fn finish(mut self) -> (String, String) {
        self.stdout = None;
        let _ = self.child.kill();
        let status = self.child.wait().map(|s| s.to_string()).unwrap_or_default();
        let msg = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default()
            .trim()
            .to_string();
        (status, msg)
    }

    /// The video.
    pub fn path(&self) -> &std::path::Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::video::tests::levels_video as levels;

    fn copies_from(info: &VideoInfo, start: usize, copies: FrameCopies) -> Result<Decoded> {
        let reader = VideoReader::from_frame(info.clone(), start)?;
        let options = DecodeOptions {
            copies: Some(copies),
            ..DecodeOptions::default()
        };
        let (source, decoder) = decode_ahead(reader, &options, CancelToken::new())?;
        let consumed: Vec<Result<Frame>> = source.frames.collect();
        let decoded = decoder.join().unwrap();
        consumed.into_iter().collect::<Result<Vec<_>>>()?;
        Ok(decoded)
    }

    /// Every `step`-th frame of the video is copied once, under its index in
    /// the video, also by a reader started part-way (a piece of the video).
    #[test]
    fn copies_are_of_every_step_th_frame_of_the_video() {
        let dir = tempfile::tempdir().unwrap();
        let info = levels(dir.path());
        // The copy: the frame's mean level, as text.
        let copy: Arc<CopyFn> = Arc::new(|_, f: &Frame| {
            let mean = f.rgb.iter().map(|&v| v as f64).sum::<f64>() / f.rgb.len() as f64;
            Ok(format!("{mean:.0}").into_bytes())
        });
        for (start, step) in [(0usize, 1usize), (0, 7), (13, 4), (29, 5)] {
            let copies = FrameCopies {
                step,
                first: start,
                copy: copy.clone(),
            };
            let decoded = copies_from(&info, start, copies).unwrap();
            let at: Vec<usize> = decoded.copies.iter().map(|(i, _)| *i).collect();
            let want: Vec<usize> = (start..30).filter(|i| i % step == 0).collect();
            assert_eq!(at, want, "from {start}, every {step}");
            for (i, bytes) in &decoded.copies {
                let level: f64 = String::from_utf8_lossy(bytes).parse().unwrap();
                assert!((level - (i * 8) as f64).abs() < 3.0, "frame {i}: {level}");
            }
        }
    }

    /// A copy that fails stops the decoding with an error naming the frame;
    /// a step of 0 is refused.
    #[test]
    fn a_failed_copy_is_an_error_naming_the_frame() {
        let dir = tempfile::tempdir().unwrap();
        let info = levels(dir.path());
        let copy: Arc<CopyFn> = Arc::new(|at, _: &Frame| {
            if at == 12 {
                Err("no room".into())
            } else {
                Ok(Vec::new())
            }
        });
        let copies = FrameCopies {
            step: 3,
            first: 0,
            copy,
        };
        let e = copies_from(&info, 0, copies.clone())
            .unwrap_err()
            .to_string();
        assert!(e.contains("frame 12") && e.contains("no room"), "{e}");
        let reader = VideoReader::from_frame(info, 0).unwrap();
        let options = DecodeOptions {
            copies: Some(FrameCopies { step: 0, ..copies }),
            ..DecodeOptions::default()
        };
        let e = decode_ahead(reader, &options, CancelToken::new())
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("copies.step"), "{e}");
    }
}
