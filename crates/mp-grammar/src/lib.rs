//! # mp-grammar — motion grammars
//!
//! Park, Lee & Lee (2011), "Finding syntactic structures from human motion
//! data": identify terminal symbols in a motion, learn a context-free grammar
//! over the symbol string, and synthesise new motion from the grammar.
//!
//! * `distance`: pose distance and segment distance (eq. 1).
//! * [`kmedoids`]: PAM and FasterPAM from given initial medoids.
//! * [`objective`], [`symbols`]: the segmentation objective and the GA + SA
//!   search for terminal symbols (§4).
//! * [`strings`], [`sentences`]: repeats (suffix array) and the MDL search
//!   for a partition of the symbol string into sentences (§5).
//! * [`abl`], [`grammar`], [`sequitur`]: grammar induction, grammars and
//!   their description length, and the single-string baseline.
//! * [`mod@derive`], [`synth`]: random derivation, the finite-state-machine
//!   baseline, greedy segment selection, stitching and subtree
//!   regeneration (§6).
//! * [`model`], [`data`]: the whole pipeline as JSON files, and motion input.
//!
//! ```no_run
//! use mp_grammar::data::Motion;
//! use mp_grammar::{learn_model, PipelineParams};
//! use mp_geom::performer::{perform, PerformerParams};
//!
//! // Symbols (PAM, genetic search, annealing), sentences and an ABL grammar of
//! // the procedural performer, with the product's parameters (`mp grammar`).
//! let track = perform(&PerformerParams::default())?.track_2d;
//! let motion = Motion { track, bvh: None, paths: Vec::new(), frame_step: 1 };
//! let model = learn_model(&motion, &PipelineParams::default())?;
//! println!("{} rules", model.grammar.rules.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod assign;
pub mod data;
mod distance;
mod error;
pub mod kmedoids;

pub use distance::{FrameSpan, PoseDistanceParams, PoseFeatures, RootMode};
pub use error::{GrammarError, Result};
pub mod objective;
pub mod symbols;

pub use objective::ClusterQuality;
pub use symbols::{identify_symbols, symbol_name, SymbolParams, SymbolSegment, SymbolString};
pub mod abl;
pub mod grammar;
pub mod score;
pub mod sentences;
pub mod sequitur;
pub mod strings;

pub use abl::{AblParams, AblResult, Alignment, Clustering, Corpus, Selection};
pub use grammar::{DescriptionLength, Grammar, Rule, Sym, Tree};
pub mod derive;
pub mod model;
pub mod synth;

pub use derive::{
    derive, derive_at_least, regenerate, Derivation, DeriveParams, Fsm, FsmWeighting, RuleWeighting,
};
pub use model::{
    find_symbols, learn_grammar, learn_model, GrammarModel, PipelineParams, SourceInfo, SourceKind,
    SymbolsFile,
};
pub use synth::{RootAlignment, StitchParams, Stitcher, Synthesis};
