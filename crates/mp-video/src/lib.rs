//! # mp-video — motion programs on video pixels
//!
//! The programs and loops that `mp run` finds in a video, applied to the
//! video's own frames:
//!
//! * `edit`: more or fewer repetitions in a counted interval (`mp edit`):
//!   the repetition closest to the interval's mean is repeated or removed, seams are
//!   placed where pose and pixels match best within a few frames and
//!   cross-faded.
//! * `predict`: the video continued by unrolling its last repetition on pixels
//!   (`mp predict VIDEO --seconds S`), with the constant (frozen last frame)
//!   and nearest-neighbour frame baselines.
//! * `interpolate`: in-between frames from the program fitted on the
//!   frames' keypoints (`mp interpolate`): both neighbouring frames are
//!   warped towards the program's pose and blended; linear blending and
//!   FFmpeg's `minterpolate` as baselines.
//!
//! Frames stream through FFmpeg pipes ([`mp_pose::VideoReader`], [`mp_pose::VideoWriter`]): an output is a
//! [`plan::Plan`] of source frames (copied or blended) rendered with a
//! bounded cache of the frames still to be used, and every video is written
//! to a temporary file in the output's folder, then renamed
//! (`AtomicVideo` in `plan.rs`).
//!
//! ```no_run
//! use mp_video::{predict_video, VideoPredictMethod, VideoPredictParams};
//!
//! // Three more seconds of a video, by unrolling its last repetition on the
//! // video's own frames (`mp predict squats.mp4 --seconds 3`).
//! let params = mp_pipeline::Params::default();
//! predict_video(
//!     "squats.mp4".as_ref(),
//!     3.0,
//!     VideoPredictMethod::default(),
//!     &VideoPredictParams::default(),
//!     &params,
//!     "more.mp4".as_ref(),
//! )?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod edit;
mod error;
mod interpolate;

mod motion;
mod plan;
mod predict;

pub use edit::{edit_video, EditChange, EditParams, EditReport};
pub use error::VideoError;
pub use interpolate::{
    interpolate_frames, interpolate_video, keep_every, Guide, InterpMethod, InterpParams,
    InterpReport, Warp,
};
pub use motion::VideoMotion;
pub use plan::{Plan, PlanFrame};
pub use predict::{predict_video, PredictReport, VideoPredictMethod, VideoPredictParams};
