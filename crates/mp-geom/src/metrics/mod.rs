//! Pose-sequence metrics: KD, PCK, MPJPE, PA-MPJPE, DTW and the largest
//! adjacent-frame jump.
//!
//! Every metric works on [`Poses`]: a `T × J × D` view of positions with an
//! optional `T × J` confidence (joint `j` of frame `t` is *valid* when its
//! confidence is > 0; no confidence means all valid). A
//! [`Track`](crate::Track) or a plain `ArrayView3` converts into [`Poses`]
//! with `.into()`, so every function accepts `&track`,
//! `Poses::new(positions, Some(conf))?` or `array.view()`.
//!
//! Conventions shared by all metrics:
//!
//! * Only joints valid in **both** sequences are compared (PCK: see [`pck`]).
//! * A valid joint with a non-finite coordinate is an error
//!   ([`GeomError::NonFinite`](crate::GeomError::NonFinite) naming the
//!   sequence, frame and joint); invalid joints are never read.
//! * Per-frame results hold `NaN` for frames that cannot be scored (too few
//!   valid joints); sequence results are the [`nanmean`] of per-frame results
//!   and are an error ([`GeomError::NoData`](crate::GeomError::NoData)) when
//!   no frame can be scored.
//! * Empty inputs (`T = 0` or `J = 0`) give
//!   [`GeomError::TooShort`](crate::GeomError::TooShort) /
//!   [`GeomError::NoData`](crate::GeomError::NoData); shapes that disagree
//!   give [`GeomError::Shape`](crate::GeomError::Shape).
//! * Distances are in the data's units (pixels or metres).
//!
//! Where they live: `poses` holds [`Poses`], the shared input checks and
//! [`nanmean`]; `distance` the per-joint distances (KD, MPJPE, the largest
//! adjacent-frame jump); `correct_keypoints` PCK; `similarity` Procrustes
//! alignment and PA-MPJPE; `time_warping` DTW and DTW alignment.

mod correct_keypoints;
mod distance;
mod poses;
mod similarity;
mod time_warping;

pub use correct_keypoints::{pck, pck_per_frame_sized, PckParams};
pub use distance::{kd, max_adjacent_jump, mpjpe, mpjpe_per_frame};
pub use poses::{nanmean, Poses};
pub use similarity::{pa_mpjpe, pa_mpjpe_per_frame};
pub use time_warping::{dtw, dtw_align, Aligned, DtwCost, DtwResult};

#[cfg(test)]
pub use correct_keypoints::{pck_per_frame, pck_with};
#[cfg(test)]
pub use distance::kd_per_frame;
#[cfg(test)]
pub use similarity::procrustes;
