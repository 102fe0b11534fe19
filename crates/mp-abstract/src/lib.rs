//! # mp-abstract — abstract motion programs (level 3)
//!
//! Concrete primitives become deterministic `{start, mid, end, duration}`
//! primitives (`synth::translate`); repeated patterns are found by
//! [`loops::detect_loops`] and rolled up into `for` loops of probabilistic
//! primitives (`model`); programs print and parse in the paper's notation
//! (`dsl`), execute deterministically or stochastically with a seed
//! (`exec`), can be edited (`edit`), report repetitive intervals and
//! counts (`repetition`: from loops, from the dominant period of the joint
//! velocities, or from the local-periodicity segmenter
//! [`repetition::segment_repetitions`]) and predict the future by unrolling
//! loops, or, with a single observed cycle, by self-match unrolling (`selfmatch`).
//! `count` turns these into the repetition counts a user gets (intervals,
//! count per interval, total, the signal and method that decided, a
//! confidence), from keypoints and, for video, from frame thumbnails.
//!
//! ```
//! use mp_abstract::{analyse, AbstractParams};
//! use mp_geom::{perform, PerformerParams};
//!
//! // The product's analysis (what `mp abstract` and `mp run` use): the
//! // concrete program, its loops and the repetitions they count.
//! let track = perform(&PerformerParams::default())?.track_2d;
//! let analysis = analyse(&track, &AbstractParams::default())?;
//! assert!(!analysis.intervals.is_empty());
//! for iv in &analysis.intervals {
//!     println!("frames {}–{}: {} repetitions", iv.start_frame, iv.end_frame, iv.count);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod analysis;
mod count;
mod dsl;
mod edit;
mod error;
mod exec;
mod loops;
mod model;
mod repetition;
mod selfmatch;
mod synth;

pub use analysis::{
    analyse, unroll, AbstractParams, Analysis, PredictMethod, PredictParams, Unrolled,
};
pub use count::json::{CountedIntervalJson, ProgramLoopJson, RepetitionsJson};
pub use count::{
    count_repetitions, count_signals, ConfidenceModel, CountFeatures, CountMethod, CountParams,
    CountSignal, CountedInterval, Counts, MISMATCH_OVER_TYPICAL, PERIOD_SLACK, REPEATS_WELL,
};
pub use error::AbstractError;
pub(crate) use error::Result;
pub use loops::{detect_loops, DetectedLoop, LoopParams};
pub use model::{AbstractProgram, DetPrim, FreqDist, Gaussian, Loop, ProbPrim, Stmt};
pub use repetition::{
    estimate_period, segment_repetitions, IntervalParams, JointSelection, PeriodParams,
    PeriodicSegment, RepetitiveInterval,
};
pub use selfmatch::{SelfMatch, SelfMatchFallback, SelfMatchKind};

pub use analysis::{predict_constant, PeriodFallback};
pub use count::found_fraction;
pub use dsl::PrintOptions;
pub use exec::{AbstractExecParams, LoopReplay};
pub use repetition::{intervals, iom, iou, PeriodEstimate};

#[cfg(test)]
mod tests;
