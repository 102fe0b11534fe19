//! Symbol identification on concatenated CMU salsa BVH takes, timed against
//! the paper's ≈ 8 minutes for 8,677 frames and K = 20 (0.5 s per GA
//! generation × 500 generations + ≈ 4 min of annealing).
//!
//! `cargo run --release -p mp-grammar --example salsa_symbols -- [FRAMES] [K]`
//! (defaults: 8677 frames, K = 20). The criterion version of this timing is
//! `cargo bench -p mp-grammar --bench grammar`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // example code: failing loudly is the point

use mp_grammar::{identify_symbols, PoseFeatures, SymbolParams};

/// The paper's time for 8,677 frames, K = 20, in seconds.
const PAPER_SECONDS: f64 = 8.0 * 60.0;

/// CPU time of this process (all threads), seconds, from `/proc/self/stat`
/// (Linux; clock ticks of 1/100 s).
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let frames: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(8677);
    let k: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(20);
    let dir = mp_geom::data_file("cmu_salsa_bvh").ok_or("cmu_salsa_bvh not found")?;
    let track = mp_grammar::salsa_track(&dir, frames)?;
    let cpu0 = cpu_seconds();
    let t0 = std::time::Instant::now();
    let feat = PoseFeatures::from_track(&track, &Default::default())?;
    let params = SymbolParams {
        k,
        ..Default::default()
    };
    let s = identify_symbols(&feat, &params)?;
    let wall = t0.elapsed().as_secs_f64();
    let cpu = cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
    println!(
        "frames {} segments {} F {:.4} R {:.4} E' {:.4} wall {wall:.2} s ({:.0}× the paper's 8 min), \
         CPU {} ({} threads)",
        track.n_frames(),
        s.segments.len(),
        s.quality.f,
        s.quality.r,
        s.quality.e_prime,
        PAPER_SECONDS / wall,
        cpu.map_or("?".into(), |c| format!("{c:.2} s ({:.0}×)", PAPER_SECONDS / c)),
        rayon::current_num_threads(),
    );
    println!("{:?}", s.stats);
    println!("{}", s.text());
    Ok(())
}
