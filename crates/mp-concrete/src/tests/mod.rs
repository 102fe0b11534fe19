//! Tests of the crate's parts: the segmentation, the notation, execution, smoothing, the binary form and the bounds.

mod binary;
mod dp;
mod dsl;
mod exec_bounds;
mod fuzz_regressions;
mod params_validation;
mod penn_action;
mod search;
mod smooth;
mod synth;
