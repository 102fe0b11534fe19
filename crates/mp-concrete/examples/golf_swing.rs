//! Fits a concrete program to the first golf swing of Penn Action and prints
//! the right wrist's primitives (compare with the paper's Figure 2a).
//!
//! ```sh
//! cargo run --release -p mp-concrete --example golf_swing [-- CLIP_INDEX_AMONG_GOLF_SWINGS]
//! ```
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // example code: failing loudly is the point

use mp_concrete::{NumberFormat, Program, Scale, SynthParams, UnobservedJoints};
use mp_geom::PennAction;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let nth: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(0);
    let pa = PennAction::open_default()?;
    let golf = pa.clips_of_action("golf_swing");
    let &i = golf.get(nth).ok_or("no such golf swing")?;
    let info = pa.clip_info(i)?;
    let track = pa.clip(i)?;
    let frame_px = info.height_px.max(info.width_px) as f64;
    let params = SynthParams {
        scale: Scale::FrameSize { frame_px },
        unobserved_joints: UnobservedJoints::Ignore,
        ..SynthParams::paper()
    };
    let program = Program::synthesize(&track, &params)?;
    let wrist = program.joint_index("right_wrist").ok_or("no right wrist")?;
    println!(
        "clip {} ({} frames, {}×{} px)",
        info.clip_id, info.n_frames, info.width_px, info.height_px
    );
    print!("{}", program.dsl_joint_block(wrist, NumberFormat::Fixed(2)));
    let st = program.stats(&track)?;
    println!(
        "{} segments, {} parameters (raw {}), KD {:.2} px ({:.2} px at 512 px)",
        st.n_segments,
        st.params_program,
        st.params_raw,
        st.kd,
        st.kd * 512.0 / frame_px
    );
    Ok(())
}
