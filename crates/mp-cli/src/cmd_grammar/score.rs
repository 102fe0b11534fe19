//! `mp grammar score MODEL SYMBOLS`: code length of a symbol string under a
//! learned grammar, the first-order FSM and a unigram model.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use mp_grammar::GrammarModel;
use mp_grammar::{load_symbol_string, ScoreParams};

/// Arguments of `mp grammar score`.
#[derive(Args, Debug)]
pub struct ScoreArgs {
    /// Grammar model JSON written by `mp grammar learn`.
    pub model: PathBuf,
    /// Symbol string: a symbols JSON (`mp grammar symbols --model MODEL`) or a text file of symbol names.
    pub symbols: PathBuf,
    /// Additive smoothing α of every count table (grammar rules, FSM transitions, unigram).
    #[arg(long, default_value_t = ScoreParams::default().alpha)]
    pub alpha: f64,
    /// Longest sentence a grammar parse may cover, symbols.
    #[arg(long, default_value_t = ScoreParams::default().max_sentence_len)]
    pub max_sentence_len: usize,
    /// Also write the scores and the parse as JSON.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Runs `mp grammar score`.
pub fn score_cmd(a: &ScoreArgs) -> anyhow::Result<()> {
    let m = GrammarModel::load_checked(&a.model)?;
    let string = load_symbol_string(&a.symbols, &m.grammar)?;
    let p = ScoreParams {
        alpha: a.alpha,
        max_sentence_len: a.max_sentence_len,
    };
    let s = m.score(&string, &p)?;
    println!("{}", s.parse_text(&m.grammar));
    println!(
        "# {} symbols ({} in derived sentences); bits per symbol: grammar {:.3}, FSM {:.3}, unigram {:.3} \
         (total bits {:.1}, {:.1}, {:.1})",
        string.len(),
        s.symbols_in_sentences,
        s.grammar.bits_per_symbol,
        s.fsm.bits_per_symbol,
        s.unigram.bits_per_symbol,
        s.grammar.bits,
        s.fsm.bits,
        s.unigram.bits
    );
    if let Some(out) = &a.output {
        let v = serde_json::json!({
            "format": "mp-grammar-score/1",
            "model": a.model,
            "symbols": a.symbols,
            "parse_text": s.parse_text(&m.grammar),
            "score": s,
        });
        mp_geom::write_atomic(out, serde_json::to_string_pretty(&v)?.as_bytes())
            .with_context(|| format!("writing {}", out.display()))?;
        eprintln!("wrote {}", out.display());
    }
    Ok(())
}
