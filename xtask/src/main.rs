//! Project tasks: `cargo xtask eval …`, `bench`, `models`, `setup`, `train-…`.

mod bench;
mod eval_concrete;
mod eval_count;
mod eval_count_long;
mod eval_count_long_synth;
mod eval_count_synth;
mod eval_count_video;
mod eval_forecast;
mod eval_grammar;
mod eval_inbetween;
mod eval_intervals;
mod eval_loops;
mod eval_people;
mod eval_pose;
mod eval_pose_rate;
mod eval_refine;
mod eval_refine_cv;
mod eval_video;
mod fit_confidence;
mod models;
mod pyenv;
mod setup;
mod stats;
mod synth_reps;
mod synth_select;
mod synth_sources;
mod synth_video;
mod train_forecast;
mod train_refine;
mod train_refine_cv;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "xtask", about = "Project tasks for the mp workspace")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate a component on data and write a JSON report.
    #[command(subcommand)]
    Eval(Eval),
    /// Install ONNX Runtime's library and the pose models into .cache/ (idempotent).
    Setup(setup::SetupArgs),
    /// Put the ONNX pose models into .cache/models (from existing files or by conversion).
    Models(models::ModelsArgs),
    /// Run the criterion benches and the synthesis timing harness; write docs/BENCH.md.
    Bench(bench::BenchArgs),
    /// Train the forecasting models (PyTorch, CPU) and export them to ONNX under models/forecast/.
    TrainForecast(train_forecast::TrainForecastArgs),
    /// Train the seven refinement networks (PyTorch, CPU) and export them to ONNX under models/refine/.
    TrainRefine(train_refine::TrainRefineArgs),
}

#[derive(Subcommand)]
enum Eval {
    /// Repetition counts from video exactly as `mp run` makes them, against per-video labels (MAE, OBO, time per frame).
    Count(eval_count::EvalCountArgs),
    /// Repetition detection, counting and prediction by unrolling (CMU mocap6, AIST++, Penn Action, QUVA).
    Loops(eval_loops::EvalLoopsArgs),
    /// Several people in one video: composites of one-person videos side by side and crossing.
    People(eval_people::EvalPeopleArgs),
    /// Motion grammars: symbols (purity, NMI), grammars (rules, DL), synthesis vs the FSM baseline.
    Grammar(eval_grammar::EvalGrammarArgs),
    /// Concrete programs on Penn Action: primitives, parameters, KD, jumps, interpolation.
    Concrete(eval_concrete::EvalConcreteArgs),
    /// Keypoints (BlazePose / MoveNet) against MediaPipe's reference, PCK on the COCO sample, speed.
    Pose(eval_pose::EvalPoseArgs),
    /// The pose model on every 2nd or 3rd frame (`--pose-fps`) against every frame: counts, keypoints, programs, time.
    PoseRate(eval_pose_rate::EvalPoseRateArgs),
    /// Forecasting (Constant, NN, Loop, AR on Φ / Θ): PCK or (PA-)MPJPE per horizon, with and without DTW.
    Forecast(eval_forecast::EvalForecastArgs),
    /// Learned motion refinement: injected flaws (MPJPE), generated motion (FID, accuracy, diversity, multimodality), ablation.
    Refine(eval_refine::EvalRefineArgs),
    /// Program-guided frame interpolation at 2×, 4×, 8× vs linear blending and FFmpeg minterpolate (KD of arms, PSNR, SSIM).
    Interpolation(eval_video::EvalInterpolationArgs),
    /// In-between poses of `mp interpolate` on real keypoint tracks (every k-th frame kept) vs linear interpolation.
    Inbetween(eval_inbetween::EvalInBetweenArgs),
    /// Video prediction by unrolling the last loop on pixels vs constant and nearest-neighbour frames (KD, PSNR, SSIM).
    VideoPredict(eval_video::EvalVideoPredictArgs),
}

fn main() {
    let cli = Cli::parse();
    let result: anyhow::Result<()> = match cli.command {
        Command::Eval(e) => match e {
            Eval::Concrete(a) => eval_concrete::run(&a),
            Eval::Count(a) => eval_count::run(&a),
            Eval::Loops(a) => eval_loops::run(&a),
            Eval::People(a) => eval_people::run(&a),
            Eval::Grammar(a) => eval_grammar::run(&a),
            Eval::Pose(a) => eval_pose::run(&a),
            Eval::PoseRate(a) => eval_pose_rate::run(&a),
            Eval::Forecast(a) => eval_forecast::run(&a),
            Eval::Refine(a) => eval_refine::run(&a),
            Eval::Interpolation(a) => eval_video::run_interpolation(&a),
            Eval::Inbetween(a) => eval_inbetween::run(&a),
            Eval::VideoPredict(a) => eval_video::run_video_predict(&a),
        },
        Command::Setup(a) => setup::run(&a),
        Command::Models(a) => models::run(&a),
        Command::Bench(a) => bench::run(&a),
        Command::TrainForecast(a) => train_forecast::run(&a),
        Command::TrainRefine(a) => train_refine::run(&a),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// Writes a report or model file through a temporary file renamed into
/// place, so an interrupted task leaves the old file or the new one.
pub(crate) fn write_file(
    path: impl AsRef<std::path::Path>,
    bytes: impl AsRef<[u8]>,
) -> mp_geom::Result<()> {
    mp_geom::io::write_atomic(path, bytes.as_ref())
}
