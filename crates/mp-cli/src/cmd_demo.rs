//! `mp performer` (the procedural performer as a track) and `mp demo` (the
//! whole pipeline on it, the embedded default of the README).

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use mp_abstract::dsl::{print_with, PrintOptions};
use mp_abstract::{analyze, write_program, AbstractParams};
use mp_geom::io::{write_atomic, write_track};
use mp_geom::performer::{perform, PerformerParams};
use mp_geom::Track;

/// Arguments of `mp performer`.
#[derive(Args, Debug)]
pub struct PerformerArgs {
    /// Output track (`.npz`, `.json` or `.csv`).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write the 3D track (metres) instead of the 2D one (pixels).
    #[arg(long = "3d")]
    pub three_d: bool,
    /// Random seed of the repetition variation and noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// Arguments of `mp demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "mp-out")]
    pub out: PathBuf,
    /// Random seed of the performer.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

pub fn performer_cmd(a: &PerformerArgs) -> anyhow::Result<()> {
    let perf = perform(&PerformerParams { seed: a.seed, ..PerformerParams::default() })?;
    let t = if a.three_d { &perf.track_3d } else { &perf.track_2d };
    write_track(&a.output, t)?;
    eprintln!("{} frames × {} joints written to {}", t.n_frames(), t.n_joints(), a.output.display());
    for s in &perf.segments {
        eprintln!("  {:<12} frames {:>4}..{:<4} {} repetitions", s.kind.name(), s.frames.start, s.frames.end, s.reps.len());
    }
    Ok(())
}

/// Writes the programs, loops and track of `track` into `out`.
pub fn analyse_into(track: &Track, out: &Path) -> anyhow::Result<mp_abstract::Analysis> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    write_track(out.join("track.npz"), track)?;
    let an = analyze(track, &AbstractParams::default())?;
    an.concrete.write(out.join("program.txt"))?;
    an.concrete.write(out.join("program.json"))?;
    write_program(&an.program, out.join("abstract.txt"))?;
    write_program(&an.program, out.join("abstract.json"))?;
    let loops = serde_json::json!({
        "fps": track.fps(),
        "frames": track.n_frames(),
        "intervals": an.intervals,
    });
    write_atomic(out.join("loops.json"), serde_json::to_string_pretty(&loops)?.as_bytes())?;
    Ok(an)
}

pub fn demo_cmd(a: &DemoArgs) -> anyhow::Result<()> {
    let perf = perform(&PerformerParams { seed: a.seed, ..PerformerParams::default() })?;
    let an = analyse_into(&perf.track_2d, &a.out)?;
    print!("{}", print_with(&an.program, &PrintOptions::summary()));
    println!();
    println!("Repetitions found (ground truth of the performer in brackets):");
    for i in &an.intervals {
        let gt = perf
            .segments
            .iter()
            .find(|s| mp_abstract::repetition::iom((i.start_frame, i.end_frame), (s.frames.start, s.frames.end)) > 0.5);
        println!(
            "  frames {:>4}..{:<4} {} × body of {} primitives  [{}]",
            i.start_frame,
            i.end_frame,
            i.count,
            i.body_size,
            gt.map(|s| format!("{} × {}", s.reps.len(), s.kind.name())).unwrap_or_else(|| "no labelled move".into())
        );
    }
    println!();
    println!("Results written to {}/ (track.npz, program.txt/.json, abstract.txt/.json, loops.json)", a.out.display());
    Ok(())
}
