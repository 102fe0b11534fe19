//! Tests of the crate's parts: fits, track formats, data sets, metrics, people and the performer.

mod fit_bad_input;
mod fit_circle_fit_protocol;
mod fit_prefix;
mod fit_real_data;
mod fit_recover;
mod fit_select;
mod fuzz_regressions;
mod io_binary;
mod io_bvh;
mod io_datasets;
mod io_exchange;
mod io_formats;
mod io_npz;
mod io_rate_and_frame;
mod metrics;
mod people;
mod performer;
