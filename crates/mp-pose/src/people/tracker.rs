//! The person tracker: which person each crop and each detection belongs to,
//! frame after frame.
//!
//! A track carries its crop region from frame to frame as MediaPipe's
//! single-person pipeline does (the landmark model's auxiliary points place
//! the next crop). Around that:
//!
//! 1. **Detections confirm tracks.** Each frame the detector searches a few
//!    tiles of the frame ([`super::tiles::TileCycle`]); its detections are
//!    assigned to the tracks by the Hungarian method on the overlap (IoU) of
//!    their regions (`pathfinding`'s Kuhn–Munkres). A track that no detection
//!    has confirmed for [`PeopleParams::recheck_s`] is searched for in its own
//!    crop every frame; one unconfirmed for [`PeopleParams::confirm_s`] is
//!    dropped, and the frames since its last confirmation are taken back
//!    ([`TrackEvent::Dropped`]): a crop that slid off a person onto a lamp
//!    post or a tripod keeps a high pose presence, but the detector never
//!    finds a person there.
//! 2. **Births** are detections that belong to no track: the landmark model
//!    runs on the detection's region, and the new track gets an id once it has
//!    a pose on [`PeopleParams::birth_frames`] frames.
//! 3. **Duplicates**: two tracks whose regions overlap by more than
//!    [`PeopleParams::duplicate_iou`] follow one person; the younger loses.
//! 4. **Lost tracks** keep their id for [`PeopleParams::lost_s`]: the
//!    detector searches, on every frame, a square around where a lost track
//!    would be by now (constant velocity of its region's centre), and a
//!    detection there brings it back under the same id, after an occlusion
//!    or a crossing.
//! 5. **At most [`PeopleParams::max_people`]** tracks; births beyond are
//!    refused and counted ([`Tracker::refused`]).
//!
//! The tracker is generic over what sees the people ([`Sensors`]: the
//! landmark model in a region, the detector in a region), so its rules are
//! tested without models.

use pathfinding::prelude::{kuhn_munkres, Matrix};

use crate::error::{PoseError, Result};
use crate::filter::{OneEuroParams, PointsFilter};
use crate::imageops::Roi;

pub use mp_geom::PersonId;

/// The tracker's parameters, in seconds and region overlaps so that they
/// hold at any frame rate and frame size.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PeopleParams {
    /// Most people tracked at once. Default 8.
    pub max_people: usize,
    /// Seconds in which the detector searches every tile once while some
    /// track is unconfirmed or nobody is tracked. Default 0.5.
    pub search_cycle_s: f64,
    /// Seconds per search of every tile while every track is confirmed.
    /// Default 2.
    pub tracked_cycle_s: f64,
    /// Tile sides as fractions of the frame's shorter side (the whole frame
    /// is always searched too). Default `[1.0, 0.5]`.
    pub tile_sides: Vec<f64>,
    /// Overlap of neighbouring tiles (fraction of a tile). Default 0.5.
    pub tile_overlap: f64,
    /// Smallest tile side in pixels. Default 224, the detector's input: a
    /// smaller tile would be enlarged, showing no more detail.
    pub min_tile_px: f64,
    /// Least detector score that makes a new track a person: the detection
    /// that starts it, or one in its own crop (turned upright, as the
    /// landmark model sees it) while it waits for its id. Any detection above
    /// the detector's own threshold starts a track and confirms an existing
    /// one. Default 0.75: with many detections a frame, weak ones on clutter
    /// (machines, furniture) are common, while a person seen upright scores
    /// above 0.8 on most frames.
    pub birth_score: f64,
    /// Seconds without a detection after which a track is searched for in
    /// its own crop every frame. Default 0.5.
    pub recheck_s: f64,
    /// Seconds without a detection after which a track is dropped, and the
    /// frames since its last detection taken back. Default 1.
    pub confirm_s: f64,
    /// Frames with a pose before a new track gets an id. Default 3.
    pub birth_frames: usize,
    /// Seconds a new track has to reach `birth_score` before it is
    /// forgotten. Default 0.5.
    pub birth_s: f64,
    /// Seconds a lost track keeps its id for a detection to bring it back.
    /// Default 2.
    pub lost_s: f64,
    /// Least overlap (IoU) of a detection's region with a track's for the
    /// detection to confirm the track. Default 0.3.
    pub match_iou: f64,
    /// Least overlap (IoU) of a detection's region with a lost track's
    /// predicted region for it to bring the track back. Default 0.2.
    pub revive_iou: f64,
    /// Overlap (IoU) above which two tracks are taken to follow one person.
    /// Default 0.5.
    pub duplicate_iou: f64,
    /// Overlap (IoU) above which two detections (from overlapping tiles) are
    /// one. Default 0.5.
    pub detection_iou: f64,
}

impl Default for PeopleParams {
    fn default() -> Self {
        PeopleParams {
            max_people: 8,
            search_cycle_s: 0.5,
            tracked_cycle_s: 2.0,
            tile_sides: vec![1.0, 0.5],
            tile_overlap: 0.5,
            min_tile_px: 224.0,
            birth_score: 0.75,
            recheck_s: 0.5,
            confirm_s: 1.0,
            birth_frames: 3,
            birth_s: 0.5,
            lost_s: 2.0,
            match_iou: 0.3,
            revive_iou: 0.2,
            duplicate_iou: 0.5,
            detection_iou: 0.5,
        }
    }
}

impl PeopleParams {
    /// Checks every value.
    pub fn validate(&self) -> Result<()> {
        if !(1..=1000).contains(&self.max_people) {
            return Err(PoseError::param(
                "max_people",
                format!("must be in 1..=1000, got {}", self.max_people),
            ));
        }
        let seconds = [
            ("search_cycle_s", self.search_cycle_s),
            ("tracked_cycle_s", self.tracked_cycle_s),
            ("recheck_s", self.recheck_s),
            ("confirm_s", self.confirm_s),
            ("lost_s", self.lost_s),
            ("birth_s", self.birth_s),
            ("min_tile_px", self.min_tile_px),
        ];
        for (name, v) in seconds {
            if !(v.is_finite() && v > 0.0) {
                return Err(PoseError::param(name, format!("must be > 0, got {v}")));
            }
        }
        if self.recheck_s > self.confirm_s {
            return Err(PoseError::param(
                "recheck_s",
                format!(
                    "must not exceed confirm_s ({} s), got {} s",
                    self.confirm_s, self.recheck_s
                ),
            ));
        }
        let fractions = [
            ("tile_overlap", self.tile_overlap, true),
            ("match_iou", self.match_iou, false),
            ("revive_iou", self.revive_iou, false),
            ("duplicate_iou", self.duplicate_iou, false),
            ("detection_iou", self.detection_iou, false),
            ("birth_score", self.birth_score, false),
        ];
        for (name, v, below_one) in fractions {
            let ok = v.is_finite() && v >= 0.0 && if below_one { v < 1.0 } else { v <= 1.0 };
            if !ok {
                return Err(PoseError::param(
                    name,
                    format!(
                        "must be in [0, 1{} got {v}",
                        if below_one { ")," } else { "]," }
                    ),
                ));
            }
        }
        if self.tile_sides.len() > 8
            || self
                .tile_sides
                .iter()
                .any(|f| !(f.is_finite() && *f > 0.0 && *f <= 1.0))
        {
            return Err(PoseError::param(
                "tile_sides",
                format!(
                    "must be at most 8 fractions in (0, 1], got {:?}",
                    self.tile_sides
                ),
            ));
        }
        if self.birth_frames == 0 {
            return Err(PoseError::param("birth_frames", "must be at least 1"));
        }
        Ok(())
    }
}

/// A detection: its score and the person's region (image pixels).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Detector score.
    pub score: f64,
    /// The crop region of the person it found.
    pub roi: Roi,
}

/// What the landmark model saw in a region.
#[derive(Debug, Clone, PartialEq)]
pub struct Seen<P> {
    /// The pose.
    pub pose: P,
    /// The region to crop on the next frame (from the pose).
    pub next_roi: Option<Roi>,
}

/// What sees the people of the current frame.
pub trait Sensors {
    /// The pose type.
    type Pose;
    /// The landmark model in `roi`; `filter` is the track's filter of the
    /// points that place the next region. `None`: no person there.
    fn landmarks(
        &mut self,
        roi: &Roi,
        filter: &mut PointsFilter,
    ) -> Result<Option<Seen<Self::Pose>>>;
    /// [`Sensors::landmarks`] in several regions of the frame, each with its
    /// track's filter; the results in the same order. The default looks in
    /// one region after the other; a model that takes several crops in one
    /// run overrides it.
    fn landmarks_many(
        &mut self,
        jobs: &mut [(Roi, &mut PointsFilter)],
    ) -> Result<Vec<Option<Seen<Self::Pose>>>> {
        jobs.iter_mut()
            .map(|(roi, filter)| self.landmarks(roi, filter))
            .collect()
    }
    /// The detector in a square `region`.
    fn detect(&mut self, region: &Roi) -> Result<Vec<Candidate>>;
}

/// A person's pose in the current frame.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackedPose<P> {
    /// The track (steady within a video, also before the track has an id).
    pub key: u64,
    /// The person's id, once the track is confirmed.
    pub id: Option<PersonId>,
    /// The pose.
    pub pose: P,
    /// The region the pose was found in.
    pub roi: Roi,
}

/// Changes of the tracks on the current frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrackEvent {
    /// A track got an id; its poses since `first_frame` belong to that person.
    Confirmed {
        /// The track.
        key: u64,
        /// The new id.
        id: PersonId,
        /// The track's first frame.
        first_frame: usize,
    },
    /// No detection confirmed the track for `confirm_s`: its poses after
    /// `keep_until` are taken back (it is lost, and may come back).
    Dropped {
        /// The track.
        key: u64,
        /// The last frame where a detection confirmed it.
        keep_until: usize,
    },
    /// The track is gone for good (lost for longer than `lost_s`, or never confirmed).
    Ended {
        /// The track.
        key: u64,
    },
}

/// What the tracker did on one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameResult<P> {
    /// The poses, one per tracked person found on this frame.
    pub poses: Vec<TrackedPose<P>>,
    /// Changes of the tracks.
    pub events: Vec<TrackEvent>,
    /// Whether the detector ran.
    pub detector_runs: usize,
}

#[derive(Debug, Clone)]
struct Track {
    key: u64,
    id: Option<PersonId>,
    first_frame: usize,
    first_t: f64,
    hits: usize,
    /// Whether a detection reached `birth_score` on this track.
    strong: bool,
    /// Region carried to the next frame; `None` while lost.
    carried: Option<Roi>,
    /// Region of the last pose.
    last_roi: Roi,
    last_seen_t: f64,
    velocity: [f64; 2],
    confirmed_t: f64,
    confirmed_frame: usize,
    filter: PointsFilter,
}

impl Track {
    fn predicted(&self, t: f64) -> Roi {
        let dt = (t - self.last_seen_t).clamp(0.0, 10.0);
        Roi {
            center_x_px: self.last_roi.center_x_px + self.velocity[0] * dt,
            center_y_px: self.last_roi.center_y_px + self.velocity[1] * dt,
            ..self.last_roi
        }
    }
}

/// Axis-aligned box `[x0, y0, x1, y1]` of a region (its rotated corners).
pub(crate) fn roi_box(r: &Roi) -> [f64; 4] {
    let (s, c) = r.rotation_rad.sin_cos();
    let hw = (c.abs() * r.width_px + s.abs() * r.height_px) / 2.0;
    let hh = (s.abs() * r.width_px + c.abs() * r.height_px) / 2.0;
    [
        r.center_x_px - hw,
        r.center_y_px - hh,
        r.center_x_px + hw,
        r.center_y_px + hh,
    ]
}

/// Intersection over union of two boxes.
pub(crate) fn box_iou(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let ix = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
    let iy = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
    let inter = ix * iy;
    let area = |r: &[f64; 4]| (r[2] - r[0]).max(0.0) * (r[3] - r[1]).max(0.0);
    let union = area(a) + area(b) - inter;
    if union > 0.0 && inter.is_finite() {
        inter / union
    } else {
        0.0
    }
}

fn roi_iou(a: &Roi, b: &Roi) -> f64 {
    box_iou(&roi_box(a), &roi_box(b))
}

/// Intersection of two boxes over the smaller one's area (1 when one holds the other).
pub(crate) fn box_ios(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let ix = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
    let iy = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
    let area = |r: &[f64; 4]| (r[2] - r[0]).max(0.0) * (r[3] - r[1]).max(0.0);
    let small = area(a).min(area(b));
    if small > 0.0 && (ix * iy).is_finite() {
        ix * iy / small
    } else {
        0.0
    }
}

/// Whether two regions follow one person: they overlap by more than `iou`,
/// or one lies mostly (`CONTAINED`) inside the other (a crop on the upper
/// body of a person whose whole body another crop holds).
fn same_person(a: &Roi, b: &Roi, iou: f64) -> bool {
    let (ba, bb) = (roi_box(a), roi_box(b));
    box_iou(&ba, &bb) > iou || box_ios(&ba, &bb) > CONTAINED
}

/// Share of the smaller region inside the larger above which two regions
/// follow one person.
pub const CONTAINED: f64 = 0.8;

/// Side of the square searched for a lost person, in sides of their last crop.
pub(crate) const LOST_SEARCH_SCALE: f64 = 1.5;

/// Pairs `(row, column)` of the assignment of rows to columns that maximises
/// the summed `score`, keeping only pairs whose score reaches `min`.
fn assign(
    n_rows: usize,
    n_cols: usize,
    score: impl Fn(usize, usize) -> f64,
    min: f64,
) -> Vec<(usize, usize)> {
    if n_rows == 0 || n_cols == 0 {
        return Vec::new();
    }
    // Kuhn–Munkres wants no more rows than columns and integer weights.
    let transpose = n_rows > n_cols;
    let (r, c) = if transpose {
        (n_cols, n_rows)
    } else {
        (n_rows, n_cols)
    };
    let weight = |i: usize, j: usize| -> i64 {
        let s = if transpose { score(j, i) } else { score(i, j) };
        if s.is_finite() && s >= min {
            (s * 1e6).round() as i64
        } else {
            0
        }
    };
    let m = Matrix::from_fn(r, c, |(i, j)| weight(i, j));
    let (_, cols) = kuhn_munkres(&m);
    cols.iter()
        .enumerate()
        .filter(|&(i, &j)| weight(i, j) > 0)
        .map(|(i, &j)| if transpose { (j, i) } else { (i, j) })
        .collect()
}

/// Merges detections of one person from overlapping tiles: the best scored
/// of every group overlapping by more than `iou`.
pub(crate) fn merge_candidates(mut c: Vec<Candidate>, iou: f64) -> Vec<Candidate> {
    c.sort_by(|a, b| b.score.total_cmp(&a.score));
    let mut out: Vec<Candidate> = Vec::new();
    for d in c {
        if d.roi.is_valid() && out.iter().all(|o| roi_iou(&o.roi, &d.roi) <= iou) {
            out.push(d);
        }
    }
    out
}

/// Several people tracked over the frames of one video.
#[derive(Debug, Clone)]
pub struct Tracker {
    params: PeopleParams,
    aux_filter: OneEuroParams,
    tracks: Vec<Track>,
    next_key: u64,
    next_id: PersonId,
    frame: usize,
    last_t: Option<f64>,
    cycle: super::tiles::TileCycle,
    refused: usize,
    refused_first_frame: Option<usize>,
    most_seen: usize,
}

impl Tracker {
    /// A tracker searching `tiles`; `aux_filter` filters the points that
    /// place a track's next crop.
    pub fn new(params: PeopleParams, aux_filter: OneEuroParams, tiles: Vec<Roi>) -> Result<Self> {
        params.validate()?;
        Ok(Tracker {
            params,
            aux_filter,
            tracks: Vec::new(),
            next_key: 0,
            next_id: 1,
            frame: 0,
            last_t: None,
            cycle: super::tiles::TileCycle::new(tiles),
            refused: 0,
            refused_first_frame: None,
            most_seen: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PeopleParams {
        &self.params
    }

    /// Births refused because `max_people` were tracked, and the first frame
    /// where that happened.
    pub fn refused(&self) -> (usize, Option<usize>) {
        (self.refused, self.refused_first_frame)
    }

    /// The most people found on one frame (tracked, plus refused).
    pub fn most_seen(&self) -> usize {
        self.most_seen
    }

    /// Frames processed.
    pub fn frames(&self) -> usize {
        self.frame
    }

    /// One frame at time `t` (seconds).
    pub fn step<S: Sensors>(&mut self, t: f64, sensors: &mut S) -> Result<FrameResult<S::Pose>> {
        let p = self.params.clone();
        let f = self.frame;
        let dt = match self.last_t {
            Some(prev) if t > prev => t - prev,
            _ => 1.0 / 30.0,
        };
        self.last_t = Some(t);
        self.frame += 1;
        let mut events = Vec::new();
        let mut found: Vec<(usize, Seen<S::Pose>, Roi)> = Vec::new();

        // 1. The carried crops, all in one look.
        let mut carried = Vec::new();
        let mut jobs = Vec::new();
        for (i, tr) in self.tracks.iter_mut().enumerate() {
            if let Some(roi) = tr.carried.take() {
                carried.push(i);
                jobs.push((roi, &mut tr.filter));
            }
        }
        let seen = sensors.landmarks_many(&mut jobs)?;
        if seen.len() != jobs.len() {
            return Err(PoseError::Contract {
                model: "landmarks".into(),
                reason: format!("{} results for {} regions", seen.len(), jobs.len()),
            });
        }
        let rois: Vec<Roi> = jobs.into_iter().map(|(roi, _)| roi).collect();
        for ((i, roi), seen) in carried.into_iter().zip(rois).zip(seen) {
            match seen {
                Some(seen) => found.push((i, seen, roi)),
                None => self.tracks[i].filter.reset(),
            }
        }

        // 2. Duplicates: the older track keeps the person.
        found.sort_by_key(|(i, _, _)| (self.tracks[*i].first_frame, self.tracks[*i].key));
        let mut kept: Vec<(usize, Seen<S::Pose>, Roi)> = Vec::new();
        for item in found {
            if kept
                .iter()
                .all(|k| !same_person(&k.2, &item.2, p.duplicate_iou))
            {
                kept.push(item);
            } else {
                self.tracks[item.0].filter.reset();
            }
        }
        let mut found = kept;

        // 3. Detections: tiles in turn, and the own crop of tracks unconfirmed for a while.
        let all_confirmed = !found.is_empty()
            && self
                .tracks
                .iter()
                .all(|tr| tr.id.is_some() && (t - tr.confirmed_t) <= p.recheck_s);
        let cycle_s = if all_confirmed {
            p.tracked_cycle_s
        } else {
            p.search_cycle_s
        };
        let mut runs = 0usize;
        let mut cands = Vec::new();
        let tiles = if f == 0 {
            self.cycle.take_all()
        } else {
            self.cycle.take(dt, cycle_s)
        };
        for tile in tiles {
            cands.extend(sensors.detect(&tile)?);
            runs += 1;
        }
        for (i, _, roi) in &found {
            let tr = &self.tracks[*i];
            if t - tr.confirmed_t > p.recheck_s || !tr.strong {
                cands.extend(sensors.detect(roi)?);
                runs += 1;
            }
        }
        // A person lost a moment ago is looked for where they would be now,
        // on every frame, as the single-person pipeline looks for its person
        // on the frame after losing them.
        for (i, tr) in self.tracks.iter().enumerate() {
            let lost = tr.id.is_some() && !found.iter().any(|(k, _, _)| *k == i);
            if lost && t - tr.last_seen_t <= p.lost_s {
                let pr = tr.predicted(t);
                let side = LOST_SEARCH_SCALE * pr.width_px.max(pr.height_px);
                let region = Roi {
                    width_px: side,
                    height_px: side,
                    rotation_rad: 0.0,
                    ..pr
                };
                if region.is_valid() {
                    cands.extend(sensors.detect(&region)?);
                    runs += 1;
                }
            }
        }
        let cands = merge_candidates(cands, p.detection_iou);

        // 4. Detections confirm the tracks found on this frame.
        let pairs = assign(
            found.len(),
            cands.len(),
            |i, j| roi_iou(&found[i].2, &cands[j].roi),
            p.match_iou,
        );
        let mut used = vec![false; cands.len()];
        for (i, j) in pairs {
            used[j] = true;
            let tr = &mut self.tracks[found[i].0];
            tr.confirmed_t = t;
            tr.confirmed_frame = f;
            tr.strong |= cands[j].score >= p.birth_score;
        }
        // A detection that overlaps a found track is that person again.
        for (j, c) in cands.iter().enumerate() {
            if !used[j]
                && found.iter().any(|(_, _, r)| {
                    roi_iou(r, &c.roi) >= p.match_iou || same_person(r, &c.roi, 1.0)
                })
            {
                used[j] = true;
            }
        }

        // 5. Lost tracks come back where a detection is near their predicted region.
        let lost: Vec<usize> = (0..self.tracks.len())
            .filter(|&i| {
                let tr = &self.tracks[i];
                tr.id.is_some() && !found.iter().any(|(k, _, _)| *k == i)
            })
            .collect();
        let free: Vec<usize> = (0..cands.len()).filter(|&j| !used[j]).collect();
        let pairs = assign(
            lost.len(),
            free.len(),
            |a, b| roi_iou(&self.tracks[lost[a]].predicted(t), &cands[free[b]].roi),
            p.revive_iou,
        );
        for (a, b) in pairs {
            let (i, j) = (lost[a], free[b]);
            let roi = cands[j].roi;
            let tr = &mut self.tracks[i];
            tr.filter.reset();
            if let Some(seen) = sensors.landmarks(&roi, &mut tr.filter)? {
                if found
                    .iter()
                    .all(|k| !same_person(&k.2, &roi, p.duplicate_iou))
                {
                    used[j] = true;
                    tr.confirmed_t = t;
                    tr.confirmed_frame = f;
                    found.push((i, seen, roi));
                }
            }
        }

        // 6. Births.
        let mut refused_now = 0usize;
        for (j, c) in cands.iter().enumerate() {
            if used[j] {
                continue;
            }
            if found.len() >= p.max_people {
                refused_now += 1;
                continue;
            }
            let mut filter = PointsFilter::new(self.aux_filter);
            let Some(seen) = sensors.landmarks(&c.roi, &mut filter)? else {
                continue;
            };
            if found
                .iter()
                .any(|k| same_person(&k.2, &c.roi, p.duplicate_iou))
            {
                continue;
            }
            let key = self.next_key;
            self.next_key += 1;
            self.tracks.push(Track {
                key,
                id: None,
                first_frame: f,
                first_t: t,
                hits: 0,
                strong: c.score >= p.birth_score,
                carried: None,
                last_roi: c.roi,
                last_seen_t: t,
                velocity: [0.0, 0.0],
                confirmed_t: t,
                confirmed_frame: f,
                filter,
            });
            found.push((self.tracks.len() - 1, seen, c.roi));
        }
        if refused_now > 0 {
            self.refused += refused_now;
            self.refused_first_frame.get_or_insert(f);
        }
        self.most_seen = self.most_seen.max(found.len() + refused_now);

        // 7. Update what was found; ids for tracks seen long enough.
        let mut is_found = vec![false; self.tracks.len()];
        let mut poses = Vec::with_capacity(found.len());
        for (i, seen, roi) in found {
            is_found[i] = true;
            let tr = &mut self.tracks[i];
            if tr.hits > 0 {
                let gap = (t - tr.last_seen_t).max(1e-3);
                let v = [
                    (roi.center_x_px - tr.last_roi.center_x_px) / gap,
                    (roi.center_y_px - tr.last_roi.center_y_px) / gap,
                ];
                let a = 0.5;
                tr.velocity = [
                    a * v[0] + (1.0 - a) * tr.velocity[0],
                    a * v[1] + (1.0 - a) * tr.velocity[1],
                ];
            }
            tr.hits += 1;
            tr.last_roi = roi;
            tr.last_seen_t = t;
            tr.carried = seen.next_roi.filter(Roi::is_valid);
            if tr.id.is_none() && tr.hits >= p.birth_frames && tr.strong {
                let id = self.next_id;
                self.next_id += 1;
                tr.id = Some(id);
                events.push(TrackEvent::Confirmed {
                    key: tr.key,
                    id,
                    first_frame: tr.first_frame,
                });
            }
            poses.push(TrackedPose {
                key: tr.key,
                id: tr.id,
                pose: seen.pose,
                roi,
            });
        }

        // 8. Unconfirmed tracks are dropped; lost ones end.
        let mut dropped_keys = Vec::new();
        for (i, tr) in self.tracks.iter_mut().enumerate() {
            if is_found[i] && t - tr.confirmed_t > p.confirm_s {
                tr.carried = None;
                tr.filter.reset();
                // It is lost from its last confirmation on.
                tr.last_seen_t = tr.confirmed_t;
                is_found[i] = false;
                events.push(TrackEvent::Dropped {
                    key: tr.key,
                    keep_until: tr.confirmed_frame,
                });
                dropped_keys.push(tr.key);
            }
        }
        poses.retain(|p| !dropped_keys.contains(&p.key));
        let mut i = 0;
        while i < self.tracks.len() {
            let tr = &self.tracks[i];
            let lost = !is_found[i];
            let weak = tr.id.is_none() && !tr.strong && t - tr.first_t > p.birth_s;
            let ends = weak || (lost && (tr.id.is_none() || t - tr.last_seen_t > p.lost_s));
            if ends {
                events.push(TrackEvent::Ended { key: tr.key });
                self.tracks.remove(i);
                is_found.remove(i);
            } else {
                i += 1;
            }
        }
        Ok(FrameResult {
            poses,
            events,
            detector_runs: runs,
        })
    }
}

#[cfg(test)]
#[path = "tracker_tests.rs"]
mod tests;
