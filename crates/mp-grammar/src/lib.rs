//! # mp-grammar — motion grammars
//!
//! Park, Lee & Lee (2011), "Finding syntactic structures from human motion
//! data": identify terminal symbols in a motion, learn a context-free grammar
//! over the symbol string, and synthesise new motion from the grammar.
//!
//! * [`distance`]: pose distance and segment distance (eq. 1).
//! * [`kmedoids`]: PAM and FasterPAM from given initial medoids.

pub mod data;
pub mod distance;
pub mod error;
pub mod kmedoids;

pub use distance::{PoseDistanceParams, PoseFeatures, RootMode, Segment};
pub use error::{GrammarError, Result};
pub mod objective;
pub mod symbols;

pub use objective::ClusterQuality;
pub use symbols::{identify_symbols, symbol_name, SymbolParams, SymbolSegment, SymbolString};
pub mod abl;
pub mod grammar;
pub mod sentences;
pub mod sequitur;
pub mod strings;

pub use abl::{AblParams, AblResult, Alignment, Corpus, Selection};
pub use grammar::{DescriptionLength, Grammar, Rule, Sym, Tree};
