//! # mp-eval — the evaluations, training-set exports and model training of the workspace
//!
//! Everything here measures the product or prepares what it ships; nothing
//! here is linked into `mp`, the Python package or the library crates. Each
//! evaluation calls the same library function as the `mp` command that does
//! that job, with the defaults a user gets, and writes a JSON report (and
//! often a Markdown table, [`table`]). `cargo xtask` parses the arguments and
//! calls the `run` function of a module here.
//!
//! | `cargo xtask …` | module |
//! |---|---|
//! | `eval count` (labelled videos; `--synthetic`, `--synthetic-video`, `--long`) | [`count`], [`count_synth`], [`count_video`], [`count_long`], [`count_long_synth`] |
//! | `eval loops` (detection, counting, repetitive intervals, unrolling) | [`loops`], [`intervals`] |
//! | `eval people` | [`people`] |
//! | `eval grammar` | [`grammar`] |
//! | `eval concrete` | [`concrete`] |
//! | `eval pose`, `eval pose-rate` | [`pose`], [`pose_rate`] |
//! | `eval forecast` | [`forecast`] (the protocol: [`forecast::protocol`]) |
//! | `eval refine` (and its cross-validation) | [`refine`], [`refine_cv`] |
//! | `eval interpolation`, `eval video-predict` | [`video`] |
//! | `eval inbetween` | [`inbetween`] |
//! | `train-forecast`, `train-refine` | [`train_forecast`], [`train_refine`], [`train_refine_cv`] |
//!
//! The synthetic validation sets (repetitions of known count cut from real
//! motion and real videos) are built by [`synth_reps`], [`synth_select`],
//! [`synth_sources`] and [`synth_video`]; [`fit_confidence`] fits the
//! counter's confidence model on them. [`pyenv`] runs the Python side
//! (reference implementations, PyTorch training) in virtual environments
//! under `.cache/`.

pub mod concrete;
pub mod count;
pub mod count_long;
pub mod count_long_synth;
pub mod count_synth;
pub mod count_video;
pub mod fit_confidence;
pub mod forecast;
pub mod grammar;
pub mod inbetween;
pub mod intervals;
pub mod live;
pub mod loops;
pub mod people;
pub mod pose;
pub mod pose_rate;
pub mod pyenv;
pub mod refine;
pub mod refine_cv;
pub mod stats;
pub mod synth_reps;
pub mod synth_select;
pub mod synth_sources;
pub mod synth_video;
pub mod table;
pub mod train_forecast;
pub mod train_refine;
pub mod train_refine_cv;
pub mod video;

use std::path::Path;

/// The workspace's root folder ([`mp_geom::workspace_root`]), or an error
/// naming why it is unknown.
pub fn workspace_dir() -> anyhow::Result<std::path::PathBuf> {
    use anyhow::Context;
    mp_geom::workspace_root().context("the workspace root is unknown: build inside the workspace")
}

/// Writes a report or model file through a temporary file renamed into
/// place, so an interrupted task leaves the old file or the new one.
pub fn write_file(
    path: impl AsRef<Path>,
    bytes: impl AsRef<[u8]>,
) -> std::result::Result<(), mp_geom::GeomError> {
    mp_geom::write_atomic(path, bytes.as_ref())
}
