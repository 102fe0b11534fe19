//! Tests of the crate's inner parts: the tensor contracts of the models.

mod contracts;

/// The MoveNet model's path, or `None` (skip recorded): the set-up converts
/// it only from the shared models or a `.tflite` the user gives.
fn movenet_model() -> Option<std::path::PathBuf> {
    match crate::model_path(crate::ModelFile::MoveNetLightning) {
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
