//! Several tracked people in one video.
//!
//! A [`People`] holds the length and frame rate of a video and one
//! [`Person`] per tracked person: a steady [`PersonId`], the video frame
//! where their track starts, and a [`Track`] over their span of frames
//! (confidence 0 on the frames of the span where they were not found).
//! All tracks share the frame rate, units, skeleton and dimensions.
//!
//! [`People::main_person`] picks the performer by a documented rule;
//! [`People::full_track`] gives anyone's track over the whole video. The
//! file formats are in [`crate::io::people`].

use ndarray::{s, Array2, Array3};

use crate::error::{GeomError, Result};
use crate::track::Track;

/// A person's steady id within one video (1, 2, 3, … in order of appearance).
pub type PersonId = u32;

/// One tracked person: an id, the video frame where the track starts and
/// the track over the person's span of frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Person {
    /// The person's id, unique within a [`People`].
    pub id: PersonId,
    /// Video frame index of the track's first frame.
    pub first_frame: usize,
    /// The person's keypoints over frames `first_frame .. first_frame +
    /// track.n_frames()`; confidence 0 on the frames where they were not found.
    pub track: Track,
}

impl Person {
    /// Video frame index of the track's last frame (inclusive). A track
    /// without frames (which [`People::new`] refuses) gives `first_frame`.
    pub fn last_frame(&self) -> usize {
        self.first_frame
            .saturating_add(self.track.n_frames().max(1))
            .saturating_sub(1)
    }

    /// Number of frames of the span where the person was found: frames with
    /// at least one joint of confidence > 0.
    pub fn frames_found(&self) -> usize {
        self.track
            .confidence()
            .outer_iter()
            .filter(|row| row.iter().any(|&c| c > 0.0))
            .count()
    }

    /// The bounding box `[x0, y0, x1, y1]` of the joints with confidence > 0
    /// at frame `t` of the track (not of the video); `None` where no joint
    /// was found. A one-dimensional track has `y0 = y1 = 0`.
    fn frame_box(&self, t: usize) -> Option<[f64; 4]> {
        let pos = self.track.positions();
        let conf = self.track.confidence();
        let d = self.track.dims();
        let mut b: Option<[f64; 4]> = None;
        for (j, &c) in conf.row(t).iter().enumerate() {
            if c <= 0.0 {
                continue;
            }
            let x = pos[[t, j, 0]];
            let y = if d >= 2 { pos[[t, j, 1]] } else { 0.0 };
            b = Some(match b {
                None => [x, y, x, y],
                Some([x0, y0, x1, y1]) => [x0.min(x), y0.min(y), x1.max(x), y1.max(y)],
            });
        }
        b
    }

    /// The mean, over the frames where the person was found, of the
    /// bounding box of the joints with confidence > 0: `[x0, y0, x1, y1]` in
    /// the track's units (the first two dimensions; a one-dimensional track
    /// has `y0 = y1 = 0`). `None` if the person was never found.
    pub fn mean_box(&self) -> Option<[f64; 4]> {
        let mut sum = [0.0; 4];
        let mut n = 0usize;
        for t in 0..self.track.n_frames() {
            if let Some(b) = self.frame_box(t) {
                for (s, v) in sum.iter_mut().zip(b) {
                    *s += v;
                }
                n += 1;
            }
        }
        (n > 0).then(|| sum.map(|s| s / n as f64))
    }

    /// The bounding box (same rule as [`Person::mean_box`]) at frame
    /// `video_frame` of the video (not of the track); `None` where the
    /// person was not found or the frame lies outside their span.
    pub fn box_at(&self, video_frame: usize) -> Option<[f64; 4]> {
        let t = video_frame.checked_sub(self.first_frame)?;
        if t >= self.track.n_frames() {
            return None;
        }
        self.frame_box(t)
    }

    /// The diagonal of [`Person::mean_box`] (0 when never found).
    fn mean_diagonal(&self) -> f64 {
        self.mean_box()
            .map_or(0.0, |[x0, y0, x1, y1]| (x1 - x0).hypot(y1 - y0))
    }

    /// How much the person moves: the path their joints travel, in the
    /// track's units — the sum over frames `t` of the mean distance of each
    /// joint from where it was `ACTIVITY_LAG_S` earlier, divided by that lag
    /// in frames (joints with confidence > 0 at both times). Measuring over a
    /// lag rather than from frame to frame keeps the keypoints' jitter, which
    /// does not grow with the lag, small beside real motion, which does.
    pub fn activity(&self) -> f64 {
        let n = self.track.n_frames();
        let lag = ((ACTIVITY_LAG_S * self.track.fps()).round() as usize).max(1);
        if n <= lag {
            return 0.0;
        }
        let (pos, conf) = (self.track.positions(), self.track.confidence());
        let (j, d) = (self.track.n_joints(), self.track.dims());
        let mut total = 0.0;
        for t in lag..n {
            let (mut sum, mut k) = (0.0, 0usize);
            for q in 0..j {
                if conf[[t, q]] > 0.0 && conf[[t - lag, q]] > 0.0 {
                    let d2: f64 = (0..d)
                        .map(|c| (pos[[t, q, c]] - pos[[t - lag, q, c]]).powi(2))
                        .sum();
                    sum += d2.sqrt();
                    k += 1;
                }
            }
            if k > 0 {
                total += sum / k as f64 / lag as f64;
            }
        }
        if total.is_finite() {
            total
        } else {
            0.0
        }
    }
}

/// The lag of [`Person::activity`], seconds.
pub const ACTIVITY_LAG_S: f64 = 0.2;

/// The people tracked in one video: its length in frames, its frame rate
/// and one [`Person`] per tracked person, sorted by id.
///
/// Invariants (checked by [`People::new`]): at least one frame; every
/// person's span lies within the video; ids are unique; all tracks share
/// the frame rate (equal to the video's), units, skeleton and dimensions.
/// A video with nobody in it has zero people.
#[derive(Debug, Clone, PartialEq)]
pub struct People {
    n_frames: usize,
    fps: f64,
    people: Vec<Person>,
}

/// Most values (frames × joints × dimensions) of one person's whole-video
/// track ([`People::full_track`]): 2²⁸, 2 GiB of coordinates, about 36
/// hours of 60-fps video of 17 joints in 2D.
pub const MAX_PEOPLE_VALUES: usize = 1 << 28;

impl People {
    /// Checks and builds: `n_frames ≥ 1` and at most `MAX_PEOPLE_VALUES`
    /// values per whole-video track; `fps` finite and > 0; every
    /// person's track has at least one frame and its span
    /// `first_frame .. first_frame + track.n_frames()` lies within
    /// `0..n_frames`; ids are unique; every track's frame rate equals `fps`
    /// and all tracks share units, skeleton and dimensions. People are
    /// sorted by id. Zero people is allowed (a video with nobody in it).
    pub fn new(n_frames: usize, fps: f64, mut people: Vec<Person>) -> Result<Self> {
        if n_frames == 0 {
            return Err(GeomError::param("n_frames", "a video has at least 1 frame"));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(GeomError::param(
                "fps",
                format!("must be finite and > 0, got {fps}"),
            ));
        }
        // A person's whole-video track (`full_track`) holds n_frames × joints
        // × dims values: a file may not ask for more than MAX_PEOPLE_VALUES.
        let per_frame = people.first().map_or(1, |p| {
            p.track
                .n_joints()
                .max(1)
                .saturating_mul(p.track.dims().max(1))
        });
        if n_frames.saturating_mul(per_frame) > MAX_PEOPLE_VALUES {
            return Err(GeomError::param(
                "n_frames",
                format!(
                    "{n_frames} frames × {per_frame} values per frame is more than the \
                     {MAX_PEOPLE_VALUES} values a whole-video track may hold"
                ),
            ));
        }
        people.sort_by_key(|p| p.id);
        if let Some(w) = people.windows(2).find(|w| w[0].id == w[1].id) {
            return Err(GeomError::param(
                "people",
                format!("person id {} appears twice", w[0].id),
            ));
        }
        for p in &people {
            let n = p.track.n_frames();
            if n == 0 {
                return Err(GeomError::param(
                    "people",
                    format!("person {}: the track has no frames", p.id),
                ));
            }
            let end = p.first_frame.checked_add(n);
            if end.is_none_or(|end| end > n_frames) {
                return Err(GeomError::param(
                    "people",
                    format!(
                        "person {}: frames {}..{} run past the video's {n_frames} frames",
                        p.id,
                        p.first_frame,
                        end.map_or_else(|| "∞".to_string(), |e| e.to_string())
                    ),
                ));
            }
            if p.track.fps() != fps {
                return Err(GeomError::param(
                    "people",
                    format!(
                        "person {}: track at {} fps, the video at {fps} fps",
                        p.id,
                        p.track.fps()
                    ),
                ));
            }
        }
        if let Some((first, rest)) = people.split_first() {
            let (a, sk) = (&first.track, first.track.skeleton());
            for p in rest {
                let b = &p.track;
                let what = if b.skeleton() != sk {
                    Some(format!(
                        "skeleton `{}` ({} joints), person {} has `{}` ({} joints)",
                        b.skeleton().name,
                        b.n_joints(),
                        first.id,
                        sk.name,
                        a.n_joints()
                    ))
                } else if b.units() != a.units() {
                    Some(format!(
                        "units `{}`, person {} has `{}`",
                        b.units().as_str(),
                        first.id,
                        a.units().as_str()
                    ))
                } else if b.dims() != a.dims() {
                    Some(format!(
                        "{} dimensions, person {} has {}",
                        b.dims(),
                        first.id,
                        a.dims()
                    ))
                } else {
                    None
                };
                if let Some(what) = what {
                    return Err(GeomError::param(
                        "people",
                        format!("person {} has {what}", p.id),
                    ));
                }
            }
        }
        Ok(People {
            n_frames,
            fps,
            people,
        })
    }

    /// One person (id 1) covering the whole track: how a single-person file
    /// reads as people. A track without frames is an error.
    pub fn from_track(track: Track) -> Result<Self> {
        let (n, fps) = (track.n_frames(), track.fps());
        People::new(
            n,
            fps,
            vec![Person {
                id: 1,
                first_frame: 0,
                track,
            }],
        )
    }

    /// Number of frames of the video.
    pub fn n_frames(&self) -> usize {
        self.n_frames
    }
    /// Frames per second of the video (and of every track).
    pub fn fps(&self) -> f64 {
        self.fps
    }

    /// The same people at another frame rate (every track with it).
    pub fn with_fps(self, fps: f64) -> Result<Self> {
        let n = self.n_frames;
        let list = self
            .people
            .into_iter()
            .map(|p| {
                Ok(Person {
                    track: p.track.with_fps(fps)?,
                    ..p
                })
            })
            .collect::<Result<Vec<_>>>()?;
        People::new(n, fps, list)
    }
    /// The people, sorted by id.
    pub fn people(&self) -> &[Person] {
        &self.people
    }
    /// Number of people.
    pub fn len(&self) -> usize {
        self.people.len()
    }
    /// True when nobody was tracked.
    pub fn is_empty(&self) -> bool {
        self.people.is_empty()
    }
    /// Decomposes into the people, sorted by id.
    pub fn into_people(self) -> Vec<Person> {
        self.people
    }

    /// The person with id `id`, if any.
    pub fn get(&self, id: PersonId) -> Option<&Person> {
        self.people
            .binary_search_by_key(&id, |p| p.id)
            .ok()
            .map(|i| &self.people[i])
    }

    /// The same people with every track passed through `f` (e.g. a mapping
    /// onto another skeleton); ids and spans are kept, and the result is
    /// validated as [`People::new`] does.
    pub fn map_tracks(self, mut f: impl FnMut(Track) -> Result<Track>) -> Result<People> {
        let (n, fps) = (self.n_frames, self.fps);
        let list = self
            .people
            .into_iter()
            .map(|p| {
                Ok(Person {
                    track: f(p.track)?,
                    ..p
                })
            })
            .collect::<Result<Vec<_>>>()?;
        People::new(n, fps, list)
    }

    /// The main person: the one who moves most, i.e. with the largest
    /// [`Person::activity`] (the path their joints travel, in the track's
    /// units), so that the performer wins over a bystander or a trainer
    /// standing beside them (found as long, but still), a passer-by (moving,
    /// but briefly) and a small figure in the back (whose motion is small in
    /// pixels). Equal activities go to the one seen longest and largest
    /// (`frames_found × diagonal of mean_box`), then to the smaller id.
    /// `None` when nobody was tracked.
    pub fn main_person(&self) -> Option<&Person> {
        let mut best: Option<(&Person, f64, f64)> = None;
        for p in &self.people {
            let a = p.activity();
            let size = p.frames_found() as f64 * p.mean_diagonal();
            let better = match best {
                None => true,
                Some((_, ba, bs)) => a > ba || (a == ba && size > bs),
            };
            if better {
                best = Some((p, a, size));
            }
        }
        best.map(|(p, _, _)| p)
    }

    /// The track of person `id` over the whole video (`n_frames` frames):
    /// their keypoints within their span, positions 0 and confidence 0
    /// outside it. An unknown id is a [`GeomError::Unknown`].
    pub fn full_track(&self, id: PersonId) -> Result<Track> {
        let p = self.get(id).ok_or_else(|| GeomError::Unknown {
            kind: "person",
            name: id.to_string(),
        })?;
        let tr = &p.track;
        let (n, j, d) = (tr.n_frames(), tr.n_joints(), tr.dims());
        let span = p.first_frame..p.first_frame + n;
        let mut pos = Array3::zeros((self.n_frames, j, d));
        let mut conf = Array2::zeros((self.n_frames, j));
        pos.slice_mut(s![span.clone(), .., ..])
            .assign(&tr.positions());
        conf.slice_mut(s![span, ..]).assign(&tr.confidence());
        Track::new(pos, Some(conf), self.fps, tr.units(), tr.skeleton().clone())
    }

    /// The main person's ([`People::main_person`]) track over the whole
    /// video; [`GeomError::NoData`] when nobody was tracked.
    pub fn main_track(&self) -> Result<Track> {
        let p = self
            .main_person()
            .ok_or_else(|| GeomError::NoData("nobody was tracked in this video".into()))?;
        self.full_track(p.id)
    }

    /// Keeps only the people found on at least `min_frames` frames
    /// ([`Person::frames_found`]); returns how many were dropped.
    pub fn retain_min_frames(&mut self, min_frames: usize) -> usize {
        let before = self.people.len();
        self.people.retain(|p| p.frames_found() >= min_frames);
        before - self.people.len()
    }
}
