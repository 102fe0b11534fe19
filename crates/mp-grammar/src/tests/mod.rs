//! Tests of the crate's inner parts: the paper's vectors, the bounds on
//! every parameter and the k-medoids search against the kmedoids crate.

mod bounds;
mod kmedoids_crate;
mod paper_vectors;
