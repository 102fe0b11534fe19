//! Repetitive intervals of a long recording by local periodicity and dynamic
//! programming.

use serde::{Deserialize, Serialize};

use super::concordance::{node_frames, Concordance};
use super::{channels, standardise, JointSelection, RepetitiveInterval};

/// Parameters of the repetition segmenter (see [`segment_repetitions`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct IntervalParams {
    /// Joints analysed. Default [`JointSelection::Limbs`].
    pub joints: JointSelection,
    /// Subtract each frame's centroid of the selected joints (per coordinate)
    /// so that translation of the whole body does not hide a repetition. Only
    /// applied to positions (pixels, metres), never to unitless features. Default true.
    pub centre_frames: bool,
    /// Shortest period considered, seconds. Default 0.4.
    pub min_period_s: f64,
    /// Longest period considered, seconds. Default 4.
    pub max_period_s: f64,
    /// An interval holds at least this many periods (≥ 1). Default 1.5:
    /// slow exercises (a torso twist, a toe touch) are often done only one
    /// and a half times in a row. Intervals of fewer than two periods must
    /// pass the stricter [`IntervalParams::short_threshold`].
    pub min_cycles: f64,
    /// The score an interval holding fewer than two periods must exceed
    /// (≥ `threshold`, ≤ 2): its self-match is measured over less than one
    /// period of overlap, so chance matches are likelier. Default 0.5.
    pub short_threshold: f64,
    /// Divide each channel of a unitless feature track (joint angles, …) by
    /// its standard deviation over the whole track, so that every channel
    /// weighs the same in the pooled score whatever its range (a joint that
    /// moves a lot in one exercise otherwise dominates the others). Positions
    /// (pixels, metres) are never rescaled. Default true.
    pub standardise_features: bool,
    /// Shortest interval, seconds. Default 1.5.
    pub min_duration_s: f64,
    /// Longest interval, seconds (bounds the search; a longer bout is reported
    /// as consecutive intervals). Default 120.
    pub max_duration_s: f64,
    /// An interval is kept when its periodicity score (see
    /// [`segment_repetitions`]) exceeds this (−2..2). Default 0.4.
    pub threshold: f64,
    /// Cost of each interval, in seconds of perfectly periodic motion: larger
    /// values merge more, but also drop short bouts (an interval of `len`
    /// seconds needs a score above `threshold + interval_penalty_s / len`).
    /// Default 0.25.
    pub interval_penalty_s: f64,
    /// Interval boundaries lie on a grid of this step, seconds (at least one
    /// frame). Default 0.2.
    pub grid_s: f64,
    /// The period of an interval is the shortest lag whose score is a local
    /// maximum reaching this fraction of the best score (multiples of the
    /// period score as high as the period). Default 0.8, in (0, 1].
    pub peak_ratio: f64,
    /// Frames whose motion (mean speed over one period) is below this fraction
    /// of the interval's median are rest: they are trimmed from the ends of an
    /// interval and split it where they last a period or longer (0 = off).
    /// Default 0.2, in [0, 1).
    pub rest_fraction: f64,
    /// Two neighbouring intervals (touching, or at most one grid step apart)
    /// are merged when the whole stretch scores at least this fraction of
    /// their length-weighted mean score (and above the threshold): the same
    /// activity cut in pieces because its period wavered (an arm circle read
    /// at its period and at a harmonic), while two activities in a row score
    /// much lower together. 0 merges every touching pair that passes the
    /// threshold; above 1 never merges. Default 0.7 (chosen by leave-one-recording-out
    /// on the CMU exercise recordings: every fold chose it).
    pub merge_ratio: f64,
    /// Interval lengths tried by the search: every grid step up to where a
    /// step is this fraction of the length, then lengths growing by this
    /// fraction (0: every grid step). Bounds the search's cost per frame on
    /// long recordings. Default 0.05.
    pub length_resolution: f64,
}

impl Default for IntervalParams {
    fn default() -> Self {
        IntervalParams {
            joints: JointSelection::Limbs,
            centre_frames: true,
            min_period_s: 0.4,
            max_period_s: 4.0,
            min_cycles: 1.5,
            short_threshold: 0.5,
            standardise_features: true,
            min_duration_s: 1.5,
            max_duration_s: 120.0,
            threshold: 0.4,
            interval_penalty_s: 0.25,
            grid_s: 0.2,
            peak_ratio: 0.8,
            rest_fraction: 0.2,
            merge_ratio: 0.7,
            length_resolution: 0.05,
        }
    }
}

impl IntervalParams {
    /// Checks every field.
    pub fn validate(&self) -> crate::Result<()> {
        use crate::AbstractError;
        let pos = AbstractError::check_positive;
        pos("min_period_s", self.min_period_s)?;
        pos("max_period_s", self.max_period_s)?;
        pos("min_duration_s", self.min_duration_s)?;
        pos("max_duration_s", self.max_duration_s)?;
        pos("grid_s", self.grid_s)?;
        if self.max_period_s < self.min_period_s {
            return Err(AbstractError::param(
                "max_period_s",
                format!(
                    "{} is below min_period_s {}",
                    self.max_period_s, self.min_period_s
                ),
            ));
        }
        if self.max_duration_s < self.min_duration_s {
            return Err(AbstractError::param(
                "max_duration_s",
                format!(
                    "{} is below min_duration_s {}",
                    self.max_duration_s, self.min_duration_s
                ),
            ));
        }
        if !(self.min_cycles.is_finite() && self.min_cycles >= 1.0) {
            return Err(AbstractError::param(
                "min_cycles",
                format!("must be finite and ≥ 1, got {}", self.min_cycles),
            ));
        }
        if !(self.threshold.is_finite() && (-2.0..=2.0).contains(&self.threshold)) {
            return Err(AbstractError::param(
                "threshold",
                format!("must be in [-2, 2], got {}", self.threshold),
            ));
        }
        if !(self.short_threshold.is_finite()
            && self.short_threshold >= self.threshold
            && self.short_threshold <= 2.0)
        {
            return Err(AbstractError::param(
                "short_threshold",
                format!(
                    "must be in [threshold = {}, 2], got {}",
                    self.threshold, self.short_threshold
                ),
            ));
        }
        if !(self.peak_ratio > 0.0 && self.peak_ratio <= 1.0) {
            return Err(AbstractError::param(
                "peak_ratio",
                format!("must be in (0, 1], got {}", self.peak_ratio),
            ));
        }
        if !(self.rest_fraction >= 0.0 && self.rest_fraction < 1.0) {
            return Err(AbstractError::param(
                "rest_fraction",
                format!("must be in [0, 1), got {}", self.rest_fraction),
            ));
        }
        AbstractError::check_non_negative("interval_penalty_s", self.interval_penalty_s)?;
        AbstractError::check_non_negative("merge_ratio", self.merge_ratio)?;
        AbstractError::check_non_negative("length_resolution", self.length_resolution)?;
        Ok(())
    }
}

/// A repetitive interval found by [`segment_repetitions`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PeriodicSegment {
    /// First frame.
    pub start_frame: usize,
    /// One past the last frame.
    pub end_frame: usize,
    /// Period, frames.
    pub period_frames: usize,
    /// Periodicity score: concordance at the period minus the positive part
    /// of the concordance at half the period.
    pub score: f64,
    /// Repetitions: length / period.
    pub count: f64,
}

impl PeriodicSegment {
    /// Length in frames.
    pub fn len_frames(&self) -> usize {
        self.end_frame - self.start_frame
    }

    /// As a [`RepetitiveInterval`]: `body_size` 0 (no loop body), iteration
    /// boundaries every period, count rounded.
    pub fn to_interval(&self) -> RepetitiveInterval {
        let count = self.count.round().max(0.0) as usize;
        let mut boundaries: Vec<usize> = (0..count)
            .map(|i| self.start_frame + i * self.period_frames)
            .filter(|&b| b < self.end_frame)
            .collect();
        boundaries.push(self.end_frame);
        RepetitiveInterval {
            start_frame: self.start_frame,
            end_frame: self.end_frame,
            body_size: 0,
            iterations: count,
            boundaries,
            count,
            score: self.score,
        }
    }
}

/// Each frame's speed: the distance from its channels (`x`, `n` frames ×
/// `c` channels, row-major) to the next frame's (the last frame: from the
/// one before).
fn frame_speeds(x: &[f64], n: usize, c: usize) -> Vec<f64> {
    (0..n)
        .map(|t| {
            let (a, b) = if t + 1 < n {
                (t, t + 1)
            } else {
                (t.saturating_sub(1), t)
            };
            (0..c)
                .map(|k| (x[b * c + k] - x[a * c + k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect()
}

/// Finds the repetitive intervals of a track (or a feature track, e.g. joint
/// angles) by local periodicity, and counts the repetitions in each.
///
/// The frames are cut at grid points into intervals, each either *rest* or
/// *repetitive*. A repetitive interval `[s, e)` has the period `p`
/// (`min_period_s..=max_period_s`, at most `(e − s) / min_cycles`) maximising
/// its score `C(p) − max(0, C(⌊p/2⌋))`, where `C(l)` is Lin's concordance of
/// the interval with itself shifted by `l` frames (all selected coordinates
/// pooled): a true period repeats the motion (`C(p)` near 1) while half of it
/// does not; a slowly drifting, non-periodic signal has a high `C` at every
/// lag and so a low score. Channels of a unitless feature track are first
/// divided by their standard deviation over the track
/// ([`IntervalParams::standardise_features`]). Dynamic programming picks the
/// partition that maximises `Σ length · (score − threshold) − interval_penalty`
/// over the repetitive intervals (rest scores 0; an interval of fewer than two
/// periods is held to [`IntervalParams::short_threshold`] instead of
/// `threshold`), so a change of exercise, where the
/// motion stops repeating, ends an interval even without a pause. Intervals
/// shorter than `min_duration_s` are not considered. The count of an interval
/// is its length over its period.
///
/// Cost: O(grid points × interval lengths × periods × coordinates); intervals
/// are bounded by `max_duration_s`.
pub fn segment_repetitions(
    track: &mp_geom::Track,
    params: &IntervalParams,
) -> crate::Result<Vec<PeriodicSegment>> {
    use crate::AbstractError;
    params.validate()?;
    let fps = track.fps();
    if !(fps.is_finite() && fps > 0.0) {
        return Err(AbstractError::param(
            "fps",
            format!("track frame rate {fps} is not positive"),
        ));
    }
    let n = track.n_frames();
    if n == 0 {
        return Ok(Vec::new());
    }
    let centre = params.centre_frames && track.units() != mp_geom::Units::Unitless;
    let Some((mut x, n, c)) = channels(track, 0, n, params.joints, centre)? else {
        return Ok(Vec::new());
    };
    // Rest is judged on the motion as recorded (each frame's speed, taken
    // before the channels are standardised); only the periodicity score
    // reads the standardised channels.
    let speed = frame_speeds(&x, n, c);
    if params.standardise_features && track.units() == mp_geom::Units::Unitless {
        standardise(&mut x, n, c);
    }
    let frames = |s: f64| (s * fps).round().max(1.0) as usize;
    let lmin = frames(params.min_period_s);
    let lmax = frames(params.max_period_s).max(lmin);
    let min_len = frames(params.min_duration_s);
    let max_len = frames(params.max_duration_s).max(min_len);
    let step = frames(params.grid_s);
    if n < min_len || c == 0 {
        return Ok(Vec::new());
    }
    let conc = Concordance::new(&x, n, c, lmax, step);
    // The concordance's prefix sums hold all that is read of the channels
    // from here on (an hour of 64 channels: 57 MB freed).
    drop(x);
    let nodes = node_frames(n, step);
    let penalty = params.interval_penalty_s * fps;
    // Best score and period of the interval between nodes i < j.
    let best_of = |s: usize, e: usize| -> Option<(f64, usize)> {
        let len = e - s;
        let top = ((len as f64 / params.min_cycles).floor() as usize).min(lmax);
        if top < lmin {
            return None;
        }
        // Concordance at every lag from half the shortest period up, each
        // computed once (a lag is also half of a longer one).
        let low = (lmin / 2).max(1);
        let at: Vec<Option<f64>> = (low..=top).map(|l| conc.at(s, e, l)).collect();
        let scores: Vec<f64> = (lmin..=top)
            .map(|l| match at[l - low] {
                Some(cl) => cl - at[(l / 2).max(1) - low].unwrap_or(1.0).max(0.0),
                None => f64::NEG_INFINITY,
            })
            .collect();
        let best = scores.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if !best.is_finite() {
            return None;
        }
        // Multiples of the period score as high as the period itself: take the
        // shortest local maximum that comes close to the best.
        let floor = if best > 0.0 {
            params.peak_ratio * best
        } else {
            best
        };
        let k = (0..scores.len()).find(|&k| {
            let left = k == 0 || scores[k] >= scores[k - 1];
            let right = k + 1 == scores.len() || scores[k] >= scores[k + 1];
            left && right && scores[k] >= floor
        })?;
        Some((scores[k], lmin + k))
    };
    let nn = nodes.len();
    let lengths = candidate_lengths(nn, params.length_resolution);
    let mut value = vec![f64::NEG_INFINITY; nn];
    // For each node: the previous node and, for a repetitive interval, its score and period.
    type Step = Option<(usize, Option<(f64, usize)>)>;
    let mut back: Vec<Step> = vec![None; nn];
    value[0] = 0.0;
    for j in 1..nn {
        value[j] = value[j - 1];
        back[j] = Some((j - 1, None));
        let e = nodes[j];
        // Candidate starts, computed in parallel for long rows.
        let cands: Vec<(usize, f64, usize)> = {
            use rayon::prelude::*;
            lengths
                .par_iter()
                .filter_map(|&k| j.checked_sub(k))
                .filter(|&i| {
                    let len = e - nodes[i];
                    len >= min_len && len <= max_len
                })
                .filter_map(|i| best_of(nodes[i], e).map(|(sc, l)| (i, sc, l)))
                .collect()
        };
        for (i, sc, l) in cands {
            let thr = threshold_for(params, e - nodes[i], l);
            if sc <= thr {
                continue;
            }
            let g = value[i] + (e - nodes[i]) as f64 * (sc - thr) - penalty;
            if g > value[j] {
                value[j] = g;
                back[j] = Some((i, Some((sc, l))));
            }
        }
    }
    let mut out = Vec::new();
    let mut j = nn - 1;
    while j > 0 {
        let Some((i, rep)) = back[j] else {
            break;
        };
        if let Some((score, l)) = rep {
            out.push((nodes[i], nodes[j], score, l));
        }
        j = i;
    }
    out.reverse();
    // Neighbours that are one activity: the whole stretch scores nearly as
    // well as its pieces.
    let mut k = 0;
    while k + 1 < out.len() {
        let (a, b) = (out[k], out[k + 1]);
        let touching = b.0 <= a.1 + step;
        let merged = touching
            .then(|| best_of(a.0, b.1))
            .flatten()
            .filter(|&(sc, l)| {
                let (la, lb) = ((a.1 - a.0) as f64, (b.1 - b.0) as f64);
                let mean = (a.2 * la + b.2 * lb) / (la + lb);
                sc > threshold_for(params, b.1 - a.0, l) && sc >= params.merge_ratio * mean
            });
        match merged {
            Some((sc, l)) => {
                out[k] = (a.0, b.1, sc, l);
                out.remove(k + 1);
            }
            None => k += 1,
        }
    }
    let mut segs = Vec::new();
    for (s, e, score, l) in out {
        let pieces = if params.rest_fraction > 0.0 {
            active_runs(&speed, s, e, l, params.rest_fraction)
        } else {
            vec![(s, e)]
        };
        let whole = pieces.len() == 1 && pieces[0] == (s, e);
        for (a, b) in pieces {
            let (score, l) = if whole {
                (score, l)
            } else if b - a < min_len {
                continue;
            } else {
                match best_of(a, b) {
                    Some((sc, l)) if sc > threshold_for(params, b - a, l) => (sc, l),
                    _ => continue,
                }
            };
            segs.push(PeriodicSegment {
                start_frame: a,
                end_frame: b,
                period_frames: l,
                score,
                count: (b - a) as f64 / l as f64,
            });
        }
    }
    Ok(segs)
}

/// The interval lengths, in grid steps, that the search tries (below
/// `max_steps`): every length up to the one where a step is `resolution` of
/// the length, then lengths growing by that fraction (0: every length). A
/// longer bout is still found whole: as consecutive pieces that the merge
/// step joins.
fn candidate_lengths(max_steps: usize, resolution: f64) -> Vec<usize> {
    let mut out = Vec::new();
    let mut k = 1usize;
    while k < max_steps {
        out.push(k);
        k = (k + 1).max((k as f64 * (1.0 + resolution)).round() as usize);
    }
    out
}

/// The score an interval of `len` frames with a period of `period` frames
/// must exceed: [`IntervalParams::short_threshold`] below two periods,
/// [`IntervalParams::threshold`] otherwise.
fn threshold_for(params: &IntervalParams, len: usize, period: usize) -> f64 {
    if len < 2 * period {
        params.short_threshold
    } else {
        params.threshold
    }
}

/// The parts of `[s, e)` that are not rest: frames whose mean speed over a
/// centred window of `period` frames is below `fraction` of the median over
/// `[s, e)` are rest; rest at the ends is trimmed, and rest lasting at least a
/// period inside splits the interval.
fn active_runs(
    speed: &[f64],
    s: usize,
    e: usize,
    period: usize,
    fraction: f64,
) -> Vec<(usize, usize)> {
    let w = period.max(1);
    let n = speed.len();
    let local: Vec<f64> = (s..e)
        .map(|t| {
            let lo = t.saturating_sub(w / 2);
            let hi = (t + w - w / 2).min(n);
            speed[lo..hi].iter().sum::<f64>() / (hi - lo).max(1) as f64
        })
        .collect();
    let mut sorted = local.clone();
    sorted.sort_by(f64::total_cmp);
    let Some(&median) = sorted.get(sorted.len() / 2) else {
        return Vec::new();
    };
    let active: Vec<bool> = local.iter().map(|&v| v >= fraction * median).collect();
    // Runs of active frames; rest gaps shorter than a period are bridged.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut start = None;
    for (k, &a) in active.iter().chain(std::iter::once(&false)).enumerate() {
        match (a, start) {
            (true, None) => start = Some(k),
            (false, Some(st)) => {
                match runs.last_mut() {
                    Some(last) if st - last.1 < w => last.1 = k,
                    _ => runs.push((st, k)),
                }
                start = None;
            }
            _ => {}
        }
    }
    runs.into_iter().map(|(a, b)| (s + a, s + b)).collect()
}

#[cfg(test)]
mod tests {
    use super::candidate_lengths;

    #[test]
    fn lengths_are_dense_then_grow_by_the_resolution() {
        let mut want: Vec<usize> = (1..=30).collect();
        want.extend([32, 34, 36, 38]);
        assert_eq!(candidate_lengths(40, 0.05), want);
        assert_eq!(candidate_lengths(6, 0.0), vec![1, 2, 3, 4, 5]);
        assert!(candidate_lengths(1, 0.05).is_empty());
        // About 90 lengths up to 600 grid steps (two minutes at 0.2 s).
        let n = candidate_lengths(600, 0.05).len();
        assert!((85..=95).contains(&n), "{n}");
    }
}
