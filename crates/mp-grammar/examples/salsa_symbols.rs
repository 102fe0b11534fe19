//! Symbol identification on concatenated CMU salsa BVH takes.
//!
//! `cargo run --release -p mp-grammar --example salsa_symbols -- [FRAMES] [K]`
//! (defaults: 8677 frames, K = 20).

use mp_grammar::{identify_symbols, PoseFeatures, SymbolParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let frames: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(8677);
    let k: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(20);
    let dir = mp_geom::paths::data_file("cmu_salsa_bvh").ok_or("cmu_salsa_bvh not found")?;
    let track = mp_grammar::data::salsa_track(&dir, frames)?;
    let t0 = std::time::Instant::now();
    let feat = PoseFeatures::from_track(&track, &Default::default())?;
    let params = SymbolParams {
        k,
        ..Default::default()
    };
    let s = identify_symbols(&feat, &params)?;
    println!(
        "frames {} segments {} F {:.4} R {:.4} E' {:.4} total {:.2}s stats {:?}",
        track.n_frames(),
        s.segments.len(),
        s.quality.f,
        s.quality.r,
        s.quality.e_prime,
        t0.elapsed().as_secs_f64(),
        s.stats
    );
    println!("{}", s.text());
    Ok(())
}
