//! ONNX Runtime: finding and loading the shared library, finding model files,
//! and building sessions with the settings this crate relies on.
//!
//! The library is looked up, in order, at `ORT_DYLIB_PATH`, at
//! `<workspace>/.cache/onnxruntime/lib/libonnxruntime.so` (installed by
//! `cargo xtask setup`), in `.cache/onnxruntime/lib` above the current
//! directory, and next to the executable. Nothing in `ort` is touched before
//! the library has been found, so a missing library is a [`PoseError`], not a
//! panic.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use ort::session::Session;

use crate::error::{PoseError, Result};

/// File name of the ONNX Runtime library on this platform.
pub const LIBRARY_FILE: &str = if cfg!(target_os = "windows") {
    "onnxruntime.dll"
} else if cfg!(target_os = "macos") {
    "libonnxruntime.dylib"
} else {
    "libonnxruntime.so"
};

/// Where `cargo xtask setup` installs the library, relative to the workspace root.
pub const LIBRARY_DIR_IN_WORKSPACE: &str = ".cache/onnxruntime/lib";
/// Where `cargo xtask models` puts the models, relative to the workspace root.
pub const MODEL_DIR_IN_WORKSPACE: &str = ".cache/models";

/// The ONNX models this crate uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModelFile {
    /// BlazePose person detector (`pose_detection.onnx`).
    PoseDetection,
    /// BlazePose GHUM landmark model, full (`pose_landmark_full.onnx`).
    LandmarkFull,
    /// BlazePose GHUM landmark model, lite (`pose_landmark_lite.onnx`).
    LandmarkLite,
    /// BlazePose GHUM landmark model, heavy (`pose_landmark_heavy.onnx`, optional).
    LandmarkHeavy,
    /// MoveNet SinglePose Lightning int8 (`movenet_singlepose_lightning_int8.onnx`).
    MoveNetLightning,
}

impl ModelFile {
    /// The models `cargo xtask models` provides.
    pub const REQUIRED: [ModelFile; 4] = [
        ModelFile::PoseDetection,
        ModelFile::LandmarkFull,
        ModelFile::LandmarkLite,
        ModelFile::MoveNetLightning,
    ];

    /// File name of the model.
    pub fn file_name(self) -> &'static str {
        match self {
            ModelFile::PoseDetection => "pose_detection.onnx",
            ModelFile::LandmarkFull => "pose_landmark_full.onnx",
            ModelFile::LandmarkLite => "pose_landmark_lite.onnx",
            ModelFile::LandmarkHeavy => "pose_landmark_heavy.onnx",
            ModelFile::MoveNetLightning => "movenet_singlepose_lightning_int8.onnx",
        }
    }
}

/// Folders searched for model files, in order: `MP_MODEL_DIR`,
/// `<workspace>/.cache/models`, `<shared>/models`.
pub fn model_dirs() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Ok(p) = std::env::var("MP_MODEL_DIR") {
        if !p.is_empty() {
            dirs.push(PathBuf::from(p));
        }
    }
    if let Some(root) = mp_geom::paths::workspace_root() {
        dirs.push(root.join(MODEL_DIR_IN_WORKSPACE));
    }
    if let Ok(cwd) = std::env::current_dir() {
        for anc in cwd.ancestors() {
            let d = anc.join(MODEL_DIR_IN_WORKSPACE);
            if d.is_dir() && !dirs.contains(&d) {
                dirs.push(d);
                break;
            }
        }
    }
    if let Some(shared) = mp_geom::paths::shared_dir() {
        dirs.push(shared.join("models"));
    }
    dirs
}

/// Path of a model file, from the first folder of [`model_dirs`] that has it.
pub fn model_path(model: ModelFile) -> Result<PathBuf> {
    find_model_file(model.file_name())
}

/// Path of a model file by name (see [`model_path`]).
pub fn find_model_file(file: &str) -> Result<PathBuf> {
    let dirs = model_dirs();
    for d in &dirs {
        let p = d.join(file);
        if p.is_file() {
            return Ok(p);
        }
    }
    Err(PoseError::ModelMissing {
        file: file.to_string(),
        searched: join_paths(&dirs),
    })
}

fn join_paths(paths: &[PathBuf]) -> String {
    if paths.is_empty() {
        return "(no candidate folder)".into();
    }
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Candidate paths of the ONNX Runtime library, in search order.
pub fn library_candidates() -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(p) = std::env::var("ORT_DYLIB_PATH") {
        if !p.is_empty() {
            // An explicit path is the only candidate: a wrong value should be reported, not skipped.
            out.push(PathBuf::from(p));
            return out;
        }
    }
    if let Some(root) = mp_geom::paths::workspace_root() {
        out.push(root.join(LIBRARY_DIR_IN_WORKSPACE).join(LIBRARY_FILE));
    }
    if let Ok(cwd) = std::env::current_dir() {
        for anc in cwd.ancestors() {
            let p = anc.join(LIBRARY_DIR_IN_WORKSPACE).join(LIBRARY_FILE);
            if !out.contains(&p) {
                out.push(p);
            }
        }
    }
    if let Some(dir) = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_path_buf))
    {
        out.push(dir.join(LIBRARY_FILE));
        out.push(dir.join("lib").join(LIBRARY_FILE));
    }
    out
}

/// The ONNX Runtime library that would be loaded, if one exists.
pub fn find_library() -> Result<PathBuf> {
    let cands = library_candidates();
    for c in &cands {
        if c.is_file() {
            return Ok(c.clone());
        }
    }
    // Only show the most useful candidates (the ancestors list can be long).
    let shown: Vec<PathBuf> = cands.into_iter().take(4).collect();
    Err(PoseError::RuntimeMissing {
        searched: join_paths(&shown),
    })
}

static ENVIRONMENT: Mutex<Option<ort::environment::Environment>> = Mutex::new(None);

/// Loads ONNX Runtime (once per process) and returns its environment.
pub fn environment() -> Result<ort::environment::Environment> {
    let mut guard = ENVIRONMENT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(env) = guard.as_ref() {
        return Ok(env.clone());
    }
    let path = find_library()?;
    let builder = ort::init_from(&path).map_err(|e| PoseError::RuntimeLoad {
        path: path.clone(),
        reason: e.to_string(),
    })?;
    let env = builder
        .with_name("mp-pose")
        .build()
        .map_err(|e| PoseError::RuntimeLoad {
            path: path.clone(),
            reason: e.to_string(),
        })?;
    *guard = Some(env.clone());
    Ok(env)
}

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
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        if self.intra_threads == 0 || self.intra_threads > 256 {
            return Err(PoseError::param(
                "intra_threads",
                format!("must be in 1..=256, got {}", self.intra_threads),
            ));
        }
        Ok(())
    }
}

/// Opens an ONNX model with the given settings.
pub fn open_session(path: &Path, params: &SessionParams) -> Result<Session> {
    params.validate()?;
    let name = path.display().to_string();
    let env = environment()?;
    let spin = if params.allow_spinning { "1" } else { "0" };
    let err = |e: ort::Error<ort::session::builder::SessionBuilder>| PoseError::model(&name, e);
    let builder = Session::builder(&env).map_err(|e| PoseError::model(&name, e))?;
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
        .map_err(|e| PoseError::model(&name, e))
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

/// Inputs of a session.
pub fn inputs_of(session: &Session) -> Vec<TensorInfo> {
    session.inputs().iter().map(outlet_info).collect()
}

/// Outputs of a session.
pub fn outputs_of(session: &Session) -> Vec<TensorInfo> {
    session.outputs().iter().map(outlet_info).collect()
}

/// Checks that a session has an input/output of this name and shape
/// (dynamic dimensions in the graph match anything).
pub(crate) fn check_tensor(
    model: &str,
    infos: &[TensorInfo],
    name: &str,
    dtype: &str,
    shape: &[i64],
) -> Result<()> {
    let Some(info) = infos.iter().find(|i| i.name == name) else {
        return Err(PoseError::Contract {
            model: model.into(),
            reason: format!(
                "no tensor named `{name}` (has: {})",
                infos
                    .iter()
                    .map(|i| i.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        });
    };
    let shape_ok = info.shape.len() == shape.len()
        && info.shape.iter().zip(shape).all(|(&a, &b)| a < 0 || a == b);
    if !shape_ok || info.dtype != dtype {
        return Err(PoseError::Contract {
            model: model.into(),
            reason: format!(
                "`{name}` is {} {:?}, expected {dtype} {shape:?}",
                info.dtype, info.shape
            ),
        });
    }
    Ok(())
}

/// Wraps a prepared `[1, n, n, 3]` (NHWC) image input of `model` as a tensor,
/// refusing a buffer of the wrong length (`what` names the input in the error).
pub(crate) fn image_tensor<'a, T>(
    input: &'a [T],
    n: usize,
    model: &str,
    what: &str,
) -> Result<ort::value::TensorRef<'a, T>>
where
    T: ort::value::PrimitiveTensorElementType + std::fmt::Debug + Clone + 'static,
{
    if input.len() != n * n * 3 {
        return Err(PoseError::param(
            "input",
            format!(
                "{what} input needs {} values, got {}",
                n * n * 3,
                input.len()
            ),
        ));
    }
    ort::value::TensorRef::from_array_view(([1usize, n, n, 3], input))
        .map_err(|e| PoseError::model(model, e))
}

/// Reads a named f32 output of a run as (shape, data).
pub(crate) fn output_f32<'a>(
    outputs: &'a ort::session::SessionOutputs<'_>,
    model: &str,
    name: &str,
    expected_len: usize,
) -> Result<&'a [f32]> {
    let value = outputs.get(name).ok_or_else(|| PoseError::Contract {
        model: model.into(),
        reason: format!("run produced no output `{name}`"),
    })?;
    let (_, data) = value
        .try_extract_tensor::<f32>()
        .map_err(|e| PoseError::model(model, e))?;
    if data.len() != expected_len {
        return Err(PoseError::Contract {
            model: model.into(),
            reason: format!(
                "output `{name}` has {} values, expected {expected_len}",
                data.len()
            ),
        });
    }
    Ok(data)
}
