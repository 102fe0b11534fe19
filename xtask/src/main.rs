//! Project tasks: `cargo xtask eval …`, `bench`, `models`, `setup`, `train-…`.

mod bench;
mod eval_concrete;
mod eval_loops;
mod eval_pose;
mod models;
mod setup;

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
}

#[derive(Subcommand)]
enum Eval {
    /// Repetition detection, counting and prediction by unrolling (CMU mocap6, AIST++, Penn Action, QUVA).
    Loops(eval_loops::EvalLoopsArgs),
    /// Concrete programs on Penn Action: primitives, parameters, KD, jumps, interpolation.
    Concrete(eval_concrete::EvalConcreteArgs),
    /// Keypoints (BlazePose / MoveNet) against MediaPipe's reference, PCK on the COCO sample, speed.
    Pose(eval_pose::EvalPoseArgs),
}

fn main() {
    let cli = Cli::parse();
    let result: anyhow::Result<()> = match cli.command {
        Command::Eval(e) => match e {
            Eval::Concrete(a) => eval_concrete::run(&a),
            Eval::Loops(a) => eval_loops::run(&a),
            Eval::Pose(a) => eval_pose::run(&a),
        },
        Command::Setup(a) => setup::run(&a),
        Command::Models(a) => models::run(&a),
        Command::Bench(a) => bench::run(&a),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
