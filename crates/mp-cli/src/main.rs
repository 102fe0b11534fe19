//! `mp` — motion programs from the command line.
//!
//! A thin layer: each subcommand parses its arguments, calls library crates
//! and prints or writes the result. Subcommands live in their own modules.

use clap::{Parser, Subcommand};

/// Motion programs: keypoints → concrete programs → abstract programs, grammars, forecasts.
#[derive(Parser)]
#[command(name = "mp", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {}

fn main() {
    let cli = Cli::parse();
    let result: anyhow::Result<()> = match cli.command {};
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
