//! Session settings, opening a model, and describing its tensors.

use std::path::Path;

use ort::session::Session;

use crate::error::{format_shape, OnnxError, Result};
use crate::library::environment;

/// Where a model runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Device {
    /// The GPU (CUDA device 0) where the ONNX Runtime library loaded has
    /// its CUDA execution provider and a GPU takes the session; the CPU
    /// otherwise. Default.
    #[default]
    Auto,
    /// The CPU.
    Cpu,
    /// CUDA device `n`; an error where ONNX Runtime cannot use it.
    Cuda(u32),
}

impl Device {
    /// Parses `auto`, `cpu`, `cuda` (device 0) or `cuda:N`.
    pub fn parse(text: &str) -> Result<Self> {
        let t = text.trim().to_ascii_lowercase();
        match t.as_str() {
            "auto" => Ok(Device::Auto),
            "cpu" => Ok(Device::Cpu),
            "cuda" | "gpu" => Ok(Device::Cuda(0)),
            other => other
                .strip_prefix("cuda:")
                .and_then(|n| n.parse::<u32>().ok())
                .map(Device::Cuda)
                .ok_or_else(|| {
                    OnnxError::param(
                        "device",
                        format!("`{text}` is not a device (auto, cpu, cuda or cuda:N)"),
                    )
                }),
        }
    }

    /// `auto`, `cpu` or `cuda:N`.
    pub fn label(&self) -> String {
        match self {
            Device::Auto => "auto".into(),
            Device::Cpu => "cpu".into(),
            Device::Cuda(n) => format!("cuda:{n}"),
        }
    }

    /// Whether the ONNX Runtime library loaded has its CUDA execution provider
    /// (the GPU build; a GPU is still needed for a session to use it). Loads
    /// the library first when needed.
    pub fn cuda_available() -> Result<bool> {
        use ort::ep::ExecutionProvider;
        environment()?;
        ort::ep::CUDA::is_available().map_err(|e| OnnxError::Device {
            device: "cuda".into(),
            reason: e.to_string(),
        })
    }
}

/// Settings of an inference session.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SessionParams {
    /// Threads of ONNX Runtime's intra-op pool. Default 2 (the target machines have 2 cores).
    pub intra_threads: usize,
    /// Whether idle intra-op threads may busy-spin. Default `false`: with spinning,
    /// two sessions on 2 cores run several times slower.
    pub allow_spinning: bool,
    /// Where the model runs. Default [`Device::Auto`].
    pub device: Device,
}

impl Default for SessionParams {
    fn default() -> Self {
        SessionParams {
            intra_threads: 2,
            allow_spinning: false,
            device: Device::default(),
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
/// when needed). One inter-op thread; spinning as [`SessionParams::allow_spinning`];
/// on the device of [`SessionParams::device`]: with [`Device::Auto`], on
/// the GPU where CUDA takes the session and on the CPU otherwise.
///
/// Errors: invalid settings, a missing or unloadable library, a model
/// that ONNX Runtime refuses ([`OnnxError::Model`], naming the file), or a
/// CUDA device asked for that ONNX Runtime cannot use ([`OnnxError::Device`]).
pub fn open_session(path: &Path, params: &SessionParams) -> Result<Session> {
    params.validate()?;
    match params.device {
        Device::Cpu => open_on(path, params, None),
        Device::Cuda(n) => {
            if !Device::cuda_available()? {
                return Err(OnnxError::Device {
                    device: format!("cuda:{n}"),
                    reason: "the ONNX Runtime library loaded is the CPU build, without CUDA \
                             (`bash scripts/setup.sh gpu` installs the GPU build)"
                        .into(),
                });
            }
            open_on(path, params, Some(n))
        }
        Device::Auto => {
            if Device::cuda_available().unwrap_or(false) {
                if let Ok(s) = open_on(path, params, Some(0)) {
                    return Ok(s);
                }
            }
            open_on(path, params, None)
        }
    }
}

/// [`open_session`] on the CPU (`cuda: None`) or on CUDA device `n`.
fn open_on(path: &Path, params: &SessionParams, cuda: Option<u32>) -> Result<Session> {
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
    let builder = builder
        .with_config_entry("session.inter_op.allow_spinning", spin)
        .map_err(err)?;
    let mut builder = match cuda {
        None => builder,
        Some(n) => {
            let device_id = i32::try_from(n).map_err(|_| {
                OnnxError::param("device", format!("CUDA device {n} is out of range"))
            })?;
            let ep = ort::ep::CUDA::default()
                .with_device_id(device_id)
                .build()
                .error_on_failure();
            builder
                .with_execution_providers([ep])
                .map_err(|e| OnnxError::Device {
                    device: format!("cuda:{n}"),
                    reason: e.to_string(),
                })?
        }
    };
    builder.commit_from_file(path).map_err(|e| match cuda {
        Some(n) => OnnxError::Device {
            device: format!("cuda:{n}"),
            reason: e.to_string(),
        },
        None => OnnxError::model(&name, e),
    })
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

    /// Inputs of a session, in graph order.
    pub fn inputs_of(session: &Session) -> Vec<TensorInfo> {
        session.inputs().iter().map(outlet_info).collect()
    }

    /// Outputs of a session, in graph order.
    pub fn outputs_of(session: &Session) -> Vec<TensorInfo> {
        session.outputs().iter().map(outlet_info).collect()
    }

    /// Checks that `infos` (the inputs or outputs of `model`) have a tensor of
    /// this name, element type and shape; a dimension the graph leaves open
    /// matches any expected size, and an expected size below 0 matches any graph
    /// size. Returns the tensor's description.
    ///
    /// Errors: [`OnnxError::Contract`], naming the model, the tensor and both shapes.
    pub fn check<'a>(
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

/// Names of tensors, comma-separated, for messages.
pub(crate) fn names_of(infos: &[TensorInfo]) -> String {
    infos
        .iter()
        .map(|i| i.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
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
    fn devices_parse_and_bad_ones_are_named() {
        assert_eq!(Device::parse("auto").unwrap(), Device::Auto);
        assert_eq!(Device::parse("CPU").unwrap(), Device::Cpu);
        assert_eq!(Device::parse("cuda").unwrap(), Device::Cuda(0));
        assert_eq!(Device::parse("cuda:1").unwrap(), Device::Cuda(1));
        assert_eq!(Device::Cuda(1).label(), "cuda:1");
        for bad in ["tpu", "cuda:", "cuda:-1", "cuda:x", ""] {
            let e = Device::parse(bad).unwrap_err().to_string();
            assert!(e.contains("device"), "{bad}: {e}");
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
        assert!(TensorInfo::check("m.onnx", &infos, "motion", "f32", &[1, 60, 60]).is_ok());
        assert!(TensorInfo::check("m.onnx", &infos, "motion", "f32", &[-1, 60, -1]).is_ok());
        let e = TensorInfo::check("m.onnx", &infos, "motion", "u8", &[1, 60, 60]).unwrap_err();
        assert!(matches!(e, OnnxError::Contract { .. }), "{e}");
        let msg = TensorInfo::check("m.onnx", &infos, "z", "f32", &[1])
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("m.onnx") && msg.contains("`z`") && msg.contains("motion"),
            "{msg}"
        );
    }
}
