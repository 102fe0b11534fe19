//! Times the segmentation of long tracks (single thread recommended:
//! `RAYON_NUM_THREADS=1`): the procedural performer (COCO-17, 567 frames)
//! repeated `reps` times, and the synthetic 13-joint track.
//!
//! `cargo run --release -p mp-concrete --example synth_timing -- [reps] [synthetic T…] [--reference]
//! [--squared λ] [--spread seconds]`: `--spread` prices segments as the
//! product does (`Lambda::Spread`, the Euclidean refit) instead of the fixed
//! λ of `SynthParams::paper()`.

use std::time::Instant;

use mp_concrete::synthetic_track;
use mp_concrete::{Continuity, Program, Scale, Segmentation, SynthParams};
use mp_geom::Track;
use mp_geom::{perform, PerformerParams};
use ndarray::{concatenate, Axis};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

fn repeated_performer(reps: usize) -> Res<Track> {
    let p = perform(&PerformerParams::default())?;
    let tr = p.track_2d;
    let views: Vec<_> = (0..reps).map(|_| tr.positions()).collect();
    let pos = concatenate(Axis(0), &views)?;
    let cviews: Vec<_> = (0..reps).map(|_| tr.confidence()).collect();
    let conf = concatenate(Axis(0), &cviews)?;
    Ok(Track::new(
        pos,
        Some(conf),
        tr.fps(),
        tr.units(),
        tr.skeleton().clone(),
    )?)
}

fn main() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let reference = args.iter().any(|a| a == "--reference");
    let squared: Option<f64> = args
        .iter()
        .position(|a| a == "--squared")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok());
    let spread: Option<f64> = args
        .iter()
        .position(|a| a == "--spread")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok());
    let nums: Vec<usize> = args
        .iter()
        .enumerate()
        .filter(|(i, _)| *i == 0 || (args[i - 1] != "--squared" && args[i - 1] != "--spread"))
        .filter_map(|(_, a)| a.parse().ok())
        .collect();
    let reps = nums.first().copied().unwrap_or(18);
    let sizes: Vec<usize> = nums.iter().skip(1).copied().collect();
    let track = repeated_performer(reps)?;
    let mut params = SynthParams::paper();
    if let Some(l) = squared {
        params.fit.norm = mp_geom::ErrorNorm::Squared;
        params.lambda = mp_concrete::Lambda::fixed(l);
    }
    if let Some(sec) = spread {
        params.lambda = mp_concrete::Lambda::spread(sec);
        params.refit_norm = mp_concrete::RefitNorm::Euclidean;
    }
    let t0 = Instant::now();
    let prog = Program::synthesize(&track, &params)?;
    println!(
        "performer ×{reps}: T = {}, J = {}: synthesize {:.3} s ({}), {} segments",
        track.n_frames(),
        track.n_joints(),
        t0.elapsed().as_secs_f64(),
        params.continuity,
        prog.n_segments()
    );
    // The search's work (the same on every machine).
    let (_, st) = Segmentation::search_with_stats(&track, &params)?;
    println!(
        "  search: {} candidates, {} dropped on λ, {} by the O(1) bounds, {} survivors \
         ({} dropped in single precision, {} joints, {} frames; {} dropped exactly; \
         {:.1} exact joints each, {} frames), {} circle fits ({} frames)",
        st.candidates,
        st.pruned_lambda,
        st.pruned_bounds,
        st.survivors,
        st.dropped_coarse,
        st.coarse_joints,
        st.coarse_frames,
        st.dropped_exact,
        st.joints_per_survivor(),
        st.exact_frames,
        st.circle_fits,
        st.circle_frames
    );
    let independent = SynthParams {
        continuity: Continuity::None,
        ..params.clone()
    };
    let t0 = Instant::now();
    let prog = Program::synthesize(&track, &independent)?;
    println!(
        "  with continuity none: {:.3} s, {} segments",
        t0.elapsed().as_secs_f64(),
        prog.n_segments()
    );
    if reference {
        let t0 = Instant::now();
        let s = Segmentation::exhaustive(&track, &params)?;
        let fast = Segmentation::search(&track, &params)?;
        println!(
            "  reference {:.3} s, cost {} vs fast {} (same boundaries: {})",
            t0.elapsed().as_secs_f64(),
            s.cost,
            fast.cost,
            s.boundaries == fast.boundaries
        );
    }
    let px = SynthParams {
        scale: Scale::UnitScale { unit_scale: 1.0 },
        ..params.clone()
    };
    for n in sizes {
        let tr = synthetic_track(n, 7)?;
        let t0 = Instant::now();
        let prog = Program::synthesize(&tr, &px)?;
        println!(
            "synthetic T = {n}: synthesize {:.3} s, {} segments",
            t0.elapsed().as_secs_f64(),
            prog.n_segments()
        );
    }
    Ok(())
}
