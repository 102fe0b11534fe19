//! The [`Forecaster`] seam and the simple baselines: [`Constant`] and [`LoopUnroll`].

use mp_abstract::PredictParams;
use mp_geom::Track;
use ndarray::{Array2, Array3};
use rayon::prelude::*;

use crate::error::{ForecastError, Result};

/// Predicts the frames that follow an observed track.
///
/// `past` is the observed motion (its last frame is the present); the result
/// holds exactly `horizon` frames with the same joints, dimensions, units, frame
/// rate and skeleton. Predicted joints have confidence 1 (0 for a joint the
/// method cannot place at all, e.g. one never observed).
pub trait Forecaster: Send + Sync {
    /// Short name used in reports (`constant`, `nn`, `loop`, `ar`, `ar_pose`).
    fn name(&self) -> &str;

    /// How many of the latest observed frames the method reads; `None` = all of them.
    /// Evaluation passes at most this many frames.
    fn context_frames(&self) -> Option<usize>;

    /// The `horizon` frames after `past`.
    fn predict(&self, past: &Track, horizon: usize) -> Result<Track>;

    /// [`Forecaster::predict`] for many observed tracks (in parallel or batched where the method can).
    fn predict_batch(&self, pasts: &[Track], horizon: usize) -> Result<Vec<Track>> {
        pasts.par_iter().map(|p| self.predict(p, horizon)).collect()
    }
}

/// The forecasting methods of the toolkit, the choice of `mp predict --method`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[non_exhaustive]
pub enum ForecastMethod {
    /// Hold the last observed pose ([`Constant`]).
    Constant,
    /// Unroll the last loop of the observed frames' abstract program, with
    /// its period and self-match fallbacks (`mp_abstract::unroll`). Default.
    #[default]
    Loop,
    /// Nearest neighbour in a training set ([`crate::NearestNeighbour`]).
    Nn,
    /// The learned autoregressive model on latents, AR on Φ ([`crate::ArSpace::Latent`]).
    Ar,
    /// The learned autoregressive model on poses, AR on Θ ([`crate::ArSpace::Pose`]).
    ArPose,
}

impl ForecastMethod {
    /// Name on the command line: `constant`, `loop`, `nn`, `ar` or `ar-pose`.
    pub fn as_str(self) -> &'static str {
        match self {
            ForecastMethod::Constant => "constant",
            ForecastMethod::Loop => "loop",
            ForecastMethod::Nn => "nn",
            ForecastMethod::Ar => "ar",
            ForecastMethod::ArPose => "ar-pose",
        }
    }
}

pub(crate) fn check_horizon(horizon: usize) -> Result<()> {
    if horizon == 0 {
        return Err(ForecastError::param("horizon", "must be ≥ 1 frame"));
    }
    Ok(())
}

/// Builds the output track of a prediction from positions `H × J × D` and confidence `H × J`.
pub(crate) fn predicted_track(
    past: &Track,
    positions: Array3<f64>,
    confidence: Array2<f64>,
) -> Result<Track> {
    Ok(Track::new(
        positions,
        Some(confidence),
        past.fps(),
        past.units(),
        past.skeleton().clone(),
    )?)
}

/// The no-motion baseline: every joint holds its last observed (valid) position.
#[derive(Debug, Clone, Copy, Default)]
pub struct Constant;

impl Forecaster for Constant {
    fn name(&self) -> &str {
        "constant"
    }
    fn context_frames(&self) -> Option<usize> {
        Some(1)
    }
    fn predict(&self, past: &Track, horizon: usize) -> Result<Track> {
        check_horizon(horizon)?;
        if past.n_frames() == 0 {
            return Err(ForecastError::TooShort {
                what: "constant prediction",
                needed: 1,
                got: 0,
            });
        }
        let (t, j, d) = past.positions().dim();
        let pos = past.positions();
        let conf = past.confidence();
        let mut out = Array3::zeros((horizon, j, d));
        let mut oc = Array2::zeros((horizon, j));
        for jj in 0..j {
            // the latest valid position; a joint never valid in the past keeps its last value with confidence 0
            let (src, c) = match (0..t).rev().find(|&f| conf[[f, jj]] > 0.0) {
                Some(f) => (f, 1.0),
                None => (t - 1, 0.0),
            };
            for h in 0..horizon {
                for k in 0..d {
                    out[[h, jj, k]] = pos[[src, jj, k]];
                }
                oc[[h, jj]] = c;
            }
        }
        predicted_track(past, out, oc)
    }
}

/// Prediction by unrolling the last detected loop of the observed frames
/// (`mp_abstract::unroll`). Where the program abstraction finds no usable
/// loop, the last period of the observed motion measured by autocorrelation
/// is repeated when the motion is periodic (`PredictParams::period_fallback`);
/// otherwise the last pose is held.
#[derive(Debug, Clone)]
pub struct LoopUnroll {
    /// Analysis and unrolling parameters (mp-abstract defaults).
    pub params: PredictParams,
    /// Observed frames the loop detector sees: `Some(n)` = the latest n, `None` = all.
    pub history_frames: Option<usize>,
    name: String,
}

impl LoopUnroll {
    /// `mp-abstract`'s prediction defaults, except that joints missing in every
    /// observed frame are left out of the segmentation instead of refusing the
    /// track (short forecasting contexts often miss an occluded joint throughout).
    pub fn default_params() -> PredictParams {
        let mut p = PredictParams::default();
        p.analysis.synth.unobserved_joints = mp_concrete::UnobservedJoints::Ignore;
        p
    }

    /// Loop unrolling on the latest `history_frames` observed frames (`None` = all).
    pub fn new(params: PredictParams, history_frames: Option<usize>) -> Result<Self> {
        if history_frames.is_some_and(|h| h < 2) {
            return Err(ForecastError::param(
                "history_frames",
                "must be ≥ 2 (loop detection needs motion)",
            ));
        }
        let name = match history_frames {
            Some(_) => "loop".to_string(),
            None => "loop_all".to_string(),
        };
        Ok(LoopUnroll {
            params,
            history_frames,
            name,
        })
    }
}

impl Forecaster for LoopUnroll {
    fn name(&self) -> &str {
        &self.name
    }
    fn context_frames(&self) -> Option<usize> {
        self.history_frames
    }
    fn predict(&self, past: &Track, horizon: usize) -> Result<Track> {
        check_horizon(horizon)?;
        let t = past.n_frames();
        if t < 2 {
            return Err(ForecastError::TooShort {
                what: "loop unrolling",
                needed: 2,
                got: t,
            });
        }
        let start = self.history_frames.map_or(0, |h| t.saturating_sub(h));
        let obs = if start > 0 {
            past.slice_frames(start, t)?
        } else {
            past.clone()
        };
        let n = obs.n_frames();
        let p = mp_abstract::unroll(&obs, n, horizon, &self.params)?;
        let (pos, _, _, _, _) = p.track.into_parts();
        let (h, j, _) = pos.dim();
        // Joints never observed cannot be placed: confidence 0, like the constant baseline.
        let mut conf = Array2::ones((h, j));
        for jj in 0..j {
            if (0..n).all(|f| obs.confidence()[[f, jj]] <= 0.0) {
                conf.column_mut(jj).fill(0.0);
            }
        }
        predicted_track(past, pos, conf)
    }
}
