//! The pose-sequence view every metric reads ([`Poses`]), the input checks
//! they share and the NaN-skipping mean of per-frame results ([`nanmean`]).

use ndarray::{Array3, ArrayView2, ArrayView3};

use crate::error::{GeomError, Result};
use crate::track::Track;

/// A borrowed pose sequence: positions `T × J × D` and optional confidence `T × J`.
#[derive(Debug, Clone, Copy)]
pub struct Poses<'a> {
    pub(super) positions: ArrayView3<'a, f64>,
    pub(super) confidence: Option<ArrayView2<'a, f64>>,
}

impl<'a> Poses<'a> {
    /// Wraps positions and an optional confidence (valid when > 0), checking shapes.
    pub fn new(
        positions: ArrayView3<'a, f64>,
        confidence: Option<ArrayView2<'a, f64>>,
    ) -> Result<Self> {
        let (t, j, _) = positions.dim();
        if let Some(c) = confidence {
            if c.dim() != (t, j) {
                return Err(GeomError::Shape(format!(
                    "confidence has shape {:?}, positions need ({t}, {j})",
                    c.dim()
                )));
            }
        }
        Ok(Poses {
            positions,
            confidence,
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
    /// Dimensions D.
    pub fn dims(&self) -> usize {
        self.positions.dim().2
    }
    /// Positions.
    pub fn positions(&self) -> ArrayView3<'a, f64> {
        self.positions
    }
    /// Whether joint `j` of frame `t` is valid (confidence > 0, or no confidence given).
    #[inline]
    pub fn valid(&self, t: usize, j: usize) -> bool {
        match &self.confidence {
            Some(c) => c[[t, j]] > 0.0,
            None => true,
        }
    }
    #[inline]
    pub(super) fn p(&self, t: usize, j: usize, k: usize) -> f64 {
        self.positions[[t, j, k]]
    }

    /// Non-empty, finite where valid, NaN confidence rejected.
    pub(super) fn check(&self, name: &str) -> Result<()> {
        let (t, j, d) = self.positions.dim();
        if t == 0 {
            return Err(GeomError::TooShort {
                what: "metric",
                needed: 1,
                got: 0,
            });
        }
        if j == 0 || d == 0 {
            return Err(GeomError::NoData(format!(
                "{name}: poses have {j} joints of {d} dimensions"
            )));
        }
        for ti in 0..t {
            for ji in 0..j {
                if let Some(c) = &self.confidence {
                    let cv = c[[ti, ji]];
                    if cv.is_nan() {
                        return Err(GeomError::NonFinite(format!(
                            "{name}: confidence of frame {ti}, joint {ji} is NaN"
                        )));
                    }
                }
                if !self.valid(ti, ji) {
                    continue;
                }
                for k in 0..d {
                    let v = self.p(ti, ji, k);
                    if !v.is_finite() {
                        return Err(GeomError::NonFinite(format!(
                            "{name}: frame {ti}, joint {ji}, axis {k} is {v}"
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    /// Euclidean distance between joint `j` of frame `t` here and frame `u` of `other`.
    #[inline]
    pub(super) fn dist(&self, t: usize, other: &Poses<'_>, u: usize, j: usize) -> f64 {
        let mut s = 0.0;
        for k in 0..self.dims() {
            let d = self.p(t, j, k) - other.p(u, j, k);
            s += d * d;
        }
        s.sqrt()
    }
}

impl<'a> From<&'a Track> for Poses<'a> {
    fn from(t: &'a Track) -> Self {
        Poses {
            positions: t.positions(),
            confidence: Some(t.confidence()),
        }
    }
}

impl<'a> From<ArrayView3<'a, f64>> for Poses<'a> {
    /// All joints valid.
    fn from(positions: ArrayView3<'a, f64>) -> Self {
        Poses {
            positions,
            confidence: None,
        }
    }
}

impl<'a> From<&'a Array3<f64>> for Poses<'a> {
    /// All joints valid.
    fn from(positions: &'a Array3<f64>) -> Self {
        Poses {
            positions: positions.view(),
            confidence: None,
        }
    }
}

/// Checks both sequences and that they have the same shape (`same_t`: also T).
pub(super) fn check_pair(a: &Poses<'_>, b: &Poses<'_>, what: &str, same_t: bool) -> Result<()> {
    a.check(&format!("{what} (first sequence)"))?;
    b.check(&format!("{what} (second sequence)"))?;
    let (ta, ja, da) = a.positions.dim();
    let (tb, jb, db) = b.positions.dim();
    if ja != jb || da != db || (same_t && ta != tb) {
        return Err(GeomError::Shape(format!(
            "{what}: sequences have shapes ({ta}, {ja}, {da}) and ({tb}, {jb}, {db})"
        )));
    }
    Ok(())
}

/// Mean of the non-NaN values; NaN when there is none (like numpy's `nanmean`).
pub fn nanmean(values: &[f64]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for v in values {
        if !v.is_nan() {
            s += v;
            n += 1;
        }
    }
    if n == 0 {
        f64::NAN
    } else {
        s / n as f64
    }
}

pub(super) fn nanmean_or_err(values: &[f64], what: &str) -> Result<f64> {
    let m = nanmean(values);
    if m.is_nan() {
        return Err(GeomError::NoData(format!(
            "{what}: no frame could be scored"
        )));
    }
    Ok(m)
}
