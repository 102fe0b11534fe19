//! Build plumbing, no code: see this crate's `Cargo.toml`. The packages that are built on their
//! own (the set-up tool `xtask`, the Python extension `mp-py`, the `mp` binary) depend on it, and
//! every library crate has it as a dev-dependency, so that their builds and one crate's tests
//! resolve the same dependency features as `cargo test --workspace` and share the compiled
//! dependencies.
