//! Every person in a video, with their id, span and mean box:
//! `cargo run --release -p mp-pose --example people -- VIDEO`.

use mp_pose::{extract_people, open_source, ExtractOptions, MultiPose, MultiPoseParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(path) = std::env::args().nth(1) else {
        return Err("usage: people VIDEO".into());
    };
    if std::env::args().nth(2).as_deref() == Some("--single") {
        let ex = mp_pose::extract_file(
            &path,
            mp_pose::ModelChoice::Full,
            &ExtractOptions::default(),
            |_, _| {},
        )?;
        println!(
            "single person: {:.1} fps (estimator, median), found {:.0}%",
            ex.estimator_fps(),
            100.0 * ex.found_fraction()
        );
        return Ok(());
    }
    let mut est = MultiPose::new(MultiPoseParams::default())?;
    let ex = extract_people(
        open_source(std::path::Path::new(&path))?,
        &mut est,
        &ExtractOptions::default(),
        |_, _| {},
    )?;
    println!(
        "{} frames, {} people, {:.0}% of frames with someone, {:.1} fps (estimator, median), {} detector runs",
        ex.people.n_frames(),
        ex.people.len(),
        100.0 * ex.found_fraction(),
        ex.estimator_fps(),
        ex.detector_runs
    );
    for p in ex.people.people() {
        let b = p.mean_box().unwrap_or([0.0; 4]);
        let c = p.track.confidence();
        let found = p.frames_found().max(1) as f64;
        let mean_conf = c.sum() / (found * c.ncols() as f64);
        println!(
            "person {}: frames {}..={} ({} found), mean box [{:.0}, {:.0}, {:.0}, {:.0}], mean visibility {:.2}",
            p.id,
            p.first_frame,
            p.last_frame(),
            p.frames_found(),
            b[0],
            b[1],
            b[2],
            b[3],
            mean_conf
        );
    }
    if let Some(w) = ex.warning() {
        println!("warning: {w}");
    }
    Ok(())
}
