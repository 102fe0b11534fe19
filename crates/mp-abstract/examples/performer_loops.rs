//! Detects the repetitions of the procedural performer and prints them next to the ground truth.
//!
//! `cargo run --release -p mp-abstract --example performer_loops`
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // example code: failing loudly is the point

use mp_abstract::{analyse, AbstractParams};
use mp_geom::{perform, PerformerParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let perf = perform(&PerformerParams::default())?;
    println!("ground truth:");
    for s in &perf.segments {
        println!(
            "  {:<12} frames {:>4}..{:<4} reps {}",
            s.kind.name(),
            s.frames.start,
            s.frames.end,
            s.reps.len()
        );
    }
    let a = analyse(&perf.track_2d, &AbstractParams::default())?;
    println!(
        "{} frames, {} primitives, unit_scale {:.3}",
        perf.track_2d.n_frames(),
        a.prims.len(),
        a.unit_scale
    );
    for i in &a.intervals {
        println!(
            "  loop frames {:>4}..{:<4} body {} iterations {} score {:.2}",
            i.start_frame, i.end_frame, i.body_size, i.iterations, i.score
        );
    }
    Ok(())
}
