//! The one JSON form of repetition counts and program loops (`loops.json`,
//! `mp loops --json`, Python `Counts.to_json`), version [`RepetitionsJson::LOOPS_VERSION`].
//!
//! Two words, never mixed:
//! * **repetitions**: what was counted — the total, and for each counted
//!   interval its frames, count, period and the frames of every repetition;
//! * **program loops**: the `for` statements of the abstract program — their
//!   frames, iterations and body.
//!
//! Every frame range is **inclusive**: `first_frame` and `last_frame` are the
//! first and the last frame of the range (as the terminal and the report print
//! them, `first–last`), and a list of ranges is a list of `[first, last]`
//! pairs.

use serde::{Deserialize, Serialize};

use super::{CountFeatures, CountMethod, CountSignal, CountedInterval, Counts};
use crate::error::{AbstractError, Result};
use crate::repetition::RepetitiveInterval;

/// The repetitions of a recording (or of one person), as JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RepetitionsJson {
    /// Repetitions counted, summed over the intervals.
    pub total: usize,
    /// The signal that decided: `keypoints` or `frames`.
    pub signal: CountSignal,
    /// How the count was reached: `period`, `intervals` or `none`.
    pub method: CountMethod,
    /// How likely it is that the motion repeats and that `total` is within
    /// one of the true count (0..1).
    pub confidence: f64,
    /// How periodic the deciding signal is (0..1).
    pub periodicity: f64,
    /// What `confidence` was computed from.
    pub confidence_features: CountFeatures,
    /// The counted intervals, in time order.
    pub intervals: Vec<CountedIntervalJson>,
}

/// One counted interval, as JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CountedIntervalJson {
    /// First frame of the interval.
    pub first_frame: usize,
    /// Last frame of the interval.
    pub last_frame: usize,
    /// Repetitions counted in it.
    pub count: usize,
    /// Period in frames.
    pub period_frames: usize,
    /// Period in seconds.
    pub period_s: f64,
    /// Length over period, before rounding.
    pub cycles: f64,
    /// How periodic the interval is (0..1).
    pub periodicity: f64,
    /// `[first, last]` frames of each repetition (`count` of them).
    pub repetitions: Vec<[usize; 2]>,
    /// The signal it was counted from, `keypoints` or `frames` (several
    /// activities may be read from different signals); absent in older
    /// files: the document's `signal`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal: Option<CountSignal>,
}

/// One loop of the abstract program, as JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProgramLoopJson {
    /// First frame the loop covers.
    pub first_frame: usize,
    /// Last frame the loop covers.
    pub last_frame: usize,
    /// Iterations of the loop (`range(N)` of its `for` statement).
    pub iterations: usize,
    /// Primitives in the loop body.
    pub body_primitives: usize,
    /// Loop score (unit-free; lower is a closer repetition).
    pub score: f64,
    /// `[first, last]` frames of each iteration.
    pub iteration_frames: Vec<[usize; 2]>,
}

/// `[first, last]` pairs from boundaries (each range's start, then one past
/// the last range's end).
fn ranges(boundaries: &[usize]) -> Vec<[usize; 2]> {
    boundaries
        .windows(2)
        .filter(|w| w[1] > w[0])
        .map(|w| [w[0], w[1] - 1])
        .collect()
}

impl CountedIntervalJson {
    /// The JSON form of a counted interval at `fps`.
    pub fn new(iv: &CountedInterval, fps: f64) -> Self {
        CountedIntervalJson {
            first_frame: iv.start_frame,
            last_frame: iv.end_frame.saturating_sub(1).max(iv.start_frame),
            count: iv.count,
            period_frames: iv.period_frames,
            period_s: iv.period_frames as f64 / fps,
            cycles: iv.cycles,
            periodicity: iv.periodicity,
            repetitions: ranges(&iv.boundaries),
            signal: Some(iv.signal),
        }
    }

    /// Back to the counted interval (read from `signal` where the interval
    /// does not state its own).
    pub fn to_interval(&self, signal: CountSignal) -> Result<CountedInterval> {
        if self.last_frame < self.first_frame {
            return Err(AbstractError::Inconsistent(format!(
                "last_frame {} is before first_frame {}",
                self.last_frame, self.first_frame
            )));
        }
        let end = self.last_frame + 1;
        let mut boundaries: Vec<usize> = self.repetitions.iter().map(|r| r[0]).collect();
        boundaries.push(end);
        Ok(CountedInterval {
            start_frame: self.first_frame,
            end_frame: end,
            period_frames: self.period_frames,
            cycles: self.cycles,
            count: self.count,
            boundaries,
            periodicity: self.periodicity,
            signal: self.signal.unwrap_or(signal),
        })
    }
}

impl RepetitionsJson {
    /// Version of the `loops.json` layout ([`RepetitionsJson`],
    /// [`ProgramLoopJson`] and the document around them). 2: repetitions and
    /// program loops in their own sections, inclusive frame ranges.
    pub const LOOPS_VERSION: u32 = 2;

    /// The name `loops.json` states in its `schema` key.
    pub const LOOPS_SCHEMA: &str = "mp-loops";

    /// The JSON form of counts.
    pub fn new(c: &Counts) -> Self {
        RepetitionsJson {
            total: c.total,
            signal: c.signal,
            method: c.method,
            confidence: c.confidence,
            periodicity: c.periodicity,
            confidence_features: c.features,
            intervals: c
                .intervals
                .iter()
                .map(|iv| CountedIntervalJson::new(iv, c.fps))
                .collect(),
        }
    }

    /// Back to counts of a recording of `frames` frames at `fps`.
    pub fn to_counts(&self, frames: usize, fps: f64) -> Result<Counts> {
        let intervals = self
            .intervals
            .iter()
            .map(|i| i.to_interval(self.signal))
            .collect::<Result<Vec<_>>>()?;
        let sum: usize = intervals.iter().map(|i| i.count).sum();
        if sum != self.total {
            return Err(AbstractError::Inconsistent(format!(
                "{} is not the sum of the intervals' counts ({sum})",
                self.total
            )));
        }
        Ok(Counts {
            intervals,
            total: self.total,
            signal: self.signal,
            method: self.method,
            confidence: self.confidence,
            periodicity: self.periodicity,
            features: self.confidence_features,
            frames,
            fps,
        })
    }
}

impl ProgramLoopJson {
    /// The JSON form of a loop of the abstract program.
    pub fn new(iv: &RepetitiveInterval) -> Self {
        ProgramLoopJson {
            first_frame: iv.start_frame,
            last_frame: iv.end_frame.saturating_sub(1).max(iv.start_frame),
            iterations: iv.iterations,
            body_primitives: iv.body_size,
            score: iv.score,
            iteration_frames: ranges(&iv.boundaries),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts() -> Counts {
        let iv = CountedInterval {
            start_frame: 10,
            end_frame: 70,
            period_frames: 20,
            cycles: 3.0,
            count: 3,
            boundaries: vec![10, 30, 50, 70],
            periodicity: 0.9,
            signal: CountSignal::Keypoints,
        };
        Counts {
            intervals: vec![iv],
            total: 3,
            signal: CountSignal::Keypoints,
            method: CountMethod::Period,
            confidence: 0.8,
            periodicity: 0.9,
            features: CountFeatures::default(),
            frames: 100,
            fps: 20.0,
        }
    }

    #[test]
    fn ranges_are_inclusive_and_read_back() {
        let c = counts();
        let j = RepetitionsJson::new(&c);
        let iv = &j.intervals[0];
        assert_eq!((iv.first_frame, iv.last_frame), (10, 69));
        assert_eq!(iv.repetitions, vec![[10, 29], [30, 49], [50, 69]]);
        assert!((iv.period_s - 1.0).abs() < 1e-12);
        let text = serde_json::to_string(&j).unwrap();
        let back: RepetitionsJson = serde_json::from_str(&text).unwrap();
        assert_eq!(back.to_counts(100, 20.0).unwrap(), c);
    }

    #[test]
    fn a_total_that_is_not_the_sum_is_refused() {
        let mut j = RepetitionsJson::new(&counts());
        j.total = 4;
        let e = j.to_counts(100, 20.0).unwrap_err().to_string();
        assert!(e.contains("not the sum"), "{e}");
    }

    #[test]
    fn program_loops_list_their_iterations() {
        let iv = RepetitiveInterval {
            start_frame: 0,
            end_frame: 40,
            body_size: 3,
            iterations: 2,
            boundaries: vec![0, 20, 40],
            count: 2,
            score: 0.5,
        };
        let j = ProgramLoopJson::new(&iv);
        assert_eq!((j.first_frame, j.last_frame, j.iterations), (0, 39, 2));
        assert_eq!(j.iteration_frames, vec![[0, 19], [20, 39]]);
        assert_eq!(j.body_primitives, 3);
    }
}
