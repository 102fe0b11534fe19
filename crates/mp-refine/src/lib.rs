//! # mp-refine — refining 3D motion with learned motion concepts
//!
//! Foundations of the refinement framework of paper 004 ("Refine synthesized
//! action-conditioned 3D human motion with unsupervised learned motion
//! concepts"):
//!
//! * `segment`: spline DP segmentation of a joint sequence into anchors
//!   (junction frames, plus first and last) and transitions (one cubic spline
//!   per joint and axis), and reconstruction from anchors + splines.
//! * `concepts`: anchor concepts — anchor poses (root-relative, optionally
//!   scale-normalised) clustered per action (k-means by default, DBSCAN as an
//!   option) and a 2-component Gaussian mixture whose log-likelihood scores
//!   anchor quality.
//! * `flaws`: seeded injection of known flaws (wrong anchor pose, frozen
//!   frames, jitter, temporal jump, foot sliding) into clean motion, with the
//!   mask of the frames touched.
//! * `baseline`: a non-learned refinement — detect flawed frames (frozen
//!   runs, velocity/acceleration outliers, low-scoring anchors) and re-fit
//!   splines between the neighbouring good frames.
//! * `nets`, `learned`: the seven refinement networks (ONNX Runtime) and
//!   the learned refinement — a learned flaw detector (and a held-pose rule)
//!   whose flagged frames and joints are refilled in the input's own frames,
//!   then anchor recognition, GMM anchor scores, anchor repair (for
//!   generated motion, [`learned::NetRefineParams::for_generated`]: flawed
//!   anchors moved to their nearest concept), transition refinement.
//! * `mapped`: refinement of BlazePose-33 world landmarks through the 20
//!   MSR joints, carried back onto the input's joints.
//! * `refiner`: the [`Refiner`] trait that both refinements implement
//!   ([`learned::NetRefiner`], [`BaselineRefiner`]).
//! * `api`: [`refine_default`], the learned refinement in one call with
//!   the defaults of `mp refine` ([`RefineOptions`]: model folder, concepts,
//!   action, steps and thresholds).
//!
//! The evaluations (injected flaws, generated motion, ablations, quality
//! metrics, training-set export) are not part of this crate: they live in
//! the workspace's evaluation crate, `mp-eval`.
//!
//! ```no_run
//! use mp_refine::{refine_default, RefineOptions};
//!
//! // A 20-joint MSR Action3D track in metres (`mp extract --world` tracks are
//! // carried through `mapped`), refined with the shipped networks and concepts.
//! let track = mp_geom::read_track("clip_msr20.npz")?;
//! let refined = refine_default(&track, &RefineOptions::default())?;
//! refined.track.positions();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod api;
mod baseline;
mod concepts;
mod error;
mod flaws;
mod learned;
mod mapped;
mod motion;
mod nets;
mod refiner;
mod segment;

pub use api::{refine_default, RefineOptions};
pub use baseline::{refine, RefineParams, Refinement};
pub use concepts::{learn_concepts, ActionConcepts, ClusterMethod, ConceptParams, Concepts, Gmm};
pub use error::RefineError;
pub use flaws::{inject, Flaw, Injected};
pub use refiner::{BaselineRefiner, Refined, Refiner};
pub use segment::{
    mpjpe_abs, segment_track, segmentation_from_anchors, SegmentParams, Segmentation3d,
    SplineTransition,
};

pub use api::{read_concepts, read_input};
pub use baseline::full_confidence;
pub use concepts::{
    anchor_feature, canonical_anchor_samples, collect_anchors, msr_anchor_samples,
    msr_training_clips, AnchorSample, Linkage, HELD_OUT_SUBJECTS, MIN_CLIP_FRAMES,
};
pub use flaws::{foot_joints, AnchorSource, FootSlide};
pub use learned::{
    foot_contacts, foot_slide, nearest_concept_thresholds, AnchorDetection, AnchorRepair,
    FlawRepair, FootContactParams, NetRefineParams, NetRefiner, RefineMode, TransitionMethod,
    TransitionReason,
};
pub use mapped::MappedRefinement;
pub use motion::{
    bvh_to_msr20, canonical_mask, canonicalize, changed_joints, from_features, to_features,
    DEFAULT_BVH_LENGTH_SCALE, FRAME_FEATURES, HIP_CENTRE, MSR_JOINTS, NET_FRAMES,
};
pub use nets::{generate_clips, read_manifest, RefineNets, N_ACTIONS};
pub use segment::per_frame_error;

pub use mapped::refine_any;
pub use motion::resample;
pub use nets::NetKind;

#[cfg(test)]
mod tests;
