//! Where the person detector looks: the whole frame, then overlapping square
//! tiles at fractions of the frame's shorter side, searched a few per frame
//! in turn.
//!
//! BlazePose's detector reads a 224 × 224 square: letterboxed, a wide frame
//! shrinks every person in it, and two people side by side in a 1280 × 360
//! frame, or pedestrians a fifth of a 576-px frame high, are too small to be
//! found. Tiles of the shorter side (one per panel of a side-by-side video)
//! and of half of it (people far away) show them at the detector's scale.

use crate::imageops::Roi;

/// The square regions the detector searches in a `width × height` frame:
/// first the whole frame (letterboxed), then for each fraction of `sides`
/// the squares of side `fraction × min(width, height)` laid over the frame
/// with `overlap` (0.5 = half a tile) between neighbours, the last one of a
/// row or column aligned with the frame's edge. A level whose tiles would
/// be no smaller than the whole frame's square, or smaller than `min_side_px`,
/// is skipped.
pub fn tile_regions(
    width: usize,
    height: usize,
    sides: &[f64],
    overlap: f64,
    min_side_px: f64,
) -> Vec<Roi> {
    let mut out = vec![Roi::letterbox(width, height)];
    if width == 0 || height == 0 {
        return out;
    }
    let (w, h) = (width as f64, height as f64);
    let short = w.min(h);
    let long = w.max(h);
    for &f in sides {
        let side = f * short;
        if !(side.is_finite() && side >= min_side_px) || side >= long * 0.999 {
            continue;
        }
        let step = (side * (1.0 - overlap)).max(1.0);
        let xs = positions(w, side, step);
        let ys = positions(h, side, step);
        for &y in &ys {
            for &x in &xs {
                out.push(Roi {
                    center_x_px: x + side / 2.0,
                    center_y_px: y + side / 2.0,
                    width_px: side,
                    height_px: side,
                    rotation_rad: 0.0,
                });
            }
        }
    }
    out
}

/// Left edges of tiles of `side` over `extent` with `step` between them, the
/// last one flush with the end.
fn positions(extent: f64, side: f64, step: f64) -> Vec<f64> {
    if side >= extent {
        return vec![(extent - side) / 2.0];
    }
    let last = extent - side;
    let mut v = Vec::new();
    let mut x = 0.0;
    while x < last - 1e-9 {
        v.push(x);
        x += step;
    }
    v.push(last);
    v
}

/// The tiles searched in turn: a cursor over [`tile_regions`] that hands out
/// as many per frame as it takes to cover the frame once per cycle.
#[derive(Debug, Clone, Default)]
pub struct TileCycle {
    tiles: Vec<Roi>,
    next: usize,
    /// Fractional tiles owed from earlier frames.
    owed: f64,
}

impl TileCycle {
    /// A cycle over `tiles`, starting with the first.
    pub fn new(tiles: Vec<Roi>) -> Self {
        TileCycle {
            tiles,
            next: 0,
            owed: 0.0,
        }
    }

    /// The tiles to search on a frame `dt_s` after the previous one, when the
    /// whole frame is to be covered every `cycle_s` seconds (none on some
    /// frames when there are more frames than tiles in a cycle, at most the
    /// whole cycle on one frame).
    pub fn take(&mut self, dt_s: f64, cycle_s: f64) -> Vec<Roi> {
        let n = self.tiles.len();
        if n == 0 {
            return Vec::new();
        }
        let rate = if dt_s > 0.0 && cycle_s > 0.0 {
            n as f64 * dt_s / cycle_s
        } else {
            n as f64
        };
        self.owed += rate;
        let k = (self.owed.floor() as usize).min(n);
        self.owed = (self.owed - k as f64).clamp(0.0, n as f64);
        (0..k)
            .map(|_| {
                let r = self.tiles[self.next % n];
                self.next = (self.next + 1) % n;
                r
            })
            .collect()
    }

    /// Every tile at once (the first frame of a video).
    pub fn take_all(&mut self) -> Vec<Roi> {
        self.next = 0;
        self.owed = 0.0;
        self.tiles.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wide_frame_gets_one_tile_per_panel_height() {
        // Two 640 × 360 panels side by side.
        let t = tile_regions(1280, 360, &[1.0], 0.5, 64.0);
        assert_eq!(t[0], Roi::letterbox(1280, 360));
        let xs: Vec<f64> = t[1..].iter().map(|r| r.center_x_px).collect();
        // Left edges 0, 180, …, 900, 920.
        assert_eq!(t[1].width_px, 360.0);
        assert_eq!(xs.first().copied(), Some(180.0));
        assert_eq!(xs.last().copied(), Some(1280.0 - 180.0));
        // A person 200 px wide in the middle of either panel lies whole inside a tile.
        for panel in [0.0, 640.0] {
            assert!(t[1..].iter().any(|r| {
                let x0 = r.center_x_px - 180.0;
                x0 <= panel + 220.0 && x0 + 360.0 >= panel + 420.0
            }));
        }
        // Every tile lies within the frame.
        for r in &t[1..] {
            assert!(r.center_x_px - 180.0 >= -1e-9 && r.center_x_px + 180.0 <= 1280.0 + 1e-9);
            assert!((r.center_y_px - 180.0).abs() < 1e-9);
        }
    }

    #[test]
    fn square_frame_skips_the_full_side_level() {
        let t = tile_regions(512, 512, &[1.0, 0.5], 0.5, 64.0);
        // Whole frame + 3 × 3 half-side tiles.
        assert_eq!(t.len(), 1 + 9);
        let t = tile_regions(512, 512, &[0.1], 0.5, 64.0);
        assert_eq!(t.len(), 1, "tiles under the minimum side are skipped");
    }

    #[test]
    fn cycle_covers_every_tile_once_per_cycle() {
        let tiles = tile_regions(768, 576, &[1.0, 0.5], 0.5, 64.0);
        let n = tiles.len();
        let mut c = TileCycle::new(tiles.clone());
        // 10 fps, cycle 1 s: n tiles over 10 frames.
        let mut seen = Vec::new();
        for _ in 0..10 {
            seen.extend(c.take(0.1, 1.0));
        }
        assert_eq!(seen.len(), n);
        assert_eq!(seen, tiles);
        // Slow cycles skip frames; a frame never searches more than the whole cycle.
        let mut c = TileCycle::new(vec![Roi::letterbox(10, 10); 3]);
        let per_frame: Vec<usize> = (0..20).map(|_| c.take(0.1, 2.0).len()).collect();
        assert_eq!(per_frame.iter().sum::<usize>(), 3);
        assert!(per_frame.iter().all(|&k| k <= 1));
        assert_eq!(c.take(100.0, 1.0).len(), 3);
    }
}
