//! Tests of the crate's inner parts.

mod foot_contact;

/// The networks and anchor concepts of `models/refine`.
fn shipped() -> (crate::RefineNets, crate::Concepts) {
    let dir = crate::RefineNets::find_dir().expect("models/refine is part of the repository");
    let nets = crate::RefineNets::load_default()
        .unwrap_or_else(|e| panic!("loading {}: {e} (run `cargo xtask setup`)", dir.display()));
    let concepts =
        crate::read_concepts(&dir.join("concepts.json")).unwrap_or_else(|e| panic!("{e}"));
    (nets, concepts)
}
