//! Error type of `mp-grammar`.

/// Everything that can go wrong in `mp-grammar`.
///
/// Each variant names what is wrong (the parameter, the sentence, the symbol,
/// the frame) so that the message can be shown to a user as it is.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GrammarError {
    /// A parameter outside its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParam {
        /// Name of the parameter (as in the `Params` struct).
        name: &'static str,
        /// Why the value is rejected.
        reason: String,
    },
    /// The input is too short for the requested operation.
    #[error("too short: {what} needs at least {needed}, got {got}")]
    TooShort {
        /// What was too short.
        what: String,
        /// How many items were needed.
        needed: usize,
        /// How many items there were.
        got: usize,
    },
    /// An empty input where a non-empty one is required.
    #[error("empty input: {0}")]
    Empty(String),
    /// Input data that is inconsistent (lengths, indices, references).
    #[error("invalid input: {0}")]
    Invalid(String),
    /// A sentence that a grammar cannot derive.
    #[error("sentence {index} (`{sentence}`) cannot be derived from the grammar")]
    NotDerivable {
        /// Index of the sentence in its corpus.
        index: usize,
        /// The sentence, space-separated.
        sentence: String,
    },
    /// A grammar without a terminating derivation for a nonterminal.
    #[error("nonterminal `{0}` has no terminating derivation")]
    NonTerminating(String),
    /// A file whose content is wrong: the file, the field (or position) and
    /// what is wrong with it.
    #[error("{}: `{field}`: {reason}", path.display())]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// The field, or the position in a text file.
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// An error from `mp-geom` (tracks, readers).
    #[error(transparent)]
    Geom(#[from] mp_geom::GeomError),
    /// A JSON (de)serialisation error on a named file or object.
    #[error("{what}: {source}")]
    Json {
        /// The file or object.
        what: String,
        /// The underlying error.
        #[source]
        source: serde_json::Error,
    },
    /// An I/O error on a named file.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl GrammarError {
    /// Helper to build a [`GrammarError::InvalidParam`].
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        GrammarError::InvalidParam {
            name,
            reason: reason.into(),
        }
    }
    /// Helper to build a [`GrammarError::File`].
    pub fn file(
        path: impl Into<std::path::PathBuf>,
        field: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        GrammarError::File {
            path: path.into(),
            field: field.into(),
            reason: reason.into(),
        }
    }
    /// Helper to build a [`GrammarError::TooShort`].
    pub fn too_short(what: impl Into<String>, needed: usize, got: usize) -> Self {
        GrammarError::TooShort {
            what: what.into(),
            needed,
            got,
        }
    }
}

/// Result alias for `mp-grammar`.
pub type Result<T, E = GrammarError> = std::result::Result<T, E>;
