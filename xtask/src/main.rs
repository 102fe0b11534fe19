//! Project tasks: `cargo xtask eval …`, `bench`, `models`, `setup`, `train-…`.
//!
//! This binary parses the arguments; the evaluations and the training live
//! in the `mp-eval` crate, the set-up ([`setup`], [`models`]) and the
//! benchmarks ([`mod@bench`]) here.

mod bench;
mod models;
mod setup;

use mp_eval::{
    concrete, count, forecast, grammar, inbetween, live, loops, people, pose, pose_rate, refine,
    train_forecast, train_refine, video,
};

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
    Count(count::EvalCountArgs),
    /// Repetition detection, counting and prediction by unrolling (CMU mocap6, AIST++, Penn Action, QUVA).
    Loops(loops::EvalLoopsArgs),
    /// The online counter of `mp live` on the synthetic repetitions: final count and delay per setting.
    Live(live::EvalLiveArgs),
    /// Several people in one video: composites of one-person videos side by side and crossing.
    People(people::EvalPeopleArgs),
    /// Motion grammars: symbols (purity, NMI), grammars (rules, DL), synthesis vs the FSM baseline.
    Grammar(grammar::EvalGrammarArgs),
    /// Concrete programs on Penn Action: primitives, parameters, KD, jumps, interpolation.
    Concrete(concrete::EvalConcreteArgs),
    /// Keypoints (BlazePose / MoveNet) against MediaPipe's reference, PCK on the COCO sample, speed.
    Pose(pose::EvalPoseArgs),
    /// The pose model on every 2nd or 3rd frame (`--pose-fps`) against every frame: counts, keypoints, programs, time.
    PoseRate(pose_rate::EvalPoseRateArgs),
    /// Forecasting (Constant, NN, Loop, AR on Φ / Θ): PCK or (PA-)MPJPE per horizon, with and without DTW.
    Forecast(forecast::EvalForecastArgs),
    /// Learned motion refinement: injected flaws (MPJPE), generated motion (FID, accuracy, diversity, multimodality), ablation.
    Refine(refine::EvalRefineArgs),
    /// Program-guided frame interpolation at 2×, 4×, 8× vs linear blending and FFmpeg minterpolate (KD of arms, PSNR, SSIM).
    Interpolation(video::EvalInterpolationArgs),
    /// In-between poses of `mp interpolate` on real keypoint tracks (every k-th frame kept) vs linear interpolation.
    Inbetween(inbetween::EvalInBetweenArgs),
    /// Video prediction by unrolling the last loop on pixels vs constant and nearest-neighbour frames (KD, PSNR, SSIM).
    VideoPredict(video::EvalVideoPredictArgs),
}

fn main() {
    let cli = Cli::parse();
    let result: anyhow::Result<()> = match cli.command {
        Command::Eval(e) => match e {
            Eval::Concrete(a) => concrete::run(&a),
            Eval::Count(a) => count::run(&a),
            Eval::Loops(a) => loops::run(&a),
            Eval::Live(a) => live::run(&a),
            Eval::People(a) => people::run(&a),
            Eval::Grammar(a) => grammar::run(&a),
            Eval::Pose(a) => pose::run(&a),
            Eval::PoseRate(a) => pose_rate::run(&a),
            Eval::Forecast(a) => forecast::run(&a),
            Eval::Refine(a) => refine::run(&a),
            Eval::Interpolation(a) => video::run_interpolation(&a),
            Eval::Inbetween(a) => inbetween::run(&a),
            Eval::VideoPredict(a) => video::run_video_predict(&a),
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

pub(crate) use mp_eval::write_file;
