//! Prints the concrete segmentation and loops of a CMU mocap6 feature file.
use mp_abstract::{analyze, AbstractParams};
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: cmu_debug FILE")?;
    let c = mp_geom::io::datasets::CmuFeatures::open(&path)?;
    let mut p = AbstractParams::default();
    if let Ok(l) = std::env::var("LAMBDA") {
        p.synth.lambda = if l == "adaptive" { mp_concrete::Lambda::adaptive() } else { mp_concrete::Lambda::fixed(l.parse()?) };
    }
    if let Ok(t) = std::env::var("THR") {
        p.loops.threshold = t.parse()?;
    }
    let a = analyze(&c.track, &p)?;
    println!("unit_scale {:.3} scale {:.1}", a.unit_scale, c.track.scale());
    let mut t = 0;
    for s in &a.concrete.segments {
        let kinds: Vec<&str> = s.primitives.iter().map(|p| p.kind().as_str()).collect();
        println!("{t:>4} +{:<3} {}", s.duration_frames, kinds.join(","));
        t += s.duration_frames;
    }
    println!("{:?}", a.intervals);
    Ok(())
}
