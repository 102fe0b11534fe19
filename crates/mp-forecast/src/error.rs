//! Error type of `mp-forecast`.

use std::path::PathBuf;

/// Everything that can go wrong while forecasting or evaluating forecasts.
///
/// Each variant names the file, model, frame, joint or parameter involved.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ForecastError {
    /// The observed track is shorter than a method needs.
    #[error("{what} needs at least {needed} observed frames, got {got}")]
    TooShort {
        what: &'static str,
        needed: usize,
        got: usize,
    },
    /// The track's joint count or dimensions do not match what a model or index was built for.
    #[error("{what} expects {expected}, the track has {got}")]
    Mismatch {
        what: String,
        expected: String,
        got: String,
    },
    /// No joint is valid where one is needed (e.g. every joint of the context is missing).
    #[error("no valid joint: {0}")]
    NoValidJoints(String),
    /// A parameter outside its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParam { name: &'static str, reason: String },
    /// A model file or manifest was not found.
    #[error("forecasting model `{file}` not found (looked in: {searched}); run `cargo xtask train-forecast` or set MP_FORECAST_MODELS")]
    ModelMissing { file: String, searched: String },
    /// ONNX Runtime failed to load or run a model, or its tensors are not the expected ones.
    #[error("model {model}: {reason}")]
    Model { model: String, reason: String },
    /// A manifest or fixture that cannot be parsed.
    #[error("{path}: {reason}")]
    Format { path: PathBuf, reason: String },
    /// An I/O error on a named file.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A number of observed frames outside what the track holds or the method needs.
    #[error("`observe` must be in {min}..={frames} (the track's length) for the {method} method, got {observe}")]
    ObserveOutOfRange {
        /// Observed frames asked for.
        observe: usize,
        /// Fewest observed frames the method accepts.
        min: usize,
        /// Frames of the track.
        frames: usize,
        /// The method (`ForecastMethod::as_str`).
        method: &'static str,
    },
    /// A horizon beyond the longest one predicted (`crate::predict::max_horizon_frames`).
    #[error("a horizon of {horizon} frames is too long: at most {limit} frames ({} frames or {} s of motion at {fps} fps, whichever is fewer)", crate::predict::MAX_HORIZON_FRAMES, crate::predict::MAX_HORIZON_SECONDS)]
    HorizonTooLong {
        /// Frames asked for.
        horizon: usize,
        /// The longest horizon accepted for the track.
        limit: usize,
        /// The track's frame rate.
        fps: f64,
    },
    /// No learned model suits the track's skeleton and dimensions.
    #[error("no forecasting model for a {dims}D track of skeleton `{skeleton}` (penn13, coco17, blazepose33 \
             in 2D → penn_action; msr20, blazepose33 world landmarks in 3D → msr_action3d); \
             pass a model folder (--models DIR)")]
    NoModelForSkeleton {
        /// The track's skeleton.
        skeleton: String,
        /// The track's dimensions per joint.
        dims: usize,
    },
    /// No training data for a method that needs it.
    #[error("no training data: {0}")]
    NoTrainingData(String),
    /// An error from `mp-geom` (tracks, metrics).
    #[error(transparent)]
    Geom(#[from] mp_geom::GeomError),
    /// An error from `mp-abstract` (loop unrolling).
    #[error(transparent)]
    Abstract(#[from] mp_abstract::AbstractError),
    /// ONNX Runtime could not be found or loaded, or refused a model or its inputs.
    #[error(transparent)]
    Runtime(#[from] mp_onnx::OnnxError),
}

impl ForecastError {
    /// Helper to build a [`ForecastError::InvalidParam`].
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        ForecastError::InvalidParam {
            name,
            reason: reason.into(),
        }
    }
    /// Helper to build a [`ForecastError::Model`].
    pub fn model(model: impl Into<String>, reason: impl std::fmt::Display) -> Self {
        ForecastError::Model {
            model: model.into(),
            reason: reason.to_string(),
        }
    }
    /// Helper to build a [`ForecastError::Mismatch`].
    pub fn mismatch(
        what: impl Into<String>,
        expected: impl std::fmt::Display,
        got: impl std::fmt::Display,
    ) -> Self {
        ForecastError::Mismatch {
            what: what.into(),
            expected: expected.to_string(),
            got: got.to_string(),
        }
    }
}

/// Result alias for `mp-forecast`.
pub type Result<T, E = ForecastError> = std::result::Result<T, E>;
