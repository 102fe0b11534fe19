//! # mp-concrete — concrete motion programs
//!
//! A concrete program (paper §3.1, Table 1) describes a track as a sequence
//! of segments shared by all joints; in each segment every joint follows one
//! parametric primitive (stationary, linear, circular or cubic spline motion).
//!
//! * [`Program`], [`Segment`]: the data type, with JSON via serde and the
//!   text DSL ([`Program::to_dsl`], [`Program::from_dsl`]; `docs/DSL.md`).
//! * [`Program::synthesize`]: the program of a track by dynamic-programming
//!   segmentation ([`Segmentation`]) over primitive fits from
//!   [`mp_geom::fit_best`].
//! * [`Program::execute`] and friends: rendering at any time resolution.
//! * [`Program::stats`]: the measurements of the paper's §4.1 (the
//!   interpolation experiment of §4.2 is in the evaluations, `mp-eval`).
//! * [`InBetweenPoses`]: the pose between two frames of a track, guided by
//!   its program (what `mp interpolate` warps in-between frames to).
//!
//! ```
//! use mp_concrete::{Program, SynthParams};
//! use mp_geom::{Skeleton, Track, Units};
//! use ndarray::Array3;
//!
//! // One joint moving right for 10 frames, then resting for 10.
//! let mut pos = Array3::zeros((20, 1, 2));
//! for t in 0..20 {
//!     pos[[t, 0, 0]] = 100.0 + 8.0 * (t.min(9) as f64);
//!     pos[[t, 0, 1]] = 50.0;
//! }
//! let track = Track::new(pos, None, 30.0, Units::Pixels, Skeleton::generic(1)).unwrap();
//! let program = Program::synthesize(&track, &SynthParams::default()).unwrap();
//! let text = program.to_dsl();
//! assert_eq!(Program::from_dsl(&text).unwrap(), program);
//! ```

mod dp;
mod dsl;
mod error;
mod exec;
mod inbetween;
mod program;
mod search;
mod smooth;
mod stats;
mod synth;
mod synthetic;

pub use dp::{CostTable, Segmentation};
pub use dsl::lex;
pub use dsl::{axis_name, NumberFormat};
pub use error::{ConcreteError, ParseError};
pub use exec::{ExecParams, Transition};
pub use inbetween::{InBetween, InBetweenPoses, Tangents};
pub use program::{Program, Segment};
pub use search::SearchStats;
pub use smooth::{Continuity, RefitNorm};
pub use stats::ProgramStats;
pub use synth::{Lambda, Scale, SynthParams, Synthesis, UnobservedJoints};
pub use synthetic::synthetic_track;

#[cfg(test)]
mod tests;
