//! The dominant period of a stretch of motion, from the autocorrelation of
//! joint velocities.

use serde::{Deserialize, Serialize};

use super::{filled_column, selected_joints, standardise, JointSelection};

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

    /// The settings for frame thumbnails (`crate::count`'s frame signal):
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

/// `Σ_c Σ_t v_c[t] · v_c[t + lag]` for `lag < lags`, accumulated one channel
/// `v_c` (of `m` values) at a time, so that a signal with many channels (the
/// 1,024 cells of frame thumbnails) never needs to be held as a whole.
struct LaggedProducts {
    m: usize,
    lags: usize,
    sums: Vec<f64>,
    fft: Option<FftProducts>,
}

/// The FFT state of [`LaggedProducts`]: the power spectrum summed over the
/// channels so far (Wiener–Khinchin), zero-padded to at least `m + lags` so
/// that no lag wraps around.
struct FftProducts {
    fwd: std::sync::Arc<dyn rustfft::Fft<f64>>,
    inv: std::sync::Arc<dyn rustfft::Fft<f64>>,
    power: Vec<rustfft::num_complex::Complex<f64>>,
    buf: Vec<rustfft::num_complex::Complex<f64>>,
}

impl LaggedProducts {
    /// Products of `lags` lags (at least 1, at most `m`) over channels of `m`
    /// values; `channels` (how many will be added) picks direct sums or the FFT.
    fn new(m: usize, lags: usize, channels: usize) -> Self {
        let lags = lags.min(m).max(1);
        let direct = m.saturating_mul(lags).saturating_mul(channels) <= DIRECT_PRODUCTS_MAX;
        Self::with_method(m, lags, !direct)
    }

    fn with_method(m: usize, lags: usize, fft: bool) -> Self {
        use rustfft::num_complex::Complex;
        let lags = lags.min(m).max(1);
        let fft = fft.then(|| {
            let len = (m + lags).next_power_of_two();
            let mut planner = rustfft::FftPlanner::<f64>::new();
            FftProducts {
                fwd: planner.plan_fft_forward(len),
                inv: planner.plan_fft_inverse(len),
                power: vec![Complex::new(0.0, 0.0); len],
                buf: vec![Complex::new(0.0, 0.0); len],
            }
        });
        LaggedProducts {
            m,
            lags,
            sums: vec![0.0; lags],
            fft,
        }
    }

    /// Adds one channel (`m` values).
    fn add(&mut self, v: &[f64]) {
        let m = self.m.min(v.len());
        match &mut self.fft {
            None => {
                for (lag, s) in self.sums.iter_mut().enumerate() {
                    *s += (0..m.saturating_sub(lag))
                        .map(|t| v[t] * v[t + lag])
                        .sum::<f64>();
                }
            }
            Some(f) => {
                use rustfft::num_complex::Complex;
                for (t, b) in f.buf.iter_mut().enumerate() {
                    *b = Complex::new(if t < m { v[t] } else { 0.0 }, 0.0);
                }
                f.fwd.process(&mut f.buf);
                for (p, b) in f.power.iter_mut().zip(&f.buf) {
                    p.re += b.norm_sqr();
                }
            }
        }
    }

    /// The products by lag.
    fn finish(self) -> Vec<f64> {
        match self.fft {
            None => self.sums,
            Some(mut f) => {
                let len = f.power.len() as f64;
                f.inv.process(&mut f.power);
                f.power[..self.lags].iter().map(|z| z.re / len).collect()
            }
        }
    }
}

/// Moving average of `x` over `w` samples, centred, shrinking at the edges
/// (prefix sums: O(len) whatever `w`).
fn smooth_into(x: &[f64], w: usize, out: &mut [f64]) {
    let n = x.len();
    let mut prefix = Vec::with_capacity(n + 1);
    prefix.push(0.0);
    let mut acc = 0.0;
    for &v in x {
        acc += v;
        prefix.push(acc);
    }
    for (ti, o) in out.iter_mut().enumerate().take(n) {
        let lo = ti.saturating_sub(w / 2);
        let hi = (ti + w - w / 2).min(n);
        *o = (prefix[hi] - prefix[lo]) / (hi - lo) as f64;
    }
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
    Ok(estimate_period_and_peaks(track, start, end, params)?.map(|(e, _)| e))
}

/// The other peaks of the autocorrelation: each lag with its strength.
pub(crate) type OtherPeaks = Vec<(usize, f64)>;

/// [`estimate_period`], with the other peaks of the autocorrelation (in
/// increasing order of lag, each with its strength as
/// [`PeriodEstimate::strength`]): the shorter periods the chosen one may be a
/// multiple of, and the longer ones it may be a part of.
pub(crate) fn estimate_period_and_peaks(
    track: &mp_geom::Track,
    start: usize,
    end: usize,
    params: &PeriodParams,
) -> crate::Result<Option<(PeriodEstimate, OtherPeaks)>> {
    params.validate()?;
    if start >= end || end > track.n_frames() {
        return Err(crate::AbstractError::param(
            "frames",
            format!("{start}..{end} outside 0..{}", track.n_frames()),
        ));
    }
    let n = end - start;
    let conf = track.confidence();
    if !conf
        .slice(ndarray::s![start..end, ..])
        .iter()
        .any(|&c| c > 0.0)
    {
        return Ok(None);
    }
    let joints = selected_joints(track.skeleton(), params.joints);
    let d = track.dims();
    let dims = joints.len() * d;
    if n < 4 || dims == 0 {
        return Ok(None);
    }
    let w = ((params.smooth_s * track.fps()).round() as usize).max(1);
    let m = n - 1;
    let max_lag = ((m as f64 / params.min_cycles).floor() as usize).min(m);
    // One channel (joint coordinate) at a time: filled, smoothed (centred
    // moving average, shrinking at the edges), differenced (which removes
    // drift and static offsets), standardised or centred, and its lagged
    // products added. Memory: a few columns of `n` values, whatever the
    // number of channels.
    let mut products = LaggedProducts::new(m, max_lag.max(1), dims);
    let mut column = vec![0.0; n];
    let mut smoothed = vec![0.0; n];
    let mut v = vec![0.0; m];
    for &ji in &joints {
        for k in 0..d {
            filled_column(track, ji, k, start, end, &mut column);
            smooth_into(&column, w, &mut smoothed);
            for (ti, x) in v.iter_mut().enumerate() {
                *x = smoothed[ti + 1] - smoothed[ti];
            }
            if params.standardise {
                standardise(&mut v, m, 1);
            } else {
                centre_columns(&mut v, m, 1);
            }
            products.add(&v);
        }
    }
    let mut r = products.finish();
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
    let unbiased = |l: usize| {
        if params.biased {
            r[l] * m as f64 / (m - l) as f64
        } else {
            r[l]
        }
    };
    let strength = unbiased(lag);
    let others = peaks
        .iter()
        .filter(|&&l| l != lag)
        .map(|&l| (l, unbiased(l)))
        .collect();
    Ok(Some((
        PeriodEstimate {
            period_frames: lag,
            strength,
            count: n as f64 / lag as f64,
        },
        others,
    )))
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

    /// Direct sums of `v` (`m` rows of `dims` values, row-major) by lag.
    fn reference_products(v: &[f64], m: usize, dims: usize, lags: usize) -> Vec<f64> {
        (0..lags)
            .map(|lag| {
                (0..m - lag)
                    .map(|t| {
                        (0..dims)
                            .map(|c| v[t * dims + c] * v[(t + lag) * dims + c])
                            .sum::<f64>()
                    })
                    .sum()
            })
            .collect()
    }

    #[test]
    fn fft_and_direct_lagged_products_agree() {
        let (m, dims) = (700, 3);
        let v: Vec<f64> = (0..m * dims)
            .map(|i| ((i as f64) * 0.37).sin() + ((i * i % 17) as f64) * 0.01)
            .collect();
        let lags = 350;
        let reference = reference_products(&v, m, dims, lags);
        for fft in [false, true] {
            let mut p = LaggedProducts::with_method(m, lags, fft);
            for c in 0..dims {
                let col: Vec<f64> = (0..m).map(|t| v[t * dims + c]).collect();
                p.add(&col);
            }
            let got = p.finish();
            assert_eq!(got.len(), lags);
            for (a, b) in reference.iter().zip(&got) {
                assert!(
                    (a - b).abs() <= 1e-9 * reference[0].abs(),
                    "fft {fft}: {a} vs {b}"
                );
            }
        }
        assert!(m * lags * dims <= DIRECT_PRODUCTS_MAX);
        assert!(LaggedProducts::new(m, lags, dims).fft.is_none());
        assert!(LaggedProducts::new(100_000, 30_000, 1024).fft.is_some());
    }

    #[test]
    fn missing_joints_are_filled_before_the_period_is_read() {
        // A 0.8 s circle per joint at 30 fps, with every fifth frame of a
        // joint missing: the estimate equals that of the track whose gaps
        // were filled beforehand.
        use mp_geom::{Skeleton, Track, Units};
        let (n, j) = (300, 4);
        let mut pos = ndarray::Array3::<f64>::zeros((n, j, 2));
        let mut conf = ndarray::Array2::<f64>::ones((n, j));
        for t in 0..n {
            for ji in 0..j {
                let a = t as f64 / 24.0 * std::f64::consts::TAU + ji as f64;
                pos[[t, ji, 0]] = 100.0 + 20.0 * a.cos() + ji as f64;
                pos[[t, ji, 1]] = 50.0 + 10.0 * a.sin() + 0.01 * ((t * 7 + ji) % 5) as f64;
                if (t + ji) % 5 == 0 {
                    conf[[t, ji]] = 0.0;
                    pos[[t, ji, 0]] = 0.0;
                }
            }
        }
        let gappy = Track::new(pos, Some(conf), 30.0, Units::Pixels, Skeleton::generic(j)).unwrap();
        let params = PeriodParams::default();
        for (a, b) in [(0, n), (40, 260)] {
            // The range, filled on its own (edges held), all frames valid.
            let mut filled = gappy.slice_frames(a, b).unwrap();
            filled.fill_missing();
            let filled = Track::new(
                filled.positions().to_owned(),
                None,
                30.0,
                Units::Pixels,
                Skeleton::generic(j),
            )
            .unwrap();
            let g = estimate_period(&gappy, a, b, &params).unwrap().unwrap();
            let f = estimate_period(&filled, 0, b - a, &params)
                .unwrap()
                .unwrap();
            assert_eq!(g.period_frames, 24);
            assert_eq!(g.period_frames, f.period_frames);
            assert!((g.strength - f.strength).abs() < 1e-12, "{g:?} vs {f:?}");
        }
        assert!(estimate_period(&gappy, 10, 10, &params).is_err());
        assert!(estimate_period(&gappy, 0, n + 1, &params).is_err());
    }
}
