//! A missing ONNX Runtime library is a clear error, not a panic. (Own test
//! binary: the library, once loaded, stays loaded for the process.)
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_pose::{BlazePose, BlazePoseParams, OnnxError, PoseError};

#[test]
fn missing_library_says_run_setup() {
    // SAFETY: this test binary has a single test, so no other thread reads the environment.
    unsafe { std::env::set_var("ORT_DYLIB_PATH", "/nonexistent/libonnxruntime.so") };
    let err = mp_onnx::environment().expect_err("must fail");
    assert!(matches!(err, OnnxError::RuntimeMissing { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("cargo xtask setup") && msg.contains("/nonexistent/libonnxruntime.so"),
        "{msg}"
    );
    // Opening a model goes through the same check (after finding the model files).
    match BlazePose::new(BlazePoseParams::default()) {
        Err(PoseError::Runtime(OnnxError::RuntimeMissing { .. }))
        | Err(PoseError::ModelMissing { .. }) => {}
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("must fail without the library"),
    }
}
