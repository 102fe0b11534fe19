//! `mp grammar synth`: a motion synthesised from a learned grammar (or its
//! finite-state-machine baseline), with the authoring interface's
//! regeneration of one subtree.

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::Args;
use mp_geom::write_track;
use mp_grammar::GrammarModel;
use mp_grammar::{symbol_name, DeriveParams, Fsm, FsmWeighting, RuleWeighting, Stitcher};
use mp_grammar::{StitchParams, SynthesizedMotion};

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
    #[arg(long, default_value_t = Stitcher::DEFAULT_SEGMENTS)]
    pub segments: usize,
    /// Deepest nonterminal nesting of a derivation.
    #[arg(long, default_value_t = DeriveParams::default().max_depth)]
    pub max_depth: usize,
    /// Choose rules in proportion to their training counts (default: uniformly, as in the paper).
    #[arg(long)]
    pub weighted: bool,
    /// Cross-fade length at each seam, frames (0 = none).
    #[arg(long, default_value_t = StitchParams::default().blend_frames)]
    pub blend_frames: usize,
    /// Use the first-order finite-state machine over the symbols instead of the grammar.
    #[arg(long)]
    pub fsm: bool,
    /// Then derive anew the subtree that produced this terminal (0-based), as in the authoring interface.
    #[arg(long)]
    pub regenerate: Option<usize>,
    /// Levels above the terminal's parent to regenerate from.
    #[arg(long, default_value_t = Stitcher::DEFAULT_REGENERATE_LEVELS)]
    pub levels: usize,
    /// Seed of the regeneration (default: seed + 1).
    #[arg(long)]
    pub regenerate_seed: Option<u64>,
}

/// Prints a synthesis's symbols (stdout) and its size and mean seam
/// distance (stderr).
fn print_synthesis(label: &str, s: &SynthesizedMotion, seams: &[f64]) {
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

/// Runs `mp grammar synth`.
pub fn synth_cmd(a: &SynthArgs) -> anyhow::Result<()> {
    let m = GrammarModel::load(&a.grammar)?;
    let motion = m
        .source
        .load(a.source.as_deref())
        .context("reading the source motion (give it with --source)")?;
    let st = m.stitcher(
        &motion,
        &StitchParams {
            blend_frames: a.blend_frames,
            ..Default::default()
        },
    )?;
    let mut derive = DeriveParams {
        max_depth: a.max_depth,
        ..Default::default()
    };
    if a.weighted {
        derive.weighting = RuleWeighting::Counts;
    }
    let mut s = if a.fsm {
        let train: Vec<u32> = m.training_string().iter().map(|&x| x as u32).collect();
        let fsm = Fsm::from_symbols(&train, m.symbols.k, FsmWeighting::default())?;
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
