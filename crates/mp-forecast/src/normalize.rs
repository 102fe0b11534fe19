//! Keypoint normalisation shared by the learned models and the nearest-neighbour
//! baseline (and, identically, by `tools/forecast/train.py`).
//!
//! A window of observed frames (the *context*) defines one similarity:
//!
//! * **root** of a frame: the mean of its valid hip joints (`left_hip`, `right_hip`);
//! * **anchor**: the root of the latest context frame that has one; when no
//!   context frame has a valid hip, the mean of the valid joints of the latest
//!   frame that has any;
//! * **scale**: the median over the context frames of the torso length
//!   `‖mid-shoulders − root‖` (frames with at least one valid shoulder and one
//!   valid hip; an even count takes the mean of the two middle values); when
//!   no frame has one, a third of the largest side of the bounding box of all
//!   valid context joints.
//!
//! Every frame of the window (context and future) is mapped by
//! `x ↦ (x − anchor) / scale`; predictions are mapped back by the inverse. A
//! joint is *valid* when its confidence is > 0; a missing joint is written as 0
//! with mask 0 in the model features.

use mp_geom::median;
use mp_geom::{Skeleton, Track};
use ndarray::{ArrayView2, ArrayView3};

use crate::error::{ForecastError, Result};

/// The joints that define the root and the torso.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BodyJoints {
    /// Hip joints (root = their valid mean).
    pub hips: Vec<usize>,
    /// Shoulder joints (mid-shoulders = their valid mean).
    pub shoulders: Vec<usize>,
}

impl BodyJoints {
    /// Finds `left_hip`, `right_hip`, `left_shoulder`, `right_shoulder` by name.
    /// Skeletons without them fall back to the bounding-box rules above.
    pub fn from_skeleton(skeleton: &Skeleton) -> Self {
        let find = |names: [&str; 2]| -> Vec<usize> {
            names
                .iter()
                .filter_map(|n| skeleton.joint_index(n))
                .collect()
        };
        BodyJoints {
            hips: find(["left_hip", "right_hip"]),
            shoulders: find(["left_shoulder", "right_shoulder"]),
        }
    }
}

/// The similarity `x ↦ (x − anchor) / scale` of one window.
#[derive(Debug, Clone, PartialEq)]
pub struct Normalizer {
    /// Anchor point (length D), in the track's units.
    pub anchor: Vec<f64>,
    /// Scale, in the track's units (> 0).
    pub scale: f64,
}

fn mean_valid(
    pos: &ArrayView3<'_, f64>,
    conf: &ArrayView2<'_, f64>,
    t: usize,
    joints: &[usize],
) -> Option<Vec<f64>> {
    let d = pos.dim().2;
    let mut m = vec![0.0; d];
    let mut n = 0usize;
    for &j in joints {
        if conf[[t, j]] > 0.0 {
            for (k, mk) in m.iter_mut().enumerate() {
                *mk += pos[[t, j, k]];
            }
            n += 1;
        }
    }
    if n == 0 {
        return None;
    }
    for v in &mut m {
        *v /= n as f64;
    }
    Some(m)
}

impl Normalizer {
    /// The normaliser of a context window given as positions `T × J × D` and confidence `T × J`.
    pub fn from_context(
        pos: ArrayView3<'_, f64>,
        conf: ArrayView2<'_, f64>,
        body: &BodyJoints,
    ) -> Result<Self> {
        let (t, j, d) = pos.dim();
        if conf.dim() != (t, j) {
            return Err(ForecastError::mismatch(
                "confidence shape",
                format!("({t}, {j})"),
                format!("{:?}", conf.dim()),
            ));
        }
        if let Some(&bad) = body.hips.iter().chain(&body.shoulders).find(|&&x| x >= j) {
            return Err(ForecastError::param(
                "body joints",
                format!("joint {bad} is outside 0..{j}"),
            ));
        }
        let roots: Vec<Option<Vec<f64>>> = (0..t)
            .map(|f| mean_valid(&pos, &conf, f, &body.hips))
            .collect();
        let mut anchor = roots.iter().rev().find_map(|r| r.clone());
        if anchor.is_none() {
            let all: Vec<usize> = (0..j).collect();
            anchor = (0..t).rev().find_map(|f| mean_valid(&pos, &conf, f, &all));
        }
        let Some(anchor) = anchor else {
            return Err(ForecastError::NoValidJoints(format!(
                "every joint of the {t} context frames has confidence 0"
            )));
        };
        let mut torso: Vec<f64> = (0..t)
            .filter_map(|f| {
                let r = roots[f].as_ref()?;
                let s = mean_valid(&pos, &conf, f, &body.shoulders)?;
                Some(
                    r.iter()
                        .zip(&s)
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum::<f64>()
                        .sqrt(),
                )
            })
            .collect();
        let mut scale = median(&mut torso).unwrap_or(0.0);
        if scale.is_nan() || scale <= 1e-9 {
            let mut lo = vec![f64::INFINITY; d];
            let mut hi = vec![f64::NEG_INFINITY; d];
            for f in 0..t {
                for jj in 0..j {
                    if conf[[f, jj]] > 0.0 {
                        for k in 0..d {
                            lo[k] = lo[k].min(pos[[f, jj, k]]);
                            hi[k] = hi[k].max(pos[[f, jj, k]]);
                        }
                    }
                }
            }
            scale = lo.iter().zip(&hi).map(|(a, b)| b - a).fold(0.0, f64::max) / 3.0;
        }
        if !(scale.is_finite() && scale > 1e-9) {
            return Err(ForecastError::NoValidJoints(format!(
                "the valid joints of the {t} context frames coincide (no torso, no extent): cannot set a scale"
            )));
        }
        Ok(Normalizer { anchor, scale })
    }

    /// The normaliser of the last `context` frames of a track.
    pub fn from_track_tail(track: &Track, context: usize, body: &BodyJoints) -> Result<Self> {
        let t = track.n_frames();
        let c = context.min(t);
        if c == 0 {
            return Err(ForecastError::TooShort {
                what: "normalisation",
                needed: 1,
                got: 0,
            });
        }
        let pos = track.positions();
        let conf = track.confidence();
        Self::from_context(
            pos.slice(ndarray::s![t - c.., .., ..]),
            conf.slice(ndarray::s![t - c.., ..]),
            body,
        )
    }

    /// `(x − anchor) / scale` for one coordinate of axis `k`.
    #[inline]
    pub fn forward(&self, k: usize, x: f64) -> f64 {
        (x - self.anchor[k]) / self.scale
    }

    /// The inverse of [`Normalizer::forward`].
    #[inline]
    pub fn inverse(&self, k: usize, x: f64) -> f64 {
        x * self.scale + self.anchor[k]
    }
}

/// Model features of frames `start..end` of a track: per frame the normalised
/// coordinates (`J·D`, joint-major, 0 for missing joints) followed by the masks
/// (`J`, 1 valid / 0 missing), appended to `out` as `f32`.
pub(crate) fn push_features(
    track: &Track,
    start: usize,
    end: usize,
    norm: &Normalizer,
    out: &mut Vec<f32>,
) {
    let (_, j, d) = track.positions().dim();
    let pos = track.positions();
    let conf = track.confidence();
    for t in start..end {
        for jj in 0..j {
            let valid = conf[[t, jj]] > 0.0;
            for k in 0..d {
                out.push(if valid {
                    norm.forward(k, pos[[t, jj, k]]) as f32
                } else {
                    0.0
                });
            }
        }
        for jj in 0..j {
            out.push(if conf[[t, jj]] > 0.0 { 1.0 } else { 0.0 });
        }
    }
}
