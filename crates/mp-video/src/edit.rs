//! `mp edit`: the repetitions of one counted interval of a video made more or
//! fewer, on the video's own frames.
//!
//! Interval `i` (from 1) is `counts.intervals[i - 1]` of the pipeline's
//! analysis (`repetitions.intervals[i - 1]` of `loops.json`), its repetitions
//! the windows between its `boundaries`. The full repetition whose keypoints
//! and thumbnails are closest to the mean repetition (resampled to the
//! period) is the one repeated (or, with its neighbours, removed). Each seam is placed where
//! pose and pixels match best within [`EditParams::seam_search`] frames of
//! the repetition's boundaries, and cross-faded over
//! [`EditParams::crossfade`] frames. Audio is dropped.

use std::path::{Path, PathBuf};

use mp_abstract::CountedInterval;
use mp_pipeline::Params;
use serde::Serialize;

use crate::error::{Result, VideoError};
use crate::motion::VideoMotion;
use crate::plan::{render_to_file, Plan, PlanFrame, RenderParams};

/// What to do with the interval's repetitions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum EditChange {
    /// Set the count to this many repetitions.
    Count(usize),
    /// Add this many repetitions.
    Add(usize),
    /// Remove this many repetitions.
    Remove(usize),
}

/// Parameters of an edit.
#[derive(Debug, Clone, PartialEq)]
pub struct EditParams {
    /// Seams are searched within this many frames of a repetition's
    /// boundaries. Default 4.
    pub seam_search: usize,
    /// Frames cross-faded after each seam. Default 3.
    pub crossfade: usize,
    /// Longest output, seconds. Default 3600.
    pub max_output_s: f64,
    /// Rendering (memory budget, encoder preset).
    pub render: RenderParams,
}

impl Default for EditParams {
    fn default() -> Self {
        EditParams {
            seam_search: 4,
            crossfade: 3,
            max_output_s: 3600.0,
            render: RenderParams::default(),
        }
    }
}

impl EditParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        if self.seam_search > 60 {
            return Err(VideoError::param(
                "seam_search",
                format!("must be at most 60, got {}", self.seam_search),
            ));
        }
        if self.crossfade > 60 {
            return Err(VideoError::param(
                "crossfade",
                format!("must be at most 60, got {}", self.crossfade),
            ));
        }
        if !(self.max_output_s.is_finite() && self.max_output_s > 0.0) {
            return Err(VideoError::param("max_output_s", "must be > 0"));
        }
        Ok(())
    }
}

/// What an edit did. Frame ranges are `[start, end)` here; its JSON
/// (`mp edit --json`) gives them as inclusive `[first, last]` pairs, as
/// `loops.json` does.
#[derive(Debug, Clone, Serialize)]
pub struct EditReport {
    /// The interval's number, from 1 as `mp run` and the report print it
    /// (`loops.json`'s `repetitions.intervals[interval_number - 1]`).
    pub interval_number: usize,
    /// The interval's frames `[start, end)`.
    #[serde(serialize_with = "inclusive")]
    pub interval: (usize, usize),
    /// Its repetitions before the edit.
    pub count_before: usize,
    /// Repetitions added (> 0) or removed (< 0).
    pub change: i64,
    /// The repetition closest to the interval's mean `[start, end)`.
    #[serde(serialize_with = "inclusive")]
    pub repetition: (usize, usize),
    /// The frames repeated (or removed) once, seams included `[start, end)`.
    #[serde(serialize_with = "inclusive")]
    pub segment: (usize, usize),
    /// Pose-and-pixel distance across the seam (1 ≈ two consecutive frames).
    pub seam_cost: f64,
    /// Frames of the input analysed.
    pub frames_in: usize,
    /// Frames of the output.
    pub frames_out: usize,
    /// Frame rate.
    pub fps: f64,
    /// The output file, once written.
    pub output: Option<PathBuf>,
    /// The output plan (not serialised).
    #[serde(skip)]
    pub plan: Plan,
}

/// `[start, end)` as the inclusive `[first, last]` of the JSON.
fn inclusive<S: serde::Serializer>(
    r: &(usize, usize),
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    [r.0, r.1.saturating_sub(1).max(r.0)].serialize(s)
}

/// The full repetitions of an interval (windows at least ¾ of the period long).
fn repetitions(iv: &CountedInterval) -> Vec<(usize, usize)> {
    iv.boundaries
        .windows(2)
        .map(|w| (w[0], w[1]))
        .filter(|(a, b)| 4 * (b - a) >= 3 * iv.period_frames.max(1))
        .collect()
}

/// Index (into `iters`) of the repetition closest to the mean repetition.
fn closest_to_mean(m: &VideoMotion, iters: &[(usize, usize)], period: usize) -> usize {
    let samples = period.clamp(2, 120);
    let feats: Vec<Vec<Vec<f64>>> = iters
        .iter()
        .map(|&(a, b)| {
            (0..samples)
                .map(|k| {
                    let t = a + ((b - a) as f64 * k as f64 / samples as f64) as usize;
                    m.feature(t.min(m.n_frames().saturating_sub(1)))
                })
                .collect()
        })
        .collect();
    let dims = feats.first().and_then(|f| f.first()).map_or(0, |f| f.len());
    let mut mean = vec![vec![0.0; dims]; samples];
    let mut cnt = vec![vec![0usize; dims]; samples];
    for f in &feats {
        for (k, row) in f.iter().enumerate() {
            for (d, v) in row.iter().enumerate().take(dims) {
                if v.is_finite() {
                    mean[k][d] += v;
                    cnt[k][d] += 1;
                }
            }
        }
    }
    for k in 0..samples {
        for d in 0..dims {
            mean[k][d] = if cnt[k][d] > 0 {
                mean[k][d] / cnt[k][d] as f64
            } else {
                f64::NAN
            };
        }
    }
    let score = |f: &Vec<Vec<f64>>| {
        let (mut s, mut n) = (0.0, 0usize);
        for (k, row) in f.iter().enumerate() {
            for (d, v) in row.iter().enumerate().take(dims) {
                let e = v - mean[k][d];
                if e.is_finite() {
                    s += e * e;
                    n += 1;
                }
            }
        }
        if n == 0 {
            f64::INFINITY
        } else {
            s / n as f64
        }
    };
    let mut best = (0, f64::INFINITY);
    for (i, f) in feats.iter().enumerate() {
        let s = score(f);
        if s < best.1 {
            best = (i, s);
        }
    }
    best.0
}

fn around(c: usize, r: usize, lo: usize, hi: usize) -> std::ops::RangeInclusive<usize> {
    c.saturating_sub(r).max(lo)..=(c + r).min(hi)
}

/// Best pair `(s, e)` with `s` near `s0` and `e` near `e0` such that frame
/// `s` can follow frame `e − 1` (frame `s` looks like frame `e`).
fn best_seam(
    m: &VideoMotion,
    s0: usize,
    e0: usize,
    r: usize,
    lo: usize,
    min_len: usize,
) -> Option<(usize, usize, f64)> {
    let n = m.n_frames();
    let mut best: Option<(usize, usize, f64)> = None;
    for s in around(s0, r, lo, n.saturating_sub(1)) {
        for e in around(e0, r, 0, n) {
            if e < s + min_len.max(2) {
                continue;
            }
            let c = if e < n {
                m.distance(s, e)
            } else if s >= 1 {
                m.distance(s - 1, e - 1)
            } else {
                continue;
            };
            // Ties go to the length closest to the boundaries' own.
            let c = c + 1e-6 * ((e - s) as f64 - (e0 - s0) as f64).abs();
            if best.is_none_or(|b| c < b.2) {
                best = Some((s, e, c));
            }
        }
    }
    best
}

/// The plan of an edit of `m`'s counted interval number `interval_number`
/// (from 1, as `mp run` and the report number them:
/// `counts.intervals[interval_number - 1]`).
pub fn plan_edit(
    m: &VideoMotion,
    interval_number: usize,
    change: EditChange,
    params: &EditParams,
) -> Result<EditReport> {
    params.validate()?;
    m.require_person()?;
    let n = m.n_frames();
    let iv = interval_number
        .checked_sub(1)
        .and_then(|i| m.counts.intervals.get(i))
        .ok_or(VideoError::NoInterval {
            number: interval_number,
            available: m.counts.intervals.len(),
        })?;
    let k: i64 = match change {
        EditChange::Count(x) => x as i64 - iv.count as i64,
        EditChange::Add(x) => x as i64,
        EditChange::Remove(x) => -(x as i64),
    };
    let iters = repetitions(iv);
    if iters.is_empty() {
        return Err(VideoError::Edit(format!(
            "interval {interval_number} has no full repetition"
        )));
    }
    let chosen = closest_to_mean(m, &iters, iv.period_frames);
    let (b0, b1) = iters[chosen];
    let r = params.seam_search;
    let c = params.crossfade;
    let mut plan = Plan::default();
    let (segment, cost);
    if k >= 0 {
        let (s, e, cst) = best_seam(m, b0, b1, r, iv.start_frame.min(b0), (b1 - b0) / 2)
            .ok_or_else(|| VideoError::Edit("no seam found".into()))?;
        let len = e - s;
        let max_frames = (params.max_output_s * m.fps()) as usize;
        if n + (k as usize).saturating_mul(len) > max_frames {
            return Err(VideoError::Edit(format!(
                "{k} more repetitions of {len} frames would make the video longer than {} s",
                params.max_output_s
            )));
        }
        plan.push_range(0..e);
        for _ in 0..k {
            for j in 0..len {
                let f = s + j;
                if j < c && e + j < n {
                    plan.frames
                        .push(PlanFrame::blend(e + j, f, (j + 1) as f32 / (c + 1) as f32));
                } else {
                    plan.frames.push(PlanFrame::copy(f));
                }
            }
        }
        plan.push_range(e..n);
        segment = (s, e);
        cost = if k > 0 { cst } else { 0.0 };
        if k == 0 {
            plan = Plan::default();
            plan.push_range(0..n);
        }
    } else {
        let kk = (-k) as usize;
        if kk >= iv.count {
            return Err(VideoError::Edit(format!(
                "cannot remove {kk} of the {} repetitions of interval {interval_number}: at least one must stay",
                iv.count
            )));
        }
        if kk > iters.len() {
            return Err(VideoError::Edit(format!(
                "interval {interval_number} has {} full repetitions, cannot remove {kk}",
                iters.len()
            )));
        }
        let first = chosen.min(iters.len() - kk);
        let (r0, r1) = (iters[first].0, iters[first + kk - 1].1);
        let (s, e, cst) = best_seam(m, r0, r1, r, 0, (r1 - r0) / 2)
            .ok_or_else(|| VideoError::Edit("no seam found".into()))?;
        plan.push_range(0..s);
        let mut j = 0;
        while e + j < n {
            let f = e + j;
            if j < c && s + j < e {
                plan.frames
                    .push(PlanFrame::blend(s + j, f, (j + 1) as f32 / (c + 1) as f32));
            } else {
                plan.frames.push(PlanFrame::copy(f));
            }
            j += 1;
        }
        segment = (s, e);
        cost = cst;
    }
    Ok(EditReport {
        interval_number,
        interval: (iv.start_frame, iv.end_frame),
        count_before: iv.count,
        change: k,
        repetition: (b0, b1),
        segment,
        seam_cost: cost,
        frames_in: n,
        frames_out: plan.len(),
        fps: m.fps(),
        output: None,
        plan,
    })
}

/// Analyses `input` as `mp run` does (with `analysis`), edits counted
/// interval number `interval_number` (from 1, as `mp run` prints it) and
/// writes the result to `output` (atomically).
pub fn edit_video(
    input: &Path,
    interval_number: usize,
    change: EditChange,
    params: &EditParams,
    analysis: &Params,
    output: &Path,
) -> Result<EditReport> {
    params.validate()?;
    let m = VideoMotion::analyse(input, analysis, None)?;
    let mut report = plan_edit(&m, interval_number, change, params)?;
    let written = render_to_file(input, &report.plan, output, m.fps(), &params.render)?;
    report.frames_out = written;
    report.output = Some(output.to_path_buf());
    Ok(report)
}
