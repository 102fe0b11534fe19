//! The confidence a count carries: the probability that the motion repeats
//! and that the count is within one of the true number of repetitions.
//!
//! The raw periodicity of a signal (the autocorrelation of its motion at the
//! period) says how regular the motion is, not whether its count is right:
//! a person walking through a street scene is as periodic as a skipping
//! rope. The confidence is a logistic model over what a count is read from
//! ([`CountFeatures`]) — the periodicity, the number of cycles counted, the
//! share of the recording they cover, and how closely the motion returns to
//! itself one period later, over the whole count and at its ends — whose weights ([`ConfidenceModel::default`])
//! were fitted on synthetic repetitions of real motion with known counts
//! (`cargo xtask eval count --synthetic --fit-confidence`; reliability in
//! docs/results/repetition.md).

use serde::{Deserialize, Serialize};

/// What a count's confidence is computed from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CountFeatures {
    /// Periodicity of the deciding signal over the whole recording (the
    /// autocorrelation of its motion at the period, 0..1), or for several
    /// activities the larger of that and the intervals' mean score.
    pub periodicity: f64,
    /// Cycles counted (length over period, summed over the intervals,
    /// before rounding).
    pub cycles: f64,
    /// Share of the recording's frames inside the counted intervals (0..1).
    pub coverage: f64,
    /// How far the motion is from itself one period later, relative to the
    /// distance between frames half a period apart (median over the counted
    /// frames): about 0 for an exact repetition, 1 or more for motion that
    /// does not repeat. 1 when there is no count.
    pub cycle_mismatch: f64,
    /// The same over the first and over the last period of the counted
    /// frames, the larger (length-weighted over several intervals): above
    /// `cycle_mismatch` when the count reaches into motion that does not
    /// repeat. 1 when there is no count.
    pub end_mismatch: f64,
    /// The count was read from the frames (thumbnails), not the keypoints.
    pub frames_signal: bool,
    /// Several intervals of different periods were counted on their own.
    pub intervals: bool,
}

impl Default for CountFeatures {
    fn default() -> Self {
        CountFeatures {
            periodicity: 0.0,
            cycles: 0.0,
            coverage: 0.0,
            cycle_mismatch: 1.0,
            end_mismatch: 1.0,
            frames_signal: false,
            intervals: false,
        }
    }
}

impl CountFeatures {
    /// The model's inputs, in the order of [`ConfidenceModel::weights`]:
    /// periodicity, ln(1 + cycles), coverage, cycle mismatch (capped at 2),
    /// frames signal (0/1), intervals (0/1), end mismatch (capped at 2).
    pub fn inputs(&self) -> [f64; 7] {
        let finite = |v: f64, fallback: f64| if v.is_finite() { v } else { fallback };
        [
            finite(self.periodicity, 0.0).clamp(0.0, 1.0),
            finite(self.cycles, 0.0).max(0.0).ln_1p(),
            finite(self.coverage, 0.0).clamp(0.0, 1.0),
            finite(self.cycle_mismatch, 2.0).clamp(0.0, 2.0),
            f64::from(u8::from(self.frames_signal)),
            f64::from(u8::from(self.intervals)),
            finite(self.end_mismatch, 2.0).clamp(0.0, 2.0),
        ]
    }
}

/// Logistic model of a count's confidence: `1 / (1 + exp(-(bias + w · x)))`
/// with `x` = [`CountFeatures::inputs`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ConfidenceModel {
    /// Intercept.
    pub bias: f64,
    /// Weights of periodicity, ln(1 + cycles), coverage, cycle mismatch,
    /// frames signal, intervals, end mismatch.
    pub weights: [f64; 7],
}

impl Default for ConfidenceModel {
    /// Fitted on seeds 0 and 1 of the synthetic validation set (1,200 cases
    /// of keypoints; see docs/results/repetition.md). The periodicity is not fitted (weight 0:
    /// a more periodic motion is never less certain), nor is the frame
    /// signal, which has no synthetic cases: its counts are scored with the
    /// same features and capped at their periodicity.
    fn default() -> Self {
        ConfidenceModel {
            bias: 2.5041,
            weights: [0.0, -0.0493, 1.3324, -1.5195, 0.0, -1.5658, -4.6841],
        }
    }
}

impl ConfidenceModel {
    /// Checks that every coefficient is finite.
    pub fn validate(&self) -> crate::error::Result<()> {
        if self.bias.is_finite() && self.weights.iter().all(|w| w.is_finite()) {
            Ok(())
        } else {
            Err(crate::error::AbstractError::param(
                "confidence",
                "every coefficient of the confidence model must be finite",
            ))
        }
    }

    /// The confidence of a count with these features (0..1). A count from
    /// the frames gets at most its periodicity (the share of the signal's
    /// variation that repeats at the period): the model was fitted on
    /// keypoints, and the thumbnails of a scene where people walk about
    /// return to themselves about as closely as a repetition does.
    pub fn confidence(&self, f: &CountFeatures) -> f64 {
        let x = f.inputs();
        let z = self.bias
            + self
                .weights
                .iter()
                .zip(x.iter())
                .map(|(w, v)| w * v)
                .sum::<f64>();
        let p = 1.0 / (1.0 + (-z).exp());
        if f.frames_signal {
            p.min(f.periodicity.clamp(0.0, 1.0))
        } else {
            p
        }
    }
}
