//! Repetition API: detected repetitive intervals in frames, with iteration
//! boundaries and a repetition count.

use serde::{Deserialize, Serialize};

use crate::loops::DetectedLoop;
use crate::model::DetPrim;

/// A repetitive interval of a track.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RepetitiveInterval {
    /// First frame.
    pub start_frame: usize,
    /// One past the last frame.
    pub end_frame: usize,
    /// Loop-body size (primitives per iteration).
    pub body_size: usize,
    /// Number of iterations.
    pub iterations: usize,
    /// Frame where each iteration starts, plus `end_frame` (length iterations + 1).
    pub boundaries: Vec<usize>,
    /// Repetition count of the interval (= iterations).
    pub count: usize,
    /// Loop score (unit-free, below the detection threshold).
    pub score: f64,
}

/// Converts detected loops (in primitive indices) to frame intervals.
pub fn intervals(
    prims: &[DetPrim],
    loops: &[DetectedLoop],
    first_frame: usize,
) -> Vec<RepetitiveInterval> {
    let mut starts = Vec::with_capacity(prims.len() + 1);
    let mut t = first_frame;
    for p in prims {
        starts.push(t);
        t += p.duration;
    }
    starts.push(t);
    loops
        .iter()
        .filter(|l| l.end <= prims.len() && l.body > 0)
        .map(|l| {
            let boundaries: Vec<usize> = (0..=l.iterations)
                .map(|i| starts[l.start + i * l.body])
                .collect();
            RepetitiveInterval {
                start_frame: starts[l.start],
                end_frame: starts[l.end],
                body_size: l.body,
                iterations: l.iterations,
                boundaries,
                count: l.iterations,
                score: l.score,
            }
        })
        .collect()
}

/// Intersection over the minimum length of two frame intervals `[a0, a1)`, `[b0, b1)`.
pub fn iom(a: (usize, usize), b: (usize, usize)) -> f64 {
    let inter = a.1.min(b.1).saturating_sub(a.0.max(b.0)) as f64;
    let m = (a.1 - a.0).min(b.1 - b.0) as f64;
    if m <= 0.0 {
        0.0
    } else {
        inter / m
    }
}

/// Intersection over union of two frame intervals.
pub fn iou(a: (usize, usize), b: (usize, usize)) -> f64 {
    let inter = a.1.min(b.1).saturating_sub(a.0.max(b.0)) as f64;
    let uni = (a.1 - a.0) as f64 + (b.1 - b.0) as f64 - inter;
    if uni <= 0.0 {
        0.0
    } else {
        inter / uni
    }
}

/// Which joints the periodicity analyses ([`estimate_period`],
/// [`segment_repetitions`]) read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum JointSelection {
    /// Every joint of the track.
    All,
    /// The twelve COCO limb joints (shoulders, elbows, wrists, hips, knees,
    /// ankles) when the skeleton maps to COCO-17; every joint otherwise. Face,
    /// hand and foot landmarks are small, noisy and redundant with the limbs:
    /// on a BlazePose-33 track they are 21 of the 33 joints and would
    /// otherwise dominate the average.
    #[default]
    Limbs,
}

/// Indices of the joints a [`JointSelection`] picks on `skeleton` (never empty
/// for a non-empty skeleton).
pub fn selected_joints(skeleton: &mp_geom::Skeleton, sel: JointSelection) -> Vec<usize> {
    let all: Vec<usize> = (0..skeleton.len()).collect();
    match sel {
        JointSelection::All => all,
        JointSelection::Limbs => {
            if !skeleton.maps_to_coco17() {
                return all;
            }
            let limbs: Vec<usize> = skeleton
                .coco17
                .iter()
                .skip(5)
                .flatten()
                .copied()
                .filter(|&j| j < skeleton.len())
                .collect();
            if limbs.is_empty() {
                all
            } else {
                limbs
            }
        }
    }
}

/// Parameters of period estimation (see [`estimate_period`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PeriodParams {
    /// Moving-average window applied to positions before differencing (frames). Default 3.
    pub smooth_frames: usize,
    /// Shortest period considered, seconds. Default 0.25.
    pub min_period_s: f64,
    /// The period is the first autocorrelation peak reaching this fraction of the
    /// highest peak (guards against picking a multiple of the period). Default 0.7.
    pub peak_ratio: f64,
    /// Joints analysed. Default [`JointSelection::Limbs`].
    pub joints: JointSelection,
    /// Periods longer than `frames / min_cycles` are not considered: a
    /// repetition is established by this many cycles. Default 3 (≥ 1).
    pub min_cycles: f64,
    /// Biased autocorrelation (each lag's sum divided by the number of frames,
    /// the standard estimator) instead of the unbiased one (divided by the
    /// number of overlapping frames). The biased estimate shrinks long lags,
    /// which are averaged over few frames and noisy. Default true.
    pub biased: bool,
}

impl Default for PeriodParams {
    fn default() -> Self {
        PeriodParams {
            smooth_frames: 3,
            min_period_s: 0.25,
            peak_ratio: 0.7,
            joints: JointSelection::Limbs,
            min_cycles: 3.0,
            biased: true,
        }
    }
}

impl PeriodParams {
    /// The settings of the first version of the period counter: every joint,
    /// unbiased autocorrelation, periods up to half the frames. Kept for
    /// comparisons.
    pub fn legacy() -> Self {
        PeriodParams {
            joints: JointSelection::All,
            min_cycles: 2.0,
            biased: false,
            ..PeriodParams::default()
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> crate::Result<()> {
        use crate::AbstractError;
        if !(self.peak_ratio > 0.0 && self.peak_ratio <= 1.0) {
            return Err(AbstractError::param("peak_ratio", "must be in (0, 1]"));
        }
        if !(self.min_period_s.is_finite() && self.min_period_s >= 0.0) {
            return Err(AbstractError::param(
                "min_period_s",
                "must be finite and ≥ 0",
            ));
        }
        if !(self.min_cycles.is_finite() && self.min_cycles >= 1.0) {
            return Err(AbstractError::param(
                "min_cycles",
                format!("must be finite and ≥ 1, got {}", self.min_cycles),
            ));
        }
        Ok(())
    }
}

/// A dominant period of a track.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PeriodEstimate {
    /// Period in frames.
    pub period_frames: usize,
    /// Autocorrelation at that lag, normalised by the lag-0 value and, for the
    /// biased estimator, rescaled to the frames that overlap: how periodic the motion is.
    pub strength: f64,
    /// Repetitions over the analysed frames: frames / period.
    pub count: f64,
}

/// `frames[start..end]` of the selected joints as a `T × C` matrix (row-major),
/// missing joints filled by linear interpolation; `None` when no joint is ever valid.
fn channels(
    track: &mp_geom::Track,
    start: usize,
    end: usize,
    sel: JointSelection,
    centre_frames: bool,
) -> crate::Result<Option<(Vec<f64>, usize, usize)>> {
    use crate::AbstractError;
    if start >= end || end > track.n_frames() {
        return Err(AbstractError::param(
            "frames",
            format!("{start}..{end} outside 0..{}", track.n_frames()),
        ));
    }
    let mut t = track.slice_frames(start, end)?;
    if t.valid_count() == 0 {
        return Ok(None);
    }
    t.fill_missing();
    let joints = selected_joints(t.skeleton(), sel);
    let (n, _, d) = t.positions().dim();
    let c = joints.len() * d;
    let pos = t.positions();
    let mut y = vec![0.0; n * c];
    for ti in 0..n {
        for (a, &ji) in joints.iter().enumerate() {
            for k in 0..d {
                y[ti * c + a * d + k] = pos[[ti, ji, k]];
            }
        }
        if centre_frames && !joints.is_empty() {
            for k in 0..d {
                let m = (0..joints.len())
                    .map(|a| y[ti * c + a * d + k])
                    .sum::<f64>()
                    / joints.len() as f64;
                for a in 0..joints.len() {
                    y[ti * c + a * d + k] -= m;
                }
            }
        }
    }
    Ok(Some((y, n, c)))
}

/// Estimates the dominant period of the motion of `track[start..end]` from the
/// autocorrelation of joint velocities: positions of the selected joints are
/// smoothed, differenced (which removes drift and static offsets), each
/// coordinate is standardised, and the autocorrelation (averaged over
/// coordinates, biased or unbiased) is searched, after its first zero crossing,
/// above `min_period_s` and below `frames / min_cycles`, for the first local
/// peak reaching `peak_ratio` of the highest one. Missing joints are filled by
/// linear interpolation first. Returns `None` when no peak exists (too short,
/// no motion).
pub fn estimate_period(
    track: &mp_geom::Track,
    start: usize,
    end: usize,
    params: &PeriodParams,
) -> crate::Result<Option<PeriodEstimate>> {
    params.validate()?;
    let Some((y, n, dims)) = channels(track, start, end, params.joints, false)? else {
        return Ok(None);
    };
    if n < 4 || dims == 0 {
        return Ok(None);
    }
    let w = params.smooth_frames.max(1);
    // Smoothed positions (centred moving average, shrinking at the edges).
    let mut sm = vec![0.0; n * dims];
    for ti in 0..n {
        let lo = ti.saturating_sub(w / 2);
        let hi = (ti + w - w / 2).min(n);
        for c in 0..dims {
            let s: f64 = (lo..hi).map(|q| y[q * dims + c]).sum();
            sm[ti * dims + c] = s / (hi - lo) as f64;
        }
    }
    let m = n - 1;
    let mut v = vec![0.0; m * dims];
    for ti in 0..m {
        for c in 0..dims {
            v[ti * dims + c] = sm[(ti + 1) * dims + c] - sm[ti * dims + c];
        }
    }
    standardise(&mut v, m, dims);
    let max_lag = ((m as f64 / params.min_cycles).floor() as usize).min(m);
    let mut r = vec![0.0; max_lag.max(1)];
    for (lag, rv) in r.iter_mut().enumerate() {
        let mut s = 0.0;
        for ti in 0..m - lag {
            for c in 0..dims {
                s += v[ti * dims + c] * v[(ti + lag) * dims + c];
            }
        }
        *rv = s / if params.biased { m } else { m - lag } as f64;
    }
    if r[0] <= 0.0 {
        return Ok(None);
    }
    let r0 = r[0];
    for x in r.iter_mut() {
        *x /= r0;
    }
    let zero = r.iter().position(|&x| x < 0.0).unwrap_or(r.len());
    let min_lag = zero
        .max((params.min_period_s * track.fps()).round() as usize)
        .max(1);
    let peaks: Vec<usize> = (min_lag + 1..r.len().saturating_sub(1))
        .filter(|&l| r[l] >= r[l - 1] && r[l] >= r[l + 1] && r[l] > 0.0)
        .collect();
    let Some(best) = peaks.iter().map(|&l| r[l]).reduce(f64::max) else {
        return Ok(None);
    };
    let Some(&lag) = peaks.iter().find(|&&l| r[l] >= params.peak_ratio * best) else {
        return Ok(None);
    };
    // Strength as the (unbiased) correlation at the chosen lag, whichever
    // estimator chose it.
    let strength = if params.biased {
        r[lag] * m as f64 / (m - lag) as f64
    } else {
        r[lag]
    };
    Ok(Some(PeriodEstimate {
        period_frames: lag,
        strength,
        count: n as f64 / lag as f64,
    }))
}

/// Standardises each column of a row-major `m × dims` matrix (constant columns become 0).
fn standardise(v: &mut [f64], m: usize, dims: usize) {
    for c in 0..dims {
        let mean = (0..m).map(|ti| v[ti * dims + c]).sum::<f64>() / m as f64;
        let var = (0..m)
            .map(|ti| (v[ti * dims + c] - mean).powi(2))
            .sum::<f64>()
            / m as f64;
        let sd = var.sqrt();
        for ti in 0..m {
            v[ti * dims + c] = if sd > 1e-12 {
                (v[ti * dims + c] - mean) / sd
            } else {
                0.0
            };
        }
    }
}

/// Parameters of the repetition segmenter (see [`segment_repetitions`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SegmentParams {
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
    /// pass the stricter [`SegmentParams::short_threshold`].
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
}

impl Default for SegmentParams {
    fn default() -> Self {
        SegmentParams {
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
        }
    }
}

impl SegmentParams {
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

/// Lin's concordance of `x[s..e-l]` and `x[s+l..e]` (all channels pooled, each
/// channel with its own means): 1 when the motion repeats exactly after `l`
/// frames, ≤ 0 when unrelated; a change of mean pose lowers it (unlike a correlation).
struct Concordance {
    c: usize,
    /// Per-channel prefix sums, `(T+1) × C`.
    cs: Vec<f64>,
    /// Prefix sums of the squared norm of each frame.
    cs2: Vec<f64>,
    /// For each lag `l` (index `l − 1`), prefix sums of `⟨x_t, x_{t+l}⟩`.
    cross: Vec<Vec<f64>>,
}

impl Concordance {
    fn new(x: &[f64], n: usize, c: usize, max_lag: usize) -> Self {
        let mut cs = vec![0.0; (n + 1) * c];
        let mut cs2 = vec![0.0; n + 1];
        for t in 0..n {
            let mut q = 0.0;
            for k in 0..c {
                let v = x[t * c + k];
                cs[(t + 1) * c + k] = cs[t * c + k] + v;
                q += v * v;
            }
            cs2[t + 1] = cs2[t] + q;
        }
        let cross = (1..=max_lag.min(n.saturating_sub(1)))
            .map(|l| {
                let mut p = vec![0.0; n - l + 1];
                for t in 0..n - l {
                    let mut s = 0.0;
                    for k in 0..c {
                        s += x[t * c + k] * x[(t + l) * c + k];
                    }
                    p[t + 1] = p[t] + s;
                }
                p
            })
            .collect();
        Concordance { c, cs, cs2, cross }
    }

    /// Concordance of `[s, e − l)` with `[s + l, e)`; `None` when undefined.
    fn at(&self, s: usize, e: usize, l: usize) -> Option<f64> {
        if l == 0 || e < s + l + 1 {
            return None;
        }
        let p = self.cross.get(l - 1)?;
        let n = (e - s - l) as f64;
        let c = self.c;
        let (mut sab, mut ssd) = (0.0, 0.0);
        for k in 0..c {
            let sa = self.cs[(e - l) * c + k] - self.cs[s * c + k];
            let sb = self.cs[e * c + k] - self.cs[(s + l) * c + k];
            sab += sa * sb;
            ssd += (sa - sb) * (sa - sb);
        }
        let saa_all: f64 = (0..c)
            .map(|k| {
                let sa = self.cs[(e - l) * c + k] - self.cs[s * c + k];
                sa * sa
            })
            .sum();
        let sbb_all: f64 = (0..c)
            .map(|k| {
                let sb = self.cs[e * c + k] - self.cs[(s + l) * c + k];
                sb * sb
            })
            .sum();
        let cross = p.get(e - l)? - p.get(s)?;
        let cov = cross - sab / n;
        let va = (self.cs2[e - l] - self.cs2[s]) - saa_all / n;
        let vb = (self.cs2[e] - self.cs2[s + l]) - sbb_all / n;
        let md = ssd / n;
        let den = va + vb + md;
        if den > 1e-12 {
            Some(2.0 * cov / den)
        } else {
            None
        }
    }
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
/// ([`SegmentParams::standardise_features`]). Dynamic programming picks the
/// partition that maximises `Σ length · (score − threshold) − interval_penalty`
/// over the repetitive intervals (rest scores 0; an interval of fewer than two
/// periods is held to [`SegmentParams::short_threshold`] instead of
/// `threshold`), so a change of exercise, where the
/// motion stops repeating, ends an interval even without a pause. Intervals
/// shorter than `min_duration_s` are not considered. The count of an interval
/// is its length over its period.
///
/// Cost: O(grid points × interval lengths × periods × coordinates); intervals
/// are bounded by `max_duration_s`.
pub fn segment_repetitions(
    track: &mp_geom::Track,
    params: &SegmentParams,
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
    // Rest is judged on the motion as recorded; only the periodicity score
    // reads the standardised channels.
    let raw = x.clone();
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
    let conc = Concordance::new(&x, n, c, lmax);
    let mut nodes: Vec<usize> = (0..n).step_by(step).collect();
    if nodes.last() != Some(&n) {
        nodes.push(n);
    }
    let penalty = params.interval_penalty_s * fps;
    // Best score and period of the interval between nodes i < j.
    let best_of = |s: usize, e: usize| -> Option<(f64, usize)> {
        let len = e - s;
        let top = ((len as f64 / params.min_cycles).floor() as usize).min(lmax);
        if top < lmin {
            return None;
        }
        let scores: Vec<f64> = (lmin..=top)
            .map(|l| match conc.at(s, e, l) {
                Some(cl) => cl - conc.at(s, e, (l / 2).max(1)).unwrap_or(1.0).max(0.0),
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
            (0..j)
                .into_par_iter()
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
    let speed: Vec<f64> = (0..n)
        .map(|t| {
            let (a, b) = if t + 1 < n {
                (t, t + 1)
            } else {
                (t.saturating_sub(1), t)
            };
            (0..c)
                .map(|k| (raw[b * c + k] - raw[a * c + k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
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

/// The score an interval of `len` frames with a period of `period` frames
/// must exceed: [`SegmentParams::short_threshold`] below two periods,
/// [`SegmentParams::threshold`] otherwise.
fn threshold_for(params: &SegmentParams, len: usize, period: usize) -> f64 {
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
