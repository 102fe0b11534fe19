//! Several activities in one recording: the segmenter's intervals joined
//! into activities, each counted over its own stretch of the recording.
//!
//! 1. **Activities** ([`activities`]): neighbouring intervals whose periods
//!    agree (within [`CountParams::period_tolerance`]), that lie at most
//!    [`GAP_PERIODS`] periods apart and whose poses continue each other
//!    (the same motion, not two exercises at one pace) are one activity cut
//!    in pieces (a hesitation, a lost pose, a change of pace).
//! 2. **Stretches**: each activity owns the recording from half way to the
//!    activity before it to half way to the one after (the recording's ends
//!    for the first and the last).
//! 3. **Count** ([`count_activity`]): inside its stretch, an activity's
//!    extent is followed outward for as long as the motion keeps matching
//!    itself about a period away, and counted at its own period. Grown from
//!    what is known to repeat, it stops at the first motion that does not,
//!    so it does not reach into a neighbour's. (Trimming the whole stretch
//!    from its ends inward, as for a recording of one activity, counted
//!    more of the real hour's clips but reached into the neighbours'
//!    motion on the synthetic long recordings: docs/results/repetition.md.)
//! 4. **Two signals** ([`merged`]): where the keypoints and the frames both
//!    read several activities, their intervals are merged, those that
//!    explain more of the recording (periodicity × frames) first, each cut
//!    back to the frames no kept interval holds (dropped when that loses
//!    more than a quarter of it), so each stretch is read from the signal
//!    that reads it better.

use super::span::{extend_repeating, frame_distance};
use super::{CountParams, CountSignal, CountedInterval, Counts};
use crate::repetition::PeriodicSegment;
use mp_geom::Track;

/// Neighbouring intervals of one period are one activity when the gap
/// between them is at most this many periods.
pub(crate) const GAP_PERIODS: f64 = 1.0;

/// One activity: consecutive intervals of one period.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Activity {
    pub start: usize,
    pub end: usize,
    /// The pieces' periods weighted by their lengths, frames.
    pub period: usize,
    /// The pieces' scores weighted by their lengths.
    pub score: f64,
}

/// The intervals (in time order) joined into activities: a piece joins the
/// activity before it when their periods agree within
/// [`CountParams::period_tolerance`] (of the shorter), the gap between them
/// is at most [`GAP_PERIODS`] periods and the piece continues the
/// activity's motion ([`same_motion`], within
/// [`CountParams::mismatch_fraction`]).
pub(crate) fn activities(
    signal: &Track,
    segs: &[PeriodicSegment],
    params: &CountParams,
) -> Vec<Activity> {
    let tolerance = params.period_tolerance;
    // Each activity with its pieces' total length, length-weighted period
    // sum and score sum.
    let mut out: Vec<(Activity, [f64; 3])> = Vec::new();
    for s in segs {
        let len = s.len_frames() as f64;
        let p = s.period_frames as f64;
        if let Some((act, [w, wp, ws])) = out.last_mut() {
            let ap = act.period as f64;
            let gap = s.start_frame.saturating_sub(act.end) as f64;
            if (ap - p).abs() <= tolerance * ap.min(p)
                && gap <= GAP_PERIODS * ap.max(p)
                && same_motion(
                    signal,
                    (act.start, act.end),
                    (s.start_frame, s.end_frame),
                    ap.max(p).round() as usize,
                    params.mismatch_fraction,
                )
            {
                *w += len;
                *wp += p * len;
                *ws += s.score * len;
                act.end = s.end_frame;
                act.period = (*wp / *w).round() as usize;
                act.score = *ws / *w;
                continue;
            }
        }
        let act = Activity {
            start: s.start_frame,
            end: s.end_frame,
            period: s.period_frames,
            score: s.score,
        };
        out.push((act, [len, p * len, s.score * len]));
    }
    out.into_iter().map(|(a, _)| a).collect()
}

/// Whether piece `b` continues the motion of piece `a` (`a` before `b`):
/// each frame of `b`'s first cycle is near some frame of `a`'s last cycle,
/// and the other way round — the median of those nearest distances within
/// `fraction` of the typical distance between frames half a period apart
/// (large for a repeating motion, which is far from itself half way through
/// its cycle). Two exercises of one pace are told apart by their poses.
fn same_motion(
    signal: &Track,
    a: (usize, usize),
    b: (usize, usize),
    period: usize,
    fraction: f64,
) -> bool {
    if fraction <= 0.0 {
        return true;
    }
    let p = period.max(2);
    let last = (a.1.saturating_sub(p).max(a.0), a.1);
    let first = (b.0, (b.0 + p).min(b.1));
    let nearest = |from: (usize, usize), to: (usize, usize)| -> f64 {
        let mut d: Vec<f64> = (from.0..from.1)
            .map(|t| {
                (to.0..to.1)
                    .map(|u| frame_distance(signal, t, u))
                    .fold(f64::INFINITY, f64::min)
            })
            .filter(|v| v.is_finite())
            .collect();
        mp_geom::median(&mut d).unwrap_or(f64::NAN)
    };
    let half = p / 2;
    let mut far: Vec<f64> = [last, first]
        .iter()
        .flat_map(|&(s, e)| (s..e.saturating_sub(half)).map(move |t| (t, t + half)))
        .map(|(t, u)| frame_distance(signal, t, u))
        .filter(|v| v.is_finite())
        .collect();
    let scale = mp_geom::median(&mut far).unwrap_or(f64::NAN);
    let mismatch = nearest(first, last).max(nearest(last, first));
    // Still pieces (no scale to measure by) are one motion.
    scale.is_nan() || scale <= 0.0 || mismatch <= fraction * scale
}

/// The stretch each activity owns: from half way to the activity before to
/// half way to the one after (`0` and `n` at the recording's ends).
pub(crate) fn stretches(acts: &[Activity], n: usize) -> Vec<(usize, usize)> {
    (0..acts.len())
        .map(|i| {
            let lo = if i == 0 {
                0
            } else {
                (acts[i - 1].end + acts[i].start) / 2
            };
            let hi = if i + 1 == acts.len() {
                n
            } else {
                (acts[i].end + acts[i + 1].start) / 2
            };
            (lo.min(acts[i].start), hi.max(acts[i].end))
        })
        .collect()
}

/// One activity counted over its stretch `lo..hi` at its own period: its
/// extent followed outward for as long as the motion keeps matching itself
/// about a period away (see [`extend_repeating`]; the limit is
/// [`CountParams::mismatch_fraction`], as for the ends of a recording of one
/// activity).
pub(crate) fn count_activity(
    signal: &Track,
    kind: CountSignal,
    act: &Activity,
    stretch: (usize, usize),
    params: &CountParams,
) -> CountedInterval {
    let p = act.period.max(1);
    let (a, b) = extend_repeating(
        signal,
        p,
        (act.start, act.end),
        stretch,
        params.mismatch_fraction,
    );
    CountedInterval::new(a, b, p as f64, act.score, kind)
}

/// Two readings of several activities made one: every interval of either,
/// the ones that explain more first (periodicity × frames), each kept where
/// it overlaps none kept before; the signal is the one whose kept intervals
/// explain more.
pub(crate) fn merged(a: Counts, b: Counts) -> Counts {
    let (ea, eb) = (explained(&a), explained(&b));
    let mut all: Vec<(f64, CountedInterval)> = a
        .intervals
        .iter()
        .chain(b.intervals.iter())
        .map(|i| {
            (
                i.periodicity * (i.end_frame - i.start_frame) as f64,
                i.clone(),
            )
        })
        .collect();
    all.sort_by(|x, y| y.0.total_cmp(&x.0));
    let mut kept: Vec<CountedInterval> = Vec::new();
    for (_, iv) in all {
        // Cut back to the frames no kept interval holds; dropped when that
        // loses more than a quarter of it.
        let (mut s0, mut e0) = (iv.start_frame, iv.end_frame);
        for k in &kept {
            if k.start_frame <= s0 && k.end_frame > s0 {
                s0 = k.end_frame;
            }
            if k.start_frame < e0 && k.end_frame >= e0 {
                e0 = k.start_frame;
            }
        }
        let inside = kept
            .iter()
            .any(|k| k.start_frame >= s0 && k.end_frame <= e0 && k.start_frame < k.end_frame);
        let len = iv.end_frame - iv.start_frame;
        if e0 <= s0 || inside || 4 * (e0 - s0) < 3 * len {
            continue;
        }
        kept.push(if (s0, e0) == (iv.start_frame, iv.end_frame) {
            iv
        } else {
            CountedInterval::new(s0, e0, iv.period_frames as f64, iv.periodicity, iv.signal)
        });
    }
    kept.sort_by_key(|i| i.start_frame);
    let mut out = if ea >= eb { a } else { b };
    out.total = kept.iter().map(|i| i.count).sum();
    out.intervals = kept;
    out
}

/// How much of the recording a count's intervals explain: their
/// periodicity weighted by their share of the frames.
fn explained(c: &Counts) -> f64 {
    c.intervals
        .iter()
        .map(|i| i.periodicity * (i.end_frame - i.start_frame) as f64)
        .sum::<f64>()
        / c.frames.max(1) as f64
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)] // test code: failing loudly is the point

    use super::*;
    use mp_geom::{Skeleton, Units};
    use ndarray::Array3;
    use std::f64::consts::TAU;

    /// Six joints over `n` frames: `motion(t, joint)` gives each position.
    fn track(n: usize, motion: impl Fn(usize, usize) -> [f64; 2]) -> Track {
        let mut p = Array3::zeros((n, 6, 2));
        for t in 0..n {
            for j in 0..6 {
                let [x, y] = motion(t, j);
                p[[t, j, 0]] = x;
                p[[t, j, 1]] = y;
            }
        }
        Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(6)).unwrap()
    }

    /// Arms swinging sideways (`sideways`) or a squat (every joint up and
    /// down), period `p` frames.
    fn exercise(t: usize, j: usize, p: f64, sideways: bool) -> [f64; 2] {
        let ph = TAU * t as f64 / p;
        let base = [200.0 + 20.0 * j as f64, 300.0 - 15.0 * j as f64];
        if sideways {
            let a = 40.0 * (j as f64 / 5.0);
            [base[0] + a * (ph + 0.3 * j as f64).sin(), base[1]]
        } else {
            [base[0], base[1] + 35.0 * ph.cos()]
        }
    }

    fn seg(s: usize, e: usize, p: usize) -> PeriodicSegment {
        PeriodicSegment {
            start_frame: s,
            end_frame: e,
            period_frames: p,
            score: 0.8,
            count: (e - s) as f64 / p as f64,
        }
    }

    #[test]
    fn pieces_of_one_motion_join_and_two_exercises_at_one_pace_do_not() {
        let t = track(900, |t, j| exercise(t, j, 30.0, !(300..600).contains(&t)));
        let params = CountParams::default();
        // Swings in two pieces with a hesitation of 10 frames, a squat at the
        // same pace, then swings again at twice the period.
        let segs = [
            seg(0, 140, 30),
            seg(150, 300, 31),
            seg(300, 600, 30),
            seg(600, 900, 60),
        ];
        let acts = activities(&t, &segs, &params);
        let spans: Vec<(usize, usize, usize)> =
            acts.iter().map(|a| (a.start, a.end, a.period)).collect();
        assert_eq!(
            spans,
            vec![(0, 300, 31), (300, 600, 30), (600, 900, 60)],
            "{acts:?}"
        );
        // A gap longer than a period keeps two bouts apart.
        let apart = activities(&t, &[seg(0, 100, 30), seg(140, 300, 30)], &params);
        assert_eq!(apart.len(), 2, "{apart:?}");
        assert_eq!(
            stretches(&apart, 900),
            vec![(0, 120), (120, 900)],
            "half way between them"
        );
    }

    #[test]
    fn an_activity_grows_over_its_repetitions_and_stops_at_other_motion() {
        // A walk (a steady drift, different poses every frame) before and
        // after ten swings of 30 frames.
        let walk = |t: usize, j: usize| {
            [
                120.0 + 1.5 * t as f64 + 9.0 * j as f64,
                260.0 + 4.0 * j as f64,
            ]
        };
        let t = track(480, |t, j| {
            if (90..390).contains(&t) {
                exercise(t - 90, j, 30.0, true)
            } else {
                walk(t, j)
            }
        });
        let act = Activity {
            start: 150,
            end: 330,
            period: 30,
            score: 0.8,
        };
        let iv = count_activity(
            &t,
            CountSignal::Keypoints,
            &act,
            (0, 480),
            &CountParams::default(),
        );
        assert!(
            (80..=100).contains(&iv.start_frame) && (380..=400).contains(&iv.end_frame),
            "{iv:?}"
        );
        assert_eq!(iv.count, 10, "{iv:?}");
        // Never less than the activity's own extent.
        let inside = count_activity(
            &t,
            CountSignal::Keypoints,
            &act,
            (150, 330),
            &CountParams::default(),
        );
        assert_eq!((inside.start_frame, inside.end_frame), (150, 330));
    }
}
