//! Tests of the crate's parts: the notation, execution, loops, counting, intervals, self-match and bounds.

mod bounds;
mod count;
mod dsl_exec;
mod fuzz_regressions;
mod loops;
mod params_validation;
mod performer;
mod program_validation;
mod repetition;
mod selfmatch;
