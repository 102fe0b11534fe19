//! # mp-forecast — forecasting human motion from keypoints
//!
//! Condition on the latest 15 observed frames, predict the next 1–30 (paper
//! 002, "Predicting 3D Human Dynamics from Video"; docs/ALGORITHMS.md).
//!
//! * [`Forecaster`]: the seam every method implements
//!   (`predict(past, horizon) -> Track`).
//! * Baselines: [`Constant`] (hold the last pose), [`NearestNeighbour`]
//!   (closest normalised training window, its continuation), [`LoopUnroll`]
//!   (unroll the last detected loop, `mp-abstract`).
//! * The learned model ([`ArForecaster`], ONNX through `ort`): a causal
//!   temporal encoder (residual GroupNorm–ReLU–Conv1d(k=3) blocks, edge
//!   padding, receptive field 13) gives a latent per frame; an autoregressive
//!   causal model of the same shape predicts the next latent; a read-out maps
//!   latents to poses ([`ArSpace::Latent`], "AR on Φ"). The ablation
//!   [`ArSpace::Pose`] ("AR on Θ") runs the same autoregressive network on
//!   poses. Trained by `tools/forecast/train.py` (`cargo xtask train-forecast`).
//! * [`forecast()`], [`search_statue`]: one call per job with the defaults of
//!   `mp predict` and `mp statue` ([`PredictOptions`], [`StatueOptions`]):
//!   training set and model lookup, the map onto the model's joints, and
//!   the path taken ([`PredictPath`]).
//! * `mapped`: the product's skeletons (COCO-17, BlazePose-33) on the
//!   Penn Action / MSR Action3D models (`MappedForecaster`).
//! * `normalize`: the root-relative, torso-scaled keypoint normalisation
//!   shared with the training code.
//! * `statue`: the frame after which prediction accuracy improves most.
//! * `data`: Penn Action / MSR Action3D clips and the validation split.
//!
//! ```
//! use mp_forecast::{Constant, Forecaster};
//! use mp_geom::{perform, PerformerParams};
//!
//! // Two seconds seen, one predicted by the Constant baseline (the learned
//! // models need their ONNX files: `ArForecaster`, `forecast`).
//! let track = perform(&PerformerParams::default())?.track_2d;
//! let past = track.slice_frames(0, 60)?;
//! let future = Constant.predict(&past, 30)?;
//! assert_eq!(future.n_frames(), 30);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod data;
mod error;
mod forecaster;
mod mapped;
mod model;
mod nn;
mod normalize;
mod predict;
mod statue;

pub use error::ForecastError;
pub use forecaster::{Constant, ForecastMethod, Forecaster, LoopUnroll};
pub use model::{ArForecaster, ArParams, ArSpace, ForecastModels};
pub use nn::{NearestNeighbour, NnParams};
pub use predict::{
    forecast, search_statue, LearnedModel, ModelMapping, PredictOptions, PredictPath, Prediction,
    StatueOptions, StatueSearch,
};
pub use statue::{find_statue, Statue, StatueParams};

pub use data::{Clip, ForecastDataset};
