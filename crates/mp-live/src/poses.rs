//! A person's recent poses, one row per stream frame: the window of the
//! online counter and the buffer of the online program.
//!
//! Rows come in stream order. A gap of up to `max_gap_s` since the previous
//! pose (dropped frames) is filled by linear interpolation; a longer one
//! stays empty. The rows become a keypoint track as `mp run` builds it:
//! pixels, the pose model's skeleton turned into COCO-17 unless
//! `all_joints`.

use std::collections::VecDeque;

use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array2, Array3};

use crate::{LiveParams, Result};

/// One stream frame's pose.
struct Row {
    frame: usize,
    points: Vec<[f64; 2]>,
    conf: Vec<f64>,
}

/// See the module docs.
pub(crate) struct Poses {
    fps: f64,
    skeleton: Skeleton,
    coco: bool,
    max_gap: usize,
    rows: VecDeque<Row>,
}

impl Poses {
    /// Poses in `skeleton` at `fps` frames per second.
    pub(crate) fn new(fps: f64, skeleton: Skeleton, params: &LiveParams) -> Self {
        let coco = !params.analysis.pose.all_joints
            && skeleton.name != "coco17"
            && skeleton.maps_to_coco17();
        Poses {
            fps,
            skeleton,
            coco,
            max_gap: (params.max_gap_s * fps).round() as usize,
            rows: VecDeque::new(),
        }
    }

    /// The joints of the tracks made of the poses.
    pub(crate) fn joints(&self) -> Vec<String> {
        if self.coco {
            Skeleton::coco17().joints
        } else {
            self.skeleton.joints.clone()
        }
    }

    /// The longest gap filled, in frames.
    pub(crate) fn max_gap(&self) -> usize {
        self.max_gap
    }

    /// Rows now.
    pub(crate) fn len(&self) -> usize {
        self.rows.len()
    }

    /// The first and the last stream frame.
    pub(crate) fn span(&self) -> Option<(usize, usize)> {
        Some((self.rows.front()?.frame, self.rows.back()?.frame))
    }

    /// The last stream frame.
    pub(crate) fn last_frame(&self) -> Option<usize> {
        self.rows.back().map(|r| r.frame)
    }

    /// Whether a pose of stream `frame` would come after a gap too long to fill.
    pub(crate) fn breaks_at(&self, frame: usize) -> bool {
        self.rows
            .back()
            .is_some_and(|last| frame > last.frame + 1 + self.max_gap)
    }

    /// Adds the pose of stream `frame` (a frame not after the last is
    /// ignored), filling a short gap since the previous one.
    pub(crate) fn push(&mut self, frame: usize, points: Vec<[f64; 2]>, conf: Vec<f64>) {
        if let Some(last) = self.rows.back() {
            if frame <= last.frame {
                return;
            }
            let gap = frame - last.frame - 1;
            if gap > 0 && gap <= self.max_gap && last.points.len() == points.len() {
                let (f0, p0, c0) = (last.frame, last.points.clone(), last.conf.clone());
                for g in 1..=gap {
                    let a = g as f64 / (gap + 1) as f64;
                    let pts = p0
                        .iter()
                        .zip(&points)
                        .map(|(p, q)| [p[0] + a * (q[0] - p[0]), p[1] + a * (q[1] - p[1])])
                        .collect();
                    let cf = c0.iter().zip(&conf).map(|(p, q)| p.min(*q)).collect();
                    self.rows.push_back(Row {
                        frame: f0 + g,
                        points: pts,
                        conf: cf,
                    });
                }
            }
        }
        self.rows.push_back(Row {
            frame,
            points,
            conf,
        });
    }

    /// The row of stream `frame`.
    fn row(&self, frame: usize) -> Option<&Row> {
        let first = self.rows.front()?.frame;
        let r = self.rows.get(frame.checked_sub(first)?)?;
        (r.frame == frame).then_some(r)
    }

    /// Root mean square distance between the poses of two stream frames
    /// (pixels), each joint weighted by the smaller of its two confidences;
    /// `None` when a frame has no row or no joint is seen in both.
    pub(crate) fn distance(&self, f: usize, g: usize) -> Option<f64> {
        let (a, b) = (self.row(f)?, self.row(g)?);
        let (mut sum, mut weight) = (0.0, 0.0);
        for q in 0..a.points.len().min(b.points.len()) {
            let w = a.conf.get(q)?.min(*b.conf.get(q)?);
            let (p, r) = (a.points[q], b.points[q]);
            let d = (p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2);
            if w > 0.0 && d.is_finite() {
                sum += w * d;
                weight += w;
            }
        }
        (weight > 0.0).then(|| (sum / weight).sqrt())
    }

    /// Forgets the rows before stream frame `frame`.
    pub(crate) fn forget_before(&mut self, frame: usize) {
        while self.rows.front().is_some_and(|r| r.frame < frame) {
            self.rows.pop_front();
        }
    }

    /// Forgets every row.
    pub(crate) fn clear(&mut self) {
        self.rows.clear();
    }

    /// Takes back the rows after stream frame `frame`.
    pub(crate) fn retract_after(&mut self, frame: usize) {
        while self.rows.back().is_some_and(|r| r.frame > frame) {
            self.rows.pop_back();
        }
    }

    /// The rows as a keypoint track of frames `first..=last` of
    /// [`span`](Self::span) (frames without a pose have confidence 0);
    /// `None` when there is no row.
    pub(crate) fn track(&self) -> Result<Option<Track>> {
        let Some((first, last)) = self.span() else {
            return Ok(None);
        };
        let n = last - first + 1;
        let j = self.skeleton.len();
        let mut pos = Array3::<f64>::zeros((n, j, 2));
        let mut conf = Array2::<f64>::zeros((n, j));
        for r in &self.rows {
            let t = r.frame - first;
            for q in 0..j.min(r.points.len()).min(r.conf.len()) {
                let (p, c) = (r.points[q], r.conf[q]);
                if p.iter().all(|v| v.is_finite()) && c.is_finite() {
                    pos[[t, q, 0]] = p[0];
                    pos[[t, q, 1]] = p[1];
                    conf[[t, q]] = c.clamp(0.0, 1.0);
                }
            }
        }
        let track = Track::new(
            pos,
            Some(conf),
            self.fps,
            Units::Pixels,
            self.skeleton.clone(),
        )?;
        Ok(Some(if self.coco { track.to_coco17()? } else { track }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_weigh_each_joint_by_its_confidence() {
        let mut p = Poses::new(30.0, Skeleton::coco17(), &LiveParams::default());
        let mut conf = vec![0.0; 17];
        conf[0] = 1.0;
        conf[1] = 0.5;
        p.push(0, vec![[0.0, 0.0]; 17], conf.clone());
        let mut moved = vec![[0.0, 0.0]; 17];
        moved[0] = [3.0, 4.0]; // 5 px, weight 1
        moved[2] = [100.0, 0.0]; // unseen
        p.push(1, moved, conf);
        assert!((p.distance(1, 0).unwrap() - (25.0f64 / 1.5).sqrt()).abs() < 1e-12);
        assert!(p.distance(1, 2).is_none());
    }
}
