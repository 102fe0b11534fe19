//! Error type of `mp-pipeline`.

use std::path::PathBuf;

/// Everything that can stop an analysis; each variant names the input,
/// stage or file involved, and wraps the library error with its message.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// The run was cancelled through its `CancelToken`.
    #[error("cancelled")]
    Cancelled,
    /// The input file does not exist.
    #[error("input {0} does not exist")]
    MissingInput(PathBuf),
    /// A track file could not be read.
    #[error("reading {path} as a keypoint track (videos need one of the extensions {extensions}): {source}")]
    Track {
        /// The file.
        path: PathBuf,
        /// Extensions read as videos.
        extensions: String,
        /// Why.
        #[source]
        source: mp_geom::GeomError,
    },
    /// The motion is too short to analyse.
    #[error("the motion has {0} frame(s); at least 2 are needed")]
    TooShort(usize),
    /// A parameter is out of range.
    #[error("parameter `{name}`: {reason}")]
    Param {
        /// The parameter.
        name: &'static str,
        /// Why.
        reason: String,
    },
    /// A step failed; `stage` says which.
    #[error("{stage}: {message}")]
    Stage {
        /// What was being done.
        stage: String,
        /// The library's message.
        message: String,
    },
    /// Video decoding or pose estimation.
    #[error(transparent)]
    Pose(#[from] mp_pose::PoseError),
    /// Concrete programs.
    #[error(transparent)]
    Concrete(#[from] mp_concrete::ConcreteError),
    /// Abstract programs and counting.
    #[error(transparent)]
    Abstract(#[from] mp_abstract::AbstractError),
    /// Tracks and geometry.
    #[error(transparent)]
    Geom(#[from] mp_geom::GeomError),
    /// Pictures, report and the output folder.
    #[error(transparent)]
    Report(#[from] mp_report::ReportError),
    /// JSON.
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
}

impl PipelineError {
    /// A [`PipelineError::Param`].
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        PipelineError::Param {
            name,
            reason: reason.into(),
        }
    }

    /// A [`PipelineError::Stage`] from any error, keeping its message.
    pub fn stage(stage: impl Into<String>, e: impl std::fmt::Display) -> Self {
        PipelineError::Stage {
            stage: stage.into(),
            message: e.to_string(),
        }
    }

    /// Turns an output-folder interruption into [`PipelineError::Cancelled`].
    pub(crate) fn from_report(e: mp_report::ReportError) -> Self {
        match e {
            mp_report::ReportError::Interrupted => PipelineError::Cancelled,
            other => PipelineError::Report(other),
        }
    }
}

/// Result alias of `mp-pipeline`.
pub(crate) type Result<T> = std::result::Result<T, PipelineError>;
