//! `mp` — motion programs from the command line.
//!
//! A thin layer: each subcommand parses its arguments, calls library crates
//! and prints or writes the result. Subcommands live in their own modules.

mod cmd_concrete;

use clap::{Parser, Subcommand};

/// Motion programs: keypoints → concrete programs → abstract programs, grammars, forecasts.
#[derive(Parser)]
#[command(name = "mp", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Fit a concrete program to a track (DP segmentation over primitives).
    Fit(cmd_concrete::FitArgs),
    /// Render a concrete program as a track, at any frame rate.
    Execute(cmd_concrete::ExecuteArgs),
    /// Size and accuracy of a program against its track.
    Stats(cmd_concrete::StatsArgs),
}

fn main() {
    let cli = Cli::parse();
    let result: anyhow::Result<()> = match cli.command {
        Command::Fit(a) => cmd_concrete::fit(&a),
        Command::Execute(a) => cmd_concrete::execute(&a),
        Command::Stats(a) => cmd_concrete::stats(&a),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
