//! # mp-onnx — ONNX Runtime for the toolkit
//!
//! Everything the model-running crates (`mp-pose`, `mp-forecast`,
//! `mp-refine`) share about ONNX Runtime:
//!
//! * `library`: finding the ONNX Runtime shared library (`ORT_DYLIB_PATH`,
//!   `.cache/onnxruntime/lib` as installed by `cargo xtask setup`, next to
//!   the executable) and loading it once per process ([`environment`]).
//!   Nothing in `ort` is touched before the library has been found, so a
//!   missing library is an [`OnnxError`], not a panic.
//! * `session`: session settings ([`SessionParams`]), opening a model
//!   ([`open_session`]) and describing its tensors ([`TensorInfo`]).
//! * `network`: [`Network`], one opened model with its input and output
//!   names and shapes, run on `f32` tensors after checking every input's
//!   name, shape and length against the graph.
//! * `lookup`: [`ModelDirs`], the ordered folders searched for model
//!   files (an environment variable, the workspace, the current directory's
//!   ancestors).
//!
//! ```no_run
//! use mp_onnx::{Network, SessionParams, TensorInput};
//! let net = Network::open("models/refine/evaluator.onnx", &SessionParams::default())?;
//! let motion = vec![0f32; 60 * 60];
//! let out = net.run(&[TensorInput::new("motion", &[1, 60, 60], &motion)], &["logits"])?;
//! println!("logits of shape {:?}", out[0].shape);
//! # Ok::<(), mp_onnx::OnnxError>(())
//! ```

mod error;
mod library;
mod lookup;
mod network;
mod session;

pub use error::OnnxError;
pub use library::{environment, find_library};
pub use lookup::ModelDirs;
pub use network::{Network, TensorInput, TensorOutput};
pub use session::{open_session, Device, SessionParams, TensorInfo};
