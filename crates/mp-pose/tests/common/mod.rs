//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use ndarray::{Array1, Array2, Array3};
use ndarray_npy::NpzReader;

/// A file under the shared data folder, or `None` when absent (the running
/// test's skip is recorded: `mp_geom::test_support::data_file_or_skip`).
pub fn data(rel: &str) -> Option<PathBuf> {
    mp_geom::test_support::data_file_or_skip(rel, &mp_geom::test_support::current_test_name())
}

/// MediaPipe reference keypoints of one video.
pub struct Reference {
    pub landmarks_px: Array3<f32>,
    pub visibility: Array2<f32>,
    pub found: Array1<bool>,
    pub roi_from_landmarks: Array2<f32>,
    pub roi_from_detection: Array2<f32>,
}

/// `None` (skip recorded) without the shared data.
pub fn reference(stem: &str) -> Option<Reference> {
    let path = data(&format!("reference_keypoints/{stem}.npz"))?;
    let mut npz = NpzReader::new(std::fs::File::open(&path).unwrap()).unwrap();
    Some(Reference {
        landmarks_px: npz.by_name("landmarks_px").unwrap(),
        visibility: npz.by_name("visibility").unwrap(),
        found: npz.by_name("found").unwrap(),
        roi_from_landmarks: npz.by_name("roi_from_landmarks").unwrap(),
        roi_from_detection: npz.by_name("roi_from_detection").unwrap(),
    })
}

/// The MoveNet model's path, or `None` (skip recorded): the set-up converts
/// it only from the shared models or a `.tflite` the user gives.
pub fn movenet_model() -> Option<PathBuf> {
    use mp_pose::{model_path, ModelFile};
    match model_path(ModelFile::MoveNetLightning) {
        Ok(p) => Some(p),
        Err(_) => {
            mp_geom::test_support::skip_test(
                &mp_geom::test_support::current_test_name(),
                "models/movenet_singlepose_lightning_int8.onnx (`cargo xtask models --movenet-tflite FILE`)",
            );
            None
        }
    }
}
