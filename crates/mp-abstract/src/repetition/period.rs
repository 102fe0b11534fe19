//! The dominant period of a stretch of motion, from the autocorrelation of
//! joint velocities.

use serde::{Deserialize, Serialize};

use super::{channels, standardise, JointSelection};

/// Parameters of period estimation (see [`estimate_period`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PeriodParams {
    /// Moving-average window applied to positions before differencing,
    /// seconds (rounded to whole frames, at least one). Default 0.1 (three
    /// frames at 25–30 fps).
    pub smooth_s: f64,
    /// Divide each velocity channel by its standard deviation, so that every
    /// joint coordinate weighs the same. Without it channels weigh by how much
    /// they move, which suits many redundant channels of which most are still
    /// (the cells of frame thumbnails: standardising would blow their noise up
    /// to the size of the motion). Default true.
    pub standardise: bool,
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
            smooth_s: 0.1,
            standardise: true,
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

    /// The settings for frame thumbnails ([`crate::count`]'s frame signal):
    /// channels weighted by their motion instead of standardised, and
    /// positions smoothed over the shortest period considered (0.25 s), so
    /// that pixel noise and flicker faster than any repetition are gone
    /// before differencing.
    pub fn frames() -> Self {
        PeriodParams {
            smooth_s: 0.25,
            standardise: false,
            joints: JointSelection::All,
            ..PeriodParams::default()
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> crate::Result<()> {
        use crate::AbstractError;
        if !(self.smooth_s.is_finite() && self.smooth_s >= 0.0) {
            return Err(AbstractError::param(
                "smooth_s",
                format!("must be finite and ≥ 0, got {}", self.smooth_s),
            ));
        }
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

/// Below this many multiply-adds the lagged products are summed directly;
/// above it (long recordings, many channels) through the FFT, which is
/// O(dims · m log m) instead of O(dims · m · lags) and equal up to rounding.
const DIRECT_PRODUCTS_MAX: usize = 1 << 26;

/// `out[lag] = Σ_t Σ_c v[t, c] · v[t + lag, c]` for `lag < lags`, `v` being
/// `m` rows of `dims` values.
fn lagged_products(v: &[f64], m: usize, dims: usize, lags: usize) -> Vec<f64> {
    let lags = lags.min(m).max(1);
    if m.saturating_mul(lags).saturating_mul(dims) <= DIRECT_PRODUCTS_MAX {
        return (0..lags)
            .map(|lag| {
                let mut s = 0.0;
                for ti in 0..m - lag {
                    for c in 0..dims {
                        s += v[ti * dims + c] * v[(ti + lag) * dims + c];
                    }
                }
                s
            })
            .collect();
    }
    lagged_products_fft(v, m, dims, lags)
}

/// [`lagged_products`] through the FFT.
fn lagged_products_fft(v: &[f64], m: usize, dims: usize, lags: usize) -> Vec<f64> {
    // Wiener–Khinchin: the sum over channels of |FFT(v_c)|², zero-padded to
    // at least m + lags so that no lag wraps around, transformed back.
    use rustfft::num_complex::Complex;
    let len = (m + lags).next_power_of_two();
    let mut planner = rustfft::FftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(len);
    let inv = planner.plan_fft_inverse(len);
    let mut power = vec![Complex::new(0.0, 0.0); len];
    let mut buf = vec![Complex::new(0.0, 0.0); len];
    for c in 0..dims {
        for (ti, b) in buf.iter_mut().enumerate() {
            *b = Complex::new(if ti < m { v[ti * dims + c] } else { 0.0 }, 0.0);
        }
        fwd.process(&mut buf);
        for (p, b) in power.iter_mut().zip(&buf) {
            p.re += b.norm_sqr();
        }
    }
    inv.process(&mut power);
    power[..lags].iter().map(|z| z.re / len as f64).collect()
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
    let w = ((params.smooth_s * track.fps()).round() as usize).max(1);
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
    if params.standardise {
        standardise(&mut v, m, dims);
    } else {
        centre_columns(&mut v, m, dims);
    }
    let max_lag = ((m as f64 / params.min_cycles).floor() as usize).min(m);
    let mut r = lagged_products(&v, m, dims, max_lag.max(1));
    for (lag, rv) in r.iter_mut().enumerate() {
        *rv /= if params.biased { m } else { m - lag } as f64;
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

/// Subtracts each column's mean from a row-major `m × dims` matrix.
fn centre_columns(v: &mut [f64], m: usize, dims: usize) {
    for c in 0..dims {
        let mean = (0..m).map(|ti| v[ti * dims + c]).sum::<f64>() / m as f64;
        for ti in 0..m {
            v[ti * dims + c] -= mean;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fft_and_direct_lagged_products_agree() {
        let (m, dims) = (700, 3);
        let v: Vec<f64> = (0..m * dims)
            .map(|i| ((i as f64) * 0.37).sin() + ((i * i % 17) as f64) * 0.01)
            .collect();
        let lags = 350;
        let direct = lagged_products(&v, m, dims, lags);
        assert!(m * lags * dims <= DIRECT_PRODUCTS_MAX);
        // The FFT path, forced by asking for it on the same data.
        let fft = lagged_products_fft(&v, m, dims, lags);
        assert_eq!(direct.len(), fft.len());
        for (a, b) in direct.iter().zip(&fft) {
            assert!((a - b).abs() <= 1e-9 * direct[0].abs(), "{a} vs {b}");
        }
    }
}
