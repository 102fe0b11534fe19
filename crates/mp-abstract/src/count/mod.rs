//! Repetition counts a user gets: intervals, a count per interval, the total,
//! the signal and method that decided, and a confidence.
//!
//! Steps, for each signal there is (the keypoints of the performer, and, for
//! video, the grey thumbnails of the frames):
//! 1. **Period of the whole recording** ([`estimate_period`]): the dominant
//!    period of the motion and its strength (the autocorrelation at that lag).
//! 2. **Intervals** ([`segment_repetitions`]): where the motion repeats, and
//!    with which period. Where two or more intervals of at least two cycles,
//!    with a period inside the search range, have clearly different periods
//!    (a change of exercise), the recording holds several activities:
//!    neighbouring intervals of one period and one motion are joined into
//!    one activity, each activity's extent is followed outward for as long
//!    as the motion keeps repeating, and counted: its length over its period
//!    (see `activities.rs`). So is a recording whose period over its whole
//!    length is too weak (below [`CountParams::min_strength`]: a pace that
//!    changes from cycle to cycle) where an interval holds the cycles that
//!    establish a period (the period estimate's `min_cycles`, 3).
//! 3. Otherwise the recording holds one repetitive activity: when its period
//!    is strong enough ([`CountParams::min_strength`]) the count is the length
//!    of the part that repeats over its mean period — rest at either end
//!    trimmed, then motion at either end that does not match itself about a
//!    period later or earlier ([`CountParams::mismatch_fraction`]) or does
//!    not come back to itself (as near itself half a period later: slow
//!    motion), at the period, at a shorter one it is a multiple of where the
//!    motion repeats as well, or at a longer one where it comes back to
//!    itself clearly better (a figure of several similar steps;
//!    `whole_cycle`); the mean period is the lag near it at which positions
//!    match best, between frames (`span.rs`); when not, or when
//!    the part counted is no nearer itself a period later than half a period
//!    later (a cycle mismatch of 1 or more: jitter, a drift), nothing
//!    repeats (a golf swing is one movement).
//!
//! The signal whose repetition is the most certain decides
//! ([`count_signals`]): keypoints are the primary signal, and frames take
//! over where no person is found (a bar lift in the dark) or where the
//! pixels repeat more clearly than the keypoints (a hula hoop that hides
//! the hips). Where both signals read several activities, each stretch is
//! counted from the signal that reads it better (the intervals that explain
//! more of the recording first, each kept where the other signal's do not
//! already count).

use serde::{Deserialize, Serialize};

mod activities;
mod confidence;
mod cycle;
pub mod json;
mod span;

pub use span::{MISMATCH_OVER_TYPICAL, PERIOD_SLACK, REPEATS_WELL};

pub use confidence::{ConfidenceModel, CountFeatures};
use cycle::{whole_cycle, Reading};
use span::cycle_mismatch;

use crate::error::{AbstractError, Result};
use crate::repetition::{
    estimate_period_and_peaks, segment_repetitions, IntervalParams, PeriodEstimate, PeriodParams,
    PeriodicSegment, RepetitiveInterval,
};
use mp_geom::Track;
use mp_geom::{Checked, Validate};

/// Which signal a count was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum CountSignal {
    /// Joint positions of the performer.
    Keypoints,
    /// Grey thumbnails of the video frames.
    Frames,
}

impl CountSignal {
    /// Lower-case name (`keypoints`, `frames`).
    pub fn as_str(self) -> &'static str {
        match self {
            CountSignal::Keypoints => "keypoints",
            CountSignal::Frames => "frames",
        }
    }
}

/// How a count was reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum CountMethod {
    /// One repetitive activity: active length over the recording's period.
    Period,
    /// Several intervals of different periods, each counted on its own.
    Intervals,
    /// Nothing repeats clearly enough.
    None,
}

impl CountMethod {
    /// Lower-case name (`period`, `intervals`, `none`).
    pub fn as_str(self) -> &'static str {
        match self {
            CountMethod::Period => "period",
            CountMethod::Intervals => "intervals",
            CountMethod::None => "none",
        }
    }
}

/// Parameters of [`count_repetitions`] and [`count_signals`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CountParams {
    /// Period of the whole recording, keypoint signal.
    pub period: PeriodParams,
    /// Period of the whole recording, frame signal ([`PeriodParams::frames`]).
    pub frame_period: PeriodParams,
    /// Repetitive intervals (for recordings with several activities).
    pub segment: IntervalParams,
    /// A recording repeats when the autocorrelation of its motion at the
    /// period reaches this (0..1). Default 0.05: a single golf swing scores
    /// about 0.01, repeated exercises 0.06–0.75 on keypoints.
    pub min_strength: f64,
    /// Two intervals count as different activities when their periods differ
    /// by more than this fraction of the shorter one. Default 0.25.
    pub period_tolerance: f64,
    /// Frames whose speed, averaged over one period, is below this fraction
    /// of the activity's level (the median speed, or half that of the most
    /// active tenth of the frames when rest is the larger part) are rest,
    /// trimmed from the ends of the activity.
    /// Default 0.2 (as [`IntervalParams::rest_fraction`]).
    pub rest_fraction: f64,
    /// Keypoints count only where a person is found in at least this fraction
    /// of the frames. Default 0.5.
    pub min_found_fraction: f64,
    /// Motion at either end of the activity that does not match itself one
    /// period later or earlier — its distance to those frames, averaged over
    /// half a period, above this fraction of the typical distance between
    /// frames half a period apart — is not part of the repetitions and is
    /// trimmed (0: no trimming). Chosen on the synthetic validation set
    /// (`cargo xtask eval count --synthetic`).
    pub mismatch_fraction: f64,
    /// A unitless feature track with more channels than this (frame
    /// thumbnails: 1,024) is pooled into this many channels (means of
    /// consecutive channels: for a row-major thumbnail, runs of cells along
    /// its rows) before the interval search, whose cost grows with the
    /// channels; the period is still read from every channel. Default 64.
    pub max_segment_channels: usize,
    /// How a count's confidence is computed from its [`CountFeatures`].
    pub confidence: ConfidenceModel,
}

impl Default for CountParams {
    fn default() -> Self {
        CountParams {
            period: PeriodParams::default(),
            frame_period: PeriodParams::frames(),
            segment: IntervalParams::default(),
            min_strength: 0.05,
            period_tolerance: 0.25,
            rest_fraction: 0.2,
            min_found_fraction: 0.5,
            mismatch_fraction: 0.5,
            max_segment_channels: 64,
            confidence: ConfidenceModel::default(),
        }
    }
}

impl Validate for CountParams {
    type Error = crate::error::AbstractError;

    fn validate(&self) -> Result<()> {
        CountParams::validate(self)
    }
}

impl CountParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        self.period.validate()?;
        self.frame_period.validate()?;
        self.segment.validate()?;
        let unit = |name: &'static str, v: f64| {
            if v.is_finite() && (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                Err(AbstractError::param(
                    name,
                    format!("must be in [0, 1], got {v}"),
                ))
            }
        };
        unit("min_strength", self.min_strength)?;
        unit("rest_fraction", self.rest_fraction)?;
        unit("min_found_fraction", self.min_found_fraction)?;
        AbstractError::check_non_negative("mismatch_fraction", self.mismatch_fraction)?;
        AbstractError::check_non_negative("period_tolerance", self.period_tolerance)?;
        self.confidence.validate()?;
        if self.max_segment_channels == 0 {
            return Err(AbstractError::param(
                "max_segment_channels",
                "must be at least 1",
            ));
        }
        Ok(())
    }
}

/// One counted interval.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CountedInterval {
    /// First frame.
    pub start_frame: usize,
    /// One past the last frame.
    pub end_frame: usize,
    /// Period, frames (rounded: `cycles` divides by it unrounded).
    pub period_frames: usize,
    /// Length over period, before rounding.
    pub cycles: f64,
    /// Repetitions (`cycles` rounded).
    pub count: usize,
    /// Frame where each repetition starts, plus `end_frame`.
    pub boundaries: Vec<usize>,
    /// How periodic the interval is (autocorrelation or concordance at the
    /// period, 0..1).
    #[serde(alias = "confidence")]
    pub periodicity: f64,
    /// The signal it was counted from (keypoints unless stated).
    #[serde(default = "keypoints_signal")]
    pub signal: CountSignal,
}

fn keypoints_signal() -> CountSignal {
    CountSignal::Keypoints
}

impl CountedInterval {
    fn new(start: usize, end: usize, period: f64, periodicity: f64, signal: CountSignal) -> Self {
        let period = period.max(1.0);
        let cycles = (end - start) as f64 / period;
        let count = cycles.round().max(0.0) as usize;
        let mut boundaries: Vec<usize> = (0..count)
            .map(|i| start + (i as f64 * period).round() as usize)
            .filter(|&b| b < end)
            .collect();
        boundaries.push(end);
        CountedInterval {
            start_frame: start,
            end_frame: end,
            period_frames: period.round() as usize,
            cycles,
            count,
            boundaries,
            periodicity,
            signal,
        }
    }

    /// The period the interval was counted at, unrounded (frames): its
    /// length over `cycles`; `period_frames` where it holds no cycle.
    pub fn period(&self) -> f64 {
        if self.cycles > 0.0 && self.end_frame > self.start_frame {
            (self.end_frame - self.start_frame) as f64 / self.cycles
        } else {
            self.period_frames as f64
        }
    }

    /// As a [`RepetitiveInterval`] (no loop body: `body_size` 0), for the
    /// report's timeline and plots.
    pub fn to_interval(&self) -> RepetitiveInterval {
        RepetitiveInterval {
            start_frame: self.start_frame,
            end_frame: self.end_frame,
            body_size: 0,
            iterations: self.count,
            boundaries: self.boundaries.clone(),
            count: self.count,
            score: self.periodicity,
        }
    }
}

/// The repetition counts of a recording.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Counts {
    /// Counted intervals, in time order.
    pub intervals: Vec<CountedInterval>,
    /// Sum of the interval counts.
    pub total: usize,
    /// The signal that decided.
    pub signal: CountSignal,
    /// How the count was reached.
    pub method: CountMethod,
    /// How likely it is that the motion repeats and that `total` is within
    /// one of the true number of repetitions (0..1): [`CountParams::confidence`]
    /// applied to `features`.
    pub confidence: f64,
    /// How periodic the deciding signal is: the autocorrelation of its motion
    /// at the period over the whole recording (0..1), or for several
    /// activities the larger of that and the intervals' mean score.
    #[serde(default)]
    pub periodicity: f64,
    /// What the confidence was computed from.
    #[serde(default)]
    pub features: CountFeatures,
    /// Frames of the recording.
    pub frames: usize,
    /// Frame rate.
    pub fps: f64,
}

impl Counts {
    fn none(
        signal: CountSignal,
        frames: usize,
        fps: f64,
        periodicity: f64,
        model: &ConfidenceModel,
    ) -> Self {
        let features = CountFeatures {
            periodicity,
            frames_signal: signal == CountSignal::Frames,
            ..CountFeatures::default()
        };
        Counts {
            intervals: Vec::new(),
            total: 0,
            signal,
            method: CountMethod::None,
            confidence: model.confidence(&features),
            periodicity,
            features,
            frames,
            fps,
        }
    }

    /// The same counts placed `offset` frames later in a recording of
    /// `frames` frames (a person's counts, made on the frames where they were
    /// seen, in the frames of the whole video).
    pub fn shifted(&self, offset: usize, frames: usize) -> Counts {
        let mut c = self.clone();
        for iv in &mut c.intervals {
            iv.start_frame += offset;
            iv.end_frame += offset;
            for b in &mut iv.boundaries {
                *b += offset;
            }
        }
        c.frames = frames;
        c
    }

    /// The intervals as [`RepetitiveInterval`]s.
    pub fn repetitive_intervals(&self) -> Vec<RepetitiveInterval> {
        self.intervals.iter().map(|i| i.to_interval()).collect()
    }
}

/// Counts the repetitions of one signal (a keypoint track, or a unitless
/// feature track such as frame thumbnails) — see the module docs.
pub fn count_repetitions(
    signal: &Track,
    kind: CountSignal,
    params: &CountParams,
) -> Result<Counts> {
    count_checked(signal, kind, &params.check()?)
}

/// [`count_repetitions`] with its parameters checked.
fn count_checked(
    signal: &Track,
    kind: CountSignal,
    params: &Checked<&CountParams>,
) -> Result<Counts> {
    let n = signal.n_frames();
    let fps = signal.fps();
    if n < 4 || signal.valid_count() == 0 {
        return Ok(Counts::none(kind, n, fps, 0.0, &params.confidence));
    }
    let period_params = match kind {
        CountSignal::Keypoints => &params.period,
        CountSignal::Frames => &params.frame_period,
    };
    let whole = estimate_period_and_peaks(signal, 0, n, period_params)?;
    let strength = whole.as_ref().map(|e| e.0.strength.max(0.0)).unwrap_or(0.0);
    let segs = match pooled(signal, params.max_segment_channels)? {
        Some(p) => segment_repetitions(&p, &params.segment)?,
        None => segment_repetitions(signal, &params.segment)?,
    };
    // Intervals of at least two cycles decide whether there are several
    // activities (shorter ones are too uncertain to stand for an activity of
    // their own); then every interval is counted.
    // A period at the upper end of the search range is not resolved (the
    // true one may be longer, or there is none): such an interval does not
    // count as an activity of its own either.
    let top_period = (params.segment.max_period_s * fps).round() as usize;
    let substantial: Vec<PeriodicSegment> = segs
        .iter()
        .filter(|s| s.count >= 2.0 && s.period_frames + 1 < top_period)
        .cloned()
        .collect();
    // A recording whose autocorrelation over its whole length is too weak
    // for a period (the pace changing from cycle to cycle blurs it) may still
    // repeat where the segmenter reads it locally: an interval holding the
    // cycles that establish a period (`min_cycles` of the period estimate)
    // is counted as the intervals of several activities are.
    let weak = strength < params.min_strength;
    let established = substantial
        .iter()
        .any(|s| s.count >= period_params.min_cycles);
    if several_activities(&substantial, params.period_tolerance) || (weak && established) {
        let acts = activities::activities(signal, &segs, params);
        let intervals: Vec<CountedInterval> = acts
            .iter()
            .zip(activities::stretches(&acts, n))
            .map(|(a, s)| activities::count_activity(signal, kind, a, s, params))
            .collect();
        let periodicity = strength.max(weighted_score(&segs).clamp(0.0, 1.0));
        let (cycle_mismatch, end_mismatch) = intervals_mismatch(signal, &intervals);
        let features = CountFeatures {
            periodicity,
            cycles: intervals.iter().map(|i| i.cycles).sum(),
            coverage: intervals
                .iter()
                .map(|i| i.end_frame - i.start_frame)
                .sum::<usize>() as f64
                / n as f64,
            cycle_mismatch,
            end_mismatch,
            frames_signal: kind == CountSignal::Frames,
            intervals: true,
        };
        return Ok(Counts {
            total: intervals.iter().map(|i| i.count).sum(),
            intervals,
            signal: kind,
            method: CountMethod::Intervals,
            confidence: params.confidence.confidence(&features),
            periodicity,
            features,
            frames: n,
            fps,
        });
    }
    match whole {
        Some((
            PeriodEstimate {
                period_frames,
                strength,
                ..
            },
            ref others,
        )) if strength >= params.min_strength => {
            let Reading {
                period: period_frames,
                strength,
                span: (a, b),
                mismatch,
            } = whole_cycle(signal, (period_frames, strength), others, params)?;
            // Counted at the repetitions' mean period (a fraction of a frame).
            let exact = span::mean_period(signal, period_frames, a, b);
            let iv = CountedInterval::new(a, b, exact, strength, kind);
            // No nearer itself a period later than half a period later: the
            // motion does not repeat at this period, whatever its
            // autocorrelation (jitter, a drift); another signal may still
            // count.
            if mismatch.0 >= DOES_NOT_REPEAT {
                return Ok(Counts::none(kind, n, fps, strength, &params.confidence));
            }
            let features = CountFeatures {
                periodicity: strength,
                cycles: iv.cycles,
                coverage: (b - a) as f64 / n as f64,
                cycle_mismatch: mismatch.0,
                end_mismatch: mismatch.1,
                frames_signal: kind == CountSignal::Frames,
                intervals: false,
            };
            Ok(Counts {
                total: iv.count,
                intervals: if iv.count > 0 { vec![iv] } else { Vec::new() },
                signal: kind,
                method: CountMethod::Period,
                confidence: params.confidence.confidence(&features),
                periodicity: strength,
                features,
                frames: n,
                fps,
            })
        }
        _ => Ok(Counts::none(kind, n, fps, strength, &params.confidence)),
    }
}

/// Counts from the keypoints (over the frames from the person's first to
/// their last pose) and, when given, the frame thumbnails of the same
/// recording (over all of it), and returns the count of the more certain
/// signal, in the recording's frames; where both read several activities,
/// their intervals are merged, each stretch read from the signal that reads
/// it better (each interval states its signal).
/// Keypoints take part only when a person is found in at least
/// [`CountParams::min_found_fraction`] of the frames; with neither signal
/// usable the count is 0 with [`CountMethod::None`].
pub fn count_signals(
    keypoints: Option<&Track>,
    frames: Option<&Track>,
    params: &CountParams,
) -> Result<Counts> {
    let params = &params.check()?;
    let mut best: Option<Counts> = None;
    let consider = |best: &mut Option<Counts>, c: Counts| {
        if best.as_ref().is_none_or(|b| decides_over(&c, b)) {
            *best = Some(c);
        }
    };
    if let Some(k) = keypoints {
        if found_fraction(k) >= params.min_found_fraction {
            // Counted from the person's first to their last pose: before and
            // after, their track would only hold those poses (a passer-by, a
            // person who walks in), which is no repetition; the counts are
            // given in the recording's frames.
            let n = k.n_frames();
            let (mut own, first) = match k.found_span() {
                Some((a, b)) if (a > 0 || b + 1 < n) && b > a => (k.slice_frames(a, b + 1)?, a),
                _ => (k.clone(), 0),
            };
            own.fill_missing();
            let c = count_checked(&own, CountSignal::Keypoints, params)?;
            consider(
                &mut best,
                if own.n_frames() < n {
                    c.shifted(first, n)
                } else {
                    c
                },
            );
        }
    }
    if let Some(f) = frames {
        let c = count_checked(f, CountSignal::Frames, params)?;
        // Two readings of several activities: each stretch is read from the
        // signal that reads it better.
        match best.take() {
            Some(b) if b.method == CountMethod::Intervals && c.method == CountMethod::Intervals => {
                best = Some(activities::merged(b, c));
            }
            b => {
                best = b;
                consider(&mut best, c);
            }
        }
    }
    match best {
        Some(b) => Ok(b),
        None => {
            let (n, fps) = keypoints
                .or(frames)
                .map(|t| (t.n_frames(), t.fps()))
                .ok_or_else(|| {
                    AbstractError::param("signals", "neither keypoints nor frames were given")
                })?;
            Ok(Counts::none(
                CountSignal::Keypoints,
                n,
                fps,
                0.0,
                &params.confidence,
            ))
        }
    }
}

/// A unitless track with more than `max` channels, pooled into `max` channels
/// (each the mean of a run of consecutive channels); `None` when no pooling
/// is needed.
fn pooled(track: &Track, max: usize) -> Result<Option<Track>> {
    let (n, j, d) = track.positions().dim();
    let c = j * d;
    if track.units() != mp_geom::Units::Unitless || c <= max {
        return Ok(None);
    }
    let pos = track.positions();
    let mut out = ndarray::Array3::<f64>::zeros((n, max, 1));
    let mut counts = vec![0usize; max];
    for k in 0..c {
        counts[k * max / c] += 1;
    }
    for t in 0..n {
        for k in 0..c {
            out[[t, k * max / c, 0]] += pos[[t, k / d, k % d]];
        }
        for (g, &m) in counts.iter().enumerate() {
            out[[t, g, 0]] /= m.max(1) as f64;
        }
    }
    Ok(Some(Track::new(
        out,
        None,
        track.fps(),
        mp_geom::Units::Unitless,
        mp_geom::Skeleton::generic(max),
    )?))
}

/// Fraction of frames with at least one valid joint.
pub fn found_fraction(track: &Track) -> f64 {
    let n = track.n_frames();
    if n == 0 {
        return 0.0;
    }
    let c = track.confidence();
    let found = (0..n)
        .filter(|&t| (0..track.n_joints()).any(|j| c[[t, j]] > 0.0))
        .count();
    found as f64 / n as f64
}

/// Whether the segmenter's intervals show two or more activities: at least
/// two intervals whose periods differ by more than `tolerance`.
fn several_activities(segs: &[PeriodicSegment], tolerance: f64) -> bool {
    let periods: Vec<f64> = segs.iter().map(|s| s.period_frames as f64).collect();
    periods.iter().enumerate().any(|(i, &a)| {
        periods[i + 1..]
            .iter()
            .any(|&b| (a - b).abs() > tolerance * a.min(b))
    })
}

/// A cycle mismatch (see [`CountFeatures::cycle_mismatch`]) at which the
/// motion is no nearer itself a period later than half a period later: it
/// does not repeat at that period, and a recording of one activity whose
/// counted span reaches it is not counted.
const DOES_NOT_REPEAT: f64 = 1.0;

/// Whether count `c` of one signal decides over count `b` of another: a
/// count beats no count; between two counts (or two non-counts) the more
/// periodic signal wins.
fn decides_over(c: &Counts, b: &Counts) -> bool {
    let (cr, br) = (c.method != CountMethod::None, b.method != CountMethod::None);
    (cr && !br) || (cr == br && c.periodicity > b.periodicity)
}

fn weighted_score(segs: &[PeriodicSegment]) -> f64 {
    let w: f64 = segs.iter().map(|s| s.len_frames() as f64).sum();
    if w <= 0.0 {
        return 0.0;
    }
    segs.iter()
        .map(|s| s.score * s.len_frames() as f64)
        .sum::<f64>()
        / w
}

/// Cycle mismatch of several counted intervals, whole and at the ends:
/// their own ([`cycle_mismatch`]) weighted by length; 1 when none can be
/// measured.
fn intervals_mismatch(signal: &Track, intervals: &[CountedInterval]) -> (f64, f64) {
    let (mut sum, mut ends, mut w) = (0.0, 0.0, 0.0);
    for iv in intervals {
        if let Some((m, e)) = cycle_mismatch(signal, iv.period_frames, iv.start_frame, iv.end_frame)
        {
            let len = (iv.end_frame - iv.start_frame) as f64;
            sum += m * len;
            ends += e * len;
            w += len;
        }
    }
    if w > 0.0 {
        (sum / w, ends / w)
    } else {
        (1.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reading(method: CountMethod, periodicity: f64, intervals: &[(usize, usize, f64)]) -> Counts {
        let intervals: Vec<CountedInterval> = intervals
            .iter()
            .map(|&(s, e, p)| CountedInterval::new(s, e, 30.0, p, CountSignal::Keypoints))
            .collect();
        Counts {
            total: intervals.iter().map(|i| i.count).sum(),
            intervals,
            signal: CountSignal::Keypoints,
            method,
            confidence: 0.5,
            periodicity,
            features: CountFeatures::default(),
            frames: 1000,
            fps: 30.0,
        }
    }

    #[test]
    fn two_readings_of_several_activities_keep_what_each_reads_best() {
        let keypoints = reading(
            CountMethod::Intervals,
            0.6,
            &[(0, 300, 0.6), (300, 400, 0.5)],
        );
        let mut frames = reading(
            CountMethod::Intervals,
            0.8,
            &[(280, 680, 0.8), (0, 100, 0.2)],
        );
        frames.signal = CountSignal::Frames;
        for iv in &mut frames.intervals {
            iv.signal = CountSignal::Frames;
        }
        let m = activities::merged(keypoints, frames);
        let got: Vec<(usize, usize, usize, CountSignal)> = m
            .intervals
            .iter()
            .map(|i| (i.start_frame, i.end_frame, i.count, i.signal))
            .collect();
        // The frames' long interval first; the keypoints' first one cut back
        // to where it does not overlap it; what lies inside either is dropped.
        assert_eq!(
            got,
            vec![
                (0, 280, 9, CountSignal::Keypoints),
                (280, 680, 13, CountSignal::Frames)
            ]
        );
        assert_eq!(m.total, 22);
        assert_eq!(m.signal, CountSignal::Frames, "the frames explain more");
    }

    #[test]
    fn a_count_beats_none_and_the_more_periodic_reading_decides() {
        let clean = reading(CountMethod::Intervals, 0.9, &[(0, 200, 0.9)]);
        let one = reading(CountMethod::Period, 0.7, &[(0, 900, 0.7)]);
        assert!(decides_over(&clean, &one) && !decides_over(&one, &clean));
        let none = reading(CountMethod::None, 0.95, &[]);
        assert!(decides_over(&one, &none) && !decides_over(&none, &one));
    }
}
