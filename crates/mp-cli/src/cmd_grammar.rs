//! `mp grammar …`: terminal symbols, grammar learning and grammar-driven
//! synthesis (Park, Lee & Lee 2011) from the command line.

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::{Args, Subcommand, ValueEnum};
use mp_geom::io::write_track;
use mp_grammar::abl::{learn, AblParams, Alignment, Corpus, Selection};
use mp_grammar::data::read_motions;
use mp_grammar::model::{find_symbols, learn_grammar, GrammarModel, SymbolsFile};
use mp_grammar::sentences::PartitionParams;
use mp_grammar::synth::{FirstSegment, StitchParams, Synthesis};
use mp_grammar::{
    symbol_name, DeriveParams, Fsm, FsmWeighting, PoseDistanceParams, RuleWeighting, SymbolParams,
};

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
}

/// Arguments of `mp grammar`.
#[derive(Args, Debug)]
pub struct GrammarArgs {
    #[command(subcommand)]
    pub command: GrammarCmd,
}

/// Arguments of `mp grammar symbols`.
#[derive(Args, Debug)]
pub struct SymbolsArgs {
    /// Motion: a track file, a BVH file, several of them (joined in order) or a folder of BVH files.
    #[arg(required = true)]
    pub track: Vec<PathBuf>,
    /// Number of symbols K.
    #[arg(long, default_value_t = 20)]
    pub k: usize,
    /// Output JSON.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Keep every N-th frame of the input (e.g. 4: 120 fps BVH → 30 fps).
    #[arg(long, default_value_t = 1)]
    pub frame_step: usize,
    /// Seed of the search.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// GA population.
    #[arg(long, default_value_t = 100)]
    pub population: usize,
    /// GA generations (at most).
    #[arg(long, default_value_t = 500)]
    pub generations: usize,
    /// SA iterations over which the step shrinks.
    #[arg(long, default_value_t = 1000)]
    pub sa_iterations: usize,
    /// Spacing of the GA's candidate cuts, frames.
    #[arg(long, default_value_t = 30)]
    pub candidate_step_frames: usize,
    /// Shortest segment, frames.
    #[arg(long, default_value_t = 10)]
    pub min_segment_frames: usize,
    /// Longest segment, frames.
    #[arg(long, default_value_t = 240)]
    pub max_segment_frames: usize,
    /// Weight ω of repetitiveness R against clarity E′.
    #[arg(long, default_value_t = 0.5)]
    pub omega: f64,
}

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

/// ABL options shared by `learn` and `learn-strings`.
#[derive(Args, Debug, Clone)]
pub struct AblOpts {
    /// Alignment method.
    #[arg(long, value_enum, default_value_t = AlignFlag::St3)]
    pub alignment: AlignFlag,
    /// Selection method.
    #[arg(long, value_enum, default_value_t = SelectFlag::Branch)]
    pub selection: SelectFlag,
}

impl AblOpts {
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
    #[arg(long, default_value_t = 200)]
    pub candidates: usize,
    /// Shortest sentence, symbols.
    #[arg(long, default_value_t = 3)]
    pub min_sentence_len: usize,
    /// Preferred longest sentence, symbols.
    #[arg(long, default_value_t = 12)]
    pub max_sentence_len: usize,
    /// Also score the whole string as one sentence (a grammar that can only reproduce it).
    #[arg(long)]
    pub include_whole_string: bool,
    /// Seed of the partition search.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub abl: AblOpts,
}

/// Arguments of `mp grammar synth`.
#[derive(Args, Debug)]
pub struct SynthArgs {
    /// Grammar JSON written by `mp grammar learn`.
    pub grammar: PathBuf,
    /// Seed of the derivation and of the first segment.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output motion: `.bvh` (BVH sources only), or a track (`.npz`, `.json`, `.csv`).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Source motion files (default: the paths stored in the grammar).
    #[arg(long, num_args = 1..)]
    pub source: Option<Vec<PathBuf>>,
    /// Derive sentences until there are at least this many segments.
    #[arg(long, default_value_t = 20)]
    pub segments: usize,
    /// Deepest nonterminal nesting of a derivation.
    #[arg(long, default_value_t = 12)]
    pub max_depth: usize,
    /// Choose rules in proportion to their training counts (default: uniformly, as in the paper).
    #[arg(long)]
    pub weighted: bool,
    /// Cross-fade length at each seam, frames (0 = none).
    #[arg(long, default_value_t = 8)]
    pub blend_frames: usize,
    /// Use the first-order finite-state machine over the symbols instead of the grammar.
    #[arg(long)]
    pub fsm: bool,
    /// Then derive anew the subtree that produced this terminal (0-based), as in the authoring interface.
    #[arg(long)]
    pub regenerate: Option<usize>,
    /// Levels above the terminal's parent to regenerate from.
    #[arg(long, default_value_t = 0)]
    pub levels: usize,
    /// Seed of the regeneration (default: seed + 1).
    #[arg(long)]
    pub regenerate_seed: Option<u64>,
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
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub abl: AblOpts,
}

/// Runs `mp grammar …`.
pub fn grammar_cmd(a: &GrammarArgs) -> anyhow::Result<()> {
    match &a.command {
        GrammarCmd::Symbols(x) => symbols_cmd(x),
        GrammarCmd::Learn(x) => learn_cmd(x),
        GrammarCmd::Synth(x) => synth_cmd(x),
        GrammarCmd::LearnStrings(x) => learn_strings_cmd(x),
    }
}

fn symbols_cmd(a: &SymbolsArgs) -> anyhow::Result<()> {
    let motion = read_motions(&a.track, a.frame_step)?;
    let mut p = SymbolParams {
        k: a.k,
        omega: a.omega,
        candidate_step_frames: a.candidate_step_frames,
        min_segment_frames: a.min_segment_frames,
        max_segment_frames: a.max_segment_frames,
        seed: a.seed,
        ..Default::default()
    };
    p.ga.population = a.population;
    p.ga.generations = a.generations;
    p.sa.iterations = a.sa_iterations;
    p.sa.max_iterations = p.sa.max_iterations.max(a.sa_iterations);
    let s = find_symbols(&motion, &PoseDistanceParams::default(), &p)?;
    s.save(&a.output)
        .with_context(|| format!("writing {}", a.output.display()))?;
    println!("{}", s.text);
    eprintln!(
        "{} frames at {:.1} fps → {} segments, K = {}; F = {:.4} (R {:.4}, E' {:.4}); {:.1} s; wrote {}",
        s.symbols.n_frames,
        s.symbols.fps,
        s.symbols.segments.len(),
        s.symbols.k,
        s.symbols.quality.f,
        s.symbols.quality.r,
        s.symbols.quality.e_prime,
        s.seconds,
        a.output.display()
    );
    Ok(())
}

fn learn_cmd(a: &LearnArgs) -> anyhow::Result<()> {
    let s = SymbolsFile::load(&a.symbols)?;
    let p = PartitionParams {
        candidates: a.candidates,
        min_sentence_len: a.min_sentence_len,
        max_sentence_len: a.max_sentence_len,
        include_whole_string: a.include_whole_string,
        abl: a.abl.params(a.seed)?,
        seed: a.seed,
        ..Default::default()
    };
    let m = learn_grammar(&s, &p)?;
    m.save(&a.output)
        .with_context(|| format!("writing {}", a.output.display()))?;
    print!("{}", m.rules_text());
    eprintln!("wrote {}", a.output.display());
    Ok(())
}

fn print_synthesis(label: &str, s: &Synthesis, seams: &[f64]) {
    let text: Vec<String> = s.symbols.iter().map(|&k| symbol_name(k)).collect();
    let mean = if seams.is_empty() {
        0.0
    } else {
        seams.iter().sum::<f64>() / seams.len() as f64
    };
    println!("{label}: {}", text.join(" "));
    eprintln!(
        "{label}: {} segments, {} frames, mean seam pose distance {mean:.4}",
        s.pieces.len(),
        s.n_frames()
    );
}

fn synth_cmd(a: &SynthArgs) -> anyhow::Result<()> {
    let m = GrammarModel::load(&a.grammar)?;
    let motion = m
        .source
        .load(a.source.as_deref())
        .context("reading the source motion (give it with --source)")?;
    let st = m.stitcher(
        &motion,
        &StitchParams {
            blend_frames: a.blend_frames,
            first_segment: FirstSegment::Random,
            ..Default::default()
        },
    )?;
    let derive = DeriveParams {
        max_depth: a.max_depth,
        weighting: if a.weighted {
            RuleWeighting::Counts
        } else {
            RuleWeighting::Uniform
        },
        ..Default::default()
    };
    let mut s = if a.fsm {
        let train: Vec<u32> = m.training_string().iter().map(|&x| x as u32).collect();
        let fsm = Fsm::from_symbols(&train, m.symbols.k, FsmWeighting::Counts)?;
        st.synthesize_fsm(&fsm, a.segments, a.seed)?
    } else {
        st.synthesize(&m.grammar, &derive, a.segments, a.seed)?
    };
    print_synthesis(
        if a.fsm { "fsm" } else { "grammar" },
        &s,
        &st.seam_distances(&s)?,
    );
    if let Some(t) = a.regenerate {
        if a.fsm {
            bail!("--regenerate needs a grammar derivation (not --fsm)");
        }
        let seed = a.regenerate_seed.unwrap_or(a.seed.wrapping_add(1));
        let r = st.regenerate(&m.grammar, &s, t, a.levels, &derive, seed)?;
        eprintln!(
            "regenerated {} (terminals {}..{} → {}..{}), frames {}..{} → {}..{}",
            m.grammar
                .nonterminals
                .get(r.regeneration.ancestor.nonterminal as usize)
                .map(String::as_str)
                .unwrap_or("?"),
            r.regeneration.ancestor.terminals.start,
            r.regeneration.ancestor.terminals.end,
            r.regeneration.new_terminals.start,
            r.regeneration.new_terminals.end,
            r.old_frames.start,
            r.old_frames.end,
            r.new_frames.start,
            r.new_frames.end
        );
        s = r.synthesis;
        print_synthesis("regenerated", &s, &st.seam_distances(&s)?);
    }
    let is_bvh = a
        .output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"));
    if is_bvh {
        let Some(b) = &s.bvh else {
            bail!(
                "{}: BVH output needs a BVH source motion (this grammar was learned on {:?})",
                a.output.display(),
                m.source.kind
            );
        };
        b.write_bvh(&a.output)?;
    } else {
        write_track(&a.output, &s.track)?;
    }
    eprintln!("wrote {}", a.output.display());
    Ok(())
}

fn learn_strings_cmd(a: &LearnStringsArgs) -> anyhow::Result<()> {
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
        mp_geom::io::write_atomic(out, serde_json::to_string_pretty(&v)?.as_bytes())?;
        eprintln!("wrote {}", out.display());
    }
    Ok(())
}
