//! Pose distance `d(x, x')` and segment distance `D(s, s')` (paper eq. 1).
//!
//! # Pose distance
//!
//! Every frame is turned once into a feature vector `φ_t` and the pose
//! distance is the Euclidean distance `d(x_t, x_t') = ‖φ_t − φ_t'‖`.
//!
//! * **Skeletal tracks** ([`Units::Pixels`] or [`Units::Metres`]): missing
//!   joints are first filled by linear interpolation in time
//!   ([`Track::fill_missing`]); joints that are never valid are dropped.
//!   Each frame is made *root-relative* by subtracting the root position
//!   `r_t` (the skeleton's root joint when it has one, otherwise the mean of
//!   the joints of that frame; see [`RootMode`]) and *scale-normalised* by one
//!   per-track body size `s = sqrt(mean_{t,j} ‖x_tj − r_t‖²)` (the RMS
//!   distance of the joints from the root over the whole track). With `J`
//!   joints, `φ_t = (x_t − r_t) / (s·√J)`, so that
//!
//!   `d(x, x') = sqrt( (1/J) Σ_j ‖(x_j − r) − (x'_j − r')‖² ) / s`,
//!
//!   the root-mean-square joint displacement in units of body size
//!   (dimensionless; 0 for identical poses, about 1.4 for unrelated poses).
//!   The distance is invariant to translation of the whole body and to the
//!   size of the performer, not to the facing direction.
//! * **Feature tracks** ([`Units::Unitless`], e.g. the 12 joint-angle channels
//!   of the CMU exercise features): `φ_t` is the flattened frame as it is, so
//!   `d` is the plain Euclidean distance of the feature vectors.
//!
//! Feature vectors are stored as `f32`, padded with zeros to a multiple of 8
//! so that the distance loop vectorises; segment distances accumulate in `f64`.
//!
//! # Segment distance (eq. 1)
//!
//! For segments `s = [a, a + l)` and `s' = [a', a' + l')` with `l ≥ l'`
//! (frames, end exclusive), uniform time warping matches the `m`-th frame of
//! the longer segment (`m = 0 … l − 1`) with frame `⌊m·l'/l⌋` of the shorter
//! one, and `D(s, s') = (1/l) Σ_m d(x_{a+m}, x_{a'+⌊m·l'/l⌋})`. `D` is
//! symmetric and `D(s, s) = 0`.

use mp_geom::{Track, Units};
use serde::{Deserialize, Serialize};

use crate::error::{GrammarError, Result};

/// A segment of frames `[start, end)` (end exclusive).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct FrameSpan {
    /// First frame.
    pub start: usize,
    /// One past the last frame.
    pub end: usize,
}

impl FrameSpan {
    /// Builds a segment; `start < end` is checked by the functions that use it.
    pub fn new(start: usize, end: usize) -> Self {
        FrameSpan { start, end }
    }
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.end.saturating_sub(self.start)
    }
    /// True when the segment has no frame.
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }
}

/// Which point is subtracted from every joint to make a pose root-relative.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[non_exhaustive]
pub enum RootMode {
    /// The skeleton's root joint (`Skeleton::root`); the mean of the joints
    /// when the skeleton has none or that joint is never valid. Default.
    #[default]
    SkeletonRoot,
    /// The mean of the (selected) joints of each frame.
    Centroid,
    /// Positions are used as they are (no root subtraction).
    None,
}

/// Parameters of the pose distance (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseDistanceParams {
    /// Root used for root-relative positions. Default [`RootMode::SkeletonRoot`].
    pub root: RootMode,
    /// Divide by the per-track body size `s`. Default `true`.
    pub scale_normalise: bool,
    /// Joints to use (indices into the track); `None` = every joint that is
    /// valid in at least one frame. Default `None`.
    pub joints: Option<Vec<usize>>,
}

impl Default for PoseDistanceParams {
    fn default() -> Self {
        PoseDistanceParams {
            root: RootMode::SkeletonRoot,
            scale_normalise: true,
            joints: None,
        }
    }
}

/// Per-frame feature vectors of a track, ready for pose and segment distances.
#[derive(Debug, Clone)]
pub struct PoseFeatures {
    n_frames: usize,
    dim: usize,
    stride: usize,
    data: Vec<f32>,
    fps: f64,
    body_scale: f64,
}

const LANES: usize = 8;

#[inline]
fn sq_dist(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0f32; LANES];
    for (ca, cb) in a.chunks_exact(LANES).zip(b.chunks_exact(LANES)) {
        for i in 0..LANES {
            let d = ca[i] - cb[i];
            acc[i] += d * d;
        }
    }
    acc.iter().sum()
}

impl PoseFeatures {
    /// Builds the features of a track (see the module documentation).
    ///
    /// Errors: an empty track, no valid joint, a joint index out of range,
    /// or a degenerate body size (every joint at the root).
    pub fn from_track(track: &Track, params: &PoseDistanceParams) -> Result<Self> {
        Self::from_track_with_scale(track, params, None)
    }

    /// Like [`from_track`](Self::from_track), but with a given body size `s`
    /// (in the track's units) instead of the one measured on this track, so
    /// that distances on a derived track (e.g. a synthesised motion) are in
    /// the units of its source. `None` measures it as `from_track` does.
    /// Ignored for feature tracks.
    pub fn from_track_with_scale(
        track: &Track,
        params: &PoseDistanceParams,
        body_scale: Option<f64>,
    ) -> Result<Self> {
        let t_len = track.n_frames();
        if t_len == 0 {
            return Err(GrammarError::Empty("track has no frame".into()));
        }
        if track.valid_count() == 0 {
            return Err(GrammarError::Invalid(
                "track: every joint of every frame has confidence 0".into(),
            ));
        }
        let mut filled = track.clone();
        filled.fill_missing();
        let conf = filled.confidence();
        let n_j = filled.n_joints();
        let d = filled.dims();
        let joints: Vec<usize> = match &params.joints {
            Some(js) => {
                if js.is_empty() {
                    return Err(GrammarError::param("joints", "empty joint list"));
                }
                if let Some(&bad) = js.iter().find(|&&j| j >= n_j) {
                    return Err(GrammarError::param(
                        "joints",
                        format!("joint index {bad} outside 0..{n_j}"),
                    ));
                }
                js.clone()
            }
            None => (0..n_j)
                .filter(|&j| (0..t_len).any(|t| conf[[t, j]] > 0.0))
                .collect(),
        };
        if joints.is_empty() {
            return Err(GrammarError::Invalid(
                "track: no joint is ever valid".into(),
            ));
        }
        let pos = filled.positions();
        let dim = joints.len() * d;
        let stride = dim.div_ceil(LANES) * LANES;
        let mut data = vec![0f32; t_len * stride];
        if track.units() == Units::Unitless {
            for t in 0..t_len {
                let row = &mut data[t * stride..t * stride + dim];
                for (k, &j) in joints.iter().enumerate() {
                    for c in 0..d {
                        row[k * d + c] = pos[[t, j, c]] as f32;
                    }
                }
            }
            return Ok(PoseFeatures {
                n_frames: t_len,
                dim,
                stride,
                data,
                fps: track.fps(),
                body_scale: 1.0,
            });
        }
        let skel_root = filled
            .skeleton()
            .root
            .filter(|&r| r < n_j && (0..t_len).any(|t| conf[[t, r]] > 0.0));
        let mut rel = vec![0f64; t_len * dim];
        let mut sum_sq = 0.0f64;
        for t in 0..t_len {
            let mut root = vec![0f64; d];
            match (params.root, skel_root) {
                (RootMode::None, _) => {}
                (RootMode::SkeletonRoot, Some(r)) => {
                    for (c, v) in root.iter_mut().enumerate() {
                        *v = pos[[t, r, c]];
                    }
                }
                _ => {
                    for &j in &joints {
                        for (c, v) in root.iter_mut().enumerate() {
                            *v += pos[[t, j, c]];
                        }
                    }
                    for v in root.iter_mut() {
                        *v /= joints.len() as f64;
                    }
                }
            }
            for (k, &j) in joints.iter().enumerate() {
                for c in 0..d {
                    let v = pos[[t, j, c]] - root[c];
                    rel[t * dim + k * d + c] = v;
                    sum_sq += v * v;
                }
            }
        }
        let n_j_sel = joints.len() as f64;
        let body_scale = match body_scale {
            Some(s) => s,
            None => (sum_sq / (t_len as f64 * n_j_sel)).sqrt(),
        };
        let divisor = if params.scale_normalise {
            if !(body_scale.is_finite() && body_scale > 1e-12) {
                return Err(GrammarError::Invalid(format!(
                    "track: degenerate body size {body_scale} (every joint at the root)"
                )));
            }
            body_scale * n_j_sel.sqrt()
        } else {
            n_j_sel.sqrt()
        };
        for t in 0..t_len {
            for k in 0..dim {
                data[t * stride + k] = (rel[t * dim + k] / divisor) as f32;
            }
        }
        Ok(PoseFeatures {
            n_frames: t_len,
            dim,
            stride,
            data,
            fps: track.fps(),
            body_scale,
        })
    }

    /// Plain feature vectors (one row per frame); the distance is Euclidean.
    pub fn from_rows(rows: ndarray::ArrayView2<'_, f64>, fps: f64) -> Result<Self> {
        let (t_len, dim) = rows.dim();
        if t_len == 0 || dim == 0 {
            return Err(GrammarError::Empty(format!(
                "feature matrix has shape ({t_len}, {dim})"
            )));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(GrammarError::param(
                "fps",
                format!("must be > 0, got {fps}"),
            ));
        }
        let stride = dim.div_ceil(LANES) * LANES;
        let mut data = vec![0f32; t_len * stride];
        for t in 0..t_len {
            for k in 0..dim {
                let v = rows[[t, k]];
                if !v.is_finite() {
                    return Err(GrammarError::Invalid(format!(
                        "feature matrix: non-finite value at frame {t}, channel {k}"
                    )));
                }
                data[t * stride + k] = v as f32;
            }
        }
        Ok(PoseFeatures {
            n_frames: t_len,
            dim,
            stride,
            data,
            fps,
            body_scale: 1.0,
        })
    }

    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.n_frames
    }
    /// Length of one feature vector (without padding).
    pub fn dim(&self) -> usize {
        self.dim
    }
    /// Frame rate of the source track.
    pub fn fps(&self) -> f64 {
        self.fps
    }
    /// Body size `s` used for normalisation (1 for feature tracks), in the
    /// track's units.
    pub fn body_scale(&self) -> f64 {
        self.body_scale
    }
    /// Feature vector of frame `t` (length [`dim`](Self::dim)), if it exists.
    pub fn frame(&self, t: usize) -> Option<&[f32]> {
        (t < self.n_frames).then(|| &self.data[t * self.stride..t * self.stride + self.dim])
    }

    #[inline]
    fn row(&self, t: usize) -> &[f32] {
        &self.data[t * self.stride..(t + 1) * self.stride]
    }

    /// Pose distance between frames `a` and `b` (no bounds check).
    #[inline]
    pub(crate) fn dist_unchecked(&self, a: usize, b: usize) -> f64 {
        (sq_dist(self.row(a), self.row(b)) as f64).sqrt()
    }

    /// Pose distance `d(x_a, x_b)` between two frames.
    pub fn pose_distance(&self, a: usize, b: usize) -> Result<f64> {
        for f in [a, b] {
            if f >= self.n_frames {
                return Err(GrammarError::Invalid(format!(
                    "frame {f} outside 0..{}",
                    self.n_frames
                )));
            }
        }
        Ok(self.dist_unchecked(a, b))
    }

    /// Segment distance (eq. 1) without bounds checks; both segments must be
    /// non-empty and inside the track.
    #[inline]
    pub(crate) fn segment_distance_unchecked(&self, a: FrameSpan, b: FrameSpan) -> f64 {
        let (long, short) = if a.len() >= b.len() { (a, b) } else { (b, a) };
        let l = long.len();
        let ls = short.len();
        if l == 0 {
            return 0.0;
        }
        let mut sum = 0.0f64;
        for m in 0..l {
            let k = m * ls / l;
            sum += self.dist_unchecked(long.start + m, short.start + k);
        }
        sum / l as f64
    }

    /// Segment distance `D(s, s')` (eq. 1). Errors when a segment is empty or
    /// extends past the last frame.
    pub fn segment_distance(&self, a: FrameSpan, b: FrameSpan) -> Result<f64> {
        self.check_segment(a)?;
        self.check_segment(b)?;
        Ok(self.segment_distance_unchecked(a, b))
    }

    /// Segment distance (eq. 1) between segment `a` of this track and
    /// segment `b` of `other` (same feature layout, e.g. a new take compared
    /// with learned medoids). Errors when a segment is empty or outside its
    /// track, or the feature lengths differ.
    pub fn segment_distance_to(
        &self,
        a: FrameSpan,
        other: &PoseFeatures,
        b: FrameSpan,
    ) -> Result<f64> {
        self.check_segment(a)?;
        other.check_segment(b)?;
        if self.dim != other.dim || self.stride != other.stride {
            return Err(GrammarError::Invalid(format!(
                "feature vectors of {} and {} values cannot be compared",
                self.dim, other.dim
            )));
        }
        let (la, lb) = (a.len(), b.len());
        let mut sum = 0.0f64;
        if la >= lb {
            for m in 0..la {
                let k = m * lb / la;
                sum += (sq_dist(self.row(a.start + m), other.row(b.start + k)) as f64).sqrt();
            }
            Ok(sum / la as f64)
        } else {
            for m in 0..lb {
                let k = m * la / lb;
                sum += (sq_dist(self.row(a.start + k), other.row(b.start + m)) as f64).sqrt();
            }
            Ok(sum / lb as f64)
        }
    }

    /// Checks that a segment is non-empty and inside the track.
    pub fn check_segment(&self, s: FrameSpan) -> Result<()> {
        if s.is_empty() || s.end > self.n_frames {
            return Err(GrammarError::Invalid(format!(
                "segment {}..{} is empty or outside 0..{}",
                s.start, s.end, self.n_frames
            )));
        }
        Ok(())
    }

    /// `d_max`: the largest pose distance over all pairs of frames (exact up
    /// to `f32` rounding). Uses the triangle inequality around the centroid to
    /// skip pairs that cannot beat the current maximum, so it is usually far
    /// cheaper than the `T²/2` pairs it stands for.
    pub fn max_pose_distance(&self) -> f64 {
        let n = self.n_frames;
        if n < 2 {
            return 0.0;
        }
        let mut c = vec![0f64; self.stride];
        for t in 0..n {
            for (k, v) in self.row(t).iter().enumerate() {
                c[k] += *v as f64;
            }
        }
        let c32: Vec<f32> = c.iter().map(|v| (*v / n as f64) as f32).collect();
        let r: Vec<f64> = (0..n)
            .map(|t| (sq_dist(self.row(t), &c32) as f64).sqrt())
            .collect();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| r[b].total_cmp(&r[a]).then(a.cmp(&b)));
        // Lower bound: double sweep from the point farthest from the centroid.
        let far = |a: usize| -> (usize, f64) {
            let mut best = (a, 0.0);
            for t in 0..n {
                let v = self.dist_unchecked(a, t);
                if v > best.1 {
                    best = (t, v);
                }
            }
            best
        };
        let (b1, _) = far(order[0]);
        let (_, mut best) = far(b1);
        let slack = 1.0 + 1e-5;
        let r0 = r[order[0]];
        for (ii, &i) in order.iter().enumerate() {
            if (r[i] + r0) * slack <= best {
                break;
            }
            for &j in &order[..ii] {
                if (r[i] + r[j]) * slack <= best {
                    break;
                }
                let v = self.dist_unchecked(i, j);
                if v > best {
                    best = v;
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_geom::Skeleton;
    use ndarray::Array3;

    fn track(positions: Array3<f64>, units: Units) -> Track {
        let j = positions.dim().1;
        Track::new(positions, None, 30.0, units, Skeleton::generic(j)).unwrap()
    }

    #[test]
    fn pose_distance_is_translation_and_scale_invariant() {
        // Two frames of 3 joints; frame 1 = frame 0 shifted by (5, -2).
        let mut p = Array3::zeros((4, 3, 2));
        let pose = [[0.0, 0.0], [1.0, 0.0], [0.0, 2.0]];
        for t in 0..4 {
            for j in 0..3 {
                for c in 0..2 {
                    p[[t, j, c]] = pose[j][c] + if t % 2 == 1 { [5.0, -2.0][c] } else { 0.0 };
                }
            }
        }
        let f = PoseFeatures::from_track(&track(p.clone(), Units::Pixels), &Default::default())
            .unwrap();
        assert!(f.pose_distance(0, 1).unwrap() < 1e-6);
        // Scaled copy gives the same features.
        let g = PoseFeatures::from_track(
            &track(p.mapv(|v| v * 3.0), Units::Pixels),
            &Default::default(),
        )
        .unwrap();
        for t in 0..4 {
            for (a, b) in f.frame(t).unwrap().iter().zip(g.frame(t).unwrap()) {
                assert!((a - b).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn documented_formula_holds() {
        // Root = centroid (generic skeleton has no root). 2 joints in 1-D-ish.
        let mut p = Array3::zeros((2, 2, 2));
        p[[0, 1, 0]] = 2.0; // frame 0: joints at (0,0), (2,0): centroid (1,0)
        p[[1, 1, 1]] = 2.0; // frame 1: joints at (0,0), (0,2): centroid (0,1)
        let f = PoseFeatures::from_track(&track(p, Units::Pixels), &Default::default()).unwrap();
        // rel0 = (-1,0),(1,0); rel1 = (0,-1),(0,1); s = 1.
        // d = sqrt((|(-1,1)|² + |(1,-1)|²)/2) / s = sqrt(2).
        assert!((f.body_scale() - 1.0).abs() < 1e-12);
        assert!((f.pose_distance(0, 1).unwrap() - 2f64.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn unitless_is_plain_euclidean() {
        let mut p = Array3::zeros((2, 12, 1));
        for k in 0..12 {
            p[[1, k, 0]] = 1.0;
        }
        let f = PoseFeatures::from_track(&track(p, Units::Unitless), &Default::default()).unwrap();
        assert!((f.pose_distance(0, 1).unwrap() - 12f64.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn segment_distance_uniform_warping() {
        // 1-D features x_t = t.
        let rows = ndarray::Array2::from_shape_fn((10, 1), |(t, _)| t as f64);
        let f = PoseFeatures::from_rows(rows.view(), 10.0).unwrap();
        // long [0,4) vs short [6,8): m=0..3 ↔ k = 0,0,1,1 → frames 6,6,7,7.
        // |0-6| + |1-6| + |2-7| + |3-7| = 6+5+5+4 = 20 → 20/4 = 5.
        let d = f
            .segment_distance(FrameSpan::new(0, 4), FrameSpan::new(6, 8))
            .unwrap();
        assert!((d - 5.0).abs() < 1e-9);
        let d2 = f
            .segment_distance(FrameSpan::new(6, 8), FrameSpan::new(0, 4))
            .unwrap();
        assert_eq!(d, d2);
        assert_eq!(
            f.segment_distance(FrameSpan::new(2, 5), FrameSpan::new(2, 5))
                .unwrap(),
            0.0
        );
        assert!(f
            .segment_distance(FrameSpan::new(3, 3), FrameSpan::new(0, 2))
            .is_err());
        assert!(f
            .segment_distance(FrameSpan::new(8, 11), FrameSpan::new(0, 2))
            .is_err());
    }

    #[test]
    fn max_distance_matches_brute_force() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for dim in [1usize, 5, 13] {
            let rows = ndarray::Array2::from_shape_fn((300, dim), |_| rng.random::<f64>());
            let f = PoseFeatures::from_rows(rows.view(), 10.0).unwrap();
            let mut brute = 0.0f64;
            for a in 0..300 {
                for b in 0..a {
                    brute = brute.max(f.dist_unchecked(a, b));
                }
            }
            assert!((f.max_pose_distance() - brute).abs() < 1e-9, "dim {dim}");
        }
    }
}
