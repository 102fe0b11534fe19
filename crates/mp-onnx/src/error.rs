//! Error type of `mp-onnx`.

use std::path::PathBuf;

/// Everything that can go wrong between a model file and its outputs.
///
/// Each variant names the library, model file, tensor or parameter involved,
/// so that the message can be shown to a user as it is.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OnnxError {
    /// The ONNX Runtime shared library was not found.
    #[error(
        "ONNX Runtime library not found (looked in: {searched}); run `cargo xtask setup`, \
         or set ORT_DYLIB_PATH to libonnxruntime.so"
    )]
    RuntimeMissing {
        /// The candidate paths, comma-separated.
        searched: String,
    },
    /// The ONNX Runtime library exists but could not be loaded.
    #[error(
        "cannot load ONNX Runtime from {path}: {reason}; run `cargo xtask setup` to reinstall it"
    )]
    RuntimeLoad {
        /// The library file.
        path: PathBuf,
        /// What ONNX Runtime reported.
        reason: String,
    },
    /// A device was asked for that ONNX Runtime cannot use.
    #[error("cannot run on {device}: {reason}")]
    Device {
        /// The device (`cuda:0`).
        device: String,
        /// Why not.
        reason: String,
    },
    /// A model file was not found.
    #[error("model file `{file}` not found (looked in: {searched})")]
    ModelMissing {
        /// The file name (or path) that is missing.
        file: String,
        /// Where it was looked for.
        searched: String,
    },
    /// ONNX Runtime failed to load a model or to run it.
    #[error("model {model}: {reason}")]
    Model {
        /// The model (its file).
        model: String,
        /// What ONNX Runtime reported.
        reason: String,
    },
    /// A model's inputs or outputs are not the ones its caller expects.
    #[error("model {model}: unexpected tensor contract: {reason}")]
    Contract {
        /// The model (its file).
        model: String,
        /// Which tensor differs, and how.
        reason: String,
    },
    /// An input whose shape does not fit the graph (rank or a fixed dimension).
    #[error(
        "model {model}: input `{input}` expects shape {}, got {got:?}",
        format_shape(.expected)
    )]
    InputShape {
        /// The model (its file).
        model: String,
        /// The input tensor.
        input: String,
        /// The graph's shape; −1 where a dimension is open.
        expected: Vec<i64>,
        /// The shape that was passed.
        got: Vec<usize>,
    },
    /// An input whose data length differs from the product of its shape.
    #[error("model {model}: input `{input}` of shape {shape:?} needs {needed} values, got {len}")]
    InputLength {
        /// The model (its file).
        model: String,
        /// The input tensor.
        input: String,
        /// The shape that was passed.
        shape: Vec<usize>,
        /// Values the shape needs.
        needed: usize,
        /// Values that were passed.
        len: usize,
    },
    /// A graph input that the run did not provide.
    #[error("model {model}: input `{input}` is missing from the run")]
    MissingInput {
        /// The model (its file).
        model: String,
        /// The input tensor.
        input: String,
    },
    /// A run input that the graph does not have (or one given twice).
    #[error("model {model}: no input `{input}` (the graph has: {known})")]
    UnknownInput {
        /// The model (its file).
        model: String,
        /// The name that was passed.
        input: String,
        /// The graph's input names, comma-separated.
        known: String,
    },
    /// A requested output that the graph does not have or the run did not produce.
    #[error("model {model}: no output `{output}` (the graph has: {known})")]
    MissingOutput {
        /// The model (its file).
        model: String,
        /// The requested output.
        output: String,
        /// The graph's output names, comma-separated.
        known: String,
    },
    /// A parameter outside its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParam {
        /// Field of a parameter struct.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
}

impl OnnxError {
    /// Helper to build an [`OnnxError::Model`].
    pub fn model(model: impl Into<String>, reason: impl std::fmt::Display) -> Self {
        OnnxError::Model {
            model: model.into(),
            reason: reason.to_string(),
        }
    }

    /// Helper to build an [`OnnxError::Contract`].
    pub fn contract(model: impl Into<String>, reason: impl Into<String>) -> Self {
        OnnxError::Contract {
            model: model.into(),
            reason: reason.into(),
        }
    }

    /// Helper to build an [`OnnxError::InvalidParam`].
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        OnnxError::InvalidParam {
            name,
            reason: reason.into(),
        }
    }

    /// Whether the error is about the shape or length of data passed to a
    /// run ([`OnnxError::InputShape`], [`OnnxError::InputLength`]), as
    /// opposed to a missing library, a broken model or a failed run.
    pub fn is_shape_mismatch(&self) -> bool {
        matches!(
            self,
            OnnxError::InputShape { .. } | OnnxError::InputLength { .. }
        )
    }
}

/// A graph shape as text, open dimensions as `?` (`[?, 60, 60]`).
pub fn format_shape(shape: &[i64]) -> String {
    let dims: Vec<String> = shape
        .iter()
        .map(|&d| {
            if d < 0 {
                "?".to_string()
            } else {
                d.to_string()
            }
        })
        .collect();
    format!("[{}]", dims.join(", "))
}

/// Result alias for `mp-onnx`.
pub(crate) type Result<T, E = OnnxError> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_print_open_dimensions_as_question_marks() {
        assert_eq!(format_shape(&[-1, 60, 60]), "[?, 60, 60]");
        assert_eq!(format_shape(&[]), "[]");
    }

    #[test]
    fn shape_error_names_model_input_and_shapes() {
        let e = OnnxError::InputShape {
            model: "evaluator.onnx".into(),
            input: "motion".into(),
            expected: vec![-1, 60, 60],
            got: vec![1, 59, 60],
        };
        let msg = e.to_string();
        assert!(msg.contains("evaluator.onnx"), "{msg}");
        assert!(msg.contains("`motion`"), "{msg}");
        assert!(
            msg.contains("[?, 60, 60]") && msg.contains("[1, 59, 60]"),
            "{msg}"
        );
        assert!(e.is_shape_mismatch());
        assert!(!OnnxError::model("m", "x").is_shape_mismatch());
    }
}
