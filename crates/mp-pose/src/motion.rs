//! Where a video moves: the motion energy of each thumbnail cell with the
//! camera's global motion discounted, and the regions where it gathers.
//!
//! A repetition that fills little of a cluttered, moving picture (an
//! apparatus filmed in competition, a hoop that hides the body) hardly shows
//! in the thumbnails of the whole frame: most cells follow the clutter. The
//! motion energy of every cell ([`MotionEnergy`]) — the part of its frame
//! difference that a global shift and brightness change of the whole
//! thumbnail (the camera panning, the exposure changing) do not explain —
//! locates what moves on its own; the cells of the region where it gathers
//! ([`moving_regions`], [`region_track`]) then form a frame signal of their
//! own. Memory: three thumbnails and one energy per cell, whatever the
//! length of the video.

use mp_geom::{Skeleton, Track, Units};

use crate::thumbs::Thumbnails;
use nalgebra::{Matrix3, Vector3};
use ndarray::Array3;

use crate::error::{PoseError, Result};

/// A region of a thumbnail grid, in cells: rows `r0..r1`, columns `c0..c1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CellRegion {
    pub r0: usize,
    pub c0: usize,
    pub r1: usize,
    pub c1: usize,
}

impl CellRegion {
    /// Cells in the region.
    pub fn cells(&self) -> usize {
        (self.r1 - self.r0) * (self.c1 - self.c0)
    }
}

/// The global motion between two thumbnails: a shift (cells, columns then
/// rows) and a brightness offset, fitted by least squares to the frame
/// difference linearised around the earlier thumbnail (valid for shifts up to
/// about a cell, 1/32 of the frame side per frame for 32-cell thumbnails).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalMotion {
    pub dx: f64,
    pub dy: f64,
    pub offset: f64,
}

/// Spatial gradients (central differences, one-sided at the borders) of a
/// `size × size` row-major grid.
fn gradients(g: &[f64], size: usize) -> (Vec<f64>, Vec<f64>) {
    let at = |r: usize, c: usize| g[r * size + c];
    let mut gx = vec![0.0; size * size];
    let mut gy = vec![0.0; size * size];
    for r in 0..size {
        for c in 0..size {
            let (cl, cr) = (c.saturating_sub(1), (c + 1).min(size - 1));
            let (ru, rd) = (r.saturating_sub(1), (r + 1).min(size - 1));
            if cr > cl {
                gx[r * size + c] = (at(r, cr) - at(r, cl)) / (cr - cl) as f64;
            }
            if rd > ru {
                gy[r * size + c] = (at(rd, c) - at(ru, c)) / (rd - ru) as f64;
            }
        }
    }
    (gx, gy)
}

/// The global motion from `prev` to `cur` and the residual difference of
/// each cell (what the global motion does not explain), both `size × size`
/// row-major grids. The frame difference `cur − prev` is modelled as
/// `−(gx · dx + gy · dy) + offset` with the gradients of the mean of the two
/// thumbnails.
pub fn global_motion(prev: &[f64], cur: &[f64], size: usize) -> (GlobalMotion, Vec<f64>) {
    let mean: Vec<f64> = prev.iter().zip(cur).map(|(a, b)| 0.5 * (a + b)).collect();
    let (gx, gy) = gradients(&mean, size);
    let mut ata = Matrix3::<f64>::zeros();
    let mut atb = Vector3::<f64>::zeros();
    for k in 0..size * size {
        let row = Vector3::new(-gx[k], -gy[k], 1.0);
        ata += row * row.transpose();
        atb += row * (cur[k] - prev[k]);
    }
    // Least squares through the pseudo-inverse: on a flat picture (no
    // gradient) only the brightness offset is fitted, the shift stays 0.
    let eps = 1e-12 * ata.trace().max(1.0);
    let x = ata
        .svd(true, true)
        .solve(&atb, eps)
        .unwrap_or_else(|_| Vector3::new(0.0, 0.0, atb[2] / (size * size) as f64));
    let (dx, dy, offset) = (x[0], x[1], x[2]);
    let residual = (0..size * size)
        .map(|k| cur[k] - prev[k] + gx[k] * dx + gy[k] * dy - offset)
        .collect();
    (GlobalMotion { dx, dy, offset }, residual)
}

/// The motion energy of every cell of a thumbnail track (the mean squared
/// residual difference of `global_motion` between consecutive frames),
/// accumulated one frame at a time.
#[derive(Debug, Clone)]
pub struct MotionEnergy {
    size: usize,
    prev: Option<Vec<f64>>,
    energy: Vec<f64>,
    pairs: usize,
}

impl MotionEnergy {
    /// An empty accumulator for `size × size` thumbnails.
    pub fn new(size: usize) -> Self {
        MotionEnergy {
            size,
            prev: None,
            energy: vec![0.0; size * size],
            pairs: 0,
        }
    }

    /// Adds the next thumbnail (`size × size` values, row-major).
    pub fn push(&mut self, thumb: &[f64]) -> Result<()> {
        if thumb.len() != self.size * self.size {
            return Err(PoseError::param(
                "motion energy",
                format!(
                    "a {0}×{0} thumbnail has {1} values, got {2}",
                    self.size,
                    self.size * self.size,
                    thumb.len()
                ),
            ));
        }
        if let Some(p) = &self.prev {
            let (_, r) = global_motion(p, thumb, self.size);
            for (e, v) in self.energy.iter_mut().zip(&r) {
                *e += v * v;
            }
            self.pairs += 1;
        }
        self.prev = Some(thumb.to_vec());
        Ok(())
    }

    /// Mean energy of each cell (row-major); zeros before two frames.
    pub fn energy(&self) -> Vec<f64> {
        let n = self.pairs.max(1) as f64;
        self.energy.iter().map(|e| e / n).collect()
    }

    /// The energy of every frame of the thumbnails.
    pub fn of_thumbnails(thumbs: &Thumbnails) -> Result<Self> {
        let side = thumbs.side();
        let mut acc = MotionEnergy::new(side);
        let mut buf = vec![0.0; side * side];
        for frame in thumbs.values().outer_iter() {
            for (v, c) in buf.iter_mut().zip(frame.iter()) {
                *v = f64::from(*c);
            }
            acc.push(&buf)?;
        }
        Ok(acc)
    }
}

/// For each side in `sides` (cells, at most the grid's), the square region
/// of that side where the motion energy gathers most (the highest mean
/// energy; positions every quarter side), with that mean over the mean of
/// the whole grid (1: no more than anywhere else). Ties go to the first
/// position in row-major order. Regions whose ratio is not above 1 are left
/// out: nothing moves there more than in the rest of the picture. Only the
/// positions `allow` accepts are considered (`|_| true`: all of them).
pub fn moving_regions(
    energy: &[f64],
    size: usize,
    sides: &[usize],
    allow: impl Fn(&CellRegion) -> bool,
) -> Vec<(CellRegion, f64)> {
    if size == 0 || energy.len() != size * size {
        return Vec::new();
    }
    let total: f64 = energy.iter().sum::<f64>() / (size * size) as f64;
    if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    // Integral image: s[r][c] = sum of rows < r, columns < c.
    let w = size + 1;
    let mut s = vec![0.0; w * w];
    for r in 0..size {
        for c in 0..size {
            s[(r + 1) * w + c + 1] =
                energy[r * size + c] + s[r * w + c + 1] + s[(r + 1) * w + c] - s[r * w + c];
        }
    }
    let sum = |r0: usize, c0: usize, r1: usize, c1: usize| {
        s[r1 * w + c1] - s[r0 * w + c1] - s[r1 * w + c0] + s[r0 * w + c0]
    };
    let mut out = Vec::new();
    for &side in sides {
        if side == 0 || side > size {
            continue;
        }
        let step = (side / 4).max(1);
        let mut starts: Vec<usize> = (0..=size - side).step_by(step).collect();
        if starts.last() != Some(&(size - side)) {
            starts.push(size - side);
        }
        let mut best: Option<(CellRegion, f64)> = None;
        for &r0 in &starts {
            for &c0 in &starts {
                let reg = CellRegion {
                    r0,
                    c0,
                    r1: r0 + side,
                    c1: c0 + side,
                };
                if !allow(&reg) {
                    continue;
                }
                let m = sum(r0, c0, r0 + side, c0 + side) / (side * side) as f64;
                if best.is_none_or(|(_, b)| m > b) {
                    best = Some((reg, m));
                }
            }
        }
        if let Some((reg, m)) = best {
            if m > total {
                out.push((reg, m / total));
            }
        }
    }
    out
}

/// The cells of `region` of the thumbnails as a track of their own (rows
/// as joints, columns as dimensions; unitless), as [`Thumbnails::track`]
/// gives the whole grid.
pub fn region_track(thumbs: &Thumbnails, region: CellRegion) -> Result<Track> {
    let (n, rows, cols) = thumbs.values().dim();
    if region.r1 > rows || region.c1 > cols || region.r0 >= region.r1 || region.c0 >= region.c1 {
        return Err(PoseError::param(
            "region",
            format!("{region:?} is not inside a {rows}×{cols} grid"),
        ));
    }
    let (h, w) = (region.r1 - region.r0, region.c1 - region.c0);
    let cells = thumbs.values();
    let mut a = Array3::<f64>::zeros((n, h, w));
    for t in 0..n {
        for r in 0..h {
            for c in 0..w {
                a[[t, r, c]] = f64::from(cells[[t, region.r0 + r, region.c0 + c]]);
            }
        }
    }
    Ok(Track::new(
        a,
        None,
        thumbs.fps(),
        Units::Unitless,
        Skeleton::generic(h),
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth texture shifted by (dx, dy) cells.
    fn texture(size: usize, dx: f64, dy: f64) -> Vec<f64> {
        (0..size * size)
            .map(|k| {
                let (r, c) = ((k / size) as f64 - dy, (k % size) as f64 - dx);
                100.0 + 40.0 * (0.4 * c).sin() + 30.0 * (0.3 * r + 0.2 * c).cos()
            })
            .collect()
    }

    #[test]
    fn a_pan_and_a_brightness_change_are_discounted() {
        let (a, b) = (texture(32, 0.0, 0.0), texture(32, 0.3, -0.2));
        let b: Vec<f64> = b.iter().map(|v| v + 5.0).collect();
        let (g, r) = global_motion(&a, &b, 32);
        assert!((g.dx - 0.3).abs() < 0.05, "{g:?}");
        assert!((g.dy + 0.2).abs() < 0.05, "{g:?}");
        assert!((g.offset - 5.0).abs() < 0.5, "{g:?}");
        let raw: f64 = a.iter().zip(&b).map(|(x, y)| (y - x).powi(2)).sum();
        let left: f64 = r.iter().map(|v| v * v).sum();
        assert!(left < 0.05 * raw, "{left} of {raw}");
    }

    #[test]
    fn the_region_that_moves_on_its_own_is_found() {
        // The whole picture pans slowly; a 6 × 6 patch at rows 20..26,
        // columns 4..10 flickers on its own.
        let size = 32;
        let mut acc = MotionEnergy::new(size);
        for t in 0..40 {
            let mut f = texture(size, 0.05 * t as f64, 0.0);
            for r in 20..26 {
                for c in 4..10 {
                    f[r * size + c] += 30.0 * (t as f64 * 0.8).sin();
                }
            }
            acc.push(&f).unwrap();
        }
        let e = acc.energy();
        let regs = moving_regions(&e, size, &[8, 16], |_| true);
        assert_eq!(regs.len(), 2);
        let (small, ratio) = regs[0];
        assert_eq!(small.r1 - small.r0, 8);
        assert!(small.r0 <= 20 && small.r1 >= 26, "{small:?}");
        assert!(small.c0 <= 4 && small.c1 >= 10, "{small:?}");
        assert!(ratio > 8.0, "{ratio}");
        assert_eq!(small.cells(), 64);
        // A picture where everything moves alike has no region of its own.
        assert!(moving_regions(&vec![1.0; 64], 8, &[2, 4], |_| true).is_empty());
        assert!(moving_regions(&[1.0; 3], 8, &[2], |_| true).is_empty());
        // Only the positions allowed are considered: in the right half, the
        // patch's square is not among them.
        for (reg, _) in moving_regions(&e, size, &[8], |r| r.c0 >= 16) {
            assert!(reg.c0 >= 16, "{reg:?}");
        }
        assert!(acc.push(&[0.0; 3]).is_err());
    }

    #[test]
    fn a_region_track_keeps_its_cells() {
        let size = 4;
        let thumbs: Vec<Vec<f32>> = (0..3)
            .map(|t| (0..16).map(|k| (t * 100 + k) as f32).collect())
            .collect();
        let tr = Thumbnails::from_flat(thumbs.concat(), size, 25.0).unwrap();
        let reg = CellRegion {
            r0: 1,
            c0: 2,
            r1: 3,
            c1: 4,
        };
        let sub = region_track(&tr, reg).unwrap();
        assert_eq!(sub.positions().dim(), (3, 2, 2));
        assert_eq!(sub.positions()[[2, 1, 0]], 200.0 + 2.0 * 4.0 + 2.0);
        assert_eq!(sub.fps(), 25.0);
        let bad = CellRegion {
            r0: 0,
            c0: 0,
            r1: 5,
            c1: 1,
        };
        assert!(region_track(&tr, bad).is_err());
        let e = MotionEnergy::of_thumbnails(&tr).unwrap().energy();
        // Every cell brightens by 100 a frame: all offset, no energy left.
        assert!(e.iter().all(|v| v.abs() < 1e-9), "{e:?}");
    }
}
