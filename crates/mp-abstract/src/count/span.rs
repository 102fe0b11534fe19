//! Where the repetitions of a recording lie: the frames that move
//! ([`active_span`]), the part of those that repeats at the period
//! ([`repeating_span`]), how closely the motion returns to itself one
//! period later ([`cycle_mismatch`]), and the repetitions' mean period
//! between frames ([`mean_period`]).

use crate::error::Result;
use mp_geom::Track;

/// Distance between frames `a` and `b` of a track: the sum over joints of
/// the Euclidean distance, or over the channels of a unitless feature track
/// of the absolute differences (the same measure as the speed of
/// [`active_span`]).
pub(crate) fn frame_distance(track: &Track, a: usize, b: usize) -> f64 {
    let pos = track.positions();
    let (_, j, d) = pos.dim();
    let unitless = track.units() == mp_geom::Units::Unitless;
    let mut s = 0.0;
    for ji in 0..j {
        if unitless {
            s += (0..d)
                .map(|k| (pos[[b, ji, k]] - pos[[a, ji, k]]).abs())
                .sum::<f64>();
        } else {
            let mut q = 0.0;
            for k in 0..d {
                q += (pos[[b, ji, k]] - pos[[a, ji, k]]).powi(2);
            }
            s += q.sqrt();
        }
    }
    s
}

/// How far from the period (a fraction of it) the next cycle's matching
/// frame may lie when the counting trims the repetitions' ends: human
/// repetitions vary their pace by this much from cycle to cycle.
pub const PERIOD_SLACK: f64 = 0.2;

/// The counting trims an end of the repetitions only where its mismatch is
/// more than this multiple of the median mismatch over the activity (the
/// recording's own variation from cycle to cycle).
pub const MISMATCH_OVER_TYPICAL: f64 = 1.5;

/// Motion repeats well at a period where its distance to the nearest frame
/// about a period away is below this share of its distance to the frames
/// half a period away: it comes back to itself, and does not merely stay
/// near itself (as slow or still motion does at any lag).
pub const REPEATS_WELL: f64 = 0.5;

/// Where [`nearest_a_period_away`] looks for the matching frame.
#[derive(Clone, Copy, PartialEq)]
enum Towards {
    Later,
    Earlier,
    Either,
}

/// Distance of frame `t` to the nearest frame about `period` frames away
/// (people do not keep an exact period: within ±[`PERIOD_SLACK`] of it) in
/// the direction `towards`, inside `a..b`; infinite where there is none.
fn nearest_a_period_away(
    track: &Track,
    t: usize,
    period: usize,
    (a, b): (usize, usize),
    towards: Towards,
) -> f64 {
    let slack = ((period as f64 * PERIOD_SLACK).round() as usize).max(1);
    let mut best = f64::INFINITY;
    for lag in period.saturating_sub(slack).max(1)..=period + slack {
        if towards != Towards::Earlier && t + lag < b {
            best = best.min(frame_distance(track, t, t + lag));
        }
        if towards != Towards::Later && t >= a + lag {
            best = best.min(frame_distance(track, t - lag, t));
        }
    }
    best
}

/// The frames of `a..b` against a period `p` ([`mismatch_profile`]).
struct Profile {
    /// Each frame's distance to the nearest frame about a period later or
    /// earlier (within [`PERIOD_SLACK`], inside `a..b`; infinite where there
    /// is none).
    mismatch: Vec<f64>,
    /// The distance from frame `a + i` to frame `a + i + half` (half a
    /// period later), for each frame with one inside `a..b`.
    half_apart: Vec<f64>,
    /// The scale the mismatch is measured against: the median of the finite
    /// `half_apart` (large for a repeating motion, which is far from itself
    /// half way through its cycle).
    scale: f64,
}

/// Each frame's mismatch a period away, its distance half a period later,
/// and the scale ([`Profile`]). `None` when the span holds no pair half a
/// period apart or the scale is 0 (no motion).
fn mismatch_profile(track: &Track, p: usize, a: usize, b: usize) -> Option<Profile> {
    let p = p.max(1);
    let mismatch: Vec<f64> = (a..b)
        .map(|t| nearest_a_period_away(track, t, p, (a, b), Towards::Either))
        .collect();
    let half = (p / 2).max(1);
    let half_apart: Vec<f64> = (a..b.saturating_sub(half))
        .map(|t| frame_distance(track, t, t + half))
        .collect();
    let mut far: Vec<f64> = half_apart
        .iter()
        .copied()
        .filter(|d| d.is_finite())
        .collect();
    if far.is_empty() {
        return None;
    }
    far.sort_by(f64::total_cmp);
    let scale = far[far.len() / 2];
    (scale.is_finite() && scale > 0.0).then_some(Profile {
        mismatch,
        half_apart,
        scale,
    })
}

/// The frames `lo..hi` of a window of `w` frames centred on frame `i` of
/// `0..n` (shrinking at the edges).
fn centred(i: usize, w: usize, n: usize) -> (usize, usize) {
    (i.saturating_sub(w / 2), (i + w - w / 2).min(n))
}

/// How closely the motion of `a..b` returns to itself one period later, as
/// `(whole, ends)`: the median over its frames of the distance to the
/// nearest frame about a period away, over the distance between frames half
/// a period apart (both as in [`repeating_span`]), and the larger of the
/// same median over its first and over its last period. About 0 for an
/// exact repetition, about 1 or more for motion that does not repeat at this
/// period; `ends` above `whole` when the span reaches into other motion.
/// `None` when the span is shorter than a period and a half or does not move.
pub(crate) fn cycle_mismatch(
    track: &Track,
    period: usize,
    a: usize,
    b: usize,
) -> Option<(f64, f64)> {
    let p = period.max(1);
    if b <= a || 2 * (b - a) < 3 * p || b > track.n_frames() {
        return None;
    }
    let Profile {
        mismatch, scale, ..
    } = mismatch_profile(track, p, a, b)?;
    let median = |v: &[f64]| {
        let mut m: Vec<f64> = v.iter().copied().filter(|v| v.is_finite()).collect();
        if m.is_empty() {
            return None;
        }
        m.sort_by(f64::total_cmp);
        Some(m[m.len() / 2] / scale)
    };
    let whole = median(&mismatch)?;
    let k = p.min(mismatch.len());
    let ends = median(&mismatch[..k])
        .into_iter()
        .chain(median(&mismatch[mismatch.len() - k..]))
        .fold(whole, f64::max);
    (whole.is_finite() && ends.is_finite()).then_some((whole, ends))
}

/// The part of `a..b` that repeats at `period`: other motion before or after
/// the repetitions (a walk into place, a different movement) is active, so
/// [`active_span`] keeps it, yet it does not match itself one period later.
///
/// Each frame's mismatch is its distance to the nearest frame about a period
/// later or earlier (within [`PERIOD_SLACK`], inside `a..b`), averaged over half a
/// period; the scale is the median distance between frames half a period
/// apart (large for a repeating motion, which is far from itself half way
/// through its cycle). The repetitions start at the first frame whose
/// mismatch is within `fraction` of that scale or within
/// [`MISMATCH_OVER_TYPICAL`] times the recording's median mismatch, and end
/// at the last; the span is kept whole when fewer than two periods remain.
/// (Requiring half a period or a whole one in a row to match trimmed more of
/// the synthetic padding but also real cycles that vary: see docs/results/repetition.md.)
pub(crate) fn repeating_span(
    track: &Track,
    period: usize,
    a: usize,
    b: usize,
    fraction: f64,
) -> (usize, usize) {
    let p = period.max(1);
    if fraction <= 0.0 || b <= a || b - a < 3 * p {
        return (a, b);
    }
    let n = b - a;
    let Some(Profile {
        mismatch,
        half_apart,
        scale,
    }) = mismatch_profile(track, p, a, b)
    else {
        return (a, b);
    };
    let half = (p / 2).max(1);
    let mismatch: Vec<f64> = mismatch
        .into_iter()
        .map(|m| if m.is_finite() { m } else { 0.0 })
        .collect();
    let mut prefix = vec![0.0; n + 1];
    for i in 0..n {
        prefix[i + 1] = prefix[i] + mismatch[i];
    }
    let w = half;
    let smooth = |i: usize| {
        let (lo, hi) = centred(i, w, n);
        (prefix[hi] - prefix[lo]) / (hi - lo).max(1) as f64
    };
    // Trimmed: motion that is both far from a repetition (above `fraction`
    // of the half-period scale) and far worse than the recording's own
    // cycle-to-cycle variation (MISMATCH_OVER_TYPICAL × its median): real
    // repetitions vary in amplitude and pace, and jitter weighs more on
    // small movements, so the scale alone would trim them. Also trimmed:
    // slow motion that stays near itself without coming back (`repeats_here`).
    let smoothed: Vec<f64> = (0..n).map(smooth).collect();
    let mut sorted = smoothed.clone();
    sorted.sort_by(f64::total_cmp);
    let typical = sorted[n / 2];
    let limit = (fraction * scale).max(MISMATCH_OVER_TYPICAL * typical);
    let repeats = repeats_here(&mismatch, &half_apart, p);
    let first = (0..n).find(|&i| smoothed[i] <= limit && repeats[i]);
    let last = (0..n).rev().find(|&i| smoothed[i] <= limit && repeats[i]);
    match (first, last) {
        (Some(i), Some(k)) if k + 1 >= i + 2 * p => (a + i, a + k + 1),
        _ => (a, b),
    }
}

/// The frames between the first and the last that move: a frame is rest
/// when its speed (summed over channels, averaged over a centred window of
/// one period) is below `fraction` of the median over the recording. Falls
/// back to the whole recording when no frame moves.
pub(crate) fn active_span(track: &Track, period: usize, fraction: f64) -> Result<(usize, usize)> {
    let n = track.n_frames();
    if fraction <= 0.0 || n < 2 {
        return Ok((0, n));
    }
    // Speed: the sum of the joints' displacements; the channels of a unitless
    // feature track (thumbnail cells) are not coordinates of a point, so each
    // counts on its own (|Δ| per channel): `frame_distance`.
    // Displacements over a quarter period, per frame: keypoint jitter, which
    // does not grow with the lag, stays small beside the motion, which does.
    let lag = (period / 4).clamp(1, n - 1);
    let speed: Vec<f64> = (0..n)
        .map(|t| {
            let b = (t + lag).min(n - 1);
            let a = b.saturating_sub(lag);
            frame_distance(track, a, b) / (b - a).max(1) as f64
        })
        .collect();
    let w = period.max(1);
    let mut prefix = vec![0.0; n + 1];
    for t in 0..n {
        prefix[t + 1] = prefix[t] + speed[t];
    }
    let local: Vec<f64> = (0..n)
        .map(|t| {
            let (lo, hi) = centred(t, w, n);
            (prefix[hi] - prefix[lo]) / (hi - lo).max(1) as f64
        })
        .collect();
    let mut sorted = local.clone();
    sorted.sort_by(f64::total_cmp);
    // The activity's level: the median speed, or half the speed of the most
    // active tenth when the rest is the larger part (a person who stops and
    // stands for most of the recording).
    let median = sorted[n / 2];
    let q90 = sorted[(n * 9 / 10).min(n - 1)];
    let level = median.max(0.5 * q90);
    if level.is_nan() || level <= 0.0 {
        return Ok((0, n));
    }
    let first = local.iter().position(|&v| v >= fraction * level);
    let last = local.iter().rposition(|&v| v >= fraction * level);
    match (first, last) {
        (Some(a), Some(b)) if b >= a => Ok((a, b + 1)),
        _ => Ok((0, n)),
    }
}

/// The repetitions of `start..end` followed outward, inside `lo..hi`, for
/// as long as the motion keeps matching itself about a period away: each
/// frame's distance to the nearest frame within [`PERIOD_SLACK`] of a period
/// towards the repetitions, averaged over half a period, must stay within
/// `fraction` of the typical distance between frames half a period apart
/// or within [`MISMATCH_OVER_TYPICAL`] times the repetitions' own median
/// mismatch (the limits of [`repeating_span`]). Grown from what is known to
/// repeat, a chance match further out does not pull the span into other
/// motion.
pub(crate) fn extend_repeating(
    track: &Track,
    period: usize,
    (start, end): (usize, usize),
    (lo, hi): (usize, usize),
    fraction: f64,
) -> (usize, usize) {
    let p = period.max(1);
    if fraction <= 0.0 || end <= start || lo > start || hi < end || end - start < 2 * p {
        return (start, end);
    }
    let Some(Profile {
        mismatch: own,
        scale,
        ..
    }) = mismatch_profile(track, p, start, end)
    else {
        return (start, end);
    };
    let mut own: Vec<f64> = own.into_iter().filter(|m| m.is_finite()).collect();
    let Some(typical) = mp_geom::median(&mut own) else {
        return (start, end);
    };
    let limit = (fraction * scale).max(MISMATCH_OVER_TYPICAL * typical);
    let w = (p / 2).max(1);
    // How far the repetitions reach along `m` (the frames' mismatches going
    // outward): up to the first frame whose mean over the half period
    // towards the repetitions is above the limit. A frame with no frame a
    // period towards the repetitions inside `lo..hi` does not match.
    let reach = |m: Vec<f64>| -> usize {
        let m: Vec<f64> = m
            .into_iter()
            .map(|v| if v.is_finite() { v } else { 4.0 * limit })
            .collect();
        let mut sum = 0.0;
        for (i, &v) in m.iter().enumerate() {
            sum += v;
            if i >= w {
                sum -= m[i - w];
            }
            let mean = sum / (i + 1).min(w) as f64;
            if mean.is_nan() || mean > limit {
                return i;
            }
        }
        m.len()
    };
    let towards = |t, way| nearest_a_period_away(track, t, p, (lo, hi), way);
    let left = (lo..start)
        .rev()
        .map(|t| towards(t, Towards::Later))
        .collect();
    let right = (end..hi).map(|t| towards(t, Towards::Earlier)).collect();
    (start - reach(left), end + reach(right))
}

/// For each frame of a span (`mismatch` holds their distances to the
/// nearest frame about a period away, 0 where there is none; `half_apart`
/// as in [`Profile`]), whether it
/// belongs with the repetitions by this test: slow motion beside them stays
/// near itself a period later, which the recording-wide scale of
/// [`repeating_span`] lets through, yet it is as near itself half a period
/// later — it does not come back. Over the period centred on each frame:
/// the motion is **slow** where the mean distance to the frames half a
/// period away is below the median over the span divided by
/// [`MISMATCH_OVER_TYPICAL`] (beyond the recording's own variation, the
/// other way), and it **comes back** where the summed mismatch over the
/// summed distance to the frames half a period away is within
/// [`REPEATS_WELL`] or within [`MISMATCH_OVER_TYPICAL`] times that ratio's
/// median (repetitions that vary, or keypoints that jitter, come back less
/// closely everywhere). A frame fails only where its motion is slow and
/// does not come back: motion at the repetitions' own pace that drifts (a
/// person moving along while skipping, a camera that follows) is left to
/// the mismatch against the scale.
fn repeats_here(mismatch: &[f64], half_apart: &[f64], p: usize) -> Vec<bool> {
    let n = mismatch.len();
    let half = (p / 2).max(1);
    let mut num = vec![0.0; n + 1];
    let mut den = vec![0.0; n + 1];
    for i in 0..n {
        let later = half_apart.get(i).copied().unwrap_or(0.0);
        let earlier = i
            .checked_sub(half)
            .and_then(|k| half_apart.get(k).copied())
            .unwrap_or(0.0);
        num[i + 1] = num[i] + mismatch[i];
        den[i + 1] = den[i] + later.max(earlier);
    }
    // Per frame, over the period centred on it: (mismatch / far, mean far).
    let around: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            let (lo, hi) = centred(i, p, n);
            let far = den[hi] - den[lo];
            let ratio = if far > 0.0 {
                (num[hi] - num[lo]) / far
            } else {
                f64::INFINITY
            };
            (ratio, far / (hi - lo).max(1) as f64)
        })
        .collect();
    let median_of = |pick: fn(&(f64, f64)) -> f64| {
        let mut v: Vec<f64> = around.iter().map(pick).filter(|x| x.is_finite()).collect();
        mp_geom::median(&mut v).unwrap_or(0.0)
    };
    let comes_back = REPEATS_WELL.max(MISMATCH_OVER_TYPICAL * median_of(|x| x.0));
    let slow = median_of(|x| x.1) / MISMATCH_OVER_TYPICAL;
    around
        .iter()
        .map(|&(ratio, far)| ratio <= comes_back || far >= slow)
        .collect()
}

/// The mean period of the repetitions in `a..b` counted at `period`, to a
/// fraction of a frame: the lag within [`PERIOD_SLACK`] of it at which the
/// frames are nearest the frames that lag later, on average over the span
/// without its first and last period (the ends may reach into other
/// motion, which is nearer itself at shorter lags), refined by the parabola
/// through the nearest lag and its neighbours. The autocorrelation of
/// velocities weighs fast repetitions more (their velocities are larger) and
/// so reads the period short when the pace varies; distances between
/// positions weigh every frame alike. `period` itself where the span holds
/// fewer than four periods: too few cycles between its ends to average.
pub(crate) fn mean_period(track: &Track, period: usize, a: usize, b: usize) -> f64 {
    let p = period.max(1);
    if b < a + 4 * p {
        return p as f64;
    }
    let (a, b) = (a + p, b - p);
    let slack = ((p as f64 * PERIOD_SLACK).round() as usize).max(1);
    let lo = p.saturating_sub(slack).max(2) - 1;
    let hi = p + slack + 1;
    if b > track.n_frames() || b < a + hi + 2 {
        return p as f64;
    }
    // Mean distance at each lag lo..=hi.
    let d: Vec<f64> = (lo..=hi)
        .map(|l| {
            (a..b - l)
                .map(|t| frame_distance(track, t, t + l))
                .sum::<f64>()
                / (b - a - l) as f64
        })
        .collect();
    let Some(i) = (1..d.len() - 1).min_by(|&x, &y| d[x].total_cmp(&d[y])) else {
        return p as f64;
    };
    if !d[i].is_finite() {
        return p as f64;
    }
    let (x, y, z) = (d[i - 1], d[i], d[i + 1]);
    let curve = x - 2.0 * y + z;
    let shift = if curve > 0.0 {
        (0.5 * (x - z) / curve).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    (lo + i) as f64 + shift
}
