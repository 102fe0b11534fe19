//! mp-refine
