//! Error type of `mp-refine`.

use mp_concrete::ConcreteError;
use mp_geom::GeomError;

/// Everything that can go wrong in `mp-refine`.
///
/// Each variant names the parameter, frame, joint or action that is wrong so
/// that the message can be shown to a user as it is.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RefineError {
    /// An error from `mp-geom` (track checks, spline fitting, data files).
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// An error from `mp-concrete` (the segmentation DP).
    #[error(transparent)]
    Concrete(#[from] ConcreteError),
    /// A parameter outside its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParam {
        /// Field of a `Params` struct.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// A track whose joint count differs from what the operation needs.
    #[error("{what}: expected {expected} joints, got {got}")]
    JointCount {
        /// The operation or argument.
        what: String,
        /// Joints needed.
        expected: usize,
        /// Joints given.
        got: usize,
    },
    /// A track with the wrong number of dimensions per joint.
    #[error("{what}: expected {expected} dimensions per joint, got {got}")]
    Dims {
        /// The operation or argument.
        what: String,
        /// Dimensions needed.
        expected: usize,
        /// Dimensions given.
        got: usize,
    },
    /// A track or sample set too short for the operation.
    #[error("{what} needs at least {needed} frames, got {got}")]
    TooShort {
        /// The operation.
        what: String,
        /// Frames (or samples) needed.
        needed: usize,
        /// Frames (or samples) given.
        got: usize,
    },
    /// Two tracks or arrays whose shapes do not agree.
    #[error("shape mismatch: {0}")]
    Shape(String),
    /// A non-finite value where a finite one is needed.
    #[error("non-finite value: {0}")]
    NonFinite(String),
    /// A clustering or mixture-model fit that failed.
    #[error("clustering of action {action}: {reason}")]
    Clustering {
        /// The action whose anchors were clustered.
        action: u32,
        /// What went wrong.
        reason: String,
    },
    /// An action that the concepts do not know.
    #[error("no anchor concepts for action {0}")]
    UnknownAction(u32),
    /// JSON that does not deserialize.
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// A network file (or its folder) that does not exist.
    #[error("refinement model `{file}` not found (looked in: {searched}); train the networks with `cargo xtask train-refine` or pass the model folder")]
    ModelMissing {
        /// File (or folder) that is missing.
        file: String,
        /// Where it was looked for.
        searched: String,
    },
    /// A network that ONNX Runtime cannot run, or whose inputs/outputs do
    /// not match the contract of `models/refine/README.md`.
    #[error("model {model}: {reason}")]
    Model {
        /// Model file.
        model: String,
        /// What is wrong.
        reason: String,
    },
    /// File I/O.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// ONNX Runtime could not be found or loaded, or failed to open or run
    /// a network.
    #[error(transparent)]
    Runtime(#[from] mp_onnx::OnnxError),
}

impl RefineError {
    /// Helper to build a [`RefineError::InvalidParam`].
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        RefineError::InvalidParam {
            name,
            reason: reason.into(),
        }
    }

    /// `Ok` when `v` is finite and above 0, else an invalid `name`.
    pub fn check_positive(name: &'static str, v: f64) -> Result<(), RefineError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(RefineError::param(
                name,
                format!("must be finite and > 0, got {v}"),
            ))
        }
    }
}

/// Result alias for `mp-refine`.
pub type Result<T, E = RefineError> = std::result::Result<T, E>;
