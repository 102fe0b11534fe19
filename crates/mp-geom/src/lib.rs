//! # mp-geom — the shared vocabulary of motion programs
//!
//! * [`Track`]: `T × J × D` joint positions (pixels or metres) with per-joint
//!   confidence, a frame rate and a [`Skeleton`].
//! * [`skeleton`]: COCO-17, BlazePose-33, Penn Action-13, MSR Action3D-20 and
//!   BVH hierarchies as data, with bones and the mapping to COCO-17;
//!   [`skeleton_map`]: mappings between skeletons (COCO-17 / BlazePose-33 →
//!   Penn-13, BlazePose-33 world landmarks → MSR-20) and back.
//! * [`People`]: several tracked people in one video (a [`Person`] per
//!   steady id, each with a [`Track`] over their span), and the main person.
//! * [`io`]: readers for the data sets and common keypoint formats, writers
//!   for the project's own npz + JSON formats (of a track or of people).
//! * [`fit`]: primitive fitting (stationary, line, circle, cubic spline) in 2D
//!   and 3D; each fit reports its error and executes at fractional time.
//! * [`metrics`]: KD, PCK, MPJPE, PA-MPJPE, DTW, max adjacent-frame jump.
//! * [`performer`]: a procedurally generated performer (jumping jacks,
//!   squats, arm circles, golf swing) with ground-truth repetitions.
//! * `cancel`: a [`CancelToken`] that long runs check between steps.
//!
//! ```
//! use mp_geom::fit::{fit_best, FitParams};
//! use mp_geom::performer::{perform, PerformerParams};
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
pub mod checked;
mod error;
pub mod fit;
pub mod io;
pub mod lanes;
pub mod metrics;
pub mod paths;
pub mod people;
pub mod performer;
mod primitive;
pub mod skeleton;
pub mod skeleton_map;
pub mod stats;
pub mod track;

pub use cancel::CancelToken;
pub use error::{GeomError, Result};
pub use people::{People, Person, PersonId};
pub use primitive::{Primitive, PrimitiveKind};
pub use skeleton::Skeleton;
pub use track::{fps_label, frames_label, Track, Units};
