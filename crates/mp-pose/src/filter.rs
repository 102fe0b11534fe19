//! Temporal filters: the One-Euro filter (Casiez, Roussel, Vogel, CHI 2012) in
//! the form MediaPipe applies it to landmarks, and a first-order low-pass.
//!
//! MediaPipe's variant filters each coordinate in pixels, scales the
//! derivative by `1 / object_scale` (so that the speed threshold does not
//! depend on how large the person is in the frame), estimates the sampling
//! frequency from consecutive timestamps, and computes the derivative from
//! the previous *raw* value.

use crate::error::{PoseError, Result};

/// Parameters of a One-Euro filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneEuroParams {
    /// Minimum cutoff frequency (Hz): lower = smoother when still.
    pub min_cutoff: f64,
    /// Speed coefficient: higher = less lag when moving fast.
    pub beta: f64,
    /// Cutoff frequency (Hz) of the derivative's low-pass.
    pub derivate_cutoff: f64,
    /// Sampling frequency (Hz) assumed before two timestamps have been seen. Default 30.
    pub default_frequency_hz: f64,
    /// Filter raw values without dividing the derivative by the object scale
    /// (MediaPipe does this for world landmarks in metres).
    pub disable_value_scaling: bool,
}

impl OneEuroParams {
    /// MediaPipe's filter of the two auxiliary landmarks that place the next crop
    /// (`min_cutoff` 0.01, `beta` 10, `derivate_cutoff` 1); always on.
    pub const AUX_LANDMARKS: OneEuroParams = OneEuroParams {
        min_cutoff: 0.01,
        beta: 10.0,
        derivate_cutoff: 1.0,
        default_frequency_hz: 30.0,
        disable_value_scaling: false,
    };
    /// MediaPipe's optional smoothing of the image landmarks (0.05, 80, 1).
    pub const LANDMARKS: OneEuroParams = OneEuroParams {
        min_cutoff: 0.05,
        beta: 80.0,
        derivate_cutoff: 1.0,
        default_frequency_hz: 30.0,
        disable_value_scaling: false,
    };
    /// MediaPipe's optional smoothing of the world landmarks (0.1, 40, 1, no value scaling).
    pub const WORLD_LANDMARKS: OneEuroParams = OneEuroParams {
        min_cutoff: 0.1,
        beta: 40.0,
        derivate_cutoff: 1.0,
        default_frequency_hz: 30.0,
        disable_value_scaling: true,
    };

    /// Checks that every value is finite and positive.
    pub fn validate(&self, what: &'static str) -> Result<()> {
        let ok = self.min_cutoff.is_finite()
            && self.min_cutoff > 0.0
            && self.beta.is_finite()
            && self.beta >= 0.0
            && self.derivate_cutoff.is_finite()
            && self.derivate_cutoff > 0.0
            && self.default_frequency_hz.is_finite()
            && self.default_frequency_hz > 0.0;
        if ok {
            Ok(())
        } else {
            Err(PoseError::param(
                what,
                format!("one-euro parameters must be finite, cutoffs and frequency > 0, beta ≥ 0: {self:?}"),
            ))
        }
    }
}

/// First-order low-pass `y = α·x + (1 − α)·y_prev`; the first value passes through.
#[derive(Debug, Clone, Default)]
pub(crate) struct LowPass {
    state: Option<(f64, f64)>, // (last raw, last filtered)
}

impl LowPass {
    /// Filters one value with the given α.
    pub fn apply(&mut self, value: f64, alpha: f64) -> f64 {
        let out = match self.state {
            Some((_, prev)) => alpha * value + (1.0 - alpha) * prev,
            None => value,
        };
        self.state = Some((value, out));
        out
    }
    /// The last raw (unfiltered) value.
    pub fn last_raw(&self) -> Option<f64> {
        self.state.map(|s| s.0)
    }
}

/// A One-Euro filter of one scalar.
#[derive(Debug, Clone)]
pub(crate) struct OneEuro {
    params: OneEuroParams,
    x: LowPass,
    dx: LowPass,
    last_time_ns: Option<i64>,
    frequency: f64,
}

impl OneEuro {
    /// A fresh filter.
    pub fn new(params: OneEuroParams) -> Self {
        OneEuro {
            params,
            x: LowPass::default(),
            dx: LowPass::default(),
            last_time_ns: None,
            frequency: params.default_frequency_hz,
        }
    }

    fn alpha(&self, cutoff: f64) -> f64 {
        let te = 1.0 / self.frequency;
        let tau = 1.0 / (2.0 * std::f64::consts::PI * cutoff);
        1.0 / (1.0 + tau / te)
    }

    /// Filters `value` observed at `time_ns`. `value_scale` multiplies the
    /// derivative (MediaPipe passes `1 / object_scale`). A timestamp that does
    /// not increase returns the value unfiltered.
    pub fn apply(&mut self, time_ns: i64, value_scale: f64, value: f64) -> f64 {
        if let Some(last) = self.last_time_ns {
            if last >= time_ns {
                return value;
            }
            self.frequency = 1e9 / (time_ns - last) as f64;
        }
        self.last_time_ns = Some(time_ns);
        let dvalue = match self.x.last_raw() {
            Some(prev) => (value - prev) * value_scale * self.frequency,
            None => 0.0,
        };
        let edvalue = self
            .dx
            .apply(dvalue, self.alpha(self.params.derivate_cutoff));
        let cutoff = self.params.min_cutoff + self.params.beta * edvalue.abs();
        self.x.apply(value, self.alpha(cutoff))
    }
}

/// One-Euro filters for a set of points (x, y, z each filtered separately),
/// restarted with [`PointsFilter::reset`] when the object is lost.
#[derive(Debug, Clone)]
pub struct PointsFilter {
    params: OneEuroParams,
    filters: Vec<[OneEuro; 3]>,
}

/// Below this object scale (pixels) MediaPipe returns landmarks unfiltered.
pub(crate) const MIN_OBJECT_SCALE: f64 = 1e-6;

impl PointsFilter {
    /// Filters for points with these parameters.
    pub fn new(params: OneEuroParams) -> Self {
        PointsFilter {
            params,
            filters: Vec::new(),
        }
    }

    /// Forgets all state.
    pub fn reset(&mut self) {
        self.filters.clear();
    }

    /// Filters the points in place. `object_scale` is the size of the object
    /// in the points' unit (ignored with `disable_value_scaling`).
    pub fn apply(&mut self, time_ns: i64, object_scale: f64, points: &mut [[f64; 3]]) {
        let value_scale = if self.params.disable_value_scaling {
            1.0
        } else {
            if !(object_scale.is_finite() && object_scale >= MIN_OBJECT_SCALE) {
                return;
            }
            1.0 / object_scale
        };
        if self.filters.len() != points.len() {
            let p = self.params;
            self.filters = (0..points.len())
                .map(|_| [OneEuro::new(p), OneEuro::new(p), OneEuro::new(p)])
                .collect();
        }
        for (pt, f) in points.iter_mut().zip(self.filters.iter_mut()) {
            for k in 0..3 {
                pt[k] = f[k].apply(time_ns, value_scale, pt[k]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_value_passes_and_constant_stays() {
        let mut f = OneEuro::new(OneEuroParams::LANDMARKS);
        assert_eq!(f.apply(1, 1.0, 5.0), 5.0);
        for k in 2..20 {
            assert!((f.apply(k * 33_333_333, 1.0, 5.0) - 5.0).abs() < 1e-12);
        }
    }

    #[test]
    fn step_is_smoothed_and_converges() {
        let p = OneEuroParams {
            min_cutoff: 1.0,
            beta: 0.0,
            derivate_cutoff: 1.0,
            default_frequency_hz: 30.0,
            disable_value_scaling: false,
        };
        let mut f = OneEuro::new(p);
        f.apply(0, 1.0, 0.0);
        let first = f.apply(33_333_333, 1.0, 10.0);
        // beta = 0: plain low-pass with α = 1 / (1 + 30/(2π)).
        let alpha = 1.0 / (1.0 + 30.0 / (2.0 * std::f64::consts::PI));
        assert!((first - 10.0 * alpha).abs() < 1e-6, "{first}");
        let mut y = first;
        for k in 2..200 {
            y = f.apply(k * 33_333_333, 1.0, 10.0);
        }
        assert!((y - 10.0).abs() < 1e-3);
    }

    #[test]
    fn repeated_timestamp_returns_raw_value() {
        let mut f = OneEuro::new(OneEuroParams::AUX_LANDMARKS);
        f.apply(100, 1.0, 1.0);
        assert_eq!(f.apply(100, 1.0, 7.0), 7.0);
    }

    #[test]
    fn high_beta_follows_fast_motion() {
        // With beta large, a fast move is followed almost at once.
        let mut slow = OneEuro::new(OneEuroParams {
            beta: 0.0,
            ..OneEuroParams::AUX_LANDMARKS
        });
        let mut fast = OneEuro::new(OneEuroParams::AUX_LANDMARKS);
        let dt = 33_333_333;
        let (mut ys, mut yf) = (0.0, 0.0);
        for k in 0..10 {
            let v = 20.0 * k as f64;
            ys = slow.apply(k * dt, 1.0 / 100.0, v);
            yf = fast.apply(k * dt, 1.0 / 100.0, v);
        }
        assert!((180.0 - yf).abs() < (180.0 - ys).abs());
    }

    #[test]
    fn params_are_validated() {
        assert!(OneEuroParams::LANDMARKS.validate("x").is_ok());
        let bad = OneEuroParams {
            min_cutoff: 0.0,
            ..OneEuroParams::LANDMARKS
        };
        assert!(bad.validate("x").is_err());
    }
}
