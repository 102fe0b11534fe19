//! Session settings, opening a model, and describing its tensors.

use std::path::Path;

use ort::session::Session;

use crate::error::{format_shape, OnnxError, Result};
use crate::library::environment;

/// Settings of an inference session.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SessionParams {
    /// Threads of ONNX Runtime's intra-op pool. Default 2 (the target machines have 2 cores).
    pub intra_threads: usize,
    /// Whether idle intra-op threads may busy-spin. Default `false`: with spinning,
    /// two sessions on 2 cores run several times slower.
    pub allow_spinning: bool,
}

impl Default for SessionParams {
    fn default() -> Self {
        SessionParams {
            intra_threads: 2,
            allow_spinning: false,
        }
    }
}

impl SessionParams {
    /// Checks the values: `intra_threads` must be in `1..=256`.
    pub fn validate(&self) -> Result<()> {
        if self.intra_threads == 0 || self.intra_threads > 256 {
            return Err(OnnxError::param(
                "intra_threads",
                format!("must be in 1..=256, got {}", self.intra_threads),
            ));
        }
        Ok(())
    }
}

/// Opens an ONNX model with the given settings (loading ONNX Runtime first
/// when needed). One inter-op thread; spinning as [`SessionParams::allow_spinning`].
///
/// Errors: invalid settings, a missing or unloadable library, or a model
/// that ONNX Runtime refuses ([`OnnxError::Model`], naming the file).
pub fn open_session(path: &Path, params: &SessionParams) -> Result<Session> {
    params.validate()?;
    let name = path.display().to_string();
    let env = environment()?;
    let spin = if params.allow_spinning { "1" } else { "0" };
    let err = |e: ort::Error<ort::session::builder::SessionBuilder>| OnnxError::model(&name, e);
    let builder = Session::builder(&env).map_err(|e| OnnxError::model(&name, e))?;
    let builder = builder
        .with_intra_threads(params.intra_threads)
        .map_err(err)?;
    let builder = builder.with_inter_threads(1).map_err(err)?;
    let builder = builder
        .with_config_entry("session.intra_op.allow_spinning", spin)
        .map_err(err)?;
    let mut builder = builder
        .with_config_entry("session.inter_op.allow_spinning", spin)
        .map_err(err)?;
    builder
        .commit_from_file(path)
        .map_err(|e| OnnxError::model(&name, e))
}

/// Name, element type and shape (−1 = dynamic) of a session input or output.
#[derive(Debug, Clone, PartialEq)]
pub struct TensorInfo {
    /// Tensor name in the graph.
    pub name: String,
    /// Element type, as ONNX Runtime prints it (`f32`, `u8`, …).
    pub dtype: String,
    /// Dimensions; −1 where the graph leaves a dimension open.
    pub shape: Vec<i64>,
}

impl TensorInfo {
    /// Whether a concrete shape fits this tensor: same rank, and every
    /// dimension the graph fixes has that size.
    pub fn accepts(&self, shape: &[usize]) -> bool {
        self.shape.len() == shape.len()
            && self
                .shape
                .iter()
                .zip(shape)
                .all(|(&g, &s)| g < 0 || g as usize == s)
    }
}

fn outlet_info(o: &ort::value::Outlet) -> TensorInfo {
    let dtype = o
        .dtype()
        .tensor_type()
        .map(|t| format!("{t}"))
        .unwrap_or_else(|| "non-tensor".into());
    let shape = o
        .dtype()
        .tensor_shape()
        .map(|s| s.to_vec())
        .unwrap_or_default();
    TensorInfo {
        name: o.name().to_string(),
        dtype,
        shape,
    }
}

/// Inputs of a session, in graph order.
pub fn inputs_of(session: &Session) -> Vec<TensorInfo> {
    session.inputs().iter().map(outlet_info).collect()
}

/// Outputs of a session, in graph order.
pub fn outputs_of(session: &Session) -> Vec<TensorInfo> {
    session.outputs().iter().map(outlet_info).collect()
}

/// Names of tensors, comma-separated, for messages.
pub(crate) fn names_of(infos: &[TensorInfo]) -> String {
    infos
        .iter()
        .map(|i| i.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Checks that `infos` (the inputs or outputs of `model`) have a tensor of
/// this name, element type and shape; a dimension the graph leaves open
/// matches any expected size, and an expected size below 0 matches any graph
/// size. Returns the tensor's description.
///
/// Errors: [`OnnxError::Contract`], naming the model, the tensor and both shapes.
pub fn check_tensor<'a>(
    model: &str,
    infos: &'a [TensorInfo],
    name: &str,
    dtype: &str,
    shape: &[i64],
) -> Result<&'a TensorInfo> {
    let Some(info) = infos.iter().find(|i| i.name == name) else {
        return Err(OnnxError::contract(
            model,
            format!("no tensor named `{name}` (has: {})", names_of(infos)),
        ));
    };
    let shape_ok = info.shape.len() == shape.len()
        && info
            .shape
            .iter()
            .zip(shape)
            .all(|(&a, &b)| a < 0 || b < 0 || a == b);
    if !shape_ok || info.dtype != dtype {
        return Err(OnnxError::contract(
            model,
            format!(
                "`{name}` is {} {}, expected {dtype} {}",
                info.dtype,
                format_shape(&info.shape),
                format_shape(shape)
            ),
        ));
    }
    Ok(info)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(name: &str, dtype: &str, shape: &[i64]) -> TensorInfo {
        TensorInfo {
            name: name.into(),
            dtype: dtype.into(),
            shape: shape.to_vec(),
        }
    }

    #[test]
    fn zero_threads_are_refused() {
        assert!(SessionParams::default().validate().is_ok());
        let bad = SessionParams {
            intra_threads: 0,
            ..Default::default()
        };
        assert!(matches!(
            bad.validate(),
            Err(OnnxError::InvalidParam {
                name: "intra_threads",
                ..
            })
        ));
    }

    #[test]
    fn open_dimensions_accept_any_size() {
        let t = info("motion", "f32", &[-1, 60, 60]);
        assert!(t.accepts(&[7, 60, 60]));
        assert!(!t.accepts(&[7, 59, 60]));
        assert!(!t.accepts(&[60, 60]));
    }

    #[test]
    fn contract_check_names_model_and_tensor() {
        let infos = [info("motion", "f32", &[-1, 60, 60])];
        assert!(check_tensor("m.onnx", &infos, "motion", "f32", &[1, 60, 60]).is_ok());
        assert!(check_tensor("m.onnx", &infos, "motion", "f32", &[-1, 60, -1]).is_ok());
        let e = check_tensor("m.onnx", &infos, "motion", "u8", &[1, 60, 60]).unwrap_err();
        assert!(matches!(e, OnnxError::Contract { .. }), "{e}");
        let msg = check_tensor("m.onnx", &infos, "z", "f32", &[1])
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("m.onnx") && msg.contains("`z`") && msg.contains("motion"),
            "{msg}"
        );
    }
}
