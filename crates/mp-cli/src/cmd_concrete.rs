//! `mp fit`, `mp execute`, `mp stats`: concrete programs from the command line.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use mp_concrete::{Continuity, ExecParams, NumberFormat, Program, RefitNorm, Transition};
use mp_geom::PrimitiveKind;
use mp_pipeline::Params;

/// Arguments of `mp fit`.
#[derive(Args, Debug)]
pub struct FitArgs {
    /// Input keypoint track (npz, npy, json, csv, bvh, mpt, c3d, parquet, pose, or an OpenPose folder).
    pub track: PathBuf,
    #[command(flatten)]
    pub rate: crate::track_arg::RateOpt,
    /// Output program: `.json` for JSON, anything else for the DSL text.
    #[arg(short, long)]
    pub output: PathBuf,
    /// A fixed segment penalty λ at the 512-px reference scale (the paper's
    /// reference value is 400) instead of the default λ from the motion.
    #[arg(long, conflicts_with_all = ["budget", "lambda_spread"])]
    pub lambda: Option<f64>,
    /// A parameter budget instead of a price per segment: the most accurate
    /// program with at most this share of the track's numbers (T·J·D), e.g.
    /// 0.1 (λ found by bisection: about a dozen fits).
    #[arg(long, conflicts_with = "lambda_spread")]
    pub budget: Option<f64>,
    /// λ from the spread of the keypoints around each frame held for this
    /// many seconds (px·frames); the default holds it for one second.
    #[arg(long)]
    pub lambda_spread: Option<f64>,
    /// Maximum segment length in frames.
    #[arg(long, default_value_t = Params::default().analysis.synth.max_segment_frames)]
    pub window: usize,
    /// `c0`: consecutive segments share their boundary pose (the executed
    /// program has no jump at a boundary); `none`: segments fitted independently.
    #[arg(long, default_value_t = Params::default().analysis.synth.continuity)]
    pub continuity: Continuity,
    /// What the C0 refit minimises per joint: `squared` residuals (least
    /// squares) or their `euclidean` lengths (the error the segmentation
    /// minimises; reweighted least squares).
    #[arg(long, default_value_t = Params::default().analysis.synth.refit_norm)]
    pub refit_norm: RefitNorm,
    /// The primitive kinds a segment may use (comma-separated: stationary,
    /// line, circle, spline).
    #[arg(long, value_delimiter = ',', default_values_t = Params::default().analysis.synth.fit.kinds)]
    pub kinds: Vec<PrimitiveKind>,
    /// Circles whose angle is quadratic in time (one more parameter: an
    /// angular acceleration) instead of linear.
    #[arg(long)]
    pub quadratic_angle: bool,
    /// Largest side of the video frame in pixels (sets the scale: frame / 512);
    /// without it the scale comes from the track's extent.
    #[arg(long)]
    pub frame_size: Option<f64>,
    /// Fail on joints that are never observed instead of fitting them to their stored positions.
    #[arg(long)]
    pub strict_joints: bool,
    /// Also print the program on the terminal (the written file holds it whole).
    #[arg(long)]
    pub print: bool,
    /// Decimals of the program printed with --print (the written file is lossless); default: by the track's units (px 2, m 4, unitless 3).
    #[arg(long)]
    pub precision: Option<usize>,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Arguments of `mp execute`.
#[derive(Args, Debug)]
pub struct ExecuteArgs {
    /// Input program (`.json` or DSL text).
    pub program: PathBuf,
    /// Output track (format by extension, as `mp_geom::write_track` writes).
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
    #[command(flatten)]
    pub rate: crate::track_arg::RateOpt,
    /// The program (`.json` or DSL text).
    pub program: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// `mp fit`: the same concrete program as `mp run` and `mp abstract` give
/// for the same track and options.
pub fn fit(a: &FitArgs) -> anyhow::Result<()> {
    let read = crate::track_arg::read_track_file(&a.track, &a.rate)?;
    let frame_px = crate::track_arg::frame_px(&read, a.frame_size);
    let track = read.track;
    let params = mp_pipeline::FitOptions {
        lambda: a.lambda,
        budget: a.budget,
        lambda_spread: a.lambda_spread,
        max_segment_frames: Some(a.window),
        continuity: Some(a.continuity),
        refit_norm: Some(a.refit_norm),
        kinds: Some(a.kinds.clone()),
        quadratic_angle: a.quadratic_angle,
        strict_joints: a.strict_joints,
    }
    .params()?;
    let syn = mp_pipeline::concrete_program(&track, frame_px, &params)
        .with_context(|| format!("fitting {}", a.track.display()))?;
    let p = &syn.program;
    if a.print {
        let decimals = a
            .precision
            .unwrap_or(NumberFormat::pretty_decimals(p.units));
        print!("{}", p.to_dsl_pretty(decimals));
    }
    p.write(&a.output)?;
    if a.quiet {
        return Ok(());
    }
    eprintln!(
        "{} frames, {} joints → {} segments, {} parameters ({} numbers written; raw {}); unit scale {:.4}; wrote {}",
        p.n_frames(),
        p.n_joints(),
        p.n_segments(),
        p.n_params(),
        p.n_numbers(),
        p.n_frames() * p.n_joints() * p.dims,
        syn.unit_scale,
        a.output.display()
    );
    Ok(())
}

/// `mp execute`.
pub fn execute(a: &ExecuteArgs) -> anyhow::Result<()> {
    let p = Program::read(&a.program)?;
    let mut params = ExecParams {
        fps_out: a.fps,
        ..ExecParams::default()
    };
    if a.extrapolate {
        params.transition = Transition::Extrapolate;
    }
    let track = p.execute_with(&params)?;
    mp_geom::write_track(&a.output, &track)
        .with_context(|| format!("writing {}", a.output.display()))?;
    eprintln!(
        "{} frames at {} fps → {}",
        track.n_frames(),
        mp_geom::fps_label(track.fps()),
        a.output.display()
    );
    Ok(())
}

/// `mp stats`.
pub fn stats(a: &StatsArgs) -> anyhow::Result<()> {
    let track = crate::track_arg::read_track(&a.track, &a.rate)?;
    let p = Program::read(&a.program)?;
    let s = p.stats(&track)?;
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
