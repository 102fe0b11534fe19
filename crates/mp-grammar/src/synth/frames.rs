//! The motion as rows of numbers, one per frame: how a row is laid out
//! (aligned axes, rotation channels), root alignment and the cross-fade
//! difference between frames, and [`Stitcher::new`], which lays a source
//! motion out so.

use std::ops::Range;

use mp_geom::Bvh;
use mp_geom::{Track, Units};
use ndarray::{Array2, ArrayView1};

use super::{Output, RootAlignment, StitchParams, Stitcher};
use crate::distance::PoseFeatures;
use crate::error::{GrammarError, Result};
use crate::symbols::SymbolString;

/// How a frame row is laid out.
#[derive(Debug, Clone)]
pub(super) struct FrameSpace {
    /// Per aligned axis: (axis, columns averaged for the root position,
    /// columns translated with the root).
    axes: Vec<(usize, Vec<usize>, Vec<usize>)>,
    /// Rotation channels (wrapped differences).
    angle: Vec<bool>,
}

fn wrap_deg(x: f64) -> f64 {
    let mut v = (x + 180.0).rem_euclid(360.0) - 180.0;
    if v == -180.0 {
        v = 180.0;
    }
    v
}

impl FrameSpace {
    fn root(&self, row: ArrayView1<'_, f64>, ai: usize) -> f64 {
        let cols = &self.axes[ai].1;
        cols.iter().map(|&c| row[c]).sum::<f64>() / cols.len().max(1) as f64
    }

    /// `Δ` taking `cur` towards `prev` (see the module documentation).
    pub(super) fn delta(&self, prev: ArrayView1<'_, f64>, cur: ArrayView1<'_, f64>) -> Vec<f64> {
        let mut d: Vec<f64> = prev
            .iter()
            .zip(cur.iter())
            .zip(&self.angle)
            .map(|((p, c), &ang)| if ang { wrap_deg(p - c) } else { p - c })
            .collect();
        for (ai, (_, _, moved)) in self.axes.iter().enumerate() {
            let rd = self.root(prev, ai) - self.root(cur, ai);
            for &c in moved {
                d[c] -= rd;
            }
        }
        d
    }

    /// Offset per aligned axis placing `next` (its first rows) after `prev`
    /// (its last rows).
    pub(super) fn placement(
        &self,
        prev: &Array2<f64>,
        prev_end: usize,
        next: &Array2<f64>,
        next_start: usize,
    ) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.axes.len());
        for ai in 0..self.axes.len() {
            let last = self.root(prev.row(prev_end - 1), ai);
            let mut steps = Vec::new();
            if prev_end >= 2 {
                steps.push(last - self.root(prev.row(prev_end - 2), ai));
            }
            if next_start + 1 < next.nrows() {
                steps.push(
                    self.root(next.row(next_start + 1), ai) - self.root(next.row(next_start), ai),
                );
            }
            let v = if steps.is_empty() {
                0.0
            } else {
                steps.iter().sum::<f64>() / steps.len() as f64
            };
            out.push(last + v - self.root(next.row(next_start), ai));
        }
        out
    }

    pub(super) fn translate(&self, rows: &mut Array2<f64>, range: Range<usize>, offset: &[f64]) {
        for (ai, (_, _, moved)) in self.axes.iter().enumerate() {
            let o = offset[ai];
            if o == 0.0 {
                continue;
            }
            for t in range.clone() {
                for &c in moved {
                    rows[[t, c]] += o;
                }
            }
        }
    }
}

fn axes_for(alignment: &RootAlignment, default: &[usize], dims: usize) -> Result<Vec<usize>> {
    let axes = match alignment {
        RootAlignment::Auto => default.to_vec(),
        RootAlignment::None => Vec::new(),
        RootAlignment::Axes(a) => a.clone(),
    };
    if let Some(&bad) = axes.iter().find(|&&a| a >= dims) {
        return Err(GrammarError::param(
            "root_alignment",
            format!("axis {bad} outside 0..{dims}"),
        ));
    }
    Ok(axes)
}

impl Stitcher {
    /// Prepares `track` (and its BVH, whose forward kinematics with length
    /// scale 1 the track must be) cut into the segments of `symbols`.
    ///
    /// Errors: frame counts that disagree, segments outside the motion, a
    /// symbol without segments, or bad parameters.
    pub fn new(
        track: &Track,
        bvh: Option<&Bvh>,
        symbols: &SymbolString,
        params: &StitchParams,
    ) -> Result<Self> {
        params.validate()?;
        let t_len = track.n_frames();
        if symbols.n_frames != t_len {
            return Err(GrammarError::Invalid(format!(
                "the symbols were found on {} frames, the motion has {t_len}",
                symbols.n_frames
            )));
        }
        if symbols.segments.is_empty() {
            return Err(GrammarError::Empty("symbol string has no segment".into()));
        }
        for (i, s) in symbols.segments.iter().enumerate() {
            if s.start >= s.end || s.end > t_len {
                return Err(GrammarError::Invalid(format!(
                    "segment {i}: frames {}..{} are empty or outside 0..{t_len}",
                    s.start, s.end
                )));
            }
            if s.symbol >= symbols.k {
                return Err(GrammarError::Invalid(format!(
                    "segment {i}: symbol {} outside 0..{}",
                    s.symbol, symbols.k
                )));
            }
        }
        let members = symbols.members();
        let medoids: Vec<usize> = (0..symbols.k)
            .map(|k| {
                symbols
                    .medoids
                    .get(k)
                    .copied()
                    .filter(|&m| symbols.segments.get(m).is_some_and(|s| s.symbol == k))
                    .or_else(|| members[k].first().copied())
                    .unwrap_or(0)
            })
            .collect();
        let features = PoseFeatures::from_track(track, &params.distance)?;
        let mut filled = track.clone();
        filled.fill_missing();
        let (space, rows, output) = match bvh {
            Some(b) => {
                if b.n_frames() != t_len || b.joints().len() != track.n_joints() {
                    return Err(GrammarError::Invalid(format!(
                        "BVH has {} frames and {} joints, the track {t_len} frames and {} joints",
                        b.n_frames(),
                        b.joints().len(),
                        track.n_joints()
                    )));
                }
                let root = b
                    .joints()
                    .first()
                    .ok_or_else(|| GrammarError::Empty("BVH has no joint".into()))?;
                let axes = axes_for(&params.root_alignment, &[0, 2], 3)?;
                let mut ax = Vec::new();
                for a in axes {
                    let col = root.channels.iter().enumerate().find_map(|(k, ch)| {
                        (ch.is_position() && ch.axis() == a).then_some(root.first_channel + k)
                    });
                    if let Some(c) = col {
                        ax.push((a, vec![c], vec![c]));
                    }
                }
                let mut angle = vec![false; b.n_channels()];
                for j in b.joints() {
                    for (k, ch) in j.channels.iter().enumerate() {
                        if !ch.is_position() {
                            if let Some(v) = angle.get_mut(j.first_channel + k) {
                                *v = true;
                            }
                        }
                    }
                }
                (
                    FrameSpace { axes: ax, angle },
                    b.motion().to_owned(),
                    Output::Bvh {
                        template: b.slice_frames(0, 1)?,
                        units: track.units(),
                    },
                )
            }
            None => {
                let (nj, d) = (track.n_joints(), track.dims());
                let default: &[usize] = match (track.units(), d) {
                    (Units::Unitless, _) => &[],
                    (_, 2) => &[0],
                    (_, 3) => &[0, 2],
                    _ => &[],
                };
                let axes = axes_for(&params.root_alignment, default, d)?;
                let conf = filled.confidence();
                let root = track
                    .skeleton()
                    .root
                    .filter(|&r| r < nj && (0..t_len).any(|t| conf[[t, r]] > 0.0));
                let ax = axes
                    .into_iter()
                    .map(|a| {
                        let moved: Vec<usize> = (0..nj).map(|j| j * d + a).collect();
                        let rc = match root {
                            Some(r) => vec![r * d + a],
                            None => moved.clone(),
                        };
                        (a, rc, moved)
                    })
                    .collect();
                let rows = filled
                    .positions()
                    .to_owned()
                    .into_shape_with_order((t_len, nj * d))
                    .map_err(|e| GrammarError::Invalid(e.to_string()))?;
                (
                    FrameSpace {
                        axes: ax,
                        angle: vec![false; nj * d],
                    },
                    rows,
                    Output::Positions {
                        n_joints: nj,
                        dims: d,
                        fps: track.fps(),
                        units: track.units(),
                        skeleton: track.skeleton().clone(),
                    },
                )
            }
        };
        Ok(Stitcher {
            params: params.clone(),
            features,
            segments: symbols.segments.clone(),
            members,
            medoids,
            space,
            rows,
            conf: track.confidence().to_owned(),
            output,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapping() {
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-190.0), 170.0);
        assert_eq!(wrap_deg(180.0), 180.0);
        assert_eq!(wrap_deg(10.0), 10.0);
    }
}
