//! `mp grammar symbols`: K terminal symbols of a motion (GA + SA), or, with
//! `--model`, the learned symbols of a model assigned to a new motion.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use mp_grammar::find_symbols;
use mp_grammar::load_learned_symbols;
use mp_grammar::{read_motions, DEFAULT_FRAME_STEP};
use mp_grammar::{PoseDistanceParams, SymbolParams};

/// Arguments of `mp grammar symbols`.
#[derive(Args, Debug)]
pub struct SymbolsArgs {
    /// Motion: a track file, a BVH file, several of them (joined in order) or a folder of BVH files.
    #[arg(required = true)]
    pub track: Vec<PathBuf>,
    /// Number of symbols K.
    #[arg(long, default_value_t = SymbolParams::default().k)]
    pub k: usize,
    /// Output JSON.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Assign the symbols learned in this file (a grammar model or a symbols JSON) to the motion
    /// instead of searching: segments on the learned cut grid, each labelled with the nearest
    /// learned medoid. The frame step, distance and segment lengths are the learned ones; the
    /// search options below are not used.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Keep every N-th frame of the input (e.g. 4: 120 fps BVH → 30 fps).
    #[arg(long, default_value_t = DEFAULT_FRAME_STEP)]
    pub frame_step: usize,
    /// Seed of the search.
    #[arg(long, default_value_t = SymbolParams::default().seed)]
    pub seed: u64,
    /// GA population.
    #[arg(long, default_value_t = SymbolParams::default().ga.population)]
    pub population: usize,
    /// GA generations (at most).
    #[arg(long, default_value_t = SymbolParams::default().ga.generations)]
    pub generations: usize,
    /// SA iterations over which the step shrinks.
    #[arg(long, default_value_t = SymbolParams::default().sa.iterations)]
    pub sa_iterations: usize,
    /// Spacing of the GA's candidate cuts, frames.
    #[arg(long, default_value_t = SymbolParams::default().candidate_step_frames)]
    pub candidate_step_frames: usize,
    /// Shortest segment, frames.
    #[arg(long, default_value_t = SymbolParams::default().min_segment_frames)]
    pub min_segment_frames: usize,
    /// Longest segment, frames.
    #[arg(long, default_value_t = SymbolParams::default().max_segment_frames)]
    pub max_segment_frames: usize,
    /// Weight ω of repetitiveness R against clarity E′.
    #[arg(long, default_value_t = SymbolParams::default().omega)]
    pub omega: f64,
}

/// Runs `mp grammar symbols`.
pub fn symbols_cmd(a: &SymbolsArgs) -> anyhow::Result<()> {
    if let Some(model) = &a.model {
        return assign_cmd(a, model);
    }
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

/// `mp grammar symbols --model FILE`: learned symbols on a new motion.
fn assign_cmd(a: &SymbolsArgs, model: &std::path::Path) -> anyhow::Result<()> {
    let learned = load_learned_symbols(model)?;
    let train = learned.source.load(None).with_context(|| {
        format!(
            "reading the motion the symbols of {} were found on",
            model.display()
        )
    })?;
    let motion = read_motions(&a.track, learned.source.frame_step)?;
    let s = learned.assign(&train, &motion)?;
    s.save(&a.output)
        .with_context(|| format!("writing {}", a.output.display()))?;
    println!("{}", s.text);
    eprintln!(
        "{} frames at {:.1} fps → {} segments over the K = {} symbols of {}; E' {:.4}; {:.1} s; wrote {}",
        s.symbols.n_frames,
        s.symbols.fps,
        s.symbols.segments.len(),
        s.symbols.k,
        model.display(),
        s.symbols.quality.e_prime,
        s.seconds,
        a.output.display()
    );
    Ok(())
}
