//! Project tasks: `cargo xtask eval …`, `bench`, `models`, `setup`, `train-…`.

mod eval_concrete;

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
}

#[derive(Subcommand)]
enum Eval {
    /// Concrete programs on Penn Action: primitives, parameters, KD, jumps, interpolation.
    Concrete(eval_concrete::EvalConcreteArgs),
}

fn main() {
    let cli = Cli::parse();
    let result: anyhow::Result<()> = match cli.command {
        Command::Eval(e) => match e {
            Eval::Concrete(a) => eval_concrete::run(&a),
        },
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
