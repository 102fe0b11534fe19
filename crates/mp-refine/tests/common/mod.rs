//! The shipped refinement networks and concepts (`models/refine`), as the tests load them.

use mp_refine::Concepts;
use mp_refine::RefineNets;

/// The networks and anchor concepts of `models/refine`.
pub fn shipped() -> (RefineNets, Concepts) {
    let dir = RefineNets::find_dir().expect("models/refine is part of the repository");
    let nets = RefineNets::load_default()
        .unwrap_or_else(|e| panic!("loading {}: {e} (run `cargo xtask setup`)", dir.display()));
    let concepts =
        mp_refine::read_concepts(&dir.join("concepts.json")).unwrap_or_else(|e| panic!("{e}"));
    (nets, concepts)
}
