//! Self-match unrolling: prediction of a repetitive motion of which about one
//! cycle has been observed.
//!
//! The most recent `w` frames of the observed track are compared with the `w`
//! frames `L` frames earlier, for every lag `L` from `min_lag_s` up to what the
//! observed frames allow. The distance is the mean over the selected joints
//! and the window frames of `|Δposition| + velocity_weight_s · |Δvelocity|`,
//! each window centred on its own mean position (a constant shift of the
//! whole body, e.g. a camera pan, is not a difference of motion), divided by
//! the body scale of the track (the median over frames of the diagonal of the
//! bounding box of the selected joints): a unit-free number, 0 for an exact
//! repetition. The lag of the smallest distance is accepted when
//!
//! * the distance is at most `max_distance` (the windows match),
//! * the motion went away and came back: some shorter lag is at least
//!   `1 / max_return_ratio` times as far (a static or steadily drifting
//!   track has no such lag),
//! * the recent window itself moves by at least `min_window_motion` (mean
//!   path length of the selected joints over the window, body scales): a
//!   still pose is better held than replaced by a replay.
//!
//! The prediction then repeats the observed motion with that lag: future
//! frame `h` (1-based) is observed frame `n − L + ((h − 1) mod L)`, plus the
//! difference between the last observed pose and the frame one lag before
//! it, fading out linearly so that the first predicted frame continues from
//! the last observed one.

use mp_geom::Track;
use ndarray::{Array3, Axis};
use serde::{Deserialize, Serialize};

use crate::error::{AbstractError, Result};
use crate::repetition::{selected_joints, JointSelection};

/// Parameters of self-match unrolling (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SelfMatchFallback {
    /// Length of the compared windows, seconds (at least 2 frames). Default
    /// 0.25: long enough to hold the direction of the motion, short enough to
    /// leave most of a single observed cycle for the lag.
    pub window_s: f64,
    /// Shortest lag, seconds (at least one window and 2 frames). Default 0.25.
    pub min_lag_s: f64,
    /// Longest lag, seconds (the observed frames bound it too). Default 5.
    pub max_lag_s: f64,
    /// Weight of the velocity difference, seconds (a velocity difference of
    /// `v` counts as a position difference of `v · velocity_weight_s`): it
    /// tells a pose passed on the way down from the same pose on the way up.
    /// Default 0.1.
    pub velocity_weight_s: f64,
    /// Largest accepted distance at the lag, body scales. Default 0.1.
    pub max_distance: f64,
    /// The distance at the lag is at most this fraction of the largest
    /// distance at shorter lags. Default 0.5.
    pub max_return_ratio: f64,
    /// Smallest mean path length of the selected joints over the recent
    /// window, body scales. Default 0.02.
    pub min_window_motion: f64,
    /// The offset between the last observed pose and the replayed motion fades
    /// out over this many lags. Default 1.
    pub offset_decay_lags: f64,
    /// Joints compared. Default [`JointSelection::Limbs`].
    pub joints: JointSelection,
    /// When no lag is found, look for a turning point instead (reflection
    /// unrolling, see [`SelfMatchKind::Reflection`]). Default true.
    pub reflect: bool,
    /// Reflection needs the observed motion to go somewhere: in some observed
    /// frame the selected joints are, on average, at least this many body
    /// scales away from their last position. Default 0.1.
    pub min_reflect_motion: f64,
}

impl Default for SelfMatchFallback {
    fn default() -> Self {
        SelfMatchFallback {
            window_s: 0.25,
            min_lag_s: 0.25,
            max_lag_s: 5.0,
            velocity_weight_s: 0.1,
            max_distance: 0.1,
            max_return_ratio: 0.5,
            min_window_motion: 0.02,
            offset_decay_lags: 1.0,
            joints: JointSelection::Limbs,
            reflect: true,
            min_reflect_motion: 0.1,
        }
    }
}

/// How the observed motion is continued.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SelfMatchKind {
    /// The recent frames repeat the frames one lag earlier: the motion is
    /// replayed with that period.
    Lag,
    /// The recent frames retrace, backwards in time, the frames before a
    /// turning point (the way back of a squat retraces the way down): the
    /// motion is played backwards from there, as a repetition returns to where
    /// it started. Used when less than a cycle is observed.
    Reflection,
}

/// What self-match unrolling found, and how well it matched.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SelfMatch {
    /// Lag or reflection.
    pub kind: SelfMatchKind,
    /// [`SelfMatchKind::Lag`]: the lag, frames (the motion is replayed with
    /// this period). [`SelfMatchKind::Reflection`]: the turning frame.
    pub lag_frames: usize,
    /// Distance of the recent window to the window one lag earlier, body scales.
    pub distance: f64,
    /// Largest distance at a shorter lag, body scales (0 for a reflection).
    pub excursion: f64,
    /// [`SelfMatchKind::Lag`]: mean path length of the selected joints over
    /// the recent window; [`SelfMatchKind::Reflection`]: their largest mean
    /// distance from the last observed pose. Body scales.
    pub window_motion: f64,
    /// Body scale of the observed track (track units).
    pub body_scale: f64,
}

impl SelfMatchFallback {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        let pos = AbstractError::check_positive;
        let nonneg = AbstractError::check_non_negative;
        pos("window_s", self.window_s)?;
        pos("min_lag_s", self.min_lag_s)?;
        pos("max_lag_s", self.max_lag_s)?;
        pos("max_distance", self.max_distance)?;
        pos("offset_decay_lags", self.offset_decay_lags)?;
        nonneg("min_reflect_motion", self.min_reflect_motion)?;
        nonneg("velocity_weight_s", self.velocity_weight_s)?;
        nonneg("min_window_motion", self.min_window_motion)?;
        if self.max_lag_s < self.min_lag_s {
            return Err(AbstractError::param(
                "max_lag_s",
                format!("{} is below min_lag_s {}", self.max_lag_s, self.min_lag_s),
            ));
        }
        if !(self.max_return_ratio > 0.0 && self.max_return_ratio <= 1.0) {
            return Err(AbstractError::param(
                "max_return_ratio",
                format!("must be in (0, 1], got {}", self.max_return_ratio),
            ));
        }
        Ok(())
    }

    /// The distance of the recent window to the window `L` frames earlier for
    /// every lag `L` considered, `(lag, distance)`, and the body scale; empty
    /// when the track is too short, has no valid joint or no extent.
    pub fn distances(&self, obs: &Track) -> Result<(Vec<(usize, f64)>, f64)> {
        self.validate()?;
        let fps = obs.fps();
        if !(fps.is_finite() && fps > 0.0) {
            return Err(AbstractError::param(
                "fps",
                format!("track frame rate {fps} is not positive"),
            ));
        }
        let n = obs.n_frames();
        if n < 4 || obs.valid_count() == 0 {
            return Ok((Vec::new(), 0.0));
        }
        let mut t = obs.clone();
        t.fill_missing();
        let joints = observed_joints(obs, self.joints);
        if joints.is_empty() {
            return Ok((Vec::new(), 0.0));
        }
        let p = t.positions();
        let d = p.dim().2;
        let scale = body_scale(&p, &joints);
        if !(scale.is_finite() && scale > 0.0) {
            return Ok((Vec::new(), 0.0));
        }
        let frames = |s: f64| (s * fps).round().max(1.0) as usize;
        let w = frames(self.window_s).max(2);
        let min_lag = frames(self.min_lag_s).max(w).max(2);
        // The earlier window must start at frame ≥ 1 (velocities by central differences).
        let Some(top) = n.checked_sub(w + 1) else {
            return Ok((Vec::new(), scale));
        };
        let max_lag = frames(self.max_lag_s).min(top);
        if max_lag < min_lag {
            return Ok((Vec::new(), scale));
        }
        let vel = |f: usize, j: usize, k: usize| velocity(&p, f, j, k, fps);
        let s0 = n - w;
        let mean = |start: usize| -> Vec<f64> {
            let mut m = vec![0.0; d];
            for f in start..start + w {
                for &j in &joints {
                    for (k, mk) in m.iter_mut().enumerate() {
                        *mk += p[[f, j, k]];
                    }
                }
            }
            let cnt = (w * joints.len()) as f64;
            m.iter().map(|v| v / cnt).collect()
        };
        let m0 = mean(s0);
        let mut out = Vec::with_capacity(max_lag - min_lag + 1);
        for lag in min_lag..=max_lag {
            let s1 = s0 - lag;
            let m1 = mean(s1);
            let mut sum = 0.0;
            for q in 0..w {
                let (fa, fb) = (s0 + q, s1 + q);
                for &j in &joints {
                    let (mut dp, mut dv) = (0.0, 0.0);
                    for k in 0..d {
                        dp += ((p[[fa, j, k]] - m0[k]) - (p[[fb, j, k]] - m1[k])).powi(2);
                        dv += (vel(fa, j, k) - vel(fb, j, k)).powi(2);
                    }
                    sum += dp.sqrt() + self.velocity_weight_s * dv.sqrt();
                }
            }
            out.push((lag, sum / (w * joints.len()) as f64 / scale));
        }
        Ok((out, scale))
    }

    /// The lag to replay, or `None` when the recent motion does not clearly
    /// repeat an earlier part of the observed frames.
    pub fn find_lag(&self, obs: &Track) -> Result<Option<SelfMatch>> {
        let (dist, scale) = self.distances(obs)?;
        // Local minima that the motion reached after moving away: the
        // distance at some shorter lag is at least 1 / max_return_ratio times
        // larger. The best of them.
        let mut excursion = 0.0f64;
        let mut best: Option<(usize, f64, f64)> = None;
        for (i, &(lag, dl)) in dist.iter().enumerate() {
            let left = i == 0 || dl <= dist[i - 1].1;
            let right = i + 1 == dist.len() || dl <= dist[i + 1].1;
            if i > 0
                && left
                && right
                && dl <= self.max_return_ratio * excursion
                && best.is_none_or(|b| dl < b.1)
            {
                best = Some((lag, dl, excursion));
            }
            excursion = excursion.max(dl);
        }
        let Some((lag, distance, excursion)) = best else {
            return Ok(None);
        };
        let window_motion = window_motion(obs, self, scale);
        if !(distance <= self.max_distance && window_motion >= self.min_window_motion) {
            return Ok(None);
        }
        Ok(Some(SelfMatch {
            kind: SelfMatchKind::Lag,
            lag_frames: lag,
            distance,
            excursion,
            window_motion,
            body_scale: scale,
        }))
    }

    /// The turning frame `m` whose reflection best matches the recent
    /// frames: recent frame `n − 1 − q` against frame `2m − (n − 1 − q)`,
    /// positions and negated velocities, windows centred, body scales; `None`
    /// when the match is worse than `max_distance` or the reflected span does
    /// not move.
    pub fn find_turn(&self, obs: &Track) -> Result<Option<SelfMatch>> {
        self.validate()?;
        let n = obs.n_frames();
        let fps = obs.fps();
        if n < 4 || obs.valid_count() == 0 || !(fps.is_finite() && fps > 0.0) {
            return Ok(None);
        }
        let mut t = obs.clone();
        t.fill_missing();
        let joints = observed_joints(obs, self.joints);
        if joints.is_empty() {
            return Ok(None);
        }
        let p = t.positions();
        let d = p.dim().2;
        let scale = body_scale(&p, &joints);
        if !(scale.is_finite() && scale > 0.0) {
            return Ok(None);
        }
        let w = ((self.window_s * fps).round().max(1.0) as usize).max(2);
        if n < 2 * w + 2 {
            return Ok(None);
        }
        let vel = |f: usize, j: usize, k: usize| velocity(&p, f, j, k, fps);
        let mut best: Option<(usize, f64)> = None;
        // Recent frames fa = n − 1 − q map to fb = 2m − fa, which must lie in 1..n.
        for m in w..n - w.div_ceil(2) - 1 {
            let pairs: Vec<(usize, usize)> = (0..w)
                .map(|q| {
                    let fa = n - 1 - q;
                    (fa, (2 * m).saturating_sub(fa))
                })
                .collect();
            if pairs.iter().any(|&(_, fb)| fb < 1 || fb >= n) {
                continue;
            }
            let mut ma = vec![0.0; d];
            let mut mb = vec![0.0; d];
            for &(fa, fb) in &pairs {
                for &j in &joints {
                    for k in 0..d {
                        ma[k] += p[[fa, j, k]];
                        mb[k] += p[[fb, j, k]];
                    }
                }
            }
            let cnt = (w * joints.len()) as f64;
            for k in 0..d {
                ma[k] /= cnt;
                mb[k] /= cnt;
            }
            let mut sum = 0.0;
            for &(fa, fb) in &pairs {
                for &j in &joints {
                    let (mut dp, mut dv) = (0.0, 0.0);
                    for k in 0..d {
                        dp += ((p[[fa, j, k]] - ma[k]) - (p[[fb, j, k]] - mb[k])).powi(2);
                        dv += (vel(fa, j, k) + vel(fb, j, k)).powi(2);
                    }
                    sum += dp.sqrt() + self.velocity_weight_s * dv.sqrt();
                }
            }
            let dist = sum / cnt / scale;
            if best.is_none_or(|b| dist < b.1) {
                best = Some((m, dist));
            }
        }
        let Some((m, distance)) = best else {
            return Ok(None);
        };
        // The observed motion must go somewhere: the largest mean distance of
        // the selected joints from their last observed position.
        let motion = (0..n)
            .map(|f| {
                joints
                    .iter()
                    .map(|&j| {
                        (0..d)
                            .map(|k| (p[[f, j, k]] - p[[n - 1, j, k]]).powi(2))
                            .sum::<f64>()
                            .sqrt()
                    })
                    .sum::<f64>()
                    / joints.len() as f64
            })
            .fold(0.0, f64::max)
            / scale;
        if !(distance <= self.max_distance && motion >= self.min_reflect_motion) {
            return Ok(None);
        }
        Ok(Some(SelfMatch {
            kind: SelfMatchKind::Reflection,
            lag_frames: m,
            distance,
            excursion: 0.0,
            window_motion: motion,
            body_scale: scale,
        }))
    }

    /// The `horizon` frames after `obs` by replaying its motion with the lag
    /// [`SelfMatchFallback::find_lag`] finds or, failing that (and with
    /// `reflect`), by playing it backwards from the turning point
    /// [`SelfMatchFallback::find_turn`] finds (frames before the first are the
    /// first); `None` when neither is found.
    pub fn unroll(&self, obs: &Track, horizon: usize) -> Result<Option<(Track, SelfMatch)>> {
        if horizon == 0 {
            return Err(AbstractError::param("horizon", "must be ≥ 1"));
        }
        let found = match self.find_lag(obs)? {
            Some(m) => Some(m),
            None if self.reflect => self.find_turn(obs)?,
            None => None,
        };
        let Some(m) = found else {
            return Ok(None);
        };
        let n = obs.n_frames();
        let mut filled = obs.clone();
        filled.fill_missing();
        let src = filled.positions();
        let (_, j, d) = src.dim();
        // Source frame of future frame h (1-based), the frame the last observed
        // one corresponds to, and the span over which the junction offset fades.
        let (source, anchor, span): (Box<dyn Fn(usize) -> usize>, usize, usize) = match m.kind {
            SelfMatchKind::Lag => {
                let lag = m.lag_frames;
                (Box::new(move |h| n - lag + (h - 1) % lag), n - 1 - lag, lag)
            }
            SelfMatchKind::Reflection => {
                let turn = m.lag_frames;
                (
                    Box::new(move |h| (2 * turn).saturating_sub(n - 1 + h)),
                    (2 * turn + 1).saturating_sub(n),
                    turn.max(1),
                )
            }
        };
        let decay = (self.offset_decay_lags * span as f64).max(1.0);
        let mut pos = Array3::zeros((horizon, j, d));
        for h in 1..=horizon {
            let f = source(h).min(n - 1);
            let wgt = (1.0 - h as f64 / decay).max(0.0);
            for ji in 0..j {
                for k in 0..d {
                    let off = src[[n - 1, ji, k]] - src[[anchor, ji, k]];
                    pos[[h - 1, ji, k]] = src[[f, ji, k]] + wgt * off;
                }
            }
        }
        Ok(Some((crate::analysis::future_track(obs, pos)?, m)))
    }
}

/// Median over frames of the diagonal of the bounding box of `joints`.
fn body_scale(p: &ndarray::ArrayView3<'_, f64>, joints: &[usize]) -> f64 {
    let (n, _, d) = p.dim();
    let mut diag: Vec<f64> = (0..n)
        .map(|f| {
            (0..d)
                .map(|k| {
                    let (lo, hi) = joints
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |a, &j| {
                            (a.0.min(p[[f, j, k]]), a.1.max(p[[f, j, k]]))
                        });
                    (hi - lo).powi(2)
                })
                .sum::<f64>()
                .sqrt()
        })
        .filter(|v| v.is_finite())
        .collect();
    if diag.is_empty() {
        return 0.0;
    }
    diag.sort_by(f64::total_cmp);
    diag[diag.len() / 2]
}

/// Mean path length of the selected joints over the last window, body scales.
fn window_motion(obs: &Track, params: &SelfMatchFallback, scale: f64) -> f64 {
    let n = obs.n_frames();
    let w = ((params.window_s * obs.fps()).round().max(1.0) as usize).max(2);
    if n < w || scale.is_nan() || scale <= 0.0 {
        return 0.0;
    }
    let mut t = obs.clone();
    t.fill_missing();
    let joints = observed_joints(obs, params.joints);
    let p = t.positions();
    let mut total = 0.0;
    for &j in &joints {
        for f in n - w + 1..n {
            let a = p.index_axis(Axis(0), f);
            let b = p.index_axis(Axis(0), f - 1);
            let s: f64 = (0..p.dim().2)
                .map(|k| (a[[j, k]] - b[[j, k]]).powi(2))
                .sum();
            total += s.sqrt();
        }
    }
    total / joints.len().max(1) as f64 / scale
}

/// The selected joints that are valid in at least one frame.
fn observed_joints(obs: &Track, sel: JointSelection) -> Vec<usize> {
    let n = obs.n_frames();
    selected_joints(obs.skeleton(), sel)
        .into_iter()
        .filter(|&j| (0..n).any(|f| obs.confidence()[[f, j]] > 0.0))
        .collect()
}

/// Velocity of joint `j`, axis `k` at frame `f ≥ 1` of `p` (`T × J × D`), per
/// second: the central difference, or the backward one at the last frame.
fn velocity(p: &ndarray::ArrayView3<'_, f64>, f: usize, j: usize, k: usize, fps: f64) -> f64 {
    let n = p.dim().0;
    let (a, b) = if f + 1 < n {
        (f - 1, f + 1)
    } else {
        (f - 1, f)
    };
    (p[[b, j, k]] - p[[a, j, k]]) / (b - a) as f64 * fps
}
