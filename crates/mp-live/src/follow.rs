//! Following a set of repetitions: whether the stretch of a stream that
//! ends where the next repetition is expected comes back to the stretch
//! before it (the person's poses, or the scene's thumbnails), so that the
//! repetition can be reported on its last frame rather than after the
//! confirmation margin of the next counting (see `counter`).

pub(crate) use mp_abstract::{PERIOD_SLACK, REPEATS_WELL};

/// A followed repetition is not reported when its motion (mean distance
/// between frames half a period apart) is weaker than the period before's by
/// more than this factor (the offline counting's ratio of a mismatch to its
/// typical value): the motion is dying down.
pub(crate) const WEAKER_AT_MOST: f64 = mp_abstract::MISMATCH_OVER_TYPICAL;

/// How a stretch of a stream comes back to the stretch before it
/// ([`comes_back`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CameBack {
    /// The least, over the lags, of the mean distance between frames a lag
    /// apart over the mean distance between frames half that lag apart.
    pub(crate) mismatch: f64,
    /// The mean distance between frames half the best lag apart, over the
    /// stretch and over the stretch before it.
    pub(crate) half_now: f64,
    pub(crate) half_before: f64,
}

impl CameBack {
    /// Whether the stretch repeats the one before well (under
    /// [`REPEATS_WELL`], the offline counting's value for motion that comes
    /// back to itself) and its motion has not died down ([`WEAKER_AT_MOST`]).
    pub(crate) fn repeats(&self) -> bool {
        self.mismatch < REPEATS_WELL && self.half_now * WEAKER_AT_MOST >= self.half_before
    }
}

/// Mean over the stream frames `f` of `from..to` of `distance(f, f − lag)`.
fn mean_distance(
    from: usize,
    to: usize,
    lag: usize,
    distance: &impl Fn(usize, usize) -> Option<f64>,
) -> Option<f64> {
    let mut sum = 0.0;
    for f in from..to {
        sum += distance(f, f.checked_sub(lag)?)?;
    }
    (to > from).then(|| sum / (to - from) as f64)
}

/// How the stretch ending at stream frame `end` (exclusive) comes back to
/// the stretch before it: for each lag, the `lag` frames before `end` against
/// the frames a lag earlier and half a lag earlier (see [`CameBack`]);
/// `distance(f, g)` is the distance between stream frames `f` and `g`.
/// `None` when a distance is missing (a frame outside the window) or a lag
/// is under 2.
pub(crate) fn comes_back(
    end: usize,
    lags: std::ops::RangeInclusive<usize>,
    distance: impl Fn(usize, usize) -> Option<f64>,
) -> Option<CameBack> {
    let mut best: Option<(f64, usize, f64)> = None;
    for lag in lags {
        if lag < 2 {
            return None;
        }
        let from = end.checked_sub(lag)?;
        let near = mean_distance(from, end, lag, &distance)?;
        let half = mean_distance(from, end, lag / 2, &distance)?;
        let m = if half > 0.0 {
            near / half
        } else {
            f64::INFINITY
        };
        if best.is_none_or(|(b, _, _)| m < b) {
            best = Some((m, lag, half));
        }
    }
    let (mismatch, lag, half_now) = best?;
    let before = end.checked_sub(lag)?;
    let half_before = mean_distance(before.checked_sub(lag)?, before, lag / 2, &distance)?;
    Some(CameBack {
        mismatch,
        half_now,
        half_before,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_swing_comes_back_to_itself_a_period_later_and_a_drift_does_not() {
        let tau = 2.0 * std::f64::consts::PI;
        let swing = |f: usize, g: usize| {
            let at = |f: usize| (tau * f as f64 / 20.0).sin();
            (f < 100 && g < 100).then(|| (at(f) - at(g)).abs())
        };
        let b = comes_back(100, 16..=22, swing).unwrap();
        assert!(b.mismatch < 0.05 && b.repeats(), "{b:?}");
        assert!((b.half_now / b.half_before - 1.0).abs() < 0.05, "{b:?}");
        let drift = |f: usize, g: usize| Some((f as f64 - g as f64).abs() / 10.0);
        let d = comes_back(100, 16..=22, drift).unwrap();
        assert!(d.mismatch > 1.5 && !d.repeats(), "{d:?}");
        // A swing that dies down does not repeat.
        let fading = |f: usize, g: usize| {
            let at = |f: usize| (tau * f as f64 / 20.0).sin() * if f >= 80 { 0.3 } else { 1.0 };
            Some((at(f) - at(g)).abs())
        };
        assert!(!comes_back(100, 16..=22, fading).unwrap().repeats());
        // Frames before the stream's first are missing; a lag under 2 is refused.
        assert!(comes_back(30, 16..=22, swing).is_none());
        assert!(comes_back(100, 1..=3, swing).is_none());
    }
}
