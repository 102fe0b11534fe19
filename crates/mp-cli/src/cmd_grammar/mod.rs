//! `mp grammar …`: terminal symbols, grammar learning and grammar-driven
//! synthesis (Park, Lee & Lee 2011) from the command line.
//!
//! One module per step: [`symbols`] (also on new motion), [`learn`] (also
//! `learn-strings`), [`synth`] and [`score`] (code length of a held-out
//! symbol string).

mod learn;
mod score;
mod symbols;
mod synth;

use clap::{Args, Subcommand};

pub use learn::{LearnArgs, LearnStringsArgs};
pub use score::ScoreArgs;
pub use symbols::SymbolsArgs;
pub use synth::SynthArgs;

/// `mp grammar` subcommands.
#[derive(Subcommand, Debug)]
pub enum GrammarCmd {
    /// Find K terminal symbols in a motion (GA + SA); writes the symbol string and segments as JSON.
    Symbols(SymbolsArgs),
    /// Partition a symbol string into sentences (MDL) and learn their grammar (ABL); writes JSON.
    Learn(LearnArgs),
    /// Synthesise a motion from a learned grammar (or its finite-state-machine baseline).
    Synth(SynthArgs),
    /// Learn a grammar with ABL from sentences, one per line, symbols separated by spaces.
    LearnStrings(LearnStringsArgs),
    /// Code length (bits per symbol) of a symbol string under a learned grammar, its FSM and a unigram model.
    Score(ScoreArgs),
}

/// Arguments of `mp grammar`.
#[derive(Args, Debug)]
pub struct GrammarArgs {
    #[command(subcommand)]
    pub command: GrammarCmd,
}

/// Runs `mp grammar …`.
pub fn grammar_cmd(a: &GrammarArgs) -> anyhow::Result<()> {
    match &a.command {
        GrammarCmd::Symbols(x) => symbols::symbols_cmd(x),
        GrammarCmd::Learn(x) => learn::learn_cmd(x),
        GrammarCmd::Synth(x) => synth::synth_cmd(x),
        GrammarCmd::LearnStrings(x) => learn::learn_strings_cmd(x),
        GrammarCmd::Score(x) => score::score_cmd(x),
    }
}
