//! # mp-grammar — motion grammars
//!
//! Park, Lee & Lee (2011), "Finding syntactic structures from human motion
//! data": identify terminal symbols in a motion, learn a context-free grammar
//! over the symbol string, and synthesise new motion from the grammar.
//!
//! The steps, each in its own module of the source:
//!
//! * `distance`: pose distance and segment distance (eq. 1), [`PoseFeatures`].
//! * `kmedoids`: PAM and FasterPAM from given initial medoids.
//! * `objective`, `symbols`: the segmentation objective ([`ClusterQuality`])
//!   and the GA + SA search for terminal symbols (§4), [`identify_symbols`].
//! * `strings`, `sentences`: repeats (suffix array) and the MDL search for a
//!   partition of the symbol string into sentences (§5), [`search_partition`].
//! * `abl`, `grammar`: grammar induction ([`learn`]), grammars and their
//!   description length ([`Grammar`]).
//! * `derive`, `synth`: random derivation ([`derive`](crate::derive())), the
//!   finite-state-machine baseline ([`Fsm`]), greedy segment selection,
//!   stitching and subtree regeneration (§6), [`Stitcher`].
//! * `model`, `data`: the whole pipeline as JSON files ([`learn_model`],
//!   [`GrammarModel`]), and motion input ([`read_motions`]).
//!
//! ```no_run
//! use mp_grammar::{learn_model, Motion, PipelineParams};
//! use mp_geom::{perform, PerformerParams};
//!
//! // Symbols (PAM, genetic search, annealing), sentences and an ABL grammar of
//! // the procedural performer, with the product's parameters (`mp grammar`).
//! let track = perform(&PerformerParams::default())?.track_2d;
//! let motion = Motion { track, bvh: None, paths: Vec::new(), frame_step: 1 };
//! let model = learn_model(&motion, &PipelineParams::default())?;
//! println!("{} rules", model.grammar.rules.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod abl;
mod assign;
mod data;
mod derive;
mod distance;
mod error;
mod grammar;
mod kmedoids;
mod model;
mod objective;
mod score;
mod sentences;
mod strings;
mod symbols;
mod synth;

pub use abl::{learn, AblParams, AblResult, Alignment, Clustering, Corpus, Selection};
pub use assign::load_learned_symbols;
pub use data::{
    bvh_files, concat_tracks, read_motions, salsa_track, subsample_bvh, Motion, DEFAULT_FRAME_STEP,
};
pub use derive::{
    derive, derive_at_least, regenerate, Derivation, DeriveParams, Fsm, FsmWeighting, RuleWeighting,
};
pub use distance::{FrameSpan, PoseDistanceParams, PoseFeatures, RootMode};
pub use error::GrammarError;
pub use grammar::{DescriptionLength, Grammar, Rule, Sym, Tree};
pub use model::{
    find_symbols, learn_grammar, learn_model, GrammarModel, PipelineParams, SourceInfo, SourceKind,
    SymbolsFile,
};
pub use objective::ClusterQuality;
pub use score::{load_symbol_string, ScoreParams};
pub use sentences::{score_partition, search_partition, PartitionParams};
pub use symbols::{
    identify_symbols, symbol_name, GaParams, SaParams, SymbolParams, SymbolSearchStats,
    SymbolSegment, SymbolString,
};
pub use synth::{RootAlignment, StitchParams, Stitcher, SynthesizedMotion};

/// Not part of the API: the string algorithms the fuzz targets call directly.
#[doc(hidden)]
pub mod fuzzing {
    pub use crate::strings::{
        allowed_cuts, lcp_array, protected_spans, repeat_classes, suffix_array,
    };
}

#[cfg(test)]
mod tests;
