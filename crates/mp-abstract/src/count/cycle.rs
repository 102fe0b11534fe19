//! Which period a recording of one activity is counted at: the
//! autocorrelation's, a shorter one it is a multiple of where the motion
//! repeats as well there, or a longer one where the motion comes back to
//! itself clearly better ([`whole_cycle`]), with the span that repeats at it
//! and how well ([`Reading`]).

use super::span::{active_span, cycle_mismatch, repeating_span, REPEATS_WELL};
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

/// The cycle mismatch below which the motion repeats well at a period
/// ([`REPEATS_WELL`]): the nearest frame a period away is nearer than half
/// the distance between frames half a period apart. At a period where it
/// does not, the longer peaks of the autocorrelation are tried
/// ([`whole_cycle`]), and a longer one must be below it (a wandering body
/// that happens to come back near itself once is no repetition).
const LONGER_CYCLE_GATE: f64 = REPEATS_WELL;

/// A longer period replaces the autocorrelation's when its cycle mismatch is
/// below this share of the chosen period's: the motion comes back to itself
/// clearly better there.
const LONGER_CYCLE_GAIN: f64 = 0.7;

/// How far from a whole multiple of a shorter peak (a share of the
/// multiple) the chosen period may lie for [`whole_cycle`] to try that peak.
const MULTIPLE_SLACK: f64 = 0.1;

/// The period the repetitions are counted at, from the autocorrelation's
/// (`chosen`, with its strength) and its `others` peaks:
///
/// 1. **A shorter period the chosen one is a multiple of** (×2, ×3, … within
///    [`MULTIPLE_SLACK`]): taken where the motion repeats well there (cycle
///    mismatch below [`REPEATS_WELL`]) and not clearly worse than at the
///    chosen one (below it over [`LONGER_CYCLE_GAIN`]); the shortest such.
///    With the pace changing from one repetition to the next, the
///    autocorrelation at one cycle's lag can fall below two or three
///    cycles' (the chosen lag is the first reaching `peak_ratio` of the
///    highest), and the count would be a half or a third.
/// 2. **A longer period**: where the motion comes back to itself poorly at
///    the period so far (cycle mismatch ≥ [`LONGER_CYCLE_GATE`]) and both
///    well and clearly better at a longer peak (below [`LONGER_CYCLE_GATE`]
///    and below [`LONGER_CYCLE_GAIN`] of the first; the best of them) — as
///    when each cycle is made of several similar movements, the steps of a
///    dance figure, and the autocorrelation of the joint velocities peaks
///    first at one of them.
///
/// A period needs the strength `min_strength`, a longer one two cycles in
/// the recording.
pub(super) fn whole_cycle(
    signal: &Track,
    chosen: (usize, f64),
    others: &[(usize, f64)],
    params: &CountParams,
) -> Result<Reading> {
    let mut first = Reading::at(signal, chosen, params)?;
    let mut shorter: Option<Reading> = None;
    for &(l, s) in others.iter().filter(|&&(l, _)| l > 0 && l < chosen.0) {
        let ratio = chosen.0 as f64 / l as f64;
        let k = ratio.round();
        if k < 2.0 || (ratio - k).abs() > MULTIPLE_SLACK * k || s < params.min_strength {
            continue;
        }
        let r = Reading::at(signal, (l, s), params)?;
        let m = r.mismatch.0;
        if m < REPEATS_WELL && m * LONGER_CYCLE_GAIN < first.mismatch.0 {
            // The peaks come in increasing order: this is the shortest.
            shorter = Some(r);
            break;
        }
    }
    if let Some(r) = shorter {
        first = r;
    }
    let m0 = first.mismatch.0;
    if m0 < LONGER_CYCLE_GATE {
        return Ok(first);
    }
    let n = signal.n_frames();
    let p0 = first.period;
    let mut best = first;
    for &(l, s) in others.iter().filter(|&&(l, _)| l > p0) {
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
