//! Error type of `mp-abstract`.

/// Everything that can go wrong in `mp-abstract`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AbstractError {
    /// An error from the geometry layer.
    #[error(transparent)]
    Geom(#[from] mp_geom::GeomError),
    /// An error from concrete-program synthesis or execution.
    #[error(transparent)]
    Concrete(#[from] mp_concrete::ConcreteError),
    /// An I/O error on a named file.
    #[error("{path}: {source}")]
    Io {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// JSON that does not deserialize to an abstract program.
    #[error("{path}: JSON: {source}")]
    Json {
        path: std::path::PathBuf,
        #[source]
        source: serde_json::Error,
    },
    /// The input holds no primitives.
    #[error("no primitives: {0}")]
    Empty(String),
    /// Inconsistent shapes (joint counts, dimensions).
    #[error("shape mismatch: {0}")]
    Shape(String),
    /// A parameter outside its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParam { name: &'static str, reason: String },
    /// A non-finite number where a finite one is required.
    #[error("non-finite value: {0}")]
    NonFinite(String),
    /// A loop that cannot exist (fewer than two iterations, empty body).
    #[error("invalid loop: {0}")]
    InvalidLoop(String),
    /// Malformed abstract-program text.
    #[error("parse error at line {line}, column {column}: {message}")]
    Parse {
        line: usize,
        column: usize,
        message: String,
    },
    /// Counts whose parts disagree (a total that is not the sum of the
    /// intervals' counts, a range that ends before it starts).
    #[error("inconsistent counts: {0}")]
    Inconsistent(String),
    /// A reference to something that does not exist (a loop index, an iteration).
    #[error("not found: {0}")]
    NotFound(String),
}

impl AbstractError {
    pub(crate) fn param(name: &'static str, reason: impl Into<String>) -> Self {
        AbstractError::InvalidParam {
            name,
            reason: reason.into(),
        }
    }

    /// `Ok` when `v` is finite and > 0, else the parameter error naming `name`.
    pub(crate) fn check_positive(name: &'static str, v: f64) -> Result<(), Self> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(Self::param(
                name,
                format!("must be finite and > 0, got {v}"),
            ))
        }
    }

    /// `Ok` when `v` is finite and ≥ 0, else the parameter error naming `name`.
    pub(crate) fn check_non_negative(name: &'static str, v: f64) -> Result<(), Self> {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(Self::param(
                name,
                format!("must be finite and ≥ 0, got {v}"),
            ))
        }
    }
}

/// Result alias for `mp-abstract`.
pub type Result<T, E = AbstractError> = std::result::Result<T, E>;
