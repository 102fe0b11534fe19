//! ONNX Runtime for the pose models: the library, sessions and tensor
//! descriptions come from `mp-onnx`; this module adds the
//! pose model files and where they are found.
//!
//! The library is looked up, in order, at `ORT_DYLIB_PATH`, at
//! `<workspace>/.cache/onnxruntime/lib/libonnxruntime.so` (installed by
//! `cargo xtask setup`), in `.cache/onnxruntime/lib` above the current
//! directory, and next to the executable (see [`mp_onnx::library`]). Nothing
//! in `ort` is touched before the library has been found, so a missing
//! library is an error ([`PoseError::Runtime`]), not a panic.

use std::path::PathBuf;

pub use mp_onnx::{open_session, Device, ModelDirs, SessionParams, TensorInfo};

use crate::error::{PoseError, Result};

/// Environment variable naming a folder of pose models.
pub const MODEL_DIR_ENV: &str = "MP_MODEL_DIR";
/// Where `cargo xtask models` puts the models, relative to the workspace root.
pub const MODEL_DIR_IN_WORKSPACE: &str = ".cache/models";

/// The ONNX models this crate uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
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

    /// File name of the landmark model without its segmentation-mask head
    /// (`pose_landmark_full_nomask.onnx`), made by `cargo xtask models`: the
    /// same graph cut to the outputs this crate reads, the same values in
    /// about half the time (ONNX Runtime runs every node of a graph, the
    /// 256×256 mask's decoder included, whichever outputs are asked for).
    /// `None` for the detector and MoveNet.
    pub fn without_mask(self) -> Option<&'static str> {
        match self {
            ModelFile::LandmarkFull => Some("pose_landmark_full_nomask.onnx"),
            ModelFile::LandmarkLite => Some("pose_landmark_lite_nomask.onnx"),
            ModelFile::LandmarkHeavy => Some("pose_landmark_heavy_nomask.onnx"),
            ModelFile::PoseDetection | ModelFile::MoveNetLightning => None,
        }
    }

    /// The files the estimators open, in order of preference in each folder:
    /// the model without its mask head ([`ModelFile::without_mask`]), then
    /// the model as converted.
    pub fn run_files(self) -> Vec<&'static str> {
        self.without_mask()
            .into_iter()
            .chain(std::iter::once(self.file_name()))
            .collect()
    }

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

/// The search list of the pose models: `MP_MODEL_DIR`,
/// `<workspace>/.cache/models`, `.cache/models` above the current directory,
/// `<shared>/models`.
fn model_search() -> ModelDirs {
    let dirs = ModelDirs::standard(MODEL_DIR_ENV, MODEL_DIR_IN_WORKSPACE);
    match mp_geom::shared_dir() {
        Some(shared) => dirs.with_dir(shared.join("models")),
        None => dirs,
    }
}

/// Path of a model file, from the first of the folders searched that has it:
/// `MP_MODEL_DIR`, `<workspace>/.cache/models`, `.cache/models` above the
/// current directory (where it exists), `<shared>/models`.
pub fn model_path(model: ModelFile) -> Result<PathBuf> {
    find_model_file(model.file_name())
}

/// Path of the file the estimators open for `model`: the first folder of
/// [`model_dirs`] with either of [`ModelFile::run_files`], the file without
/// the mask head preferred within a folder.
pub fn run_model_path(model: ModelFile) -> Result<PathBuf> {
    let dirs = model_search();
    dirs.find_first_of(&model.run_files())
        .ok_or_else(|| PoseError::ModelMissing {
            file: model.file_name().to_string(),
            searched: dirs.describe(usize::MAX),
        })
}

/// Path of a model file by name (see [`model_path`]).
pub(crate) fn find_model_file(file: &str) -> Result<PathBuf> {
    let dirs = model_search();
    dirs.find_file(file).ok_or_else(|| PoseError::ModelMissing {
        file: file.to_string(),
        searched: dirs.describe(usize::MAX),
    })
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
    image_batch_tensor(input, 1, n, model, what)
}

/// Wraps `count` prepared `n × n × 3` (NHWC) images laid end to end as one
/// `[count, n, n, 3]` input of `model`, refusing a buffer of the wrong length.
pub(crate) fn image_batch_tensor<'a, T>(
    input: &'a [T],
    count: usize,
    n: usize,
    model: &str,
    what: &str,
) -> Result<ort::value::TensorRef<'a, T>>
where
    T: ort::value::PrimitiveTensorElementType + std::fmt::Debug + Clone + 'static,
{
    let want = count * n * n * 3;
    if count == 0 || input.len() != want {
        return Err(PoseError::param(
            "input",
            format!(
                "{what} input needs {want} values ({count} of {n} × {n} × 3), got {}",
                input.len()
            ),
        ));
    }
    ort::value::TensorRef::from_array_view(([count, n, n, 3], input))
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
