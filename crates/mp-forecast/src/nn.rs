//! The nearest-neighbour baseline (paper 002 §4.2).
//!
//! Every window of `context_frames` consecutive frames of the training tracks
//! that is followed by at least `min_future_frames` frames is stored in
//! normalised form ([`crate::normalize`]: root-relative to the window's last
//! root, divided by its torso length). A query's latest `context_frames` frames
//! are normalised the same way; the nearest window is the one with the smallest
//! **mean squared** coordinate difference over the joints valid in both
//! (windows sharing fewer than half of the query's valid joint entries are
//! skipped; ties go to the earliest window). Its continuation, normalised by the
//! *training* window's similarity, is mapped back with the *query's* similarity.
//! Missing joints of the continuation are filled by linear interpolation in
//! time within the training track.

use mp_geom::Track;
use ndarray::{Array2, Array3};
use rayon::prelude::*;

use crate::error::{ForecastError, Result};
use crate::forecaster::{check_horizon, predicted_track, Forecaster};
use crate::normalize::{push_features, BodyJoints, Normalizer};

/// Parameters of [`NearestNeighbour`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NnParams {
    /// Frames in a query / training window. Default 15 (paper 002: condition on 15 frames).
    pub context_frames: usize,
    /// A training window is kept only when this many frames follow it. Default 30
    /// (the longest evaluated horizon). Longer queries repeat the last frame.
    pub min_future_frames: usize,
    /// Frames between consecutive training windows. Default 1 (every window).
    pub window_stride_frames: usize,
}

impl Default for NnParams {
    fn default() -> Self {
        NnParams {
            context_frames: 15,
            min_future_frames: 30,
            window_stride_frames: 1,
        }
    }
}

impl NnParams {
    /// Every value ≥ 1.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("context_frames", self.context_frames),
            ("min_future_frames", self.min_future_frames),
            ("window_stride_frames", self.window_stride_frames),
        ] {
            if v == 0 {
                return Err(ForecastError::param(name, "must be ≥ 1"));
            }
        }
        Ok(())
    }
}

struct WindowRef {
    track: usize,
    /// First frame of the window.
    start: usize,
    norm: Normalizer,
}

/// Nearest-neighbour forecaster over a set of training tracks.
pub struct NearestNeighbour {
    params: NnParams,
    body: BodyJoints,
    /// The training tracks' skeleton.
    skeleton: mp_geom::Skeleton,
    n_joints: usize,
    dims: usize,
    /// Per training track: positions with missing joints interpolated, and which joints were ever valid.
    tracks: Vec<(Array3<f64>, Vec<bool>)>,
    windows: Vec<WindowRef>,
    /// `windows × (context · J · D)` normalised coordinates.
    coords: Vec<f32>,
    /// `windows × (context · J)` masks.
    masks: Vec<u8>,
}

impl std::fmt::Debug for NearestNeighbour {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NearestNeighbour")
            .field("params", &self.params)
            .field("windows", &self.windows.len())
            .field("tracks", &self.tracks.len())
            .finish()
    }
}

impl NearestNeighbour {
    /// Indexes every eligible window of `train` (all tracks must share joints and dimensions).
    pub fn build(train: &[Track], params: NnParams) -> Result<Self> {
        params.validate()?;
        let first = train.first().ok_or_else(|| {
            ForecastError::NoTrainingData(
                "the nearest-neighbour baseline got no training track".into(),
            )
        })?;
        let (n_joints, dims) = (first.n_joints(), first.dims());
        let body = BodyJoints::from_skeleton(first.skeleton());
        let c = params.context_frames;
        let per = c * n_joints * dims;
        let mut tracks = Vec::with_capacity(train.len());
        let mut windows = Vec::new();
        let mut coords = Vec::new();
        let mut masks = Vec::new();
        let mut feat = Vec::new();
        for (ti, tr) in train.iter().enumerate() {
            if tr.n_joints() != n_joints || tr.dims() != dims {
                return Err(ForecastError::mismatch(
                    format!("training track {ti}"),
                    format!("{n_joints} joints × {dims} dims (as track 0)"),
                    format!("{} joints × {} dims", tr.n_joints(), tr.dims()),
                ));
            }
            let mut filled = tr.clone();
            filled.fill_missing();
            let ever: Vec<bool> = (0..n_joints)
                .map(|j| (0..tr.n_frames()).any(|f| tr.confidence()[[f, j]] > 0.0))
                .collect();
            let t = tr.n_frames();
            let mut s = 0;
            while s + c + params.min_future_frames <= t {
                let pos = tr.positions();
                let conf = tr.confidence();
                if let Ok(norm) = Normalizer::from_context(
                    pos.slice(ndarray::s![s..s + c, .., ..]),
                    conf.slice(ndarray::s![s..s + c, ..]),
                    &body,
                ) {
                    feat.clear();
                    push_features(tr, s, s + c, &norm, &mut feat);
                    let fpf = n_joints * dims + n_joints;
                    for f in 0..c {
                        let row = &feat[f * fpf..(f + 1) * fpf];
                        coords.extend_from_slice(&row[..n_joints * dims]);
                        masks.extend(row[n_joints * dims..].iter().map(|&m| u8::from(m > 0.5)));
                    }
                    windows.push(WindowRef {
                        track: ti,
                        start: s,
                        norm,
                    });
                }
                s += params.window_stride_frames;
            }
            tracks.push((filled.positions().to_owned(), ever));
        }
        if windows.is_empty() {
            return Err(ForecastError::NoTrainingData(format!(
                "no training track has {} frames ({} context + {} future)",
                c + params.min_future_frames,
                c,
                params.min_future_frames
            )));
        }
        debug_assert_eq!(coords.len(), windows.len() * per);
        Ok(NearestNeighbour {
            params,
            body,
            skeleton: first.skeleton().clone(),
            n_joints,
            dims,
            tracks,
            windows,
            coords,
            masks,
        })
    }

    /// The skeleton of the training tracks (what a track must have, or map
    /// onto: `crate::mapped`).
    pub fn skeleton(&self) -> &mp_geom::Skeleton {
        &self.skeleton
    }

    /// Number of indexed training windows.
    pub fn n_windows(&self) -> usize {
        self.windows.len()
    }

    /// The parameters.
    pub fn params(&self) -> &NnParams {
        &self.params
    }

    /// Index of the nearest window to a query's normalised coordinates and masks, with its distance.
    fn search(&self, q: &[f32], qm: &[u8]) -> Option<(usize, f64)> {
        let per = q.len();
        let d = self.dims;
        let need = (qm.iter().filter(|&&m| m > 0).count() * d)
            .div_ceil(2)
            .max(1);
        let chunk = 256;
        self.coords
            .par_chunks(per * chunk)
            .enumerate()
            .filter_map(|(ci, block)| {
                let mut best: Option<(usize, f64)> = None;
                for (wi, w) in block.chunks_exact(per).enumerate() {
                    let idx = ci * chunk + wi;
                    let wm = &self.masks[idx * qm.len()..(idx + 1) * qm.len()];
                    let (mut s, mut n) = (0.0f32, 0usize);
                    for (e, (&a, &b)) in qm.iter().zip(wm).enumerate() {
                        if a > 0 && b > 0 {
                            for k in 0..d {
                                let x = q[e * d + k] - w[e * d + k];
                                s += x * x;
                            }
                            n += d;
                        }
                    }
                    if n < need {
                        continue;
                    }
                    let dist = s as f64 / n as f64;
                    if best.is_none_or(|(_, b)| dist < b) {
                        best = Some((idx, dist));
                    }
                }
                best
            })
            .reduce_with(|a, b| {
                if b.1 < a.1 || (b.1 == a.1 && b.0 < a.0) {
                    b
                } else {
                    a
                }
            })
    }

    fn predict_one(&self, past: &Track, horizon: usize) -> Result<Track> {
        check_horizon(horizon)?;
        let c = self.params.context_frames;
        if past.n_joints() != self.n_joints || past.dims() != self.dims {
            return Err(ForecastError::mismatch(
                "the nearest-neighbour index",
                format!("{} joints × {} dims", self.n_joints, self.dims),
                format!("{} joints × {} dims", past.n_joints(), past.dims()),
            ));
        }
        let t = past.n_frames();
        if t < c {
            return Err(ForecastError::TooShort {
                what: "nearest-neighbour prediction",
                needed: c,
                got: t,
            });
        }
        let norm = Normalizer::from_track_tail(past, c, &self.body)?;
        let mut feat = Vec::new();
        push_features(past, t - c, t, &norm, &mut feat);
        let (j, d) = (self.n_joints, self.dims);
        let fpf = j * d + j;
        let mut q = Vec::with_capacity(c * j * d);
        let mut qm = Vec::with_capacity(c * j);
        for f in 0..c {
            let row = &feat[f * fpf..(f + 1) * fpf];
            q.extend_from_slice(&row[..j * d]);
            qm.extend(row[j * d..].iter().map(|&m| u8::from(m > 0.5)));
        }
        let (wi, _) = self.search(&q, &qm).ok_or_else(|| {
            ForecastError::NoValidJoints(
                "no training window shares at least half of the query's valid joints".into(),
            )
        })?;
        let w = &self.windows[wi];
        let (pos, ever) = &self.tracks[w.track];
        let tt = pos.dim().0;
        let mut out = Array3::zeros((horizon, j, d));
        let mut conf = Array2::zeros((horizon, j));
        for h in 0..horizon {
            let f = (w.start + c + h).min(tt - 1);
            for jj in 0..j {
                for k in 0..d {
                    let x = w.norm.forward(k, pos[[f, jj, k]]);
                    out[[h, jj, k]] = norm.inverse(k, x);
                }
                conf[[h, jj]] = if ever[jj] { 1.0 } else { 0.0 };
            }
        }
        predicted_track(past, out, conf)
    }
}

impl Forecaster for NearestNeighbour {
    fn name(&self) -> &str {
        "nn"
    }
    fn context_frames(&self) -> Option<usize> {
        Some(self.params.context_frames)
    }
    fn predict(&self, past: &Track, horizon: usize) -> Result<Track> {
        self.predict_one(past, horizon)
    }
}
