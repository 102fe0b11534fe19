//! [`Network`]: one opened ONNX model, run on `f32` tensors after checking
//! every input against the graph.
//!
//! ONNX Runtime reports a wrong input shape from deep inside the graph (a
//! failing `MatMul` or `Reshape` node, sometimes only for some sizes);
//! [`Network::run`] checks names, ranks, fixed dimensions and data lengths
//! first, so the error names the model, the input and both shapes.

use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use ort::session::{Session, SessionInputValue};
use ort::value::TensorRef;

use crate::error::{OnnxError, Result};
use crate::session::{names_of, open_session};
use crate::session::{SessionParams, TensorInfo};

/// Element type name of the tensors [`Network::run`] passes and reads.
const F32: &str = "f32";

/// One `f32` input of a run: tensor name, shape and row-major data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TensorInput<'a> {
    /// Input name in the graph.
    pub name: &'a str,
    /// Shape of the tensor.
    pub shape: &'a [usize],
    /// Row-major values; as many as the product of `shape`.
    pub data: &'a [f32],
}

impl<'a> TensorInput<'a> {
    /// An input named `name` of the given shape and data.
    pub fn new(name: &'a str, shape: &'a [usize], data: &'a [f32]) -> Self {
        TensorInput { name, shape, data }
    }
}

/// One `f32` output of a run: tensor name, shape and row-major data.
#[derive(Debug, Clone, PartialEq)]
pub struct TensorOutput {
    /// Output name in the graph.
    pub name: String,
    /// Shape of the tensor as produced.
    pub shape: Vec<usize>,
    /// Row-major values.
    pub data: Vec<f32>,
}

/// An opened ONNX model with the names and shapes of its inputs and outputs.
///
/// `Send + Sync`: the session sits behind a mutex, so one run at a time goes
/// through ONNX Runtime (which uses its own intra-op threads).
pub struct Network {
    name: String,
    path: PathBuf,
    inputs: Vec<TensorInfo>,
    outputs: Vec<TensorInfo>,
    session: Mutex<Session>,
}

impl std::fmt::Debug for Network {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Network")
            .field("path", &self.path)
            .field("inputs", &self.inputs)
            .field("outputs", &self.outputs)
            .finish()
    }
}

/// Product of a shape's dimensions; `None` on overflow.
fn element_count(shape: &[usize]) -> Option<usize> {
    shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d))
}

impl Network {
    /// Opens the model file at `path` with the given session settings.
    ///
    /// Errors: [`OnnxError::ModelMissing`] when the file does not exist
    /// (checked before ONNX Runtime is loaded), and those of [`open_session`].
    pub fn open(path: impl AsRef<Path>, params: &SessionParams) -> Result<Self> {
        let path = path.as_ref();
        if !path.is_file() {
            return Err(OnnxError::ModelMissing {
                file: path.file_name().map_or_else(
                    || path.display().to_string(),
                    |f| f.to_string_lossy().into(),
                ),
                searched: path
                    .parent()
                    .map_or_else(|| "(no folder)".into(), |p| p.display().to_string()),
            });
        }
        let session = open_session(path, params)?;
        Ok(Network {
            name: path.display().to_string(),
            path: path.to_path_buf(),
            inputs: TensorInfo::inputs_of(&session),
            outputs: TensorInfo::outputs_of(&session),
            session: Mutex::new(session),
        })
    }

    /// The model's name in messages (its path).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The model file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The graph's inputs, in graph order.
    pub fn inputs(&self) -> &[TensorInfo] {
        &self.inputs
    }

    /// The graph's outputs, in graph order.
    pub fn outputs(&self) -> &[TensorInfo] {
        &self.outputs
    }

    /// The graph input of this name.
    pub fn input(&self, name: &str) -> Option<&TensorInfo> {
        self.inputs.iter().find(|i| i.name == name)
    }

    /// The graph output of this name.
    pub fn output(&self, name: &str) -> Option<&TensorInfo> {
        self.outputs.iter().find(|o| o.name == name)
    }

    /// Checks that the graph has an input of this name, element type and
    /// shape (see [`TensorInfo::check`]); [`OnnxError::Contract`] otherwise.
    pub fn expect_input(&self, name: &str, dtype: &str, shape: &[i64]) -> Result<&TensorInfo> {
        TensorInfo::check(&self.name, &self.inputs, name, dtype, shape)
    }

    /// Checks that the graph has an output of this name, element type and
    /// shape (see [`TensorInfo::check`]); [`OnnxError::Contract`] otherwise.
    pub fn expect_output(&self, name: &str, dtype: &str, shape: &[i64]) -> Result<&TensorInfo> {
        TensorInfo::check(&self.name, &self.outputs, name, dtype, shape)
    }

    /// Checks a run's inputs against the graph without running it: every
    /// name known and given once, every graph input given, each an `f32`
    /// input whose shape fits the graph and whose data fills the shape.
    ///
    /// Errors: [`OnnxError::UnknownInput`], [`OnnxError::MissingInput`],
    /// [`OnnxError::InputShape`], [`OnnxError::InputLength`], and
    /// [`OnnxError::Contract`] for a graph input that is not `f32` or a name
    /// given twice.
    pub fn check_inputs(&self, inputs: &[TensorInput<'_>]) -> Result<()> {
        for (k, input) in inputs.iter().enumerate() {
            let Some(info) = self.input(input.name) else {
                return Err(OnnxError::UnknownInput {
                    model: self.name.clone(),
                    input: input.name.to_string(),
                    known: names_of(&self.inputs),
                });
            };
            if inputs[..k].iter().any(|i| i.name == input.name) {
                return Err(OnnxError::contract(
                    &self.name,
                    format!("input `{}` is given twice", input.name),
                ));
            }
            if info.dtype != F32 {
                return Err(OnnxError::contract(
                    &self.name,
                    format!(
                        "input `{}` is {}, the run gives {F32}",
                        input.name, info.dtype
                    ),
                ));
            }
            if !info.accepts(input.shape) {
                return Err(OnnxError::InputShape {
                    model: self.name.clone(),
                    input: input.name.to_string(),
                    expected: info.shape.clone(),
                    got: input.shape.to_vec(),
                });
            }
            let needed = element_count(input.shape);
            if needed != Some(input.data.len()) {
                return Err(OnnxError::InputLength {
                    model: self.name.clone(),
                    input: input.name.to_string(),
                    shape: input.shape.to_vec(),
                    needed: needed.unwrap_or(usize::MAX),
                    len: input.data.len(),
                });
            }
        }
        if let Some(missing) = self
            .inputs
            .iter()
            .find(|g| !inputs.iter().any(|i| i.name == g.name))
        {
            return Err(OnnxError::MissingInput {
                model: self.name.clone(),
                input: missing.name.clone(),
            });
        }
        Ok(())
    }

    /// Runs the model on `inputs` and returns the requested `outputs` (as
    /// `f32`, in the order asked), after [`Network::check_inputs`] and a
    /// check that every requested output exists.
    ///
    /// Errors: those of [`Network::check_inputs`];
    /// [`OnnxError::MissingOutput`] for an output the graph does not have;
    /// [`OnnxError::Model`] when ONNX Runtime fails to run or an output is
    /// not `f32`.
    pub fn run(&self, inputs: &[TensorInput<'_>], outputs: &[&str]) -> Result<Vec<TensorOutput>> {
        self.check_inputs(inputs)?;
        let missing_output = |name: &str| OnnxError::MissingOutput {
            model: self.name.clone(),
            output: name.to_string(),
            known: names_of(&self.outputs),
        };
        if let Some(name) = outputs.iter().find(|n| self.output(n).is_none()) {
            return Err(missing_output(name));
        }
        let mut values: Vec<(Cow<'_, str>, SessionInputValue<'_>)> =
            Vec::with_capacity(inputs.len());
        for input in inputs {
            let tensor = TensorRef::from_array_view((input.shape.to_vec(), input.data))
                .map_err(|e| OnnxError::model(&self.name, e))?;
            values.push((Cow::Borrowed(input.name), tensor.into()));
        }
        let mut session = self.session.lock().unwrap_or_else(|e| e.into_inner());
        let out = session
            .run(values)
            .map_err(|e| OnnxError::model(&self.name, e))?;
        outputs
            .iter()
            .map(|&name| {
                let value = out.get(name).ok_or_else(|| missing_output(name))?;
                let (shape, data) = value
                    .try_extract_tensor::<f32>()
                    .map_err(|e| OnnxError::model(&self.name, format!("output `{name}`: {e}")))?;
                Ok(TensorOutput {
                    name: name.to_string(),
                    shape: shape.iter().map(|&d| d.max(0) as usize).collect(),
                    data: data.to_vec(),
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn element_counts_refuse_overflow() {
        assert_eq!(element_count(&[2, 3, 4]), Some(24));
        assert_eq!(element_count(&[]), Some(1));
        assert_eq!(element_count(&[usize::MAX, 2]), None);
    }

    #[test]
    fn a_missing_file_is_reported_before_the_runtime_is_loaded() {
        let tmp = tempfile::tempdir().unwrap();
        let e =
            Network::open(tmp.path().join("absent.onnx"), &SessionParams::default()).unwrap_err();
        assert!(
            matches!(&e, OnnxError::ModelMissing { file, .. } if file == "absent.onnx"),
            "{e}"
        );
    }
}
