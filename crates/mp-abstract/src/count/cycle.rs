//! Which period a recording of one activity is counted at: the
//! autocorrelation's, or a longer one where the motion comes back to itself
//! clearly better ([`whole_cycle`]), with the span that repeats at it and
//! how well ([`Reading`]).

use super::span::{active_span, cycle_mismatch, repeating_span};
use super::CountParams;
use crate::error::Result;
use mp_geom::Track;

/// A period, its strength, its repeating span and that span's mismatch.
pub(super) struct Reading {
    pub(super) period: usize,
    pub(super) strength: f64,
    pub(super) span: (usize, usize),
    /// `(whole, ends)` as [`cycle_mismatch`] gives it; (1, 1) when it has none.
    pub(super) mismatch: (f64, f64),
}

impl Reading {
    /// Where and how well the motion repeats at `period`: its repeating span
    /// (the active frames, trimmed to those that match themselves a period
    /// away) and that span's cycle mismatch.
    pub(super) fn at(
        signal: &Track,
        (period, strength): (usize, f64),
        params: &CountParams,
    ) -> Result<Self> {
        let (a, b) = active_span(signal, period, params.rest_fraction)?;
        let (a, b) = repeating_span(signal, period, a, b, params.mismatch_fraction);
        Ok(Reading {
            period,
            strength,
            span: (a, b),
            mismatch: cycle_mismatch(signal, period, a, b).unwrap_or((1.0, 1.0)),
        })
    }
}

/// The cycle mismatch below which the motion repeats well at a period: the
/// nearest frame a period away is nearer than half the distance between
/// frames half a period apart. At a period where it does not, the longer
/// peaks of the autocorrelation are tried ([`whole_cycle`]), and a longer
/// one must be below it (a wandering body that happens to come back near
/// itself once is no repetition).
const LONGER_CYCLE_GATE: f64 = 0.5;

/// A longer period replaces the autocorrelation's when its cycle mismatch is
/// below this share of the chosen period's: the motion comes back to itself
/// clearly better there.
const LONGER_CYCLE_GAIN: f64 = 0.7;

/// The period the repetitions are counted at: the autocorrelation's
/// (`chosen`, with its strength), unless the motion comes back to itself
/// poorly there (cycle mismatch ≥ [`LONGER_CYCLE_GATE`]) and both well and
/// clearly better at one of the `longer` peaks of the autocorrelation (below
/// [`LONGER_CYCLE_GATE`] and below [`LONGER_CYCLE_GAIN`] of the first; the
/// best of them) — as when each cycle is made of several similar movements,
/// the steps of a dance figure, and the autocorrelation of the joint
/// velocities peaks first at one of them. A longer period needs two cycles
/// in the recording and the strength `min_strength`.
pub(super) fn whole_cycle(
    signal: &Track,
    chosen: (usize, f64),
    longer: &[(usize, f64)],
    params: &CountParams,
) -> Result<Reading> {
    let first = Reading::at(signal, chosen, params)?;
    let m0 = first.mismatch.0;
    if m0 < LONGER_CYCLE_GATE {
        return Ok(first);
    }
    let n = signal.n_frames();
    let mut best = first;
    for &(l, s) in longer {
        if 2 * l > n {
            break;
        }
        if s < params.min_strength {
            continue;
        }
        let r = Reading::at(signal, (l, s), params)?;
        let m = r.mismatch.0;
        if m < LONGER_CYCLE_GATE && m < LONGER_CYCLE_GAIN * m0 && m < best.mismatch.0 {
            best = r;
        }
    }
    Ok(best)
}
