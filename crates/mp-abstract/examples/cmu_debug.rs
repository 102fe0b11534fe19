//! Prints the concrete segmentation and loops of a CMU mocap6 feature file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // example code: failing loudly is the point
use mp_abstract::{analyse, AbstractParams};
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: cmu_debug FILE")?;
    let c = mp_geom::CmuFeatures::open(&path)?;
    let mut p = AbstractParams::default();
    if let Ok(l) = std::env::var("LAMBDA") {
        p.synth.lambda = if l == "adaptive" {
            mp_concrete::Lambda::adaptive()
        } else {
            mp_concrete::Lambda::fixed(l.parse()?)
        };
    }
    if let Ok(t) = std::env::var("REL") {
        p.loops.relative_threshold = Some(t.parse()?);
    }
    if let Ok(t) = std::env::var("THR") {
        p.loops.threshold = t.parse()?;
    }
    let a = analyse(&c.track, &p)?;
    println!(
        "unit_scale {:.3} scale {:.1}",
        a.unit_scale,
        c.track.scale()
    );
    let mut t = 0;
    for s in &a.concrete.segments {
        let kinds: Vec<&str> = s.primitives.iter().map(|p| p.kind().as_str()).collect();
        println!("{t:>4} +{:<3} {}", s.duration_frames, kinds.join(","));
        t += s.duration_frames;
    }
    println!("{:?}", a.intervals);
    for k in 1..=4 {
        let w = 2 * k;
        let sc: Vec<String> = (0..=a.prims.len().saturating_sub(w))
            .map(|i| {
                format!(
                    "{:.2}",
                    mp_abstract::loops::window_score_with(
                        &a.prims,
                        i,
                        i + w,
                        k,
                        &mp_abstract::LoopParams {
                            unit_scale: a.unit_scale,
                            ..p.loops.clone()
                        }
                    )
                    .map(|x| x.0)
                    .unwrap_or(f64::NAN)
                )
            })
            .collect();
        println!("k={k} w={w}: {}", sc.join(" "));
    }
    Ok(())
}
