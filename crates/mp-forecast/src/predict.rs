//! One entry point per job: [`forecast`] (the frames after the observed ones,
//! by any [`ForecastMethod`]) and [`search_statue`] (the statue moment of a
//! track under the learned forecaster), with the defaults of `mp predict` and
//! `mp statue`.
//!
//! Both resolve everything a method needs from its options: the training set
//! of the nearest-neighbour baseline (default: the shared Penn Action train
//! split), the model folder of the learned forecasters (default: the one
//! [`model_dataset`] names for the track's skeleton, found by
//! [`ForecastModels::find_dir`]) and the map onto the model's joints for the product's
//! skeletons ([`crate::mapped`]). The result says which path was taken
//! ([`PredictPath`], [`Prediction::explanation`]).

use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Arc;

use mp_abstract::PeriodEstimate;
use mp_abstract::{PredictParams, RepetitiveInterval, SelfMatch, SelfMatchKind};
use mp_geom::PennAction;
use mp_geom::Track;
use mp_onnx::SessionParams;

use crate::data::ForecastDataset;
use crate::error::{ForecastError, Result};
use crate::forecaster::{Constant, ForecastMethod, Forecaster, LoopUnroll};
use crate::mapped::{map_to_model, model_dataset, MappedForecaster};
use crate::model::{ArForecaster, ArParams, ArSpace, ForecastModels};
use crate::nn::{NearestNeighbour, NnParams};
use crate::statue::{find_statue, Statue, StatueParams};

/// The longest horizon [`forecast`] accepts, in frames (whatever the frame rate).
pub const MAX_HORIZON_FRAMES: usize = 100_000;
/// The longest horizon [`forecast`] accepts, in seconds of motion at the track's frame rate.
pub const MAX_HORIZON_SECONDS: f64 = 3600.0;

/// The longest horizon accepted for a track of `fps` frames per second: the
/// smaller of [`MAX_HORIZON_FRAMES`] and [`MAX_HORIZON_SECONDS`] of motion
/// (at least 1 frame).
pub fn max_horizon_frames(fps: f64) -> usize {
    let by_time = if fps.is_finite() && fps > 0.0 {
        (MAX_HORIZON_SECONDS * fps)
            .floor()
            .min(MAX_HORIZON_FRAMES as f64) as usize
    } else {
        MAX_HORIZON_FRAMES
    };
    by_time.clamp(1, MAX_HORIZON_FRAMES)
}

impl FromStr for ForecastMethod {
    type Err = ForecastError;

    /// Parses the names of [`ForecastMethod::as_str`] (`ar_pose` is also accepted).
    fn from_str(s: &str) -> Result<Self> {
        Ok(match s {
            "constant" => ForecastMethod::Constant,
            "loop" => ForecastMethod::Loop,
            "nn" => ForecastMethod::Nn,
            "ar" => ForecastMethod::Ar,
            "ar-pose" | "ar_pose" => ForecastMethod::ArPose,
            other => {
                return Err(ForecastError::param(
                    "method",
                    format!(
                        "unknown forecasting method `{other}` (constant, loop, nn, ar, ar-pose)"
                    ),
                ))
            }
        })
    }
}

/// Everything [`forecast`] needs besides the track; `PredictOptions::default()`
/// is what `mp predict` uses without flags.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictOptions {
    /// The method. Default [`ForecastMethod::Loop`].
    pub method: ForecastMethod,
    /// Training set of [`ForecastMethod::Nn`] (a Penn Action or MSR Action3D
    /// npz; its training split is indexed, see `crate::data`). Default
    /// `None`: the shared Penn Action train split, if present.
    pub train: Option<PathBuf>,
    /// Model folder of [`ForecastMethod::Ar`] / [`ForecastMethod::ArPose`].
    /// Default `None`: `models/forecast/<dataset>` with the data set that
    /// `model_dataset` names for the track's skeleton.
    pub models: Option<PathBuf>,
    /// Loop unrolling of [`ForecastMethod::Loop`]. Default
    /// [`LoopUnroll::default_params`]: `mp-abstract`'s prediction defaults
    /// with joints never observed left out of the segmentation, as the
    /// analysis of `mp run` does.
    pub loop_params: PredictParams,
    /// The nearest-neighbour index. Default [`NnParams::default`].
    pub nn_params: NnParams,
    /// The learned forecasters. Default [`ArParams::default`].
    pub ar_params: ArParams,
    /// ONNX Runtime sessions of the learned forecasters. Default [`SessionParams::default`].
    pub session: SessionParams,
}

impl Default for PredictOptions {
    fn default() -> Self {
        PredictOptions {
            method: ForecastMethod::default(),
            train: None,
            models: None,
            loop_params: LoopUnroll::default_params(),
            nn_params: NnParams::default(),
            ar_params: ArParams::default(),
            session: SessionParams::default(),
        }
    }
}

impl PredictOptions {
    /// Options for `method` with every other field at its default.
    pub fn with_method(method: ForecastMethod) -> Self {
        PredictOptions {
            method,
            ..PredictOptions::default()
        }
    }

    /// Checks the parameters the chosen method reads.
    pub fn validate(&self) -> Result<()> {
        match self.method {
            ForecastMethod::Constant => {}
            ForecastMethod::Loop => {
                let p = &self.loop_params;
                p.analysis
                    .synth
                    .validate()
                    .map_err(mp_abstract::AbstractError::from)?;
                p.analysis.loops.validate()?;
                for (name, v) in [
                    ("loop_params.max_tail_periods", p.max_tail_periods),
                    ("loop_params.offset_decay_periods", p.offset_decay_periods),
                ] {
                    if !(v.is_finite() && v >= 0.0) {
                        return Err(ForecastError::param(
                            name,
                            format!("must be finite and ≥ 0, got {v}"),
                        ));
                    }
                }
                if let Some(fb) = &p.period_fallback {
                    fb.period.validate()?;
                }
                if let Some(sm) = &p.self_match {
                    sm.validate()?;
                }
            }
            ForecastMethod::Nn => self.nn_params.validate()?,
            ForecastMethod::Ar | ForecastMethod::ArPose => {
                if self.ar_params.max_batch == 0 {
                    return Err(ForecastError::param("ar_params.max_batch", "must be ≥ 1"));
                }
                self.session.validate()?;
            }
        }
        Ok(())
    }

    /// The fewest observed frames the method accepts (2 for loop unrolling, else 1).
    pub fn min_observed_frames(&self) -> usize {
        match self.method {
            ForecastMethod::Loop => 2,
            _ => 1,
        }
    }
}

/// How a track reached a learned model.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelMapping {
    /// The model's data set (`penn_action`, `msr_action3d`).
    pub dataset: String,
    /// The track's skeleton.
    pub source: String,
    /// The model's skeleton.
    pub target: String,
    /// The model's joint count.
    pub target_joints: usize,
}

impl ModelMapping {
    /// One line saying how the track reaches the model and comes back.
    pub fn explanation(&self) -> String {
        format!(
            "forecasting through the {} model: {} joints mapped onto {} ({} joints), the prediction carried back",
            self.dataset, self.source, self.target, self.target_joints
        )
    }
}

/// The learned model a forecast ran on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LearnedModel {
    /// The model's data set (`penn_action`, `msr_action3d`).
    pub dataset: String,
    /// The model folder.
    pub dir: PathBuf,
    /// The map onto the model's joints; `None` when the track has them.
    pub mapping: Option<ModelMapping>,
}

/// Which path produced a [`Prediction`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum PredictPath {
    /// [`ForecastMethod::Constant`]: the last observed pose held.
    Constant,
    /// [`ForecastMethod::Loop`]: the last loop of the observed frames' abstract program unrolled.
    Loop(RepetitiveInterval),
    /// [`ForecastMethod::Loop`] without a usable loop: the last autocorrelation period repeated.
    Period(PeriodEstimate),
    /// [`ForecastMethod::Loop`] without a loop or a period: the observed
    /// motion replayed with its self-match lag (or retraced from its turning frame).
    SelfMatch(SelfMatch),
    /// [`ForecastMethod::Loop`] without any repetition: the last observed pose held.
    Hold,
    /// [`ForecastMethod::Nn`]: the continuation of the nearest training window.
    NearestNeighbour {
        /// The training set.
        train: PathBuf,
    },
    /// [`ForecastMethod::Ar`] / [`ForecastMethod::ArPose`].
    Learned(LearnedModel),
}

impl PredictPath {
    /// One line saying what was done, as `mp predict` prints it; `None` for
    /// the paths that need no explanation (constant, nearest neighbour, a
    /// learned model of the track's own skeleton).
    pub fn explanation(&self) -> Option<String> {
        match self {
            PredictPath::Loop(i) => Some(format!(
                "unrolling the loop of frames {}..{} ({} iterations of body {})",
                i.start_frame, i.end_frame, i.iterations, i.body_size
            )),
            PredictPath::Period(e) => Some(format!(
                "no loop program: repeating the last period of {} frames (autocorrelation {:.2})",
                e.period_frames, e.strength
            )),
            PredictPath::SelfMatch(m) => Some(match m.kind {
                SelfMatchKind::Lag => format!(
                    "no loop program: replaying the motion with its self-match lag of {} frames",
                    m.lag_frames
                ),
                SelfMatchKind::Reflection => format!(
                    "no loop program: retracing the motion backwards from its turning frame {}",
                    m.lag_frames
                ),
            }),
            PredictPath::Hold => {
                Some("no repetition in the observed frames: holding the last pose".to_string())
            }
            PredictPath::Learned(m) => m.mapping.as_ref().map(ModelMapping::explanation),
            PredictPath::Constant | PredictPath::NearestNeighbour { .. } => None,
        }
    }
}

/// The result of [`forecast`].
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// The predicted frames: `horizon` frames after the observed ones, with
    /// the track's skeleton, dimensions, units and frame rate.
    pub track: Track,
    /// The method.
    pub method: ForecastMethod,
    /// The path taken.
    pub path: PredictPath,
    /// KD (mean joint distance, track units) of the prediction to the track's
    /// own frames after the observed ones, when the track holds all `horizon` of them.
    pub actual_kd: Option<f64>,
}

impl Prediction {
    /// See [`PredictPath::explanation`].
    pub fn explanation(&self) -> Option<String> {
        self.path.explanation()
    }
}

/// Checks `observe` against the track and the method.
fn check_observe(track: &Track, observe: usize, min: usize, method: ForecastMethod) -> Result<()> {
    let frames = track.n_frames();
    if observe < min || observe > frames {
        return Err(ForecastError::ObserveOutOfRange {
            observe,
            min,
            frames,
            method: method.as_str(),
        });
    }
    Ok(())
}

/// Checks a horizon: at least 1 frame, at most [`max_horizon_frames`] at the track's frame rate.
pub(crate) fn check_horizon_for(track: &Track, horizon: usize) -> Result<()> {
    if horizon == 0 {
        return Err(ForecastError::param("horizon", "must be ≥ 1 frame"));
    }
    let limit = max_horizon_frames(track.fps());
    if horizon > limit {
        return Err(ForecastError::HorizonTooLong {
            horizon,
            limit,
            fps: track.fps(),
        });
    }
    Ok(())
}

/// Predicts the `horizon` frames after the first `observe` frames of `track`
/// with `opts.method` (see [`PredictOptions`] for where training data and
/// models come from).
///
/// Errors: `observe` outside `1..=frames` (`2..=frames` for loop unrolling),
/// a horizon of 0 frames or beyond `max_horizon_frames`, no model for the
/// track's skeleton, no training set for the nearest-neighbour method, and
/// the errors of the method itself.
pub fn forecast(
    track: &Track,
    observe: usize,
    horizon: usize,
    opts: &PredictOptions,
) -> Result<Prediction> {
    opts.validate()?;
    check_observe(track, observe, opts.min_observed_frames(), opts.method)?;
    check_horizon_for(track, horizon)?;
    let past = track.slice_frames(0, observe)?;
    let (pred, path) = match opts.method {
        ForecastMethod::Constant => (Constant.predict(&past, horizon)?, PredictPath::Constant),
        ForecastMethod::Loop => {
            let p = mp_abstract::unroll(track, observe, horizon, &opts.loop_params)?;
            let path = match (p.used, p.period, p.self_match) {
                (Some(i), _, _) => PredictPath::Loop(i),
                (None, Some(e), _) => PredictPath::Period(e),
                (None, None, Some(m)) => PredictPath::SelfMatch(m),
                (None, None, None) => PredictPath::Hold,
            };
            (p.track, path)
        }
        ForecastMethod::Nn => {
            let (nn, train) = nearest_neighbour(opts.train.as_deref(), &opts.nn_params)?;
            // A track of another product skeleton is mapped onto the
            // training set's joints and the prediction carried back.
            let pred = match map_to_model(track.skeleton(), track.dims(), &nn.skeleton().joints)? {
                Some(map) => MappedForecaster::new(nn, map).predict(&past, horizon)?,
                None => nn.predict(&past, horizon)?,
            };
            (pred, PredictPath::NearestNeighbour { train })
        }
        ForecastMethod::Ar | ForecastMethod::ArPose => {
            let space = if opts.method == ForecastMethod::Ar {
                ArSpace::Latent
            } else {
                ArSpace::Pose
            };
            let (f, model) = learned_forecaster(
                track,
                opts.models.as_deref(),
                space,
                &opts.ar_params,
                &opts.session,
            )?;
            (f.predict(&past, horizon)?, PredictPath::Learned(model))
        }
    };
    let actual_kd = if observe + horizon <= track.n_frames() {
        let truth = track.slice_frames(observe, observe + horizon)?;
        Some(mp_geom::kd(&pred, &truth)?)
    } else {
        None
    };
    Ok(Prediction {
        track: pred,
        method: opts.method,
        path,
        actual_kd,
    })
}

/// The nearest-neighbour forecaster over the training split of `train`
/// (default: the shared Penn Action train split), with the file it read.
pub(crate) fn nearest_neighbour(
    train: Option<&Path>,
    params: &NnParams,
) -> Result<(NearestNeighbour, PathBuf)> {
    let path = match train {
        Some(p) => p.to_path_buf(),
        None => mp_geom::data_file(PennAction::TRAIN_FILE).ok_or_else(|| {
            ForecastError::NoTrainingData(format!(
                "the nn method needs a training set (a Penn Action or MSR Action3D npz; \
                 `mp predict --train PATH`); the shared Penn Action train split ({}) was not found \
                 (set MP_DATA_DIR)",
                PennAction::TRAIN_FILE
            ))
        })?,
    };
    if !path.is_file() {
        return Err(ForecastError::NoTrainingData(format!(
            "the training set {} does not exist",
            path.display()
        )));
    }
    let ds = ForecastDataset::open(&path)?;
    let (train, _) = ds.split();
    let tracks: Vec<Track> = train.iter().map(|c| c.track.clone()).collect();
    if tracks.is_empty() {
        return Err(ForecastError::NoTrainingData(format!(
            "{} holds no training clip",
            path.display()
        )));
    }
    Ok((NearestNeighbour::build(&tracks, params.clone())?, path))
}

/// The model folder for a track: `models` when given, else the folder of the
/// data set that [`model_dataset`] names for the track's skeleton.
pub(crate) fn model_dir_for(track: &Track, models: Option<&Path>) -> Result<PathBuf> {
    match models {
        Some(d) => Ok(d.to_path_buf()),
        None => {
            let ds = model_dataset(track.skeleton(), track.dims()).ok_or_else(|| {
                ForecastError::NoModelForSkeleton {
                    skeleton: track.skeleton().name.clone(),
                    dims: track.dims(),
                }
            })?;
            ForecastModels::find_dir(ds)
        }
    }
}

/// The learned forecaster (AR on Φ for [`ArSpace::Latent`], on Θ for
/// [`ArSpace::Pose`]) for a track, through the map onto the model's joints
/// when the track has another skeleton ([`crate::mapped`]), with the model it runs.
pub(crate) fn learned_forecaster(
    track: &Track,
    models: Option<&Path>,
    space: ArSpace,
    params: &ArParams,
    session: &SessionParams,
) -> Result<(Box<dyn Forecaster>, LearnedModel)> {
    let dir = model_dir_for(track, models)?;
    let loaded = Arc::new(ForecastModels::load(&dir, session)?);
    let map = map_to_model(track.skeleton(), track.dims(), &loaded.manifest().joints)?;
    let dataset = loaded.manifest().dataset.clone();
    let ar = ArForecaster::new(loaded, space, params.clone())?;
    Ok(match map {
        Some(map) => {
            let mapping = ModelMapping {
                dataset: dataset.clone(),
                source: map.source().name.clone(),
                target: map.target().name.clone(),
                target_joints: map.target().len(),
            };
            (
                Box::new(MappedForecaster::new(ar, map)),
                LearnedModel {
                    dataset,
                    dir,
                    mapping: Some(mapping),
                },
            )
        }
        None => (
            Box::new(ar),
            LearnedModel {
                dataset,
                dir,
                mapping: None,
            },
        ),
    })
}

/// Everything [`search_statue`] needs besides the track; the default is what
/// `mp statue` uses without flags.
#[derive(Debug, Clone, PartialEq)]
pub struct StatueOptions {
    /// AR on latents (Φ, default) or on poses (Θ).
    pub space: ArSpace,
    /// Model folder; default `None` as [`PredictOptions::models`].
    pub models: Option<PathBuf>,
    /// The search. Default [`StatueParams::default`].
    pub params: StatueParams,
    /// The learned forecaster. Default [`ArParams::default`].
    pub ar_params: ArParams,
    /// ONNX Runtime sessions. Default [`SessionParams::default`].
    pub session: SessionParams,
}

impl Default for StatueOptions {
    fn default() -> Self {
        StatueOptions {
            space: ArSpace::Latent,
            models: None,
            params: StatueParams::default(),
            ar_params: ArParams::default(),
            session: SessionParams::default(),
        }
    }
}

impl StatueOptions {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        self.params.validate()?;
        if self.ar_params.max_batch == 0 {
            return Err(ForecastError::param("ar_params.max_batch", "must be ≥ 1"));
        }
        self.session.validate()?;
        Ok(())
    }
}

/// The result of [`search_statue`].
#[derive(Debug, Clone, PartialEq)]
pub struct StatueSearch {
    /// The statue frame and the per-window errors.
    pub statue: Statue,
    /// The model the forecasts ran on.
    pub model: LearnedModel,
}

/// The statue moment of `track` under the learned forecaster ([`find_statue`]),
/// with the model found as for [`forecast`].
pub fn search_statue(track: &Track, opts: &StatueOptions) -> Result<StatueSearch> {
    opts.validate()?;
    let (f, model) = learned_forecaster(
        track,
        opts.models.as_deref(),
        opts.space,
        &opts.ar_params,
        &opts.session,
    )?;
    let statue = find_statue(f.as_ref(), track, &opts.params)?;
    Ok(StatueSearch { statue, model })
}

#[cfg(test)]
#[path = "predict_tests.rs"]
mod tests;
