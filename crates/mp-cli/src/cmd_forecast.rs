//! `mp statue`, and the options of `mp predict` read by its nearest-neighbour
//! and learned methods (`mp_forecast::forecast`, `mp_forecast::search_statue`).

use std::path::PathBuf;

use clap::Args;
use mp_forecast::{search_statue, ArSpace, StatueOptions, StatueParams};

/// Options of `mp predict` used by the `nn` and `ar` methods.
#[derive(Args, Debug, Clone, Default)]
pub struct ForecastOpts {
    /// Training set of the `nn` method (Penn Action or MSR Action3D npz; its training
    /// split is indexed). Default: the shared Penn Action train split, if present.
    #[arg(long)]
    pub train: Option<PathBuf>,
    /// Model folder of the `ar` / `ar-pose` methods (default: models/forecast/DATASET:
    /// penn_action for 2D Penn-13, COCO-17 and BlazePose-33 tracks, msr_action3d for 3D MSR-20
    /// tracks and BlazePose-33 world landmarks).
    #[arg(long)]
    pub models: Option<PathBuf>,
}

/// Arguments of `mp statue`.
#[derive(Args, Debug)]
pub struct StatueArgs {
    /// Input track (Penn Action-13, COCO-17 or BlazePose-33 in 2D; MSR-20 or BlazePose-33 world
    /// landmarks in 3D; or any track with the joints of --models).
    pub track: PathBuf,
    #[command(flatten)]
    pub rate: crate::track_arg::RateOpt,
    /// Use AR on poses (Θ) instead of AR on latents (Φ).
    #[arg(long)]
    pub pose_space: bool,
    /// Conditioning frames.
    #[arg(long, default_value_t = StatueParams::default().context_frames)]
    pub context: usize,
    /// Future frames scored after each window.
    #[arg(long, default_value_t = StatueParams::default().future_frames)]
    pub future: usize,
    /// Half-width of the low-pass difference filter, in frames.
    #[arg(long, default_value_t = StatueParams::default().filter_frames)]
    pub filter: usize,
    /// Print the per-window errors as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub opts: ForecastOpts,
}

/// `mp statue`: the frame after which the learned forecaster's error drops most.
pub fn statue_cmd(a: &StatueArgs) -> anyhow::Result<()> {
    let track = crate::track_arg::read_track(&a.track, &a.rate)?;
    let opts = StatueOptions {
        space: if a.pose_space {
            ArSpace::Pose
        } else {
            ArSpace::Latent
        },
        models: a.opts.models.clone(),
        params: StatueParams {
            context_frames: a.context,
            future_frames: a.future,
            filter_frames: a.filter,
        },
        ..StatueOptions::default()
    };
    let found = search_statue(&track, &opts)?;
    if let Some(m) = &found.model.mapping {
        eprintln!("{}", m.explanation());
    }
    let s = &found.statue;
    if a.json {
        println!("{}", serde_json::to_string_pretty(s)?);
    } else {
        println!(
            "statue frame {} ({:.2} s): prediction error drops by {:.3} torso lengths once it is seen",
            s.frame,
            s.frame as f64 / track.fps(),
            s.improvement
        );
    }
    Ok(())
}
