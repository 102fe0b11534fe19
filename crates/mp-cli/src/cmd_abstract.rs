//! `mp abstract`, `mp loops`, `mp extend`, `mp sample`, `mp predict`: abstract programs from the command line.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use mp_abstract::{AbstractExecParams, AbstractParams, AbstractProgram, LoopReplay, PrintOptions};
use mp_forecast::{ForecastMethod, PredictOptions};
use mp_geom::write_track;
use mp_pipeline::{analyse_track, Params};

/// Options shared by the commands that analyse a track.
#[derive(Args, Debug, Clone)]
pub struct AnalysisOpts {
    /// Largest side of the video frame in pixels (scale = frame / 512); default: from the track's extent.
    #[arg(long)]
    pub frame_size: Option<f64>,
    #[command(flatten)]
    pub rate: crate::track_arg::RateOpt,
    /// Loop score threshold at the 512-px reference scale.
    #[arg(long, default_value_t = Params::default().analysis.loops.threshold)]
    pub threshold: f64,
    /// Largest loop-body size tried.
    #[arg(long, default_value_t = Params::default().analysis.loops.max_body)]
    pub max_body: usize,
}

impl AnalysisOpts {
    /// The pipeline's parameters with these options.
    pub fn pipeline_params(&self) -> Params {
        let mut p = Params::default();
        p.analysis.loops.threshold = self.threshold;
        p.analysis.loops.max_body = self.max_body;
        p
    }

    /// The abstract analysis parameters with these options, at the scale of
    /// a frame of `frame_px` ([`crate::track_arg::frame_px`]).
    fn params_at(&self, frame_px: Option<f64>) -> AbstractParams {
        let p = self.pipeline_params();
        AbstractParams {
            synth: p.synth_for(frame_px),
            loops: p.analysis.loops,
        }
    }
}

/// Arguments of `mp abstract`.
#[derive(Args, Debug)]
pub struct AbstractArgs {
    /// Input track.
    pub track: PathBuf,
    /// Output abstract program: `.json`, or the text form for any other extension.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub opts: AnalysisOpts,
    /// Do not print the program summary.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Arguments of `mp loops`.
#[derive(Args, Debug)]
pub struct LoopsArgs {
    /// Input track, or a video (keypoints and frames are read as `mp run` reads them).
    pub track: PathBuf,
    #[command(flatten)]
    pub opts: AnalysisOpts,
    #[command(flatten)]
    pub people: crate::cmd_run::PeopleOpts,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `mp extend`.
#[derive(Args, Debug)]
pub struct ExtendArgs {
    /// Input abstract program.
    pub program: PathBuf,
    /// Which loop, numbered from 1 in program order (as `mp edit`, `mp loops` and the report number loops).
    #[arg(long = "loop", default_value_t = 1)]
    pub loop_number: usize,
    /// New number of iterations.
    #[arg(long)]
    pub iters: usize,
    /// Output track; a `.txt`/`.json` name writes the edited program instead.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Arguments of `mp sample`.
#[derive(Args, Debug)]
pub struct SampleArgs {
    /// Input abstract program.
    pub program: PathBuf,
    /// Random seed (the same seed gives the same motion).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output track.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Prediction methods (names as [`ForecastMethod::as_str`]).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Hold the last observed pose.
    Constant,
    /// Unroll the last detected loop.
    Loop,
    /// Nearest neighbour in a training set (`--train`).
    Nn,
    /// Learned autoregressive model on latents (AR on Φ).
    Ar,
    /// Learned autoregressive model on poses (AR on Θ).
    ArPose,
}

impl From<Method> for ForecastMethod {
    fn from(m: Method) -> Self {
        match m {
            Method::Constant => ForecastMethod::Constant,
            Method::Loop => ForecastMethod::Loop,
            Method::Nn => ForecastMethod::Nn,
            Method::Ar => ForecastMethod::Ar,
            Method::ArPose => ForecastMethod::ArPose,
        }
    }
}

/// Arguments of `mp predict`.
#[derive(Args, Debug)]
pub struct PredictArgs {
    /// Input track, or a video (continued for --seconds into -o OUT.mp4).
    pub track: PathBuf,
    /// Number of observed frames (from the start); a track input needs it.
    #[arg(long)]
    pub observe: Option<usize>,
    /// Number of frames to predict; a track input needs it.
    #[arg(long)]
    pub horizon: Option<usize>,
    /// Method.
    #[arg(long, value_enum, default_value = ForecastMethod::default().as_str())]
    pub method: Method,
    /// Output track of the predicted frames.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub opts: AnalysisOpts,
    #[command(flatten)]
    pub forecast: crate::cmd_forecast::ForecastOpts,
    #[command(flatten)]
    pub video: crate::cmd_video::VideoPredictOpts,
}

/// `mp abstract`: the abstract program of a track, written and summarised.
pub fn abstract_cmd(a: &AbstractArgs) -> anyhow::Result<()> {
    let read = crate::track_arg::read_track_file(&a.track, &a.opts.rate)?;
    let frame_px = crate::track_arg::frame_px(&read, a.opts.frame_size);
    let track = read.track;
    let an = analyse_track(&track, frame_px, &a.opts.pipeline_params())?;
    an.program.write(&a.output)?;
    if !a.quiet {
        print!("{}", an.program.to_dsl_with(&PrintOptions::summary()));
    }
    eprintln!(
        "{} frames → {} primitives → {} statements, {} program loop{}; written to {}",
        track.n_frames(),
        an.prims.len(),
        an.program.stmts.len(),
        an.loops.len(),
        if an.loops.len() == 1 { "" } else { "s" },
        a.output.display()
    );
    Ok(())
}

/// `mp loops`: the repetition counts `mp run` writes (intervals, counts, the
/// signal and method that decided), from a track or a video.
pub fn loops_cmd(a: &LoopsArgs) -> anyhow::Result<()> {
    let mut params = a.opts.pipeline_params();
    a.people.apply(&mut params, false)?;
    let input = crate::track_arg::open_input(&a.track, a.opts.frame_size, &a.opts.rate)?;
    let out = mp_pipeline::analyse_input(
        input,
        &params,
        &mp_pipeline::Silent,
        &crate::progress::ctrl_c_token(),
    )?;
    let c = &out.counts;
    if a.json {
        let v = out.loops_file();
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    let fps = out.keypoints.track.fps();
    println!("repetitions (counted; on a video, `mp edit --interval N` repeats interval N):");
    println!(
        "{:>4} {:>13} {:>9} {:>9} {:>9} {:>6} {:>11}",
        "#", "frames", "start_s", "end_s", "period_s", "count", "periodicity"
    );
    for (i, r) in c.intervals.iter().enumerate() {
        println!(
            "{:>4} {:>13} {:>9.2} {:>9.2} {:>9.2} {:>6} {:>11.2}",
            i + 1,
            mp_geom::frames_label(r.start_frame, r.end_frame),
            r.start_frame as f64 / fps,
            r.end_frame as f64 / fps,
            r.period_frames as f64 / fps,
            r.count,
            r.periodicity
        );
    }
    println!(
        "total {} repetition{} in {} frames (from the {}, {}, confidence {:.2})",
        c.total,
        if c.total == 1 { "" } else { "s" },
        out.keypoints.track.n_frames(),
        c.signal.as_str(),
        c.method.as_str(),
        c.confidence
    );
    // The program loops (the abstract program's `for` statements, what
    // --threshold and --max-body set, and `mp extend --loop N` numbers) are
    // another thing than the repetitions counted above.
    if let Some(an) = &out.analysis {
        println!();
        println!(
            "program loops (the abstract program's `for` statements; `mp extend --loop N`; --threshold {}, --max-body {}):",
            a.opts.threshold, a.opts.max_body
        );
        if an.intervals.is_empty() {
            println!("  none");
        } else {
            println!(
                "{:>4} {:>13} {:>10} {:>12}",
                "#", "frames", "iterations", "body (prims)"
            );
            for (i, l) in an.intervals.iter().enumerate() {
                println!(
                    "{:>4} {:>13} {:>10} {:>12}",
                    i + 1,
                    mp_geom::frames_label(l.start_frame, l.end_frame),
                    l.iterations,
                    l.body_size
                );
            }
        }
    }
    crate::cmd_run::print_people(&out);
    Ok(())
}

fn is_program_path(p: &std::path::Path) -> bool {
    p.extension()
        .is_some_and(|e| e == "txt" || e == "json" || e == "mp")
}

/// `mp extend`: a loop's iteration count changed, then the program executed
/// (loops replayed as observed) or written.
pub fn extend_cmd(a: &ExtendArgs) -> anyhow::Result<()> {
    let mut prog = AbstractProgram::read(&a.program)?;
    let index = a.loop_number.checked_sub(1).ok_or_else(|| {
        anyhow::anyhow!("no loop 0: loops are numbered from 1 (--loop 1 is the first loop)")
    })?;
    prog.set_iterations(index, a.iters).map_err(|e| match e {
        mp_abstract::AbstractError::NotFound(_) => anyhow::anyhow!(
            "no loop {}: the program has {} loop(s), numbered from 1",
            a.loop_number,
            prog.loop_indices().len()
        ),
        e => e.into(),
    })?;
    if is_program_path(&a.output) {
        prog.write(&a.output)?;
    } else {
        let params = AbstractExecParams {
            replay: LoopReplay::Observed,
            ..AbstractExecParams::default()
        };
        let t = prog.execute(&params)?;
        write_track(&a.output, &t)?;
        eprintln!("{} frames written to {}", t.n_frames(), a.output.display());
    }
    Ok(())
}

/// `mp sample`: one seeded stochastic execution of an abstract program.
pub fn sample_cmd(a: &SampleArgs) -> anyhow::Result<()> {
    let prog = AbstractProgram::read(&a.program)?;
    let t = prog.sample(a.seed, &AbstractExecParams::default())?;
    write_track(&a.output, &t)?;
    eprintln!(
        "{} frames (seed {}) written to {}",
        t.n_frames(),
        a.seed,
        a.output.display()
    );
    Ok(())
}

/// `mp predict`: the frames after the observed ones, by the chosen method
/// (`mp_forecast::forecast`), with their KD to the actual frames when the track has them.
pub fn predict_cmd(a: &PredictArgs) -> anyhow::Result<()> {
    if mp_pipeline::Input::is_video(&a.track) {
        return crate::cmd_video::predict_video_cmd(
            &a.track,
            a.video.seconds,
            a.method.into(),
            a.output.as_deref(),
        );
    }
    let (Some(observe), Some(horizon)) = (a.observe, a.horizon) else {
        anyhow::bail!(
            "a track input needs --observe N and --horizon H (frames observed from the start, frames predicted)"
        );
    };
    let read = crate::track_arg::read_track_file(&a.track, &a.opts.rate)?;
    let frame_px = crate::track_arg::frame_px(&read, a.opts.frame_size);
    let track = read.track;
    let mut opts = PredictOptions {
        method: a.method.into(),
        train: a.forecast.train.clone(),
        models: a.forecast.models.clone(),
        ..PredictOptions::default()
    };
    opts.loop_params.analysis = a.opts.params_at(frame_px);
    let p = mp_forecast::forecast(&track, observe, horizon, &opts)?;
    if let Some(text) = p.explanation() {
        eprintln!("{text}");
    }
    if let Some(out) = &a.output {
        write_track(out, &p.track)?;
        eprintln!(
            "{} predicted frames written to {}",
            p.track.n_frames(),
            out.display()
        );
    }
    if let Some(kd) = p.actual_kd {
        println!(
            "KD to the actual frames: {kd:.3} {}",
            track.units().as_str()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn predict_without_flags_uses_the_library_defaults() {
        let opts = AnalysisOpts {
            frame_size: None,
            rate: Default::default(),
            threshold: Params::default().analysis.loops.threshold,
            max_body: Params::default().analysis.loops.max_body,
        };
        assert_eq!(
            opts.params_at(None),
            PredictOptions::default().loop_params.analysis
        );
        assert_eq!(ForecastMethod::from(Method::ArPose), ForecastMethod::ArPose);
    }
}
