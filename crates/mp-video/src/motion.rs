//! The analysis of a video that the edits read: keypoints, grey frame
//! thumbnails and repetition counts, exactly as `mp run` computes them
//! (`mp_pipeline::keypoints` and `mp_pipeline::count` with the same
//! parameters), and a distance between frames from pose and pixels.

use std::path::{Path, PathBuf};

use mp_abstract::Counts;
use mp_geom::median;
use mp_geom::{CancelToken, Track};
use mp_pipeline::{Input, Keep, Params, Silent};
use mp_pose::VideoInfo;
use ndarray::Axis;

use crate::error::{Result, VideoError};

/// A video's keypoints, thumbnails and counts.
#[derive(Debug, Clone)]
pub struct VideoMotion {
    /// The video.
    pub path: PathBuf,
    /// Size and frame rate.
    pub info: VideoInfo,
    /// Keypoints (COCO-17, pixels), one frame per analysed video frame.
    pub track: Track,
    /// Grey thumbnails of the frames (`T × cells × 1`), when decoded.
    pub thumbnails: Option<Track>,
    /// Repetition counts, as in `loops.json` (`counts.intervals[i]` is loop `i`).
    pub counts: Counts,
    pose_scale: f64,
    thumb_scale: f64,
}

impl VideoMotion {
    /// Confidence above which a joint counts as seen.
    pub const MIN_CONFIDENCE: f64 = 0.3;

    /// Keypoints, thumbnails and counts of the first `max_frames` frames of a
    /// video (all frames when `None`), with `params` (`mp run` uses
    /// `Params::default()`).
    pub fn analyse(path: &Path, params: &Params, max_frames: Option<usize>) -> Result<VideoMotion> {
        let mut params = params.clone();
        if max_frames.is_some() {
            params.pose.max_frames = max_frames;
        }
        let info = mp_pose::probe(path)?;
        let input = Input::open(path, None)?;
        let (kp, _) = mp_pipeline::keypoints(
            input,
            &params,
            Keep::default(),
            &Silent,
            &CancelToken::new(),
        )?;
        let counts = mp_pipeline::count(&kp.track, kp.thumbnails.as_ref(), &params)?;
        Ok(Self::new(path, info, kp.track, kp.thumbnails, counts))
    }

    /// Wraps an analysis (the distance scales are measured here).
    pub fn new(
        path: &Path,
        info: VideoInfo,
        track: Track,
        thumbnails: Option<Track>,
        counts: Counts,
    ) -> Self {
        let mut m = VideoMotion {
            path: path.to_path_buf(),
            info,
            track,
            thumbnails,
            counts,
            pose_scale: 1.0,
            thumb_scale: 1.0,
        };
        let n = m.n_frames();
        let (mut p, mut q) = (Vec::new(), Vec::new());
        for t in 1..n {
            if let Some(d) = m.pose_raw(t - 1, t) {
                p.push(d);
            }
            if let Some(d) = m.thumb_raw(t - 1, t) {
                q.push(d);
            }
        }
        m.pose_scale = median(&mut p).filter(|v| *v > 1e-9).unwrap_or(1.0);
        m.thumb_scale = median(&mut q).filter(|v| *v > 1e-9).unwrap_or(1.0);
        m
    }

    /// Frames analysed.
    pub fn n_frames(&self) -> usize {
        self.track.n_frames()
    }

    /// Frames per second.
    pub fn fps(&self) -> f64 {
        self.info.fps
    }

    /// Whether a person is seen in some frame.
    pub fn has_person(&self) -> bool {
        (0..self.track.n_frames()).any(|t| {
            (0..self.track.n_joints()).any(|j| self.track.is_valid(t, j, Self::MIN_CONFIDENCE))
        })
    }

    /// Errors with [`VideoError::NoPerson`] when no person is seen.
    pub fn require_person(&self) -> Result<()> {
        if self.has_person() {
            Ok(())
        } else {
            Err(VideoError::NoPerson(self.path.clone()))
        }
    }

    fn pose_raw(&self, a: usize, b: usize) -> Option<f64> {
        let (mut s, mut n) = (0.0, 0usize);
        for j in 0..self.track.n_joints() {
            if self.track.is_valid(a, j, Self::MIN_CONFIDENCE)
                && self.track.is_valid(b, j, Self::MIN_CONFIDENCE)
            {
                let (p, q) = (self.track.point(a, j), self.track.point(b, j));
                s += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                n += 1;
            }
        }
        (n >= 3).then(|| s / n as f64)
    }

    fn thumb_raw(&self, a: usize, b: usize) -> Option<f64> {
        let th = self.thumbnails.as_ref()?;
        if a >= th.n_frames() || b >= th.n_frames() {
            return None;
        }
        let pos = th.positions();
        let (fa, fb) = (pos.index_axis(Axis(0), a), pos.index_axis(Axis(0), b));
        let c = fa.len();
        let s: f64 = fa.iter().zip(fb.iter()).map(|(x, y)| (x - y).powi(2)).sum();
        Some((s / c.max(1) as f64).sqrt())
    }

    /// How different frames `a` and `b` look: the mean keypoint distance and
    /// the RMS thumbnail difference, each in units of its median between
    /// consecutive frames, summed (a term that cannot be measured counts
    /// twice the other).
    pub fn distance(&self, a: usize, b: usize) -> f64 {
        let p = self.pose_raw(a, b).map(|d| d / self.pose_scale);
        let q = self.thumb_raw(a, b).map(|d| d / self.thumb_scale);
        match (p, q) {
            (Some(p), Some(q)) => p + q,
            (Some(p), None) => 2.0 * p,
            (None, Some(q)) => 2.0 * q,
            (None, None) => f64::INFINITY,
        }
    }

    /// The feature of frame `t` used to compare iterations: keypoints in
    /// units of the pose scale, thumbnail cells in units of the thumbnail
    /// scale (missing joints as `NaN`).
    pub(crate) fn feature(&self, t: usize) -> Vec<f64> {
        let mut f = Vec::new();
        for j in 0..self.track.n_joints() {
            let ok = self.track.is_valid(t, j, Self::MIN_CONFIDENCE);
            let p = self.track.point(t, j);
            for d in 0..2 {
                f.push(if ok { p[d] / self.pose_scale } else { f64::NAN });
            }
        }
        if let Some(th) = &self.thumbnails {
            if t < th.n_frames() {
                let pos = th.positions();
                let cells = pos.index_axis(Axis(0), t);
                // Scaled so the thumbnail part weighs like the pose part.
                let scale = self.thumb_scale * (cells.len() as f64).sqrt();
                f.extend(cells.iter().map(|v| v / scale));
            }
        }
        f
    }
}
