//! `mp grammar learn` (sentences of a symbol string, then their grammar) and
//! `mp grammar learn-strings` (a grammar of given sentences), both with ABL.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};
use mp_grammar::PartitionParams;
use mp_grammar::{learn, AblParams, Alignment, Clustering, Corpus, Selection};
use mp_grammar::{learn_grammar, SymbolsFile};

/// ABL alignment flag.
#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum AlignFlag {
    /// Edit distance.
    Wm,
    /// Biased edit distance.
    Wb,
    /// Suffix tree, suffixes.
    St1,
    /// Suffix tree, prefixes.
    St2,
    /// Suffix tree, both (the paper's choice).
    St3,
    /// Suffix tree, all begin × end pairs.
    St4,
}

/// ABL selection.
#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum SelectFlag {
    /// Best-scoring combination (the paper's choice).
    Branch,
    /// Earlier hypotheses win.
    First,
}

/// ABL clustering of labels into nonterminals.
#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum ClusterFlag {
    /// Labels sharing a span merged transitively, then nonterminals with identical rules merged.
    Equivalence,
    /// One pass, first mapping wins (the reference description).
    FirstMapping,
}

/// ABL options shared by `learn` and `learn-strings`.
#[derive(Args, Debug, Clone)]
pub struct AblOpts {
    /// Alignment method.
    #[arg(long, value_enum, default_value = AblParams::default().alignment.flag())]
    pub alignment: AlignFlag,
    /// Selection method.
    #[arg(long, value_enum, default_value = AblParams::default().selection.as_str())]
    pub selection: SelectFlag,
    /// Clustering of labels into nonterminals.
    #[arg(long, value_enum, default_value = AblParams::default().clustering.as_str())]
    pub clustering: ClusterFlag,
}

impl AblOpts {
    /// ABL's parameters with these options and `seed`.
    fn params(&self, seed: u64) -> anyhow::Result<AblParams> {
        let flag = match self.alignment {
            AlignFlag::Wm => "wm",
            AlignFlag::Wb => "wb",
            AlignFlag::St1 => "st1",
            AlignFlag::St2 => "st2",
            AlignFlag::St3 => "st3",
            AlignFlag::St4 => "st4",
        };
        Ok(AblParams {
            alignment: Alignment::from_flag(flag)?,
            selection: match self.selection {
                SelectFlag::Branch => Selection::Branch,
                SelectFlag::First => Selection::First,
            },
            clustering: match self.clustering {
                ClusterFlag::Equivalence => Clustering::Equivalence,
                ClusterFlag::FirstMapping => Clustering::FirstMapping,
            },
            seed,
        })
    }
}

/// Arguments of `mp grammar learn`.
#[derive(Args, Debug)]
pub struct LearnArgs {
    /// Symbols JSON written by `mp grammar symbols`.
    pub symbols: PathBuf,
    /// Output grammar JSON.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Random candidate partitions scored by description length.
    #[arg(long, default_value_t = PartitionParams::default().candidates)]
    pub candidates: usize,
    /// Shortest sentence, symbols.
    #[arg(long, default_value_t = PartitionParams::default().min_sentence_len)]
    pub min_sentence_len: usize,
    /// Preferred longest sentence, symbols.
    #[arg(long, default_value_t = PartitionParams::default().max_sentence_len)]
    pub max_sentence_len: usize,
    /// Also score the whole string as one sentence (a grammar that can only reproduce it).
    #[arg(long)]
    pub include_whole_string: bool,
    /// Seed of the partition search.
    #[arg(long, default_value_t = PartitionParams::default().seed)]
    pub seed: u64,
    #[command(flatten)]
    pub abl: AblOpts,
}

/// Arguments of `mp grammar learn-strings`.
#[derive(Args, Debug)]
pub struct LearnStringsArgs {
    /// Text file: one sentence per line, symbols separated by whitespace.
    pub file: PathBuf,
    /// Also write the grammar, trees and description length as JSON.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Seed of ABL's tie-breaking.
    #[arg(long, default_value_t = AblParams::default().seed)]
    pub seed: u64,
    #[command(flatten)]
    pub abl: AblOpts,
}

/// Runs `mp grammar learn`.
pub fn learn_cmd(a: &LearnArgs) -> anyhow::Result<()> {
    let s = SymbolsFile::load(&a.symbols)?;
    let mut p = PartitionParams {
        candidates: a.candidates,
        min_sentence_len: a.min_sentence_len,
        max_sentence_len: a.max_sentence_len,
        abl: a.abl.params(a.seed)?,
        seed: a.seed,
        ..Default::default()
    };
    if a.include_whole_string {
        p.include_whole_string = true;
    }
    let m = learn_grammar(&s, &p)?;
    m.save(&a.output)
        .with_context(|| format!("writing {}", a.output.display()))?;
    print!("{}", m.rules_text());
    eprintln!("wrote {}", a.output.display());
    Ok(())
}

/// Runs `mp grammar learn-strings`.
pub fn learn_strings_cmd(a: &LearnStringsArgs) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(&a.file)
        .with_context(|| format!("reading {}", a.file.display()))?;
    let corpus = Corpus::from_lines(&text).with_context(|| a.file.display().to_string())?;
    let r = learn(&corpus.sentences, &corpus.vocab, &a.abl.params(a.seed)?)?;
    let dl = r.description_length();
    print!("{}", r.grammar);
    println!(
        "# {} sentences: {} nonterminals, {} rules, DL = {:.2} bits (grammar {:.2} + sentences {:.2})",
        corpus.sentences.len(),
        r.grammar.n_nonterminals(),
        r.grammar.n_rules(),
        dl.total_bits,
        dl.grammar_bits,
        dl.data_bits
    );
    if let Some(out) = &a.output {
        let v = serde_json::json!({
            "format": "mp-grammar-abl/1",
            "grammar": r.grammar,
            "rules_text": r.grammar.to_string(),
            "n_nonterminals": r.grammar.n_nonterminals(),
            "n_rules": r.grammar.n_rules(),
            "description_length": dl,
            "stats": r.stats,
            "trees": r.trees,
        });
        mp_geom::write_atomic(out, serde_json::to_string_pretty(&v)?.as_bytes())?;
        eprintln!("wrote {}", out.display());
    }
    Ok(())
}
