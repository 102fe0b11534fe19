//! `mp predict VIDEO --seconds S`: the video continued by unrolling its last
//! repetition on pixels.
//!
//! The last repetition of the last counted interval is the cycle: its start is placed
//! where the frames before it match the video's last frames best (pose and
//! pixels, within [`VideoPredictParams::seam_search`] frames of one period
//! earlier), so the cycle is phase-aligned with the end of the video; it is
//! then played again and again, the last [`VideoPredictParams::crossfade`] frames
//! of each repeat faded into the frames one cycle earlier so that every seam
//! joins frames that followed each other in the video. Without counted
//! repetitions in the observed frames, the dominant period of the keypoints (else of
//! the frame thumbnails) is the cycle's length; without any, the
//! nearest-neighbour continuation is used.
//!
//! Baselines (§4.4 of the paper, on frames): [`VideoPredictMethod::Constant`]
//! holds the last frame; [`VideoPredictMethod::Nearest`] plays on from the
//! earlier frame most like the last one (pose and pixels), jumping back the
//! same way whenever it reaches the end, without seam search or fades.

use std::path::{Path, PathBuf};

use mp_abstract::{estimate_period, PeriodParams};
use mp_pipeline::Params;
use serde::Serialize;

use crate::error::{Result, VideoError};
use crate::motion::VideoMotion;
use crate::plan::{render_to_file, Plan, PlanFrame, RenderParams};

/// Longest prediction, seconds.
pub(crate) const MAX_SECONDS: f64 = 3600.0;

/// How the future frames are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[non_exhaustive]
pub enum VideoPredictMethod {
    /// Unroll the last counted repetition (ours).
    #[default]
    Loop,
    /// Hold the last frame.
    Constant,
    /// Play on from the nearest earlier frame.
    Nearest,
}

impl VideoPredictMethod {
    /// Name.
    pub fn as_str(self) -> &'static str {
        match self {
            VideoPredictMethod::Loop => "loop",
            VideoPredictMethod::Constant => "constant",
            VideoPredictMethod::Nearest => "nearest",
        }
    }
}

/// Parameters of a prediction.
#[derive(Debug, Clone, PartialEq)]
pub struct VideoPredictParams {
    /// The cycle's start is searched within this many frames of one period
    /// before the end. Default 4.
    pub seam_search: usize,
    /// Frames faded before each seam. Default 3.
    pub crossfade: usize,
    /// The nearest-neighbour baseline looks at least this many seconds back. Default 0.2.
    pub min_lag_s: f64,
    /// Rendering (memory budget, encoder preset).
    pub render: RenderParams,
}

impl Default for VideoPredictParams {
    fn default() -> Self {
        VideoPredictParams {
            seam_search: 4,
            crossfade: 3,
            min_lag_s: 0.2,
            render: RenderParams::default(),
        }
    }
}

/// What a prediction did.
#[derive(Debug, Clone, Serialize)]
pub struct PredictReport {
    /// The method asked for.
    pub method: VideoPredictMethod,
    /// The method used (`Nearest` when nothing repeats).
    pub used: VideoPredictMethod,
    /// Where the cycle's length came from: `counted repetitions` (the last
    /// interval of `loops.json`'s repetitions), `autocorrelation period`
    /// (no repetition counted in the
    /// observed frames: the dominant period of the keypoints, else of the
    /// frame thumbnails), `nearest frame` or `last frame`.
    pub source: &'static str,
    /// The cycle played `[start, end)` (one frame for `Constant`).
    pub cycle: (usize, usize),
    /// Observed frames.
    pub observed: usize,
    /// Predicted frames.
    pub predicted: usize,
    /// Frame rate.
    pub fps: f64,
    /// The output file, once written.
    pub output: Option<PathBuf>,
    /// The predicted frames (not serialised).
    #[serde(skip)]
    pub plan: Plan,
}

/// Checks a prediction length and turns it into frames.
pub(crate) fn horizon_frames(seconds: f64, fps: f64) -> Result<usize> {
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= MAX_SECONDS) {
        return Err(VideoError::Seconds {
            seconds,
            max: MAX_SECONDS,
        });
    }
    Ok(((seconds * fps).round() as usize).max(1))
}

fn nearest_cycle(m: &VideoMotion, min_lag: usize) -> Option<(usize, usize)> {
    let n = m.n_frames();
    let last = n.checked_sub(1)?;
    let mut best: Option<(usize, f64)> = None;
    for j in 0..last.saturating_sub(min_lag.max(1) - 1) {
        if last - j < min_lag.max(1) {
            continue;
        }
        let d = m.distance(j, last);
        if d.is_finite() && best.is_none_or(|b| d < b.1) {
            best = Some((j, d));
        }
    }
    best.map(|(j, _)| (j + 1, n))
}

/// The period of the last repetition: the last counted interval's, else the dominant
/// period of the keypoints (`mp_abstract::estimate_period`), else of the
/// frame thumbnails.
fn loop_period(m: &VideoMotion) -> Result<Option<(usize, &'static str)>> {
    if let Some(iv) = m.counts.intervals.last() {
        return Ok(Some((iv.period_frames, "counted repetitions")));
    }
    let n = m.n_frames();
    let from = |t: &mp_geom::Track, p: &PeriodParams| -> Result<Option<usize>> {
        Ok(estimate_period(t, 0, n.min(t.n_frames()), p)
            .map_err(|e| VideoError::Edit(format!("period: {e}")))?
            .map(|e| e.period_frames))
    };
    if let Some(p) = from(&m.track, &PeriodParams::default())? {
        return Ok(Some((p, "autocorrelation period")));
    }
    if let Some(th) = &m.thumbnails {
        if let Some(p) = from(th, &PeriodParams::frames())? {
            return Ok(Some((p, "autocorrelation period")));
        }
    }
    Ok(None)
}

impl VideoMotion {
    /// The predicted frames (only those after the observed ones) of this video
    /// for `horizon` frames.
    pub fn plan_prediction(
        &self,
        horizon: usize,
        method: VideoPredictMethod,
        params: &VideoPredictParams,
    ) -> Result<PredictReport> {
        let n = self.n_frames();
        if n < 2 {
            return Err(VideoError::Edit(format!(
                "{} has {n} frame(s), too few to continue",
                self.path.display()
            )));
        }
        let min_lag = ((params.min_lag_s * self.fps()).round() as usize).max(2);
        let mut used = method;
        let mut fade = 0;
        let mut source = match method {
            VideoPredictMethod::Loop => "counted repetitions",
            VideoPredictMethod::Constant => "last frame",
            VideoPredictMethod::Nearest => "nearest frame",
        };
        let cycle = match method {
            VideoPredictMethod::Constant => (n - 1, n),
            VideoPredictMethod::Nearest => nearest_cycle(self, min_lag).unwrap_or((n - 1, n)),
            VideoPredictMethod::Loop => {
                self.require_person()?;
                match loop_period(self)? {
                    Some((p, src)) if p >= 2 => {
                        fade = params.crossfade;
                        source = src;
                        let p = p.min(n - 1);
                        // The cycle ends at the video's end; its start is where
                        // the frame before it looks most like the last frame.
                        let s0 = n - p;
                        let r = params.seam_search.min(p / 2);
                        let mut best = (s0, f64::INFINITY);
                        for s in s0.saturating_sub(r).max(1)..=(s0 + r).min(n - 2) {
                            let d = self.distance(s - 1, n - 1);
                            if d < best.1 {
                                best = (s, d);
                            }
                        }
                        (best.0, n)
                    }
                    _ => {
                        used = VideoPredictMethod::Nearest;
                        nearest_cycle(self, min_lag).unwrap_or((n - 1, n))
                    }
                }
            }
        };
        let (s, e) = cycle;
        let len = (e - s).max(1);
        let fade = fade.min(len / 2).min(s);
        let mut plan = Plan::default();
        for i in 0..horizon {
            let j = i % len;
            let f = s + j;
            // Before each seam, fade into the frames one cycle earlier.
            let to_seam = len - j;
            if fade > 0 && to_seam <= fade && i + to_seam < horizon {
                let w = (fade + 1 - to_seam) as f32 / (fade + 1) as f32;
                plan.frames.push(PlanFrame::blend(f, f - len.min(f), w));
            } else {
                plan.frames.push(PlanFrame::copy(f.min(n - 1)));
            }
        }
        if used == VideoPredictMethod::Nearest {
            source = "nearest frame";
        }
        Ok(PredictReport {
            method,
            used,
            source,
            cycle,
            observed: n,
            predicted: horizon,
            fps: self.fps(),
            output: None,
            plan,
        })
    }
}

/// Analyses `input` as `mp run` does (with `analysis`) and writes it to
/// `output` followed by `seconds` of predicted frames (atomically).
pub fn predict_video(
    input: &Path,
    seconds: f64,
    method: VideoPredictMethod,
    params: &VideoPredictParams,
    analysis: &Params,
    output: &Path,
) -> Result<PredictReport> {
    let info = mp_pose::probe(input)?;
    let horizon = horizon_frames(seconds, info.fps)?;
    let m = VideoMotion::analyse(input, analysis, None)?;
    let mut report = m.plan_prediction(horizon, method, params)?;
    let mut whole = Plan::default();
    whole.push_range(0..m.n_frames());
    whole.frames.extend(report.plan.frames.iter().copied());
    render_to_file(input, &whole, output, m.fps(), &params.render)?;
    report.output = Some(output.to_path_buf());
    Ok(report)
}
