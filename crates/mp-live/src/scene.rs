//! The scene's online repetition counter: the repetitions of the picture
//! itself until a person's first repetition is counted (a person the pose
//! model does not find, a hula hoop whose dancer's head is out of the
//! frame), as `mp run` counts a video where nobody is found.
//!
//! The grey thumbnails of the whole frame (`mp run`'s: 32 × 32 cells by
//! default, `PoseParams::thumbnail_size`) sit in a sliding window of at most `window_s` seconds of stream frames, one
//! per stream frame (a dropped frame repeats the one before), so memory is
//! bounded whatever the stream's length. Every `count_every_s` seconds the
//! window is counted from the frames alone ([`mp_pipeline::count_frames`]:
//! `mp run`'s choice of the frame signal, then its counting) and its
//! repetitions become a running total exactly as a person's do (see
//! `counter`), a set followed by the thumbnails' root mean square
//! difference. The run reports them as person 0.

use std::collections::VecDeque;

use mp_pose::Thumbnails;

use crate::counter::{Repetition, Tally};
use crate::{LiveParams, Result};

/// Root mean square difference of the thumbnails of stream frames `f` and
/// `g`, `thumbs` holding those of the frames from `first` on; `None` where
/// a frame has none.
fn thumbnail_distance(
    first: usize,
    thumbs: &VecDeque<Vec<f32>>,
    f: usize,
    g: usize,
) -> Option<f64> {
    let a = thumbs.get(f.checked_sub(first)?)?;
    let b = thumbs.get(g.checked_sub(first)?)?;
    let sum: f64 = a.iter().zip(b).map(|(x, y)| f64::from(x - y).powi(2)).sum();
    (!a.is_empty() && a.len() == b.len()).then(|| (sum / a.len() as f64).sqrt())
}

/// See the module docs.
pub(crate) struct SceneCounter {
    fps: f64,
    size: usize,
    /// The stream frame of the window's first thumbnail.
    first: usize,
    thumbs: VecDeque<Vec<f32>>,
    tally: Tally,
    /// The repetitions reported that end within a window of the last one.
    reported: VecDeque<Repetition>,
}

impl SceneCounter {
    /// A counter of a stream at `fps` frames per second.
    pub(crate) fn new(fps: f64, params: &LiveParams) -> Self {
        SceneCounter {
            fps,
            size: params.analysis.pose.thumbnail_size,
            first: 0,
            thumbs: VecDeque::new(),
            tally: Tally::new(fps, params),
            reported: VecDeque::new(),
        }
    }

    /// The side of the thumbnails it keeps.
    pub(crate) fn thumbnail_size(&self) -> usize {
        self.size
    }

    /// Repetitions reported so far.
    #[cfg(test)]
    pub(crate) fn total(&self) -> usize {
        self.tally.total()
    }

    /// Stream frames in the window now.
    #[cfg(test)]
    pub(crate) fn window_len(&self) -> usize {
        self.thumbs.len()
    }

    /// The most stream frames the window may hold.
    #[cfg(test)]
    pub(crate) fn max_window(&self) -> usize {
        self.tally.max_frames
    }

    /// Adds the thumbnail of stream frame `frame`; the frames dropped since
    /// the previous one repeat it. A frame not after the last is ignored.
    pub(crate) fn push(&mut self, frame: usize, thumb: Vec<f32>) {
        if self.thumbs.is_empty() {
            self.first = frame;
        } else {
            let next = self.first + self.thumbs.len();
            if frame < next {
                return;
            }
            if let Some(prev) = self.thumbs.back().cloned() {
                // At most a window's worth of repeats: older ones are forgotten anyway.
                for _ in next..frame.min(next + self.tally.max_frames) {
                    self.thumbs.push_back(prev.clone());
                }
                // After a gap longer than the window, the repeats end just before `frame`.
                self.first = frame - self.thumbs.len();
            }
        }
        self.thumbs.push_back(thumb);
        while self.thumbs.len() > self.tally.max_frames {
            self.thumbs.pop_front();
            self.first += 1;
        }
    }

    /// The last stream frame in the window.
    fn back(&self) -> Option<usize> {
        (!self.thumbs.is_empty()).then(|| self.first + self.thumbs.len() - 1)
    }

    /// Returns the repetitions newly confirmed: the one expected next while
    /// a set is followed (the thumbnails of its period come back to those of
    /// the period before, as a person's poses do in `counter`), and those of
    /// the window's counting when it is due.
    pub(crate) fn update(&mut self, params: &LiveParams) -> Result<Vec<Repetition>> {
        let mut out = Vec::new();
        if let Some(back) = self.back() {
            let (first, thumbs) = (self.first, &self.thumbs);
            let followed = self
                .tally
                .follow(back, |f, g| thumbnail_distance(first, thumbs, f, g));
            self.reported.extend(followed);
            out.extend(followed);
        }
        if self.tally.due(self.back()) {
            out.extend(self.count_window(params, false)?);
        }
        Ok(out)
    }

    /// Counts the window once more and reports every new repetition in it
    /// (the end of the stream).
    pub(crate) fn finish(&mut self, params: &LiveParams) -> Result<Vec<Repetition>> {
        self.count_window(params, true)
    }

    fn count_window(&mut self, params: &LiveParams, last: bool) -> Result<Vec<Repetition>> {
        let Some(back) = self.back() else {
            return Ok(Vec::new());
        };
        self.tally.counting(back);
        if self.thumbs.len() < 4 {
            return Ok(Vec::new());
        }
        let counts = mp_pipeline::count_frames(self.thumbnails()?, &params.analysis)?;
        let (first, thumbs) = (self.first, &self.thumbs);
        let reps = self.tally.take(&counts, first, back, last, |f, g| {
            thumbnail_distance(first, thumbs, f, g)
        });
        self.reported.extend(reps.iter().copied());
        let keep_from = back.saturating_sub(self.tally.max_frames);
        while self
            .reported
            .front()
            .is_some_and(|r| r.end_frame < keep_from)
        {
            self.reported.pop_front();
        }
        Ok(reps)
    }

    /// The repetitions this scene reported that are the person's whose first
    /// counted repetition is `first`: those that end before it starts (up to a
    /// quarter of its period after), at its period (within a quarter). The
    /// person was there doing the same thing before the tracker found them
    /// (upside down on the floor, in the dark), and the scene counted them.
    /// Only those that ended within a window of the scene's last one are kept.
    pub(crate) fn before(&self, first: &Repetition) -> Vec<Repetition> {
        let period = first.end_frame.saturating_sub(first.start_frame) as f64;
        if period <= 0.0 {
            return Vec::new();
        }
        self.reported
            .iter()
            .filter(|r| {
                let p = r.end_frame.saturating_sub(r.start_frame) as f64;
                r.end_frame as f64 <= first.start_frame as f64 + 0.25 * period
                    && (p / period - 1.0).abs() <= 0.25
            })
            .copied()
            .collect()
    }

    /// The window's thumbnails, as `mp run` holds them.
    fn thumbnails(&self) -> Result<Thumbnails> {
        let values: Vec<f32> = self.thumbs.iter().flatten().copied().collect();
        Ok(Thumbnails::from_flat(values, self.size, self.fps)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_pose::DEFAULT_THUMBNAIL_SIZE;

    /// A 32 × 32 grey picture with a bright 6 × 6 square that swings left
    /// and right with period `period` frames.
    fn thumb(f: usize, period: f64) -> Vec<f32> {
        let x0 = 13.0 + 10.0 * (2.0 * std::f64::consts::PI * f as f64 / period).sin();
        let x0 = x0.round() as usize;
        (0..32 * 32)
            .map(|c| {
                let (y, x) = (c / 32, c % 32);
                if (13..19).contains(&y) && (x0..x0 + 6).contains(&x) {
                    220.0
                } else {
                    40.0
                }
            })
            .collect()
    }

    #[test]
    fn counts_the_picture_as_mp_run_counts_its_frames() {
        let (fps, period, frames) = (30.0, 30.0, 300);
        let params = LiveParams::default();
        let mut s = SceneCounter::new(fps, &params);
        let mut reps = Vec::new();
        for f in 0..frames {
            s.push(f, thumb(f, period));
            reps.extend(s.update(&params).unwrap());
            assert!(s.window_len() <= s.max_window());
        }
        reps.extend(s.finish(&params).unwrap());
        let all: Vec<f32> = (0..frames).flat_map(|f| thumb(f, period)).collect();
        let whole = Thumbnails::from_flat(all, DEFAULT_THUMBNAIL_SIZE, fps).unwrap();
        let offline = mp_pipeline::count_frames(whole, &params.analysis)
            .unwrap()
            .total;
        assert_eq!(offline, 10);
        assert!(
            reps.len().abs_diff(offline) <= 1,
            "{} for {offline}: {reps:?}",
            reps.len()
        );
        for (k, r) in reps.iter().enumerate() {
            assert_eq!(r.count, k + 1);
            assert!(r.end_frame > r.start_frame);
        }
        assert_eq!(s.total(), reps.len());
    }

    fn rep(count: usize, start_frame: usize, end_frame: usize) -> Repetition {
        Repetition {
            count,
            start_frame,
            end_frame,
        }
    }

    #[test]
    fn a_person_takes_over_the_scenes_repetitions_before_their_own() {
        let params = LiveParams::default();
        let scene_with = |reported: &[Repetition]| {
            let mut s = SceneCounter::new(30.0, &params);
            s.reported.extend(reported.iter().copied());
            s
        };
        // The scene counted 0–93, 93–186, 186–279 (93 frames a cycle); the
        // person's first counted repetition is 118–204 (86 frames).
        let first = rep(1, 118, 204);
        let s = scene_with(&[rep(1, 0, 93), rep(2, 93, 186), rep(3, 186, 279)]);
        assert_eq!(s.before(&first), vec![rep(1, 0, 93)]);
        // Another period (a hoop at twice the person's rate) is not theirs.
        assert!(scene_with(&[rep(1, 0, 40), rep(2, 40, 80)])
            .before(&first)
            .is_empty());
        // Nor is a repetition that ends well inside the person's first.
        assert!(scene_with(&[rep(1, 60, 150)]).before(&first).is_empty());
    }

    #[test]
    fn dropped_frames_repeat_the_last_picture_and_the_window_stays_bounded() {
        let params = LiveParams {
            window_s: 2.0,
            ..LiveParams::default()
        };
        let mut s = SceneCounter::new(30.0, &params);
        s.push(0, thumb(0, 30.0));
        s.push(5, thumb(5, 30.0));
        assert_eq!(s.window_len(), 6);
        assert_eq!(s.back(), Some(5));
        // A frame not after the last is ignored.
        s.push(3, thumb(3, 30.0));
        assert_eq!(s.window_len(), 6);
        // A gap longer than the window: the window ends at the new frame.
        s.push(1000, thumb(1000, 30.0));
        assert_eq!(s.window_len(), s.max_window());
        assert_eq!(s.back(), Some(1000));
    }
}
