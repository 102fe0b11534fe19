//! `mp fit`, `mp execute`, `mp stats`: concrete programs from the command line.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use mp_concrete::{
    dsl, program_stats, synthesize_detailed, ExecParams, Lambda, Program, Scale, SynthParams,
    Transition, UnobservedJoints,
};

/// Arguments of `mp fit`.
#[derive(Args, Debug)]
pub struct FitArgs {
    /// Input track (any format `mp_geom::io::read_track` reads).
    pub track: PathBuf,
    /// Output program: `.json` for JSON, anything else for the DSL text.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Fixed segment penalty λ at the 512-px reference scale.
    #[arg(long, default_value_t = Lambda::DEFAULT_FIXED, conflicts_with = "adaptive")]
    pub lambda: f64,
    /// Adaptive λ from the keypoint covariance around each frame (clamped to [100, 1600]).
    #[arg(long)]
    pub adaptive: bool,
    /// Maximum segment length in frames.
    #[arg(long, default_value_t = 60)]
    pub window: usize,
    /// Largest side of the video frame in pixels (sets the scale: frame / 512);
    /// without it the scale comes from the track's extent.
    #[arg(long)]
    pub frame_size: Option<f64>,
    /// Keep joints that are never observed (fitted to their stored positions) instead of failing.
    #[arg(long)]
    pub allow_unobserved: bool,
    /// Decimals of the program printed on the terminal (the written file is lossless).
    #[arg(long, default_value_t = 2)]
    pub precision: usize,
    /// Do not print the program.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Arguments of `mp execute`.
#[derive(Args, Debug)]
pub struct ExecuteArgs {
    /// Input program (`.json` or DSL text).
    pub program: PathBuf,
    /// Output track (format by extension, as `mp_geom::io::write_track` writes).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output frame rate (default: the program's).
    #[arg(long)]
    pub fps: Option<f64>,
    /// Between segments, continue the primitive instead of blending into the next one.
    #[arg(long)]
    pub extrapolate: bool,
}

/// Arguments of `mp stats`.
#[derive(Args, Debug)]
pub struct StatsArgs {
    /// The track the program encodes.
    pub track: PathBuf,
    /// The program (`.json` or DSL text).
    pub program: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// `mp fit`.
pub fn fit(a: &FitArgs) -> anyhow::Result<()> {
    let track = mp_geom::io::read_track(&a.track)
        .with_context(|| format!("reading {}", a.track.display()))?;
    let params = SynthParams {
        lambda: if a.adaptive {
            Lambda::adaptive()
        } else {
            Lambda::fixed(a.lambda)
        },
        max_segment_frames: a.window,
        scale: match a.frame_size {
            Some(frame_px) => Scale::FrameSize { frame_px },
            None => Scale::Auto,
        },
        unobserved_joints: if a.allow_unobserved {
            UnobservedJoints::Ignore
        } else {
            UnobservedJoints::Error
        },
        ..SynthParams::default()
    };
    let syn = synthesize_detailed(&track, &params)
        .with_context(|| format!("fitting {}", a.track.display()))?;
    let p = &syn.program;
    if !a.quiet {
        print!("{}", dsl::print_pretty(p, a.precision));
    }
    p.write(&a.output)?;
    eprintln!(
        "{} frames, {} joints → {} segments, {} parameters (raw {}); unit scale {:.4}; wrote {}",
        p.n_frames(),
        p.n_joints(),
        p.n_segments(),
        p.n_params(),
        p.n_frames() * p.n_joints() * p.dims,
        syn.unit_scale,
        a.output.display()
    );
    Ok(())
}

/// `mp execute`.
pub fn execute(a: &ExecuteArgs) -> anyhow::Result<()> {
    let p = Program::read(&a.program)?;
    let track = p.execute_with(&ExecParams {
        fps_out: a.fps,
        transition: if a.extrapolate {
            Transition::Extrapolate
        } else {
            Transition::Blend
        },
    })?;
    mp_geom::io::write_track(&a.output, &track)
        .with_context(|| format!("writing {}", a.output.display()))?;
    eprintln!(
        "{} frames at {} fps → {}",
        track.n_frames(),
        track.fps(),
        a.output.display()
    );
    Ok(())
}

/// `mp stats`.
pub fn stats(a: &StatsArgs) -> anyhow::Result<()> {
    let track = mp_geom::io::read_track(&a.track)
        .with_context(|| format!("reading {}", a.track.display()))?;
    let p = Program::read(&a.program)?;
    let s = program_stats(&p, &track)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
        return Ok(());
    }
    let u = track.units().as_str();
    println!(
        "frames × joints × dims   {} × {} × {}",
        s.n_frames, s.n_joints, s.dims
    );
    println!("segments                 {}", s.n_segments);
    let kinds: Vec<String> = s.kinds.iter().map(|(k, n)| format!("{k} {n}")).collect();
    println!("primitives by kind       {}", kinds.join(", "));
    println!(
        "parameters               {} (raw {}, ratio {:.3})",
        s.params_program,
        s.params_raw,
        s.params_program as f64 / s.params_raw.max(1) as f64
    );
    println!("KD                       {:.3} {u}", s.kd);
    println!(
        "max adjacent-frame jump  raw {:.3} {u}, program {:.3} {u}",
        s.max_jump_raw, s.max_jump_program
    );
    Ok(())
}
