//! Error type of `mp-pose`.

use std::path::PathBuf;

/// Everything that can go wrong between a video file and a keypoint track.
///
/// Each variant names the file, frame, model or parameter involved, so that
/// the message can be shown to a user as it is.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PoseError {
    /// ONNX Runtime could not be found or loaded, or a session could not be
    /// opened or checked (see [`mp_onnx::OnnxError`]).
    #[error(transparent)]
    Runtime(#[from] mp_onnx::OnnxError),
    /// A model file was not found in any model folder.
    #[error("model file `{file}` not found (looked in: {searched}); run `cargo xtask models`")]
    ModelMissing { file: String, searched: String },
    /// ONNX Runtime failed to load a model or to run it.
    #[error("model {model}: {reason}")]
    Model { model: String, reason: String },
    /// A model's inputs/outputs are not the ones this crate expects.
    #[error("model {model}: unexpected tensor contract: {reason}")]
    Contract { model: String, reason: String },
    /// `ffmpeg` or `ffprobe` is not installed.
    #[error("`{program}` not found on PATH; install FFmpeg (Debian: `apt-get install ffmpeg`, or run scripts/setup.sh)")]
    FfmpegMissing { program: String },
    /// A video file cannot be decoded (corrupt, no video stream, unsupported).
    #[error("{path}: cannot decode video: {reason}")]
    Video { path: PathBuf, reason: String },
    /// Decoding failed in the middle of a video.
    #[error("{path}: decoding failed at frame {frame}: {reason}")]
    VideoFrame {
        path: PathBuf,
        frame: usize,
        reason: String,
    },
    /// An image file cannot be read.
    #[error("{path}: cannot read image: {reason}")]
    Image { path: PathBuf, reason: String },
    /// An I/O error on a named file.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A parameter outside its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParam { name: &'static str, reason: String },
    /// A frame whose buffer does not match its stated size.
    #[error("frame {frame}: {reason}")]
    BadFrame { frame: usize, reason: String },
    /// An error from `mp-geom` (building a track).
    #[error(transparent)]
    Geom(#[from] mp_geom::GeomError),
}

impl PoseError {
    /// Helper to build a [`PoseError::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        PoseError::Io {
            path: path.into(),
            source,
        }
    }
    /// Helper to build a [`PoseError::InvalidParam`].
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        PoseError::InvalidParam {
            name,
            reason: reason.into(),
        }
    }
    /// Helper to build a [`PoseError::Model`].
    pub fn model(model: impl Into<String>, reason: impl std::fmt::Display) -> Self {
        PoseError::Model {
            model: model.into(),
            reason: reason.to_string(),
        }
    }
}

/// Result alias for `mp-pose`.
pub type Result<T, E = PoseError> = std::result::Result<T, E>;
