//! `mp` — motion programs from the command line.
//!
//! A thin layer: each subcommand parses its arguments, calls library crates
//! and prints or writes the result. Subcommands live in their own modules.

mod cmd_abstract;
mod cmd_batch;
mod cmd_concrete;
mod cmd_demo;
mod cmd_forecast;
mod cmd_grammar;
mod cmd_live;
mod cmd_pose;
mod cmd_refine;
mod cmd_run;
mod cmd_video;
mod live_page;
mod live_view;
mod progress;
mod track_arg;

use std::sync::OnceLock;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Motion programs: keypoints → concrete programs → abstract programs, grammars, forecasts.
#[derive(Parser)]
#[command(name = "mp", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Extract keypoints from a video (BlazePose or MoveNet) into a track.
    Extract(cmd_pose::ExtractArgs),
    /// Draw a track's skeleton on its video: contact sheet (.png) or video (.mp4).
    Overlay(cmd_pose::OverlayArgs),
    /// Fit a concrete program to a track (DP segmentation over primitives).
    Fit(cmd_concrete::FitArgs),
    /// Render a concrete program as a track, at any frame rate.
    Execute(cmd_concrete::ExecuteArgs),
    /// Size and accuracy of a program against its track.
    Stats(cmd_concrete::StatsArgs),
    /// Abstract program of a track: loops of probabilistic primitives.
    Abstract(cmd_abstract::AbstractArgs),
    /// Repetitive intervals of a track, with iterations and counts.
    Loops(cmd_abstract::LoopsArgs),
    /// Live analysis of a file or a stream on standard input (`-`): people, repetitions as they happen.
    Live(cmd_live::LiveArgs),
    /// Change a program loop's iteration count and execute (or write) the edited program.
    Extend(cmd_abstract::ExtendArgs),
    /// Stochastic execution of an abstract program with a seed.
    Sample(cmd_abstract::SampleArgs),
    /// Predict future frames of a track, or continue a video by unrolling its last loop (--seconds).
    Predict(cmd_abstract::PredictArgs),
    /// More or fewer repetitions in a counted interval of a video, on its own frames.
    Edit(cmd_video::EditArgs),
    /// Raise a video's frame rate 2, 4 or 8 times with frames guided by the motion program.
    Interpolate(cmd_video::InterpolateArgs),
    /// The "statue" frame: after which the learned forecaster's accuracy improves most.
    Statue(cmd_forecast::StatueArgs),
    /// Write the procedural performer (jumping jacks, squats, arm circles, a swing) as a track.
    Performer(cmd_demo::PerformerArgs),
    /// The whole pipeline on the procedural performer (the embedded default).
    Demo(cmd_demo::DemoArgs),
    /// Motion grammars: terminal symbols, grammar learning (ABL), synthesis.
    Grammar(cmd_grammar::GrammarArgs),
    /// Video or track → programs, loops, pictures and an HTML report in one folder.
    Run(cmd_run::RunArgs),
    /// Many videos or tracks (a folder or a list) through `mp run`, several at once, with a resumable manifest.
    Batch(cmd_batch::BatchArgs),
    /// Every setting of `mp run` and `mp batch` as JSON: the defaults, or a file's settings completed and checked.
    Params(cmd_run::ParamsArgs),
    /// Refine a 20-joint 3D track: learned flaw detection and repair (anchor and transition networks as options).
    Refine(cmd_refine::RefineArgs),
    /// Learn anchor concepts (clusters + quality model) from MSR Action3D or a folder of tracks.
    Concepts(cmd_refine::ConceptsArgs),
}

/// The parsed command line, for [`given`].
static MATCHES: OnceLock<clap::ArgMatches> = OnceLock::new();

/// Whether the running subcommand's argument `id` (its field name) was
/// given on the command line rather than left at its default.
pub fn given(id: &str) -> bool {
    MATCHES
        .get()
        .and_then(|m| m.subcommand())
        .is_some_and(|(_, m)| {
            m.ids().any(|i| i.as_str() == id)
                && m.value_source(id) == Some(clap::parser::ValueSource::CommandLine)
        })
}

fn main() {
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let _ = MATCHES.set(matches);
    progress::install_ctrl_c();
    let result: anyhow::Result<()> = match cli.command {
        Command::Extract(a) => cmd_pose::extract_cmd(&a),
        Command::Overlay(a) => cmd_pose::overlay_cmd(&a),
        Command::Fit(a) => cmd_concrete::fit(&a),
        Command::Execute(a) => cmd_concrete::execute(&a),
        Command::Stats(a) => cmd_concrete::stats(&a),
        Command::Abstract(a) => cmd_abstract::abstract_cmd(&a),
        Command::Loops(a) => cmd_abstract::loops_cmd(&a),
        Command::Live(a) => cmd_live::live_cmd(&a),
        Command::Extend(a) => cmd_abstract::extend_cmd(&a),
        Command::Sample(a) => cmd_abstract::sample_cmd(&a),
        Command::Predict(a) => cmd_abstract::predict_cmd(&a),
        Command::Edit(a) => cmd_video::edit_cmd(&a),
        Command::Interpolate(a) => cmd_video::interpolate_cmd(&a),
        Command::Statue(a) => cmd_forecast::statue_cmd(&a),
        Command::Performer(a) => cmd_demo::performer_cmd(&a),
        Command::Demo(a) => cmd_demo::demo_cmd(&a),
        Command::Grammar(a) => cmd_grammar::grammar_cmd(&a),
        Command::Run(a) => cmd_run::run_cmd(&a),
        Command::Batch(a) => cmd_batch::batch_cmd(&a),
        Command::Params(a) => cmd_run::params_cmd(&a),
        Command::Refine(a) => cmd_refine::refine_cmd(&a),
        Command::Concepts(a) => cmd_refine::concepts_cmd(&a),
    };
    if let Err(e) = result {
        eprintln!("error: {}", error_text(&e));
        std::process::exit(1);
    }
}

/// The error and its causes joined by `: `, as anyhow's `{:#}` does, leaving
/// out a cause whose message the text already holds (library errors that
/// wrap another often print its message in their own).
fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let m = cause.to_string();
        if text.contains(&m) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&m);
    }
    text
}

#[cfg(test)]
mod tests {
    use super::error_text;

    #[derive(Debug, thiserror::Error)]
    #[error("reading x.mp3 as a track: {0}")]
    struct Wrapping(#[source] std::io::Error);

    #[test]
    fn a_cause_already_in_the_message_is_printed_once() {
        let inner = std::io::Error::other("unknown extension `mp3`");
        let e = anyhow::Error::new(Wrapping(inner)).context("mp run");
        assert_eq!(
            error_text(&e),
            "mp run: reading x.mp3 as a track: unknown extension `mp3`"
        );
        let plain = anyhow::anyhow!("inner").context("outer");
        assert_eq!(error_text(&plain), "outer: inner");
    }
}
