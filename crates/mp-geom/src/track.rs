//! The track: T frames × J joints × D dimensions, with per-joint confidence.

use ndarray::{s, Array2, Array3, ArrayView2, ArrayView3, Axis};
use serde::{Deserialize, Serialize};

use crate::error::{GeomError, Result};
use crate::skeleton::Skeleton;

/// Units of the positions of a track.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    /// Image pixels (D = 2).
    Pixels,
    /// Metres (usually D = 3).
    Metres,
    /// Anything else (e.g. joint-angle features).
    Unitless,
}

impl Units {
    /// Short name used in files and messages.
    pub fn as_str(&self) -> &'static str {
        match self {
            Units::Pixels => "px",
            Units::Metres => "m",
            Units::Unitless => "1",
        }
    }
    /// Parses the short name written by [`Units::as_str`].
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "px" | "pixels" => Ok(Units::Pixels),
            "m" | "metres" | "meters" => Ok(Units::Metres),
            "1" | "unitless" => Ok(Units::Unitless),
            _ => Err(GeomError::Unknown {
                kind: "unit",
                name: s.into(),
            }),
        }
    }
}

/// The largest coordinate magnitude a [`Track`] holds: 10^100 (any unit).
/// Fits and metrics square distances, which overflow beyond about 10^154;
/// a larger finite coordinate is an error, not a missing joint.
pub const MAX_COORDINATE: f64 = 1e100;

/// The most cells (frames × joints) one generated motion may hold: 10
/// million, i.e. at most 240 MB of positions at 3 dimensions × 8 bytes
/// (1 hour at 30 fps of 92 joints, or 588 000 frames of 17 joints). The
/// execution of programs and the synthesis of grammars refuse larger
/// requests (an absurd frame rate or duration) with an error instead of an
/// allocation failure.
pub const MAX_FRAME_JOINTS: usize = 10_000_000;

/// A motion track: positions `T × J × D` (D = 2 pixels or 3 metres),
/// per-joint confidence in `[0, 1]` (0 = missing), a frame rate and a skeleton.
///
/// Invariant: positions are finite everywhere; a joint that was missing in
/// the source has confidence 0 (its position is then meaningless, stored as
/// the last valid position of that joint or 0).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Track {
    positions: Array3<f64>,
    confidence: Array2<f64>,
    fps: f64,
    units: Units,
    skeleton: Skeleton,
}

/// A frame rate as people write it: a whole number when the rate is within
/// 0.01 % of one (a BVH frame time of 0.008333 s is 120 fps, not
/// 120.0048), else at most three decimals (29.97).
pub fn fps_label(fps: f64) -> String {
    let r = fps.round();
    if r > 0.0 && (fps - r).abs() <= 1e-4 * r {
        format!("{r:.0}")
    } else {
        let s = format!("{fps:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Frames `start..end` (the end excluded, as in files and JSON) as people
/// read a range: the first and the last frame, `"56–131"` (one frame: `"56"`).
pub fn frames_label(start: usize, end: usize) -> String {
    let last = end.saturating_sub(1).max(start);
    if last == start {
        start.to_string()
    } else {
        format!("{start}–{last}")
    }
}

impl Track {
    /// Builds a track, checking shapes and turning non-finite positions into
    /// missing joints (confidence 0); a finite coordinate beyond
    /// ±`MAX_COORDINATE` is an error. Confidence values are clamped to [0, 1];
    /// NaN confidence counts as 0.
    pub fn new(
        positions: Array3<f64>,
        confidence: Option<Array2<f64>>,
        fps: f64,
        units: Units,
        skeleton: Skeleton,
    ) -> Result<Self> {
        let (t, j, d) = positions.dim();
        if !(d == 2 || d == 3) && units != Units::Unitless {
            return Err(GeomError::Shape(format!(
                "positions must have 2 or 3 dimensions per joint, got {d}"
            )));
        }
        if d == 0 {
            return Err(GeomError::Shape(
                "positions have 0 dimensions per joint".into(),
            ));
        }
        if skeleton.len() != j {
            return Err(GeomError::Shape(format!(
                "skeleton `{}` has {} joints but positions have {j}",
                skeleton.name,
                skeleton.len()
            )));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(GeomError::param(
                "fps",
                format!("must be finite and > 0, got {fps}"),
            ));
        }
        let mut confidence = match confidence {
            Some(c) => {
                if c.dim() != (t, j) {
                    return Err(GeomError::Shape(format!(
                        "confidence has shape {:?}, positions need ({t}, {j})",
                        c.dim()
                    )));
                }
                c.mapv(|v| {
                    if v.is_finite() {
                        v.clamp(0.0, 1.0)
                    } else {
                        0.0
                    }
                })
            }
            None => Array2::ones((t, j)),
        };
        let mut positions = positions;
        for ti in 0..t {
            for ji in 0..j {
                let row = positions.slice(s![ti, ji, ..]);
                if let Some(v) = row
                    .iter()
                    .find(|v| v.is_finite() && v.abs() > MAX_COORDINATE)
                {
                    return Err(GeomError::param(
                        "positions",
                        format!(
                            "{v:e} (joint `{}`, frame {ti}) is beyond ±{MAX_COORDINATE:e}: \
                             squared distances would overflow",
                            skeleton.joints.get(ji).map_or("?", String::as_str)
                        ),
                    ));
                }
                let finite = row.iter().all(|v| v.is_finite());
                if !finite {
                    confidence[[ti, ji]] = 0.0;
                    positions.slice_mut(s![ti, ji, ..]).fill(0.0);
                }
            }
        }
        Ok(Track {
            positions,
            confidence,
            fps,
            units,
            skeleton,
        })
    }

    /// Number of frames T.
    pub fn n_frames(&self) -> usize {
        self.positions.dim().0
    }
    /// Number of joints J.
    pub fn n_joints(&self) -> usize {
        self.positions.dim().1
    }
    /// Dimensions per joint D.
    pub fn dims(&self) -> usize {
        self.positions.dim().2
    }
    /// Frames per second.
    pub fn fps(&self) -> f64 {
        self.fps
    }
    /// Units of the positions.
    pub fn units(&self) -> Units {
        self.units
    }
    /// The skeleton.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }
    /// Positions `T × J × D`.
    pub fn positions(&self) -> ArrayView3<'_, f64> {
        self.positions.view()
    }
    /// Confidence `T × J`.
    pub fn confidence(&self) -> ArrayView2<'_, f64> {
        self.confidence.view()
    }
    /// Position of joint `j` at frame `t` (length D).
    pub fn point(&self, t: usize, j: usize) -> ndarray::ArrayView1<'_, f64> {
        self.positions.slice(s![t, j, ..])
    }
    /// Trajectory of joint `j`: `T × D`.
    pub fn joint(&self, j: usize) -> ArrayView2<'_, f64> {
        self.positions.slice(s![.., j, ..])
    }
    /// Whether joint `j` at frame `t` has confidence above `min_conf`.
    pub fn is_valid(&self, t: usize, j: usize, min_conf: f64) -> bool {
        self.confidence[[t, j]] > min_conf
    }
    /// Replace the frame rate.
    pub fn with_fps(mut self, fps: f64) -> Result<Self> {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(GeomError::param(
                "fps",
                format!("must be finite and > 0, got {fps}"),
            ));
        }
        self.fps = fps;
        Ok(self)
    }
    /// Decomposes into parts.
    pub fn into_parts(self) -> (Array3<f64>, Array2<f64>, f64, Units, Skeleton) {
        (
            self.positions,
            self.confidence,
            self.fps,
            self.units,
            self.skeleton,
        )
    }

    /// Tracks joined in time. They need the same joints, dimensions, units
    /// and frame rate; the skeleton of the first is kept.
    pub fn concat(parts: &[&Track]) -> Result<Self> {
        let first = parts
            .first()
            .ok_or_else(|| GeomError::Shape("no track to join".into()))?;
        for (i, t) in parts.iter().enumerate().skip(1) {
            if t.n_joints() != first.n_joints()
                || t.dims() != first.dims()
                || t.units() != first.units()
                || (t.fps() - first.fps()).abs() > 1e-9 * first.fps()
            {
                return Err(GeomError::Shape(format!(
                    "track {i} ({} joints × {} dims, {} fps, {}) cannot follow track 0 \
                     ({} joints × {} dims, {} fps, {})",
                    t.n_joints(),
                    t.dims(),
                    t.fps(),
                    t.units().as_str(),
                    first.n_joints(),
                    first.dims(),
                    first.fps(),
                    first.units().as_str()
                )));
            }
        }
        let pos: Vec<_> = parts.iter().map(|t| t.positions()).collect();
        let conf: Vec<_> = parts.iter().map(|t| t.confidence()).collect();
        let shape = |e: ndarray::ShapeError| GeomError::Shape(e.to_string());
        Track::new(
            ndarray::concatenate(ndarray::Axis(0), &pos).map_err(shape)?,
            Some(ndarray::concatenate(ndarray::Axis(0), &conf).map_err(shape)?),
            first.fps(),
            first.units(),
            first.skeleton().clone(),
        )
    }

    /// Frames `start..end` (end exclusive) as a new track.
    pub fn slice_frames(&self, start: usize, end: usize) -> Result<Self> {
        if start >= end || end > self.n_frames() {
            return Err(GeomError::param(
                "frames",
                format!(
                    "range {start}..{end} is empty or outside 0..{}",
                    self.n_frames()
                ),
            ));
        }
        Ok(Track {
            positions: self.positions.slice(s![start..end, .., ..]).to_owned(),
            confidence: self.confidence.slice(s![start..end, ..]).to_owned(),
            fps: self.fps,
            units: self.units,
            skeleton: self.skeleton.clone(),
        })
    }

    /// Keeps every `step`-th frame starting at frame 0; the frame rate is divided by `step`.
    pub fn subsample(&self, step: usize) -> Result<Self> {
        if step == 0 {
            return Err(GeomError::param("step", "must be ≥ 1"));
        }
        Ok(Track {
            positions: self.positions.slice(s![..;step, .., ..]).to_owned(),
            confidence: self.confidence.slice(s![..;step, ..]).to_owned(),
            fps: self.fps / step as f64,
            units: self.units,
            skeleton: self.skeleton.clone(),
        })
    }

    /// Keeps the given joints (in that order); the skeleton becomes generic
    /// unless every kept joint has a name, which is kept.
    pub fn select_joints(&self, joints: &[usize], skeleton: Skeleton) -> Result<Self> {
        if joints.iter().any(|&j| j >= self.n_joints()) {
            return Err(GeomError::param(
                "joints",
                format!("index out of range 0..{}", self.n_joints()),
            ));
        }
        if skeleton.len() != joints.len() {
            return Err(GeomError::Shape(format!(
                "skeleton `{}` has {} joints, selection has {}",
                skeleton.name,
                skeleton.len(),
                joints.len()
            )));
        }
        let positions = self.positions.select(Axis(1), joints);
        let confidence = self.confidence.select(Axis(1), joints);
        Ok(Track {
            positions,
            confidence,
            fps: self.fps,
            units: self.units,
            skeleton,
        })
    }

    /// Maps the track to COCO-17 using the skeleton's mapping. Joints this
    /// skeleton lacks are marked missing (confidence 0).
    pub fn to_coco17(&self) -> Result<Self> {
        if !self.skeleton.maps_to_coco17() {
            return Err(GeomError::NoData(format!(
                "skeleton `{}` has no mapping to COCO-17",
                self.skeleton.name
            )));
        }
        let (t, _, d) = self.positions.dim();
        let mut pos = Array3::zeros((t, 17, d));
        let mut conf = Array2::zeros((t, 17));
        for (c, src) in self.skeleton.coco17.iter().enumerate() {
            if let Some(src) = *src {
                pos.slice_mut(s![.., c, ..])
                    .assign(&self.positions.slice(s![.., src, ..]));
                conf.slice_mut(s![.., c])
                    .assign(&self.confidence.slice(s![.., src]));
            }
        }
        Track::new(pos, Some(conf), self.fps, self.units, Skeleton::coco17())
    }

    /// The first and last frames with a joint of confidence > 0 (`None`
    /// when there is none).
    pub fn found_span(&self) -> Option<(usize, usize)> {
        let found = |t: &usize| self.confidence.row(*t).iter().any(|&c| c > 0.0);
        let first = (0..self.n_frames()).find(found)?;
        let last = (0..self.n_frames()).rev().find(found)?;
        Some((first, last))
    }

    /// Number of (frame, joint) entries with confidence > 0.
    pub fn valid_count(&self) -> usize {
        self.confidence.iter().filter(|&&c| c > 0.0).count()
    }

    /// Checks that the track has at least `needed` frames and some valid joint.
    pub fn require_frames(&self, what: &'static str, needed: usize) -> Result<()> {
        if self.n_frames() < needed {
            return Err(GeomError::TooShort {
                what,
                needed,
                got: self.n_frames(),
            });
        }
        if self.valid_count() == 0 {
            return Err(GeomError::NoData(format!(
                "{what}: every joint of every frame has confidence 0"
            )));
        }
        Ok(())
    }

    /// Axis-aligned bounding box `(min, max)` per dimension over all valid entries.
    pub fn bounds(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        let d = self.dims();
        let mut lo = vec![f64::INFINITY; d];
        let mut hi = vec![f64::NEG_INFINITY; d];
        let mut any = false;
        for ((t, j), &c) in self.confidence.indexed_iter() {
            if c > 0.0 {
                any = true;
                for k in 0..d {
                    let v = self.positions[[t, j, k]];
                    lo[k] = lo[k].min(v);
                    hi[k] = hi[k].max(v);
                }
            }
        }
        any.then_some((lo, hi))
    }

    /// Characteristic size of the motion: the diagonal of the bounding box of
    /// all valid positions (pixels or metres). Used to make thresholds unit-free.
    pub fn scale(&self) -> f64 {
        match self.bounds() {
            Some((lo, hi)) => lo
                .iter()
                .zip(&hi)
                .map(|(a, b)| (b - a) * (b - a))
                .sum::<f64>()
                .sqrt(),
            None => 0.0,
        }
    }

    /// Fills missing joints by linear interpolation in time between the
    /// nearest valid frames (holding the edge values). Confidence is left as is.
    pub fn fill_missing(&mut self) {
        let (t, j, d) = self.positions.dim();
        for ji in 0..j {
            let valid: Vec<usize> = (0..t)
                .filter(|&ti| self.confidence[[ti, ji]] > 0.0)
                .collect();
            if valid.is_empty() {
                continue;
            }
            for ti in 0..t {
                if self.confidence[[ti, ji]] > 0.0 {
                    continue;
                }
                let Some((a, b, w)) = bracket(&valid, ti) else {
                    continue;
                };
                for k in 0..d {
                    let v = self.positions[[a, ji, k]] * (1.0 - w) + self.positions[[b, ji, k]] * w;
                    self.positions[[ti, ji, k]] = v;
                }
            }
        }
    }

    /// Mutable positions (finite values only: the caller keeps the invariant).
    pub fn positions_mut(&mut self) -> ndarray::ArrayViewMut3<'_, f64> {
        self.positions.view_mut()
    }
    /// Mutable confidence.
    pub fn confidence_mut(&mut self) -> ndarray::ArrayViewMut2<'_, f64> {
        self.confidence.view_mut()
    }
}

/// The nearest entries of the sorted frame list `valid` around frame `f`
/// and the linear-interpolation weight of the later one: `(a, b, w)` with
/// `a ≤ f ≤ b` where both exist (an edge repeats the nearest entry, `w = 0`).
/// `None` when `valid` is empty.
pub fn bracket(valid: &[usize], f: usize) -> Option<(usize, usize, f64)> {
    let next = valid.partition_point(|&v| v < f);
    let (a, b) = match (
        next.checked_sub(1).map(|p| valid[p]),
        valid.get(next).copied(),
    ) {
        (Some(a), Some(b)) => (a, b),
        (Some(a), None) => (a, a),
        (None, Some(b)) => (b, b),
        (None, None) => return None,
    };
    let w = if b == a {
        0.0
    } else {
        (f as f64 - a as f64) / (b - a) as f64
    };
    Some((a, b, w))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_read_first_to_last() {
        assert_eq!(frames_label(0, 124), "0–123");
        assert_eq!(frames_label(56, 57), "56");
        assert_eq!(frames_label(5, 5), "5");
    }

    #[test]
    fn frame_rates_read_as_people_write_them() {
        assert_eq!(fps_label(30.0), "30");
        assert_eq!(fps_label(1.0 / 0.008333), "120");
        assert_eq!(fps_label(29.97), "29.97");
        assert_eq!(fps_label(30000.0 / 1001.0), "29.97");
        assert_eq!(fps_label(12.5), "12.5");
    }

    fn tiny() -> Track {
        let mut p = Array3::zeros((4, 2, 2));
        for t in 0..4 {
            p[[t, 0, 0]] = t as f64;
            p[[t, 1, 1]] = 2.0 * t as f64;
        }
        p[[2, 1, 0]] = f64::NAN;
        Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(2)).unwrap()
    }

    #[test]
    fn nan_becomes_missing() {
        let tr = tiny();
        assert_eq!(tr.confidence()[[2, 1]], 0.0);
        assert!(tr.positions().iter().all(|v| v.is_finite()));
        assert_eq!(tr.valid_count(), 7);
    }

    #[test]
    fn found_span_skips_empty_frames_at_the_ends() {
        let mut p = Array3::from_elem((5, 2, 2), f64::NAN);
        p[[1, 0, 0]] = 1.0;
        p[[1, 0, 1]] = 1.0;
        p[[3, 1, 0]] = 2.0;
        p[[3, 1, 1]] = 2.0;
        let tr = Track::new(p.clone(), None, 30.0, Units::Pixels, Skeleton::generic(2)).unwrap();
        assert_eq!(tr.found_span(), Some((1, 3)));
        p.fill(f64::NAN);
        let empty = Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(2)).unwrap();
        assert_eq!(empty.found_span(), None);
    }

    #[test]
    fn fill_missing_interpolates() {
        let mut tr = tiny();
        tr.fill_missing();
        assert!((tr.point(2, 1)[1] - 4.0).abs() < 1e-12);
    }

    #[test]
    fn subsample_and_slice() {
        let tr = tiny();
        let s = tr.subsample(2).unwrap();
        assert_eq!(s.n_frames(), 2);
        assert_eq!(s.fps(), 15.0);
        assert!(tr.slice_frames(3, 3).is_err());
        assert!(tr.subsample(0).is_err());
    }

    #[test]
    fn rejects_bad_shapes() {
        let p = Array3::zeros((4, 2, 2));
        assert!(Track::new(p.clone(), None, 0.0, Units::Pixels, Skeleton::generic(2)).is_err());
        assert!(Track::new(p, None, 30.0, Units::Pixels, Skeleton::generic(3)).is_err());
    }
}
