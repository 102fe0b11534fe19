//! Prints the segmentation, loop scores and loops of one Penn Action clip.
//! `cargo run --release -p mp-abstract --example penn_debug -- PENN.npz CLIP_INDEX`
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // example code: failing loudly is the point
use mp_abstract::{analyse, AbstractParams};
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: penn_debug FILE INDEX")?;
    let idx: usize = args.next().ok_or("usage: penn_debug FILE INDEX")?.parse()?;
    let penn = mp_geom::PennAction::open(&path)?;
    let info = penn.clip_info(idx)?.clone();
    let mut t = penn.clip(idx)?;
    t.fill_missing();
    let mut p = AbstractParams::default();
    if std::env::var("FRAME").is_ok() {
        p.synth.scale = mp_concrete::Scale::FrameSize {
            frame_px: info.height_px.max(info.width_px) as f64,
        };
    }
    if let Ok(l) = std::env::var("LAMBDA") {
        p.synth.lambda = if l == "adaptive" {
            mp_concrete::Lambda::adaptive()
        } else {
            mp_concrete::Lambda::fixed(l.parse()?)
        };
    }
    p.synth.unobserved_joints = mp_concrete::UnobservedJoints::Ignore;
    let a = analyse(&t, &p)?;
    println!(
        "{} {} frames {} unit_scale {:.3}",
        info.clip_id,
        info.action,
        t.n_frames(),
        a.unit_scale
    );
    let mut f = 0;
    for s in &a.concrete.segments {
        print!("{f}+{} ", s.duration_frames);
        f += s.duration_frames;
    }
    println!();
    for k in 1..=4 {
        let w = 2 * k;
        if w > a.prims.len() {
            break;
        }
        let s: Vec<String> = (0..=a.prims.len().saturating_sub(w))
            .map(|i| {
                format!(
                    "{:.0}",
                    mp_abstract::loops::window_score(&a.prims, i, i + w, k, a.unit_scale).unwrap()
                )
            })
            .collect();
        println!("k={k} w={w}: {}", s.join(" "));
    }
    let period =
        mp_abstract::repetition::estimate_period(&t, 0, t.n_frames(), &Default::default())?;
    println!("loops {:?}\nperiod {:?}", a.intervals, period);
    Ok(())
}
