//! A whole video to the keypoints of every person in it.
//!
//! Poses are collected per track while the video plays; a track's poses
//! belong to a person once the tracker gives it an id, poses the tracker takes
//! back (a crop no detection confirmed) are removed, and tracks that never got
//! an id are forgotten. People are numbered 1, 2, … in the order they first
//! appear.

use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

use mp_geom::{People, Person, Skeleton, Track, Units};
use ndarray::{Array2, Array3};

use super::{MultiPose, TrackEvent};
use crate::error::{PoseError, Result};
use crate::extract::{is_posed_frame, ExtractOptions, PoseSmoother};
use crate::video::FrameSource;

/// What [`extract_people`] found.
#[derive(Debug, Clone)]
pub struct PeopleExtraction {
    /// Every person's keypoints (pixels, BlazePose-33), numbered by first appearance.
    pub people: People,
    /// People with a pose on each frame (0 on the frames the model skipped).
    pub people_per_frame: Vec<usize>,
    /// Whether the pose model ran on each frame ([`ExtractOptions::pose_every`]).
    pub posed: Vec<bool>,
    /// Detector runs over the whole video.
    pub detector_runs: usize,
    /// Milliseconds spent in the estimator per posed frame (no decoding).
    pub estimate_ms: Vec<f64>,
    /// Milliseconds for the whole run, decoding included.
    pub total_ms: f64,
    /// Frame size.
    pub width: usize,
    /// Frame size.
    pub height: usize,
    /// The limit on people tracked at once.
    pub max_people: usize,
    /// The most people found on one frame (tracked, plus those refused).
    pub most_seen: usize,
    /// People not tracked because `max_people` were, and the first frame where that happened.
    pub refused: (usize, Option<usize>),
}

impl PeopleExtraction {
    /// Fraction of the posed frames with at least one person.
    pub fn found_fraction(&self) -> f64 {
        let found: Vec<bool> = self.people_per_frame.iter().map(|&n| n > 0).collect();
        crate::extract::posed_fraction(&found, &self.posed)
    }

    /// Frames per second of the estimator alone (median per-frame time).
    pub fn estimator_fps(&self) -> f64 {
        crate::extract::median_fps(&self.estimate_ms)
    }

    /// A sentence for the user when more people were in view than are
    /// tracked at once.
    pub fn warning(&self) -> Option<String> {
        let (n, first) = self.refused;
        (n > 0).then(|| {
            format!(
                "{} people were in view at once{}, more than max_people = {}: only {} were tracked at a time (raise max_people to follow more)",
                self.most_seen,
                first.map(|f| format!(" (first on frame {f})")).unwrap_or_default(),
                self.max_people,
                self.max_people
            )
        })
    }
}

/// The poses of one track: frame index, keypoints `(x, y)` and visibility.
#[derive(Default)]
struct Collected {
    id: Option<u32>,
    frames: Vec<(usize, Vec<[f64; 2]>, Vec<f64>)>,
}

/// Every track's poses, gathered frame by frame as the tracker reports them
/// ([`TrackEvent`]s included), and turned into [`People`] at the end: the
/// tracks that got an id, without the poses the tracker took back.
/// [`extract_people`] gathers a video with it; a live run replays what it
/// saw into one.
pub struct PeopleCollector {
    joints: usize,
    tracks: HashMap<u64, Collected>,
}

impl PeopleCollector {
    /// A collector of poses with `joints` keypoints each.
    pub fn new(joints: usize) -> Self {
        PeopleCollector {
            joints,
            tracks: HashMap::new(),
        }
    }

    /// The pose of track `key` on `frame`. Errors: a pose whose keypoint
    /// count is not the collector's (`who` names the estimator).
    pub fn pose(
        &mut self,
        key: u64,
        frame: usize,
        keypoints_px: Vec<[f64; 2]>,
        visibility: Vec<f64>,
        who: &str,
    ) -> Result<()> {
        let j = self.joints;
        if keypoints_px.len() != j || visibility.len() != j {
            return Err(PoseError::BadFrame {
                frame,
                reason: format!(
                    "{who} returned {} keypoints, its skeleton has {j}",
                    keypoints_px.len()
                ),
            });
        }
        self.tracks
            .entry(key)
            .or_default()
            .frames
            .push((frame, keypoints_px, visibility));
        Ok(())
    }

    /// The last frame with a pose of track `key`.
    pub fn last_frame(&self, key: u64) -> Option<usize> {
        self.tracks.get(&key)?.frames.last().map(|l| l.0)
    }

    /// A change of the tracks, as the tracker reported it.
    pub fn event(&mut self, event: &TrackEvent) {
        match *event {
            TrackEvent::Confirmed { key, id, .. } => {
                self.tracks.entry(key).or_default().id = Some(id);
            }
            TrackEvent::Dropped { key, keep_until } => {
                if let Some(c) = self.tracks.get_mut(&key) {
                    c.frames.retain(|x| x.0 <= keep_until);
                }
            }
            TrackEvent::Ended { key } => {
                if self.tracks.get(&key).is_some_and(|c| c.id.is_none()) {
                    self.tracks.remove(&key);
                }
            }
        }
    }

    /// The people of a video of `n_frames` at `fps`: the tracks with an id
    /// and a pose in `skeleton` (pixels), numbered 1, 2, … by first
    /// appearance, or with the tracker's ids when `keep_ids`. Also adds one
    /// to `per_frame[f]` for each person with a pose on frame `f`.
    pub fn finish(
        self,
        n_frames: usize,
        fps: f64,
        skeleton: &Skeleton,
        keep_ids: bool,
        per_frame: &mut [usize],
    ) -> Result<People> {
        let j = self.joints;
        let mut kept: Vec<Collected> = self
            .tracks
            .into_values()
            .filter(|c| c.id.is_some() && !c.frames.is_empty())
            .collect();
        kept.sort_by_key(|c| (c.frames[0].0, c.id));
        let mut people = Vec::with_capacity(kept.len());
        for (k, c) in kept.into_iter().enumerate() {
            let first = c.frames[0].0;
            let last = c.frames.last().map_or(first, |l| l.0);
            let len = last - first + 1;
            let mut pos = Array3::<f64>::zeros((len, j, 2));
            let mut conf = Array2::<f64>::zeros((len, j));
            for (f, kps, vis) in &c.frames {
                let ti = f - first;
                if let Some(slot) = per_frame.get_mut(*f) {
                    *slot += 1;
                }
                for q in 0..j {
                    if kps[q].iter().all(|v| v.is_finite()) && vis[q].is_finite() {
                        pos[[ti, q, 0]] = kps[q][0];
                        pos[[ti, q, 1]] = kps[q][1];
                        conf[[ti, q]] = vis[q].clamp(0.0, 1.0);
                    }
                }
            }
            let track = Track::new(pos, Some(conf), fps, Units::Pixels, skeleton.clone())?;
            let id = match (keep_ids, c.id) {
                (true, Some(id)) => id,
                _ => k as u32 + 1,
            };
            people.push(Person {
                id,
                first_frame: first,
                track,
            });
        }
        Ok(People::new(n_frames, fps, people)?)
    }
}

/// Runs the multi-person estimator over the frames of `source` (every
/// frame, or those [`ExtractOptions::pose_every`] names; a person's poses
/// are then on those frames only). `progress(done, total)` is called after
/// each frame.
pub fn extract_people(
    mut source: FrameSource,
    estimator: &mut MultiPose,
    options: &ExtractOptions,
    mut progress: impl FnMut(usize, Option<usize>),
) -> Result<PeopleExtraction> {
    if let Some(s) = &options.smoothing {
        s.validate()?;
    }
    estimator.reset();
    let skeleton = estimator.skeleton();
    let j = skeleton.len();
    let total = match (source.frame_count, options.max_frames) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, None) => a,
        (None, b) => b,
    };
    let start = Instant::now();
    let mut collector = PeopleCollector::new(j);
    let mut smoothers: HashMap<u64, PoseSmoother> = HashMap::new();
    let mut per_frame = Vec::new();
    let mut posed = Vec::new();
    let mut estimate_ms = Vec::new();
    let mut detector_runs = 0usize;
    while options.max_frames.is_none_or(|m| per_frame.len() < m) {
        let Some(frame) = source.frames.next() else {
            break;
        };
        let frame = frame?;
        if !is_posed_frame(per_frame.len(), options.pose_every, total) {
            per_frame.push(0);
            posed.push(false);
            progress(per_frame.len(), total);
            continue;
        }
        posed.push(true);
        let t0 = Instant::now();
        let r = estimator.process(&frame)?;
        estimate_ms.push(t0.elapsed().as_secs_f64() * 1000.0);
        detector_runs += r.detector_runs;
        let f = frame.index;
        for mut tp in r.poses {
            if let Some(sp) = options.smoothing {
                let step = options.pose_every.max(1);
                let restart = collector.last_frame(tp.key).is_none_or(|l| f > l + step);
                if restart || !smoothers.contains_key(&tp.key) {
                    smoothers.insert(tp.key, PoseSmoother::new(sp)?);
                }
                if let Some(sm) = smoothers.get_mut(&tp.key) {
                    sm.apply(frame.timestamp_s, &mut tp.pose);
                }
            }
            let (kps, vis) = (tp.pose.keypoints_px, tp.pose.visibility);
            collector.pose(tp.key, f, kps, vis, estimator.name())?;
        }
        for e in r.events {
            if let TrackEvent::Dropped { key, .. } | TrackEvent::Ended { key } = e {
                smoothers.remove(&key);
            }
            collector.event(&e);
        }
        per_frame.push(0);
        progress(per_frame.len(), total);
    }
    let total_ms = start.elapsed().as_secs_f64() * 1000.0;
    let n = per_frame.len();
    if n == 0 {
        return Err(PoseError::Video {
            path: Path::new("(input)").to_path_buf(),
            reason: "no frames".into(),
        });
    }
    // People with an id and a pose, by first appearance.
    let people = collector.finish(n, source.fps, &skeleton, false, &mut per_frame)?;
    let (refused, most_seen) = estimator
        .tracker()
        .map_or(((0, None), 0), |t| (t.refused(), t.most_seen()));
    Ok(PeopleExtraction {
        people,
        people_per_frame: per_frame,
        posed,
        detector_runs,
        estimate_ms,
        total_ms,
        width: source.width,
        height: source.height,
        max_people: estimator.params().people.max_people,
        most_seen,
        refused,
    })
}
