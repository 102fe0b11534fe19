//! `mp edit`, `mp interpolate` and `mp predict VIDEO --seconds`: motion
//! programs on video pixels — argument parsing and printing around
//! `mp_video`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use mp_pipeline::Params;
use mp_video::{
    EditChange, EditParams, InterpMethod, InterpParams, VideoPredictMethod, VideoPredictParams,
};

/// Arguments of `mp edit`.
#[derive(Args, Debug)]
#[command(group(clap::ArgGroup::new("change").required(true).args(["count", "add", "remove"])))]
pub struct EditArgs {
    /// Input video.
    pub video: PathBuf,
    /// Which interval of repetitions, numbered from 1 as `mp run`, `mp loops`
    /// and the report print them (`repetitions.intervals[I - 1]` of
    /// `mp run`'s loops.json).
    #[arg(
        long = "interval",
        alias = "loop",
        default_value_t = 1,
        value_name = "I"
    )]
    pub interval: usize,
    /// Set the interval's count to N repetitions.
    #[arg(long, alias = "iterations", value_name = "N")]
    pub count: Option<usize>,
    /// Add K repetitions.
    #[arg(long, value_name = "K")]
    pub add: Option<usize>,
    /// Remove K repetitions.
    #[arg(long, value_name = "K")]
    pub remove: Option<usize>,
    /// Output video (mp4).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Seams are searched within this many frames of an iteration's boundaries.
    #[arg(long, default_value_t = EditParams::default().seam_search)]
    pub seam_search: usize,
    /// Frames cross-faded after each seam.
    #[arg(long, default_value_t = EditParams::default().crossfade)]
    pub crossfade: usize,
    /// Print what was done as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `mp edit`: the repetitions of a video's counted interval made more or
/// fewer.
pub fn edit_cmd(a: &EditArgs) -> Result<()> {
    let change = match (a.count, a.add, a.remove) {
        (Some(n), _, _) => EditChange::Count(n),
        (_, Some(k), _) => EditChange::Add(k),
        (_, _, Some(k)) => EditChange::Remove(k),
        _ => bail!("one of --count, --add, --remove is needed"),
    };
    let params = EditParams {
        seam_search: a.seam_search,
        crossfade: a.crossfade,
        ..EditParams::default()
    };
    let r = mp_video::edit_video(
        &a.video,
        a.interval,
        change,
        &params,
        &Params::default(),
        &a.output,
    )
    .with_context(|| format!("editing {}", a.video.display()))?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    let fps = r.fps;
    println!(
        "interval {}: frames {} ({} repetitions); the repetition at frames {} is closest to the mean",
        r.interval_number,
        mp_geom::frames_label(r.interval.0, r.interval.1),
        r.count_before,
        mp_geom::frames_label(r.repetition.0, r.repetition.1)
    );
    println!(
        "{} {} repetition{} of frames {} (seam cost {:.2}); {} → {} frames ({:.2} → {:.2} s) written to {}",
        if r.change >= 0 { "added" } else { "removed" },
        r.change.unsigned_abs(),
        if r.change.unsigned_abs() == 1 { "" } else { "s" },
        mp_geom::frames_label(r.segment.0, r.segment.1),
        r.seam_cost,
        r.frames_in,
        r.frames_out,
        r.frames_in as f64 / fps,
        r.frames_out as f64 / fps,
        a.output.display()
    );
    Ok(())
}

/// Interpolation methods.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum InterpChoice {
    /// Warp both neighbours towards the program's pose, then blend.
    Program,
    /// Blend the neighbours.
    Linear,
    /// FFmpeg's motion-compensated minterpolate filter.
    Minterpolate,
}

impl From<InterpChoice> for InterpMethod {
    fn from(m: InterpChoice) -> Self {
        match m {
            InterpChoice::Program => InterpMethod::Program,
            InterpChoice::Linear => InterpMethod::Linear,
            InterpChoice::Minterpolate => InterpMethod::Minterpolate,
        }
    }
}

/// Arguments of `mp interpolate`.
#[derive(Args, Debug)]
pub struct InterpolateArgs {
    /// Input video.
    pub video: PathBuf,
    /// Frames out per frame in: 2, 4 or 8.
    #[arg(long)]
    pub factor: usize,
    /// Method.
    #[arg(long, value_enum, default_value = InterpMethod::default().as_str())]
    pub method: InterpChoice,
    /// Output video (mp4), at `factor` times the frame rate.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `mp interpolate`: in-between frames from the motion program.
pub fn interpolate_cmd(a: &InterpolateArgs) -> Result<()> {
    let r = mp_video::interpolate_video(
        &a.video,
        a.factor,
        a.method.into(),
        &InterpParams::default(),
        &Params::default(),
        &a.output,
    )
    .with_context(|| format!("interpolating {}", a.video.display()))?;
    println!(
        "{} → {} frames ({:.2} → {:.2} fps, {}), written to {}",
        r.frames_in,
        r.frames_out,
        r.fps_in,
        r.fps_out,
        r.method.as_str(),
        a.output.display()
    );
    Ok(())
}

/// Options of `mp predict` for a video input.
#[derive(Args, Debug, Clone, Default)]
pub struct VideoPredictOpts {
    /// For a video input: seconds of video to predict after its end (the output video holds the
    /// input followed by the prediction).
    #[arg(long)]
    pub seconds: Option<f64>,
}

/// `mp predict VIDEO --seconds S -o OUT.mp4`: the video continued by
/// unrolling its last loop (`--method loop`), holding its last frame
/// (`constant`) or playing on from the nearest earlier frame (`nn`).
pub fn predict_video_cmd(
    video: &Path,
    seconds: Option<f64>,
    method: mp_forecast::ForecastMethod,
    output: Option<&Path>,
) -> Result<()> {
    use mp_forecast::ForecastMethod as F;
    let Some(seconds) = seconds else {
        bail!(
            "a video input needs --seconds S: how many seconds of video to predict after its end \
             (e.g. mp predict {} --seconds 2 -o OUT.mp4); --observe/--horizon are for tracks",
            video.display()
        );
    };
    let Some(output) = output else {
        bail!("a video input needs -o OUT.mp4 (the video followed by the prediction)");
    };
    let method = match method {
        F::Loop => VideoPredictMethod::Loop,
        F::Constant => VideoPredictMethod::Constant,
        F::Nn => VideoPredictMethod::Nearest,
        other => bail!(
            "--method {} predicts keypoints, not frames; for a video use loop, constant or nn",
            other.as_str()
        ),
    };
    let r = mp_video::predict_video(
        video,
        seconds,
        method,
        &VideoPredictParams::default(),
        &Params::default(),
        output,
    )
    .with_context(|| format!("predicting {}", video.display()))?;
    if r.used != r.method {
        eprintln!(
            "no repetition or period found: the {} continuation is used",
            r.used.as_str()
        );
    }
    println!(
        "{} observed + {} predicted frames ({:.2} s, {} from the {}; cycle at frames {}) written to {}",
        r.observed,
        r.predicted,
        r.predicted as f64 / r.fps,
        r.used.as_str(),
        r.source,
        mp_geom::frames_label(r.cycle.0, r.cycle.1),
        output.display()
    );
    Ok(())
}
