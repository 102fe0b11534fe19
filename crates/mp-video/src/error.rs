//! Error type of `mp-video`.

use std::path::PathBuf;

/// Everything that can stop a video edit, prediction or interpolation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VideoError {
    /// Decoding, encoding or the pose model.
    #[error(transparent)]
    Pose(#[from] mp_pose::PoseError),
    /// The analysis (keypoints, programs, counts).
    #[error(transparent)]
    Pipeline(#[from] mp_pipeline::PipelineError),
    /// Tracks and metrics.
    #[error(transparent)]
    Geom(#[from] mp_geom::GeomError),
    /// Concrete programs.
    #[error("program: {0}")]
    Program(String),
    /// The counted interval asked for does not exist.
    #[error("{}", no_interval_message(*.number, *.available))]
    NoInterval {
        /// The interval number asked for (from 1, as `mp run` prints them).
        number: usize,
        /// Counted intervals found.
        available: usize,
    },
    /// The interpolation factor is not supported.
    #[error("interpolation factor {0}: must be one of 2, 4, 8")]
    Factor(usize),
    /// No person was found in any frame.
    #[error("no person found in any frame of {0}")]
    NoPerson(PathBuf),
    /// A prediction length out of range.
    #[error("--seconds {seconds}: must be a finite number in (0, {max}]")]
    Seconds {
        /// Asked for.
        seconds: f64,
        /// Largest allowed.
        max: f64,
    },
    /// An edit that cannot be made.
    #[error("edit: {0}")]
    Edit(String),
    /// A parameter out of range.
    #[error("parameter `{name}`: {reason}")]
    Param {
        /// The parameter.
        name: &'static str,
        /// Why.
        reason: String,
    },
    /// The frames a plan needs at once do not fit the memory budget.
    #[error("the output needs {frames} frames held at once ({mb} MB), more than the budget of {budget_mb} MB")]
    Memory {
        /// Frames held at once.
        frames: usize,
        /// Their size.
        mb: usize,
        /// The budget.
        budget_mb: usize,
    },
    /// A file operation.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
}

impl VideoError {
    /// A parameter error.
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        VideoError::Param {
            name,
            reason: reason.into(),
        }
    }

    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        VideoError::Io {
            path: path.into(),
            source,
        }
    }
}

fn no_interval_message(number: usize, available: usize) -> String {
    let have = match available {
        0 => "the video has no repetitions (`mp run` counts none)".to_string(),
        1 => "the video has 1 interval of repetitions: --interval 1".to_string(),
        n => format!("the video has {n} intervals of repetitions: --interval 1 to {n}"),
    };
    format!(
        "no interval {number}: {have}; intervals are numbered from 1 as `mp run`, `mp loops` and the report print them"
    )
}

/// Result with [`VideoError`].
pub(crate) type Result<T> = std::result::Result<T, VideoError>;
