//! The forecasting evaluation protocol (paper 002 §4.2; docs/ALGORITHMS.md, "Forecasting").
//!
//! For every clip and every start frame `s` (every frame in 2D, every 25th in
//! 3D: [`EvalParams::start_stride_frames`]) with at least one frame after the
//! context, a method sees the observed frames up to `s + context_frames`
//! (at most its [`Forecaster::context_frames`] latest ones) and predicts
//! `max(horizons)` frames. The truth is the next `L = min(max horizon, frames
//! left)` frames.
//!
//! * **Without DTW**, the score at horizon `h` is the metric of predicted frame
//!   `h` against true frame `h` (NaN when `h > L`).
//! * **With DTW**, the prediction's first `L` frames are aligned to the `L` true
//!   frames by [`mp_geom::dtw_align`] (steps (1,0), (0,1), (1,1), each
//!   frame matched at least once, monotone; local cost = the **mean Euclidean
//!   distance** over the joints valid in both frames, summed along the path, no
//!   square root: [`DtwCost::Euclidean`]); the score at `h` is the metric of the
//!   aligned frame `h`.
//!
//! Metrics: 2D — PCK@0.05 ([`mp_geom::pck_per_frame_sized`]: the size
//! is the larger side of the clip's annotated person box where the data set has
//! one ([`Clip::box_sizes`], Penn Action), else of the bounding box of the
//! visible true joints; after the optimal scale + translation of the
//! prediction; frames with fewer than 6 visible joints are NaN). 3D — MPJPE after root alignment and PA-MPJPE (similarity transform
//! with the reflection fix), reported in millimetres for metre tracks.
//!
//! Aggregation: per clip, the nan-mean over start frames; overall, the nan-mean
//! over clips (and per action, over the clips of that action).

use std::collections::BTreeMap;

use mp_geom::{
    dtw_align, mpjpe_per_frame, nanmean, pa_mpjpe_per_frame, pck_per_frame_sized, DtwCost,
    PckParams, Poses,
};
use mp_geom::{Track, Units};
use rayon::prelude::*;
use serde::Serialize;

use mp_forecast::Clip;
use mp_forecast::ForecastError;
use mp_forecast::Forecaster;

/// The result of the forecasting protocol (its errors are mp-forecast's).
type Result<T, E = ForecastError> = std::result::Result<T, E>;

/// Parameters of [`evaluate`].
#[derive(Debug, Clone, PartialEq)]
pub struct EvalParams {
    /// Observed frames before each prediction. Default 15.
    pub context_frames: usize,
    /// Horizons reported, in frames. Default 1, 5, 10, 20, 30.
    pub horizons: Vec<usize>,
    /// Frames between start frames. Default 1 (2D); use 25 for 3D ([`EvalParams::for_track`]).
    pub start_stride_frames: usize,
    /// PCK settings (2D). Default α = 0.05, at least 6 visible joints.
    pub pck: PckParams,
    /// DTW local-cost convention. Default [`DtwCost::Euclidean`].
    pub dtw_cost: DtwCost,
    /// Root joint for MPJPE (3D); `None` aligns the mean of the joints. Default: the skeleton's root.
    pub root_joint: Option<usize>,
    /// Factor applied to 3D errors (1000: metres → millimetres). Default 1000 for metre tracks.
    pub error_scale: f64,
    /// Named groups of action classes reported together ([`MetricTable::per_group`]):
    /// the nan-mean over the clips of those classes. Default none.
    pub action_groups: BTreeMap<String, Vec<String>>,
}

impl Default for EvalParams {
    fn default() -> Self {
        EvalParams {
            context_frames: 15,
            horizons: vec![1, 5, 10, 20, 30],
            start_stride_frames: 1,
            pck: PckParams::default(),
            dtw_cost: DtwCost::Euclidean,
            root_joint: None,
            error_scale: 1.0,
            action_groups: BTreeMap::new(),
        }
    }
}

impl EvalParams {
    /// The protocol's defaults for a data set of this track kind: 2D → start at every
    /// frame; 3D → every 25th frame, root from the skeleton (centroid alignment
    /// when the root joint is valid in fewer than half of `track`'s frames),
    /// millimetres for metres.
    pub fn for_track(track: &Track) -> Self {
        let mut p = EvalParams::default();
        if track.dims() == 3 {
            p.start_stride_frames = 25;
            // root alignment on the skeleton's root joint, unless that joint is valid in
            // fewer than half of the frames (MSR's hip centre: ~4 %): then align centroids
            p.root_joint = track.skeleton().root.filter(|&r| {
                let n = track.n_frames();
                r < track.n_joints()
                    && 2 * (0..n).filter(|&t| track.confidence()[[t, r]] > 0.0).count() >= n
            });
            if track.units() == Units::Metres {
                p.error_scale = 1000.0;
            }
        }
        p
    }

    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        if self.context_frames == 0 {
            return Err(ForecastError::param("context_frames", "must be ≥ 1"));
        }
        if self.start_stride_frames == 0 {
            return Err(ForecastError::param("start_stride_frames", "must be ≥ 1"));
        }
        if self.horizons.is_empty() || self.horizons.contains(&0) {
            return Err(ForecastError::param(
                "horizons",
                "must be a non-empty list of horizons ≥ 1 frame",
            ));
        }
        if !(self.error_scale.is_finite() && self.error_scale > 0.0) {
            return Err(ForecastError::param(
                "error_scale",
                "must be finite and > 0",
            ));
        }
        self.pck.validate()?;
        Ok(())
    }

    fn max_horizon(&self) -> usize {
        self.horizons.iter().copied().max().unwrap_or(1)
    }
}

/// Scores at each horizon: `"h1" → value`.
pub type HorizonScores = BTreeMap<String, f64>;

/// One metric (e.g. `pck_dtw`) of one method.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct MetricTable {
    /// Nan-mean over clips of the per-clip means.
    pub overall: HorizonScores,
    /// The same per action class.
    pub per_action: BTreeMap<String, HorizonScores>,
    /// The same per group of classes ([`EvalParams::action_groups`]); groups
    /// without an evaluated clip are left out.
    pub per_group: BTreeMap<String, HorizonScores>,
}

/// Every metric of one method.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct MethodReport {
    /// Method name.
    pub method: String,
    /// Clips evaluated.
    pub clips: usize,
    /// Predictions made (clip × start frame).
    pub predictions: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// `pck`, `pck_dtw` (2D) or `mpjpe`, `mpjpe_dtw`, `pa_mpjpe`, `pa_mpjpe_dtw` (3D).
    pub metrics: BTreeMap<String, MetricTable>,
}

/// Per-clip, per-metric, per-horizon means over the start frames.
type ClipScores = BTreeMap<String, Vec<f64>>;

fn metric_names(dims: usize) -> Vec<&'static str> {
    if dims == 2 {
        vec!["pck", "pck_dtw"]
    } else {
        vec!["mpjpe", "mpjpe_dtw", "pa_mpjpe", "pa_mpjpe_dtw"]
    }
}

/// Per-frame scores of `pred` against `truth` (same length) for one metric family.
fn per_frame(
    pred: Poses<'_>,
    truth: &Track,
    sizes: Option<&[f64]>,
    (dims, pa): (usize, bool),
    params: &EvalParams,
) -> Result<Vec<f64>> {
    Ok(if dims == 2 {
        pck_per_frame_sized(pred, truth, sizes, &params.pck)?
    } else if pa {
        pa_mpjpe_per_frame(pred, truth)?
            .into_iter()
            .map(|v| v * params.error_scale)
            .collect()
    } else {
        mpjpe_per_frame(pred, truth, params.root_joint)?
            .into_iter()
            .map(|v| v * params.error_scale)
            .collect()
    })
}

/// Scores of one prediction: metric name → value per horizon (NaN where not scored).
fn score_prediction(
    pred: &Track,
    truth: &Track,
    sizes: Option<&[f64]>,
    params: &EvalParams,
) -> Result<BTreeMap<&'static str, Vec<f64>>> {
    let l = truth.n_frames();
    let pred = if pred.n_frames() > l {
        pred.slice_frames(0, l)?
    } else {
        pred.clone()
    };
    let dims = truth.dims();
    let at = |v: &[f64]| -> Vec<f64> {
        params
            .horizons
            .iter()
            .map(|&h| v.get(h - 1).copied().unwrap_or(f64::NAN))
            .collect()
    };
    let mut out = BTreeMap::new();
    // pred frames with no valid joint make DTW impossible: score those without DTW only
    let aligned = match dtw_align(&pred, truth, params.dtw_cost) {
        Ok(a) => Some(a),
        Err(mp_geom::GeomError::NoData(_)) => None,
        Err(e) => return Err(e.into()),
    };
    let nan = vec![f64::NAN; params.horizons.len()];
    if dims == 2 {
        out.insert(
            "pck",
            at(&per_frame(
                (&pred).into(),
                truth,
                sizes,
                (2, false),
                params,
            )?),
        );
        out.insert(
            "pck_dtw",
            match &aligned {
                Some(a) => at(&per_frame(a.poses(), truth, sizes, (2, false), params)?),
                None => nan.clone(),
            },
        );
    } else {
        for (name, name_dtw, pa) in [
            ("mpjpe", "mpjpe_dtw", false),
            ("pa_mpjpe", "pa_mpjpe_dtw", true),
        ] {
            out.insert(
                name,
                at(&per_frame(
                    (&pred).into(),
                    truth,
                    sizes,
                    (dims, pa),
                    params,
                )?),
            );
            out.insert(
                name_dtw,
                match &aligned {
                    Some(a) => at(&per_frame(a.poses(), truth, sizes, (dims, pa), params)?),
                    None => nan.clone(),
                },
            );
        }
    }
    Ok(out)
}

/// Evaluates one clip: per metric, per horizon, the nan-mean over start frames; and the prediction count.
pub fn evaluate_clip(
    method: &dyn Forecaster,
    clip: &Track,
    params: &EvalParams,
) -> Result<(ClipScores, usize)> {
    evaluate_clip_sized(method, clip, None, params)
}

/// [`evaluate_clip`] with per-frame PCK reference sizes ([`Clip::box_sizes`]).
pub fn evaluate_clip_sized(
    method: &dyn Forecaster,
    clip: &Track,
    box_sizes: Option<&[f64]>,
    params: &EvalParams,
) -> Result<(ClipScores, usize)> {
    params.validate()?;
    if let Some(b) = box_sizes {
        if b.len() != clip.n_frames() {
            return Err(ForecastError::param(
                "box_sizes",
                format!("{} sizes for a clip of {} frames", b.len(), clip.n_frames()),
            ));
        }
    }
    let c = params.context_frames;
    let hmax = params.max_horizon();
    let t = clip.n_frames();
    let mut starts = Vec::new();
    let mut s = 0;
    while s + c < t {
        starts.push(s);
        s += params.start_stride_frames;
    }
    let names = metric_names(clip.dims());
    if starts.is_empty() {
        let empty = names
            .iter()
            .map(|n| (n.to_string(), vec![f64::NAN; params.horizons.len()]))
            .collect();
        return Ok((empty, 0));
    }
    let keep = method.context_frames();
    let pasts = starts
        .iter()
        .map(|&s| {
            let end = s + c;
            let begin = keep.map_or(0, |k| end.saturating_sub(k.max(1)));
            clip.slice_frames(begin, end)
        })
        .collect::<std::result::Result<Vec<Track>, _>>()?;
    let preds = method.predict_batch(&pasts, hmax)?;
    let scores = starts
        .par_iter()
        .zip(preds.par_iter())
        .map(|(&s, pred)| {
            let end = (s + c + hmax).min(t);
            let truth = clip.slice_frames(s + c, end)?;
            score_prediction(pred, &truth, box_sizes.map(|b| &b[s + c..end]), params)
        })
        .collect::<Result<Vec<_>>>()?;
    let mut out = ClipScores::new();
    for n in names {
        let per_h: Vec<f64> = (0..params.horizons.len())
            .map(|hi| {
                let v: Vec<f64> = scores
                    .iter()
                    .map(|sc| sc.get(n).map_or(f64::NAN, |x| x[hi]))
                    .collect();
                nanmean(&v)
            })
            .collect();
        out.insert(n.to_string(), per_h);
    }
    Ok((out, starts.len()))
}

/// Runs the protocol for one method over clips (all with the same joints and dimensions).
pub fn evaluate(
    method: &dyn Forecaster,
    clips: &[Clip],
    params: &EvalParams,
    mut progress: impl FnMut(usize, usize),
) -> Result<MethodReport> {
    params.validate()?;
    let t0 = std::time::Instant::now();
    let first = clips
        .first()
        .ok_or_else(|| ForecastError::param("clips", "no clip to evaluate"))?;
    let dims = first.track.dims();
    let mut per_clip = Vec::with_capacity(clips.len());
    let mut predictions = 0;
    for (i, clip) in clips.iter().enumerate() {
        if clip.track.dims() != dims || clip.track.n_joints() != first.track.n_joints() {
            return Err(ForecastError::mismatch(
                format!("clip `{}`", clip.name),
                format!("{} joints × {dims} dims", first.track.n_joints()),
                format!(
                    "{} joints × {} dims",
                    clip.track.n_joints(),
                    clip.track.dims()
                ),
            ));
        }
        let (scores, n) =
            evaluate_clip_sized(method, &clip.track, clip.box_sizes.as_deref(), params)?;
        predictions += n;
        per_clip.push(scores);
        progress(i + 1, clips.len());
    }
    let label = |hi: usize| format!("h{}", params.horizons[hi]);
    let aggregate = |members: &[usize], name: &str| -> HorizonScores {
        (0..params.horizons.len())
            .map(|hi| {
                let v: Vec<f64> = members
                    .iter()
                    .map(|&ci| per_clip[ci].get(name).map_or(f64::NAN, |x| x[hi]))
                    .collect();
                (label(hi), nanmean(&v))
            })
            .collect()
    };
    let mut actions: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (i, c) in clips.iter().enumerate() {
        actions.entry(c.action.clone()).or_default().push(i);
    }
    let all: Vec<usize> = (0..clips.len()).collect();
    let groups: Vec<(&String, Vec<usize>)> = params
        .action_groups
        .iter()
        .map(|(g, members)| {
            let idx: Vec<usize> = (0..clips.len())
                .filter(|&i| members.contains(&clips[i].action))
                .collect();
            (g, idx)
        })
        .filter(|(_, idx)| !idx.is_empty())
        .collect();
    let metrics = metric_names(dims)
        .into_iter()
        .map(|name| {
            let table = MetricTable {
                overall: aggregate(&all, name),
                per_action: actions
                    .iter()
                    .map(|(a, m)| (a.clone(), aggregate(m, name)))
                    .collect(),
                per_group: groups
                    .iter()
                    .map(|(g, m)| ((*g).clone(), aggregate(m, name)))
                    .collect(),
            };
            (name.to_string(), table)
        })
        .collect();
    Ok(MethodReport {
        method: method.name().to_string(),
        clips: clips.len(),
        predictions,
        seconds: t0.elapsed().as_secs_f64(),
        metrics,
    })
}
