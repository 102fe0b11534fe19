//! Prints what prediction by unrolling does on a jumping-jack performer.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // example code: failing loudly is the point
use mp_abstract::{analyse, unroll, AbstractParams, PredictParams};
use mp_geom::{perform, Move, PerformerParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let params = PerformerParams {
        moves: vec![(Move::JumpingJack, 8)],
        transition_seconds: 0.0,
        ..PerformerParams::default()
    };
    let perf = perform(&params)?;
    let track = &perf.track_2d;
    let observe = track.n_frames() / 2 + 7;
    println!(
        "frames {} observe {observe} reps {:?}",
        track.n_frames(),
        perf.segments[0].reps
    );
    let a = analyse(&track.slice_frames(0, observe)?, &AbstractParams::default())?;
    println!("intervals {:?}", a.intervals);
    let p = unroll(track, observe, 30, &PredictParams::default())?;
    for h in [0, 5, 10, 20, 29] {
        let pr = p.track.point(h, 9);
        let gt = track.point(observe + h, 9);
        println!(
            "h={h} pred ({:.1},{:.1}) gt ({:.1},{:.1})",
            pr[0], pr[1], gt[0], gt[1]
        );
    }
    Ok(())
}
