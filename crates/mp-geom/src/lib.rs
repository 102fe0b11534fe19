//! # mp-geom — the shared vocabulary of motion programs
//!
//! * [`Track`]: `T × J × D` joint positions (pixels or metres) with per-joint
//!   confidence, a frame rate and a [`Skeleton`].
//! * `skeleton`: COCO-17, BlazePose-33, Penn Action-13, MSR Action3D-20 and
//!   BVH hierarchies as data, with bones and the mapping to COCO-17;
//!   `skeleton_map`: mappings between skeletons (COCO-17 / BlazePose-33 →
//!   Penn-13, BlazePose-33 world landmarks → MSR-20) and back.
//! * [`People`]: several tracked people in one video (a [`Person`] per
//!   steady id, each with a [`Track`] over their span), and the main person.
//! * `io`: readers for the data sets and common keypoint formats, writers
//!   for the project's own npz + JSON formats (of a track or of people).
//! * `fit`: primitive fitting (stationary, line, circle, cubic spline) in 2D
//!   and 3D; each fit reports its error and executes at fractional time.
//! * `metrics`: KD, PCK, MPJPE, PA-MPJPE, DTW, max adjacent-frame jump.
//! * `performer`: a procedurally generated performer (jumping jacks,
//!   squats, arm circles, golf swing) with ground-truth repetitions.
//! * `cancel`: a [`CancelToken`] that long runs check between steps.
//!
//! ```
//! use mp_geom::{fit_best, FitParams};
//! use mp_geom::{perform, PerformerParams};
//!
//! // The procedural performer (COCO-17, pixels) and the best primitive of its
//! // right wrist over the first second, with the product's fitting rules.
//! let track = perform(&PerformerParams::default())?.track_2d;
//! assert_eq!(track.skeleton().name, "coco17");
//! let wrist = track.skeleton().joints.iter().position(|j| j == "right_wrist").unwrap();
//! let first_second = track.positions().slice(ndarray::s![0..30, wrist, ..]).to_owned();
//! let fit = fit_best(first_second.view(), None, &FitParams::default())?;
//! println!("{} with error {:.1} px", fit.primitive.kind().as_str(), fit.error);
//! # Ok::<(), mp_geom::GeomError>(())
//! ```

mod cancel;
mod checked;
mod error;
mod fit;
mod io;
mod lanes;
mod metrics;
mod paths;
mod people;
mod performer;
mod primitive;
mod skeleton;
mod skeleton_map;
mod stats;
/// Not part of the API: helpers for the workspace's tests.
#[doc(hidden)]
pub mod test_support;
mod track;

pub use cancel::CancelToken;
pub use error::GeomError;
pub use people::{People, Person, PersonId};
pub use primitive::{Primitive, PrimitiveKind};
pub use skeleton::Skeleton;
pub use track::{fps_label, frames_label, Track, Units};

pub use checked::{Checked, Validate};
pub use fit::atan::{atan2_into, atan2_lanes};
pub use fit::prefix::PrefixFits;
pub use fit::{
    bullock_from_sums, bullock_terms, fit_best, fit_best_checked, fit_circle, fit_kind, fit_line,
    fit_spline, fit_stationary, residual_error, unwrap_degrees, ErrorNorm, Fit, FitParams,
};
pub use io::binary;
pub use io::bvh::{Bvh, BvhTrackParams};
pub use io::datasets::{
    msr_action_name, AistPlusPlus, CmuFeatures, MediaPipeReference, MsrAction3D, MsrClip,
    PennAction,
};
pub use io::native::{track_from_bincode, track_to_bincode, track_to_npz_bytes_framed};
pub use io::npz::{read_npy, Npz, NpzOut};
pub use io::people::{people_from_bincode, people_to_bincode};
pub use io::{
    abandon_partial_writes, holds_people, needs_3d, people_to_npz_bytes_framed, read_people,
    read_track, read_track_rated, write_atomic, write_people, write_people_framed, write_track,
    write_track_framed, PartialFile, RateSource, ReadOptions, TrackRead, DEFAULT_FPS,
    TRACK_EXTENSIONS,
};
pub use lanes::{has_avx2, Arith, Avx2, F64x4, Portable};
pub use metrics::{
    dtw, dtw_align, kd, max_adjacent_jump, mpjpe, mpjpe_per_frame, nanmean, pa_mpjpe,
    pa_mpjpe_per_frame, pck, pck_per_frame_sized, Aligned, DtwCost, DtwResult, PckParams, Poses,
};
pub use paths::{data_dir, data_file, footage_file, shared_dir, workspace_root};
pub use performer::{perform, Move, Performance, PerformerParams};
pub use skeleton::BLAZEPOSE_TO_COCO17;
pub use skeleton_map::{FramePairing, SkeletonMap};
pub use stats::median;

pub use track::{bracket, MAX_FRAME_JOINTS};

/// Not part of the API: the format parsers the fuzz targets call directly.
#[doc(hidden)]
pub mod fuzzing {
    pub use crate::io::{bvh, csv, native, npz, openpose, people};
}

#[cfg(test)]
mod tests;
