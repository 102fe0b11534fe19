//! Build plumbing, no code: see this crate's `Cargo.toml`. The packages that are built on their
//! own (the set-up tool `xtask`, the Python extension `mp-py`, the `mp` binary) depend on it, so
//! that they resolve the same dependency features as `cargo test --workspace` and their builds
//! share the compiled dependencies.
