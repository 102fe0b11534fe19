//! `mp performer` (the procedural performer as a track) and `mp demo` (the
//! whole `mp run` pipeline on it, the embedded default of the README: programs,
//! loops, pictures and the report).

use std::path::PathBuf;

use clap::Args;
use mp_geom::write_track;
use mp_geom::{perform, PerformerParams};

use mp_pipeline::{Input, Params};

use crate::cmd_run;

/// Arguments of `mp performer`.
#[derive(Args, Debug)]
pub struct PerformerArgs {
    /// Output track (format by extension, as `mp_geom::write_track` writes; `.bvh` and `.c3d` with --3d).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write the 3D track (metres) instead of the 2D one (pixels).
    #[arg(long = "3d")]
    pub three_d: bool,
    /// Random seed of the repetition variation and noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// Arguments of `mp demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "mp-out")]
    pub out: PathBuf,
    /// Random seed of the performer.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// No progress bars or timings.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn performer_cmd(a: &PerformerArgs) -> anyhow::Result<()> {
    let perf = perform(&PerformerParams {
        seed: a.seed,
        ..PerformerParams::default()
    })?;
    let t = if a.three_d {
        &perf.track_3d
    } else {
        &perf.track_2d
    };
    write_track(&a.output, t)?;
    eprintln!(
        "{} frames × {} joints written to {}",
        t.n_frames(),
        t.n_joints(),
        a.output.display()
    );
    for s in &perf.segments {
        eprintln!(
            "  {:<12} frames {:<11} {} repetitions",
            s.kind.name(),
            mp_geom::frames_label(s.frames.start, s.frames.end),
            s.reps.len()
        );
    }
    Ok(())
}

pub fn demo_cmd(a: &DemoArgs) -> anyhow::Result<()> {
    crate::track_arg::check_out_dir(&a.out)?;
    let perf_params = PerformerParams {
        seed: a.seed,
        ..PerformerParams::default()
    };
    let perf = perform(&perf_params)?;
    let (w, h) = perf_params.frame_size_px;
    let track = perf.track_2d.clone();
    let input = Input::Track {
        description: format!(
            "procedural performer (seed {}) · {} frames × {} joints (COCO-17, px) at {} fps · {}×{} frame · {}",
            a.seed,
            track.n_frames(),
            track.n_joints(),
            mp_geom::fps_label(track.fps()),
            w,
            h,
            perf.segments
                .iter()
                .map(|s| format!("{} × {}", s.reps.len(), s.kind.name()))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        title: "procedural performer".into(),
        track,
        frame_size: Some((w, h)),
        // Scale from the performer's own extent (as for any track file), not the canvas size.
        frame_px: None,
        fps_assumed: false,
    };
    let summary = cmd_run::run_or_exit(input, &a.out, &Params::default(), a.quiet)?;
    let o = &summary.outcome;
    let c = &o.counts;
    let repeated: Vec<_> = perf.segments.iter().filter(|s| s.reps.len() >= 2).collect();
    let single: Vec<String> = perf
        .segments
        .iter()
        .filter(|s| s.reps.len() == 1)
        .map(|s| s.kind.name().to_string())
        .collect();
    println!(
        "Repetitions counted: {} (from the {}, {}, confidence {:.2}); the performer repeated {}: {}{}",
        c.total,
        c.signal.as_str(),
        c.method.as_str(),
        c.confidence,
        repeated.iter().map(|s| s.reps.len()).sum::<usize>(),
        repeated
            .iter()
            .map(|s| format!("{} × {}", s.reps.len(), s.kind.name()))
            .collect::<Vec<_>>()
            .join(", "),
        if single.is_empty() {
            String::new()
        } else {
            format!(" (and one {}: a single movement)", single.join(", one "))
        }
    );
    for (k, i) in c.intervals.iter().enumerate() {
        println!(
            "  interval {}: frames {:<11} {} repetition{}  [{}]",
            k + 1,
            mp_geom::frames_label(i.start_frame, i.end_frame),
            i.count,
            if i.count == 1 { "" } else { "s" },
            truth(&perf, i.start_frame, i.end_frame)
        );
    }
    if let Some(an) = &o.analysis {
        println!(
            "Program loops, the `for` statements of the abstract program ({}; ground truth of the performer in brackets):",
            a.out.join("abstract.txt").display()
        );
        for (k, i) in an.intervals.iter().enumerate() {
            println!(
                "  loop {}: frames {:<11} {} iterations of a body of {} primitives  [{}]",
                k + 1,
                mp_geom::frames_label(i.start_frame, i.end_frame),
                i.iterations,
                i.body_size,
                truth(&perf, i.start_frame, i.end_frame)
            );
        }
    }
    println!();
    if !a.quiet {
        println!("{}", cmd_run::stage_table(&summary));
    }
    println!(
        "Results written to {}/ (track.npz, program.txt/.json, abstract.txt/.json, loops.json, plots/, timeline.svg/.png, contact_sheet.png)",
        a.out.display()
    );
    if let Some(r) = &summary.report {
        println!("Open the report: {}", r.display());
    }
    Ok(())
}

/// The performer's labelled move overlapping frames `a..b` (IoM > 0.5).
fn truth(perf: &mp_geom::Performance, a: usize, b: usize) -> String {
    perf.segments
        .iter()
        .find(|s| mp_abstract::iom((a, b), (s.frames.start, s.frames.end)) > 0.5)
        .map(|s| format!("{} × {}", s.reps.len(), s.kind.name()))
        .unwrap_or_else(|| "no labelled move".into())
}
