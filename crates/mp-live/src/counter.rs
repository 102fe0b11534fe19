//! The online repetition counter of one person.
//!
//! The person's recent poses sit in a sliding window of at most
//! `window_s` seconds of stream frames (older ones are forgotten, so memory
//! is bounded whatever the stream's length). Every `count_every_s` seconds
//! of stream time the window is counted with the offline counting
//! ([`mp_pipeline::count`], the keypoints of `mp run`), and its repetitions
//! (their boundaries, in stream frames) become a running total:
//!
//! - a counting whose confidence (`Counts::confidence`) is below
//!   `min_confidence` is set aside: early on, with a cycle or two in the
//!   window, the counting often takes a harmonic for the period — unless
//!   its repetitions run to the window's end and the last two of its
//!   periods each come back to the period before (the test of a followed
//!   set, below), which a period too short or too long for the motion fails;
//! - a repetition is **confirmed** once its end lies `confirm_periods` of
//!   its period before the window's last frame (the counting of a window
//!   often stretches or cuts the repetition still under way);
//! - the part of it after the end of the last repetition taken (the stream
//!   frame up to which the stream is counted, which only grows) is added,
//!   in periods, to the cycles seen so far (as the offline counting divides
//!   an interval's length by its period); the running total is those cycles
//!   rounded, so a repetition is reported when they pass the next half. Two countings of overlapping windows place their
//!   boundaries differently (each from its own window's start): taking
//!   whole repetitions again would count the overlap twice;
//! - while the last confident (or vouched-for) counting's repetitions run
//!   to the window's end, they are **followed**: the next repetition is expected a period
//!   after the last one taken, and is reported on the frame it ends when the
//!   poses of that period come back to those of the period before (and the
//!   motion has not slowed), without waiting for the margin or the next
//!   counting, or on a later frame up to 1.2 periods (a pace that slows);
//!   a period that does not come back waits for the countings;
//! - at the end of the stream (or when the person leaves) the window is
//!   counted once more and every new repetition in it is reported, confirmed
//!   or not, so that on a stream shorter than the window the total is the
//!   offline count of the same frames whenever the earlier countings agreed
//!   with the last one.

use mp_abstract::Counts;
use mp_geom::Skeleton;

use crate::follow::{self, PERIOD_SLACK};
use crate::poses::Poses;
use crate::{LiveParams, Result};

/// One repetition reported.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Repetition {
    /// The person's running total, this repetition included.
    pub count: usize,
    /// First stream frame.
    pub start_frame: usize,
    /// One past the last stream frame.
    pub end_frame: usize,
}

/// A window's countings and their repetitions turned into a running total
/// (see the module docs): the window's size and when it is next counted, the
/// part of the stream counted so far, the cycles seen and the repetitions
/// reported.
pub(crate) struct Tally {
    /// The most stream frames the window may hold.
    pub(crate) max_frames: usize,
    every: usize,
    last_counted: Option<usize>,
    confirm_periods: f64,
    min_confidence: f64,
    reported_until: usize,
    cycles: f64,
    total: usize,
    /// The period (frames, unrounded) of the last counting taken whose
    /// repetitions run to the window's end: the next repetition is expected
    /// one period after `reported_until`.
    following: Option<f64>,
    /// The first stream frame and the end of the expected repetition last checked.
    checked: Option<(usize, usize)>,
}

impl Tally {
    /// The tally of a window of a stream at `fps` frames per second.
    pub(crate) fn new(fps: f64, params: &LiveParams) -> Self {
        let frames = |s: f64| (s * fps).round().max(1.0) as usize;
        Tally {
            max_frames: frames(params.window_s).max(4),
            every: frames(params.count_every_s),
            last_counted: None,
            confirm_periods: params.confirm_periods,
            min_confidence: params.min_confidence,
            reported_until: 0,
            cycles: 0.0,
            total: 0,
            following: None,
            checked: None,
        }
    }

    /// Repetitions reported so far.
    pub(crate) fn total(&self) -> usize {
        self.total
    }

    /// Counts `n` repetitions reported elsewhere as this tally's first ones
    /// (the scene's, which a person takes over): the next one reported is `n` later.
    pub(crate) fn add_earlier(&mut self, n: usize) {
        self.total += n;
        self.cycles += n as f64;
    }

    /// Whether a window ending at stream frame `back` is due to be counted.
    pub(crate) fn due(&self, back: Option<usize>) -> bool {
        match (back, self.last_counted) {
            (None, _) => false,
            (Some(_), None) => true,
            (Some(b), Some(c)) => b >= c + self.every,
        }
    }

    /// Records that the window ending at stream frame `back` is being counted.
    pub(crate) fn counting(&mut self, back: usize) {
        self.last_counted = Some(back);
    }

    /// The repetitions newly confirmed by `counts`, the counting of the
    /// window of stream frames `first..=back` (every new one when `last`).
    pub(crate) fn take(
        &mut self,
        counts: &Counts,
        first: usize,
        back: usize,
        last: bool,
        distance: impl Fn(usize, usize) -> Option<f64>,
    ) -> Vec<Repetition> {
        let mut out = Vec::new();
        let running = running_period(counts, first, back);
        // An unsure counting (the window holds too few cycles, or the
        // period found is a harmonic) waits for a surer one, unless the
        // stream's last two of its periods each come back to the one before.
        if !last && counts.confidence < self.min_confidence && !vouched(running, back, &distance) {
            self.following = None;
            return out;
        }
        // Repetitions that run to the window's end are followed.
        self.following = running.filter(|_| !last);
        for iv in &counts.intervals {
            let margin = (self.confirm_periods * iv.period_frames as f64).ceil() as usize;
            for w in iv.boundaries.windows(2) {
                let (s, e) = (first + w[0], first + w[1]);
                if e <= s || e <= self.reported_until {
                    continue;
                }
                // `e` is one past the repetition's last frame.
                if !last && e + margin > back + 1 {
                    break;
                }
                let new = (e - s.max(self.reported_until)) as f64 / iv.period_frames.max(1) as f64;
                out.extend(self.advance(s, e, new));
            }
        }
        out
    }

    /// Takes the stream up to frame `e` (exclusive) as `new` more cycles of
    /// the repetition that began at `s`: a repetition when the cycles pass
    /// the next half.
    fn advance(&mut self, s: usize, e: usize, new: f64) -> Option<Repetition> {
        self.reported_until = e;
        self.cycles += new;
        if self.cycles < self.total as f64 + 0.5 {
            return None;
        }
        self.total += 1;
        Some(Repetition {
            count: self.total,
            start_frame: s,
            end_frame: e,
        })
    }

    /// The repetition expected next while repetitions are followed: its
    /// first stream frame, one past its last, and the period.
    fn expected(&self) -> Option<(usize, usize, f64)> {
        let period = self.following?;
        let start = self.reported_until;
        (start > 0).then(|| (start, start + period.round().max(2.0) as usize, period))
    }

    /// While the last counting taken has repetitions that run to the
    /// window's end, the next repetition is expected a period after the last one
    /// taken. It is reported once the stream's last frame `back` reaches its
    /// end, when that period comes back to the period before
    /// ([`follow::comes_back`] over lags of 0.8–1 period, [`follow::CameBack::repeats`]:
    /// as the offline counting's test of where repetitions end) by
    /// `distance(f, g)` between stream frames. If not, it is checked again
    /// on each later frame up to 1 + [`PERIOD_SLACK`] periods after the last one
    /// (lags up to the frames since), and counted as one cycle when it comes
    /// back; otherwise it waits for the window's next counting.
    pub(crate) fn follow(
        &mut self,
        back: usize,
        distance: impl Fn(usize, usize) -> Option<f64>,
    ) -> Option<Repetition> {
        let (start, due, period) = self.expected()?;
        let end = back + 1;
        let latest = start + ((1.0 + PERIOD_SLACK) * period).round() as usize;
        if end < due || end > latest || self.checked == Some((start, end)) {
            return None;
        }
        self.checked = Some((start, end));
        let lags = shortest_lag(period)..=end - start;
        if !follow::comes_back(end, lags, distance)?.repeats() {
            return None;
        }
        self.advance(
            start,
            end,
            if end == due {
                (end - start) as f64 / period
            } else {
                1.0
            },
        )
    }

    /// The stream before the expected repetition changed (poses taken back):
    /// it is checked again.
    pub(crate) fn forget_checked(&mut self) {
        self.checked = None;
    }
}

/// The shortest lag a period is compared at: human repetitions vary their
/// pace by [`PERIOD_SLACK`] (the offline counting's) from cycle to cycle.
fn shortest_lag(period: f64) -> usize {
    ((1.0 - PERIOD_SLACK) * period).round().max(2.0) as usize
}

/// The period (frames, unrounded) of the counted repetitions that run to
/// the end of the window of stream frames `first..=back`: their span ends
/// less than a period before its last frame.
fn running_period(counts: &Counts, first: usize, back: usize) -> Option<f64> {
    counts
        .intervals
        .iter()
        .filter(|iv| iv.cycles > 0.0)
        .find(|iv| (first + iv.end_frame) as f64 + iv.period() >= (back + 1) as f64)
        .map(|iv| iv.period())
}

/// Whether the last two periods before stream frame `back` (inclusive)
/// each come back to the period before them ([`follow::comes_back`] over
/// lags of 0.8–1 period): a counting at that period is taken even when
/// its confidence is low. The test refuses a period too short for the
/// motion (frames a period apart are no nearer than frames half of it
/// apart) and one too long (frames half of it apart are as near).
fn vouched(
    period: Option<f64>,
    back: usize,
    distance: &impl Fn(usize, usize) -> Option<f64>,
) -> bool {
    let Some(period) = period else {
        return false;
    };
    let t = period.round().max(2.0) as usize;
    let lags = shortest_lag(period)..=t;
    [back + 1, (back + 1).saturating_sub(t)]
        .iter()
        .all(|&end| follow::comes_back(end, lags.clone(), distance).is_some_and(|b| b.repeats()))
}

/// See the module docs.
pub struct OnlineCounter {
    rows: Poses,
    tally: Tally,
    longest: usize,
}

impl OnlineCounter {
    /// A counter of poses in `skeleton` at `fps` frames per second; they are
    /// counted in COCO-17 unless `params.analysis.pose.all_joints` (as `mp run`).
    pub fn new(fps: f64, skeleton: Skeleton, params: &LiveParams) -> Self {
        OnlineCounter {
            rows: Poses::new(fps, skeleton, params),
            tally: Tally::new(fps, params),
            longest: 0,
        }
    }

    /// Repetitions reported so far.
    pub fn total(&self) -> usize {
        self.tally.total()
    }

    /// Takes `n` repetitions counted before this counter's first as its own
    /// first ones: its next repetition is reported `n` later.
    pub fn add_earlier(&mut self, n: usize) {
        self.tally.add_earlier(n);
    }

    /// Stream frames in the window now.
    pub fn window_len(&self) -> usize {
        self.rows.len()
    }

    /// The most stream frames the window ever held.
    pub fn longest_window(&self) -> usize {
        self.longest
    }

    /// The most stream frames the window may hold.
    pub fn max_window(&self) -> usize {
        self.tally.max_frames
    }

    /// Adds the pose of stream frame `frame` (after the previous one).
    /// A short gap since the previous pose (dropped frames) is filled by
    /// linear interpolation; a longer one stays empty (no pose).
    pub fn push(&mut self, frame: usize, points: Vec<[f64; 2]>, conf: Vec<f64>) {
        self.rows.push(frame, points, conf);
        if let Some(last) = self.rows.last_frame() {
            self.rows
                .forget_before((last + 1).saturating_sub(self.tally.max_frames));
        }
        self.longest = self.longest.max(self.rows.len());
    }

    /// Takes back the poses after stream frame `frame` (the tracker took them back).
    pub fn retract_after(&mut self, frame: usize) {
        self.rows.retract_after(frame);
        self.tally.forget_checked();
    }

    /// Whether the window is due to be counted again.
    pub fn due(&self) -> bool {
        self.tally.due(self.rows.last_frame())
    }

    /// Returns the repetitions newly confirmed: the one expected next while
    /// a set is followed, once its poses come back to those of the period
    /// before (see the module docs), and those of the window's counting when
    /// it is due.
    pub fn update(&mut self, params: &LiveParams) -> Result<Vec<Repetition>> {
        let mut out: Vec<Repetition> = self.follow().into_iter().collect();
        if self.due() {
            out.extend(self.count_window(params, false)?);
        }
        Ok(out)
    }

    /// The repetition expected next while a set is followed
    /// ([`Tally::follow`]), the poses compared by [`Poses::distance`].
    fn follow(&mut self) -> Option<Repetition> {
        let back = self.rows.last_frame()?;
        let rows = &self.rows;
        self.tally.follow(back, |f, g| rows.distance(f, g))
    }

    /// Counts the window once more and reports every new repetition in it
    /// (the end of the stream, or the person left).
    pub fn finish(&mut self, params: &LiveParams) -> Result<Vec<Repetition>> {
        self.count_window(params, true)
    }

    fn count_window(&mut self, params: &LiveParams, last: bool) -> Result<Vec<Repetition>> {
        let Some((first, back)) = self.rows.span() else {
            return Ok(Vec::new());
        };
        self.tally.counting(back);
        if back - first + 1 < 4 {
            return Ok(Vec::new());
        }
        let Some(track) = self.rows.track()? else {
            return Ok(Vec::new());
        };
        let counts = mp_pipeline::count(&track, None, &params.analysis)?;
        let rows = &self.rows;
        Ok(self
            .tally
            .take(&counts, first, back, last, |f, g| rows.distance(f, g)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_geom::{Track, Units};
    use ndarray::{Array2, Array3};

    /// A COCO-17 pose whose wrists and elbows swing with period `period` frames.
    fn pose(f: usize, period: f64) -> (Vec<[f64; 2]>, Vec<f64>) {
        pose_at(f as f64 / period)
    }

    /// The pose of [`pose`] at `cycles` cycles of its swing.
    fn pose_at(cycles: f64) -> (Vec<[f64; 2]>, Vec<f64>) {
        let a = (2.0 * std::f64::consts::PI * cycles).sin();
        let pts = (0..17)
            .map(|q| {
                let x = 100.0 + 10.0 * (q % 4) as f64;
                let y = 100.0 + 20.0 * (q / 4) as f64;
                let swing = if (7..=10).contains(&q) { 60.0 } else { 3.0 };
                [x + 0.3 * swing * a, y - swing * a]
            })
            .collect();
        (pts, vec![0.9; 17])
    }

    fn offline_total(frames: usize, period: f64, fps: f64) -> usize {
        let mut pos = Array3::<f64>::zeros((frames, 17, 2));
        for f in 0..frames {
            for (q, p) in pose(f, period).0.into_iter().enumerate() {
                pos[[f, q, 0]] = p[0];
                pos[[f, q, 1]] = p[1];
            }
        }
        let conf = Array2::from_elem((frames, 17), 0.9);
        let track = Track::new(pos, Some(conf), fps, Units::Pixels, Skeleton::coco17()).unwrap();
        mp_pipeline::count(&track, None, &mp_pipeline::Params::default())
            .unwrap()
            .total
    }

    #[test]
    fn reports_each_repetition_once_and_matches_offline() {
        let (fps, period, frames) = (30.0, 30.0, 300);
        let params = LiveParams::default();
        let mut c = OnlineCounter::new(fps, Skeleton::coco17(), &params);
        let mut reps = Vec::new();
        for f in 0..frames {
            let (p, v) = pose(f, period);
            c.push(f, p, v);
            reps.extend(c.update(&params).unwrap());
        }
        let before_end = reps.len();
        reps.extend(c.finish(&params).unwrap());
        let offline = offline_total(frames, period, fps);
        assert!(
            before_end >= offline - 2,
            "{before_end} of {offline} before the end"
        );
        assert_eq!(reps.len(), offline, "{reps:?}");
        for (k, r) in reps.iter().enumerate() {
            assert_eq!(r.count, k + 1);
            assert!(r.end_frame > r.start_frame);
            if k > 0 {
                assert!(r.end_frame > reps[k - 1].end_frame, "{reps:?}");
            }
        }
    }

    #[test]
    fn followed_repetitions_are_reported_as_they_end_and_stop_with_the_motion() {
        let (fps, period, frames, still_from) = (30.0, 30.0, 330, 240);
        let params = LiveParams::default();
        let mut c = OnlineCounter::new(fps, Skeleton::coco17(), &params);
        let mut reported = Vec::new();
        for f in 0..frames {
            // Swings until `still_from`, then holds the pose of that frame.
            let (p, v) = pose(f.min(still_from), period);
            c.push(f, p, v);
            for r in c.update(&params).unwrap() {
                reported.push((f, r));
            }
        }
        let first_batch = reported[0].0;
        let later: Vec<_> = reported.iter().filter(|(f, _)| *f > first_batch).collect();
        assert!(later.len() >= 3, "{reported:?}");
        // Once followed, a repetition is reported on its own last frame, not
        // half a period (15 frames) after it.
        for (f, r) in &later {
            assert!(*f + 1 - r.end_frame <= 2, "{f}: {r:?}");
        }
        // Nothing is reported for the held pose: 8 cycles swung.
        let total = c.total() + c.finish(&params).unwrap().len();
        assert!((7..=8).contains(&total), "{total}: {reported:?}");
    }

    #[test]
    fn a_pace_slowing_down_is_still_followed() {
        // 30-frame swings, then 36-frame ones (phase continuous).
        let phase = |f: usize| {
            if f < 180 {
                f as f64 / 30.0
            } else {
                6.0 + (f - 180) as f64 / 36.0
            }
        };
        let params = LiveParams::default();
        let mut c = OnlineCounter::new(30.0, Skeleton::coco17(), &params);
        let mut late = Vec::new();
        for f in 0..400 {
            let (p, v) = pose_at(phase(f));
            c.push(f, p, v);
            for r in c.update(&params).unwrap() {
                // The repetitions of the slower pace, after its first.
                if r.start_frame >= 216 {
                    late.push(f + 1 - r.end_frame);
                }
            }
        }
        assert!(late.len() >= 4, "{late:?}");
        assert!(late.iter().all(|&d| d <= 2), "{late:?}");
    }

    #[test]
    fn an_unsure_counting_is_vouched_for_only_at_a_period_that_comes_back() {
        let params = LiveParams::default();
        let mut rows = Poses::new(30.0, Skeleton::coco17(), &params);
        for f in 0..200 {
            let (p, v) = pose(f, 30.0);
            rows.push(f, p, v);
        }
        let d = |f: usize, g: usize| rows.distance(f, g);
        assert!(vouched(Some(30.0), 199, &d));
        assert!(vouched(Some(31.5), 199, &d));
        // Too short for the motion, a harmonic, about twice the period, none.
        assert!(!vouched(Some(8.0), 199, &d));
        assert!(!vouched(Some(15.0), 199, &d));
        assert!(!vouched(Some(57.0), 199, &d));
        assert!(!vouched(None, 199, &d));
        // Two periods before the window's first frame cannot be compared.
        assert!(!vouched(Some(30.0), 70, &d));
    }

    #[test]
    fn repetitions_taken_over_come_first_and_none_is_skipped() {
        let (fps, period, frames) = (30.0, 30.0, 300);
        let params = LiveParams::default();
        let mut c = OnlineCounter::new(fps, Skeleton::coco17(), &params);
        let mut reps = Vec::new();
        for f in 0..frames {
            let (p, v) = pose(f, period);
            c.push(f, p, v);
            let new = c.update(&params).unwrap();
            if reps.is_empty() && !new.is_empty() {
                // Two repetitions counted elsewhere before these.
                c.add_earlier(2);
                reps.extend(new.into_iter().map(|r| Repetition {
                    count: r.count + 2,
                    ..r
                }));
            } else {
                reps.extend(new);
            }
        }
        reps.extend(c.finish(&params).unwrap());
        let offline = offline_total(frames, period, fps);
        assert_eq!(c.total(), offline + 2);
        let counts: Vec<usize> = reps.iter().map(|r| r.count).collect();
        assert_eq!(counts, (3..=offline + 2).collect::<Vec<_>>());
    }

    #[test]
    fn window_stays_bounded_over_twenty_minutes() {
        // A short window and sparse countings keep the test quick; the bound
        // is the same whatever the stream's length.
        let fps = 15.0;
        let params = LiveParams {
            window_s: 8.0,
            count_every_s: 4.0,
            ..LiveParams::default()
        };
        let mut c = OnlineCounter::new(fps, Skeleton::coco17(), &params);
        let frames = (20.0 * 60.0 * fps) as usize;
        let mut last = 0;
        for f in 0..frames {
            let (p, v) = pose(f, 24.0);
            c.push(f, p, v);
            for r in c.update(&params).unwrap() {
                assert_eq!(r.count, last + 1);
                last = r.count;
            }
            assert!(c.window_len() <= c.max_window());
        }
        assert_eq!(c.max_window(), 120);
        assert_eq!(c.longest_window(), 120);
        // 1.6 s cycles over 20 minutes: 750.
        let total = c.total() + c.finish(&params).unwrap().len();
        assert!((748..=751).contains(&total), "{total}");
    }

    #[test]
    fn short_gaps_are_filled_and_taken_back() {
        let params = LiveParams::default();
        let mut c = OnlineCounter::new(30.0, Skeleton::coco17(), &params);
        let (p, v) = pose(0, 30.0);
        c.push(0, p.clone(), v.clone());
        c.push(4, p.clone(), v.clone());
        assert_eq!(c.window_len(), 5);
        c.push(100, p, v);
        assert_eq!(c.window_len(), 6);
        c.retract_after(4);
        assert_eq!(c.window_len(), 5);
    }
}
