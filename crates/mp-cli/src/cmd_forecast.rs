//! `mp statue` and the learned / nearest-neighbour methods of `mp predict`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{bail, Context};
use clap::Args;
use mp_forecast::data::ForecastDataset;
use mp_forecast::model::find_model_dir;
use mp_forecast::{
    find_statue, map_to_model, model_dataset, ArForecaster, ArParams, ArSpace, ForecastModels,
    Forecaster, MappedForecaster, NearestNeighbour, NnParams, StatueParams,
};
use mp_geom::io::datasets::PennAction;
use mp_geom::io::read_track;
use mp_geom::Track;
use mp_pose::SessionParams;

/// Options of `mp predict` used by the `nn` and `ar` methods.
#[derive(Args, Debug, Clone, Default)]
pub struct ForecastOpts {
    /// Training set of the `nn` method (Penn Action or MSR Action3D npz; its training
    /// split is indexed). Default: the shared Penn Action train split, if present.
    #[arg(long)]
    pub train: Option<PathBuf>,
    /// Model folder of the `ar` / `ar-pose` methods (default: models/forecast/<dataset>:
    /// penn_action for 2D Penn-13, COCO-17 and BlazePose-33 tracks, msr_action3d for 3D MSR-20
    /// tracks and BlazePose-33 world landmarks).
    #[arg(long)]
    pub models: Option<PathBuf>,
}

fn load_models(track: &Track, dir: Option<&Path>) -> anyhow::Result<Arc<ForecastModels>> {
    let dir = match dir {
        Some(d) => d.to_path_buf(),
        None => {
            let name = &track.skeleton().name;
            let ds = model_dataset(track.skeleton(), track.dims()).with_context(|| {
                format!(
                    "no forecasting model for a {}D track of skeleton `{name}` (penn13, coco17, blazepose33 \
                     in 2D → penn_action; msr20, blazepose33 world landmarks in 3D → msr_action3d); \
                     pass --models DIR",
                    track.dims()
                )
            })?;
            find_model_dir(ds)?
        }
    };
    Ok(Arc::new(
        ForecastModels::load(&dir, &SessionParams::default())
            .with_context(|| format!("loading forecasting models from {}", dir.display()))?,
    ))
}

/// The learned forecaster (`latent`: AR on Φ; otherwise AR on Θ) for a
/// track, through the map onto the model's joints when the track has
/// another skeleton (`mp_forecast::mapped`).
pub fn ar_forecaster(
    track: &Track,
    opts: &ForecastOpts,
    latent: bool,
) -> anyhow::Result<Box<dyn Forecaster>> {
    let models = load_models(track, opts.models.as_deref())?;
    let map = map_to_model(track.skeleton(), track.dims(), &models.manifest().joints)?;
    let space = if latent {
        ArSpace::Latent
    } else {
        ArSpace::Pose
    };
    let ar = ArForecaster::new(models, space, ArParams::default())?;
    Ok(match map {
        Some(map) => {
            eprintln!(
                "forecasting through the {} model: {} joints mapped onto {} ({} joints), the prediction carried back",
                ar.models().manifest().dataset,
                map.source().name,
                map.target().name,
                map.target().len()
            );
            Box::new(MappedForecaster::new(ar, map))
        }
        None => Box::new(ar),
    })
}

/// The nearest-neighbour forecaster over the training split of `--train`.
pub fn nn_forecaster(opts: &ForecastOpts) -> anyhow::Result<NearestNeighbour> {
    let path = match &opts.train {
        Some(p) => p.clone(),
        None => mp_geom::paths::data_file(PennAction::TRAIN_FILE).context(
            "the nn method needs a training set: pass --train PATH (a Penn Action or MSR Action3D npz); \
             the shared Penn Action train split was not found",
        )?,
    };
    let ds = ForecastDataset::open(&path).with_context(|| format!("reading {}", path.display()))?;
    let (train, _) = ds.split();
    let tracks: Vec<Track> = train.iter().map(|c| c.track.clone()).collect();
    Ok(NearestNeighbour::build(&tracks, NnParams::default())?)
}

/// Predicts with the nn / ar / ar-pose methods: `horizon` frames after the first `observe` frames.
pub fn predict_with(
    method: &str,
    track: &Track,
    observe: usize,
    horizon: usize,
    opts: &ForecastOpts,
) -> anyhow::Result<Track> {
    if observe == 0 || observe > track.n_frames() {
        bail!(
            "--observe must be in 1..={} (the track's length)",
            track.n_frames()
        );
    }
    let past = track.slice_frames(0, observe)?;
    let f: Box<dyn Forecaster> = match method {
        "nn" => Box::new(nn_forecaster(opts)?),
        "ar" => ar_forecaster(track, opts, true)?,
        "ar-pose" => ar_forecaster(track, opts, false)?,
        other => bail!("unknown forecasting method `{other}`"),
    };
    Ok(f.predict(&past, horizon)?)
}

/// Arguments of `mp statue`.
#[derive(Args, Debug)]
pub struct StatueArgs {
    /// Input track (Penn Action-13, COCO-17 or BlazePose-33 in 2D; MSR-20 or BlazePose-33 world
    /// landmarks in 3D; or any track with the joints of --models).
    pub track: PathBuf,
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
    let track = read_track(&a.track).with_context(|| format!("reading {}", a.track.display()))?;
    let f = ar_forecaster(&track, &a.opts, !a.pose_space)?;
    let params = StatueParams {
        context_frames: a.context,
        future_frames: a.future,
        filter_frames: a.filter,
    };
    let s = find_statue(f.as_ref(), &track, &params)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
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
