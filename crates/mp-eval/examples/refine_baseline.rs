//! Injects known flaws into MSR Action3D clips, refines them with the
//! non-learned baseline and prints MPJPE to the clean clips before and after.
//!
//! `cargo run -p mp-eval --example refine_baseline -- [clip_stride] [lambda] [concepts(0/1)]`
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // example code: failing loudly is the point

use mp_eval::refine::baseline::{evaluate_injected, EvalParams};
use mp_geom::MsrAction3D;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let stride: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(4);
    let lambda: f64 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(200.0);
    let concepts = args.get(3).map(|s| s == "1").unwrap_or(false);
    let data = MsrAction3D::open_default()?;
    let mut p = EvalParams {
        clip_stride: stride,
        use_concepts: concepts,
        ..EvalParams::default()
    };
    p.refine.segment.lambda = lambda;
    let r = evaluate_injected(&data, &p)?;
    println!("{}", serde_json::to_string_pretty(&r)?);
    Ok(())
}
