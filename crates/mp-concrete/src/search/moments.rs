//! Running moments of one 2D joint over the candidate segment, updated in
//! O(1) when the segment's start moves one frame back.

/// Per frame, the point the moments of segments ending there are taken
/// about: the frame's own point, or where it is missing the last valid point
/// before it (the first valid point of the track before that one), so the
/// sums stay local even at a missing frame far from the origin (missing
/// points are zeroed). All zeros if no frame is valid.
pub(super) fn anchors(pts: &[[f64; 2]], wts: &[f64]) -> Vec<[f64; 2]> {
    let first = pts
        .iter()
        .zip(wts)
        .find(|(_, &w)| w > 0.0)
        .map_or([0.0, 0.0], |(p, _)| *p);
    let mut last = first;
    pts.iter()
        .zip(wts)
        .map(|(p, &w)| {
            if w > 0.0 {
                last = *p;
            }
            last
        })
        .collect()
}

/// Running moments of one 2D joint over `k..n`, relative to `(t, x) = (n − 1, ref)`.
#[derive(Clone, Copy, Default)]
pub(super) struct Acc2 {
    pub(super) rx: f64,
    pub(super) ry: f64,
    pub(super) count: usize,
    pub(super) sw: f64,
    pub(super) st: f64,
    pub(super) stt: f64,
    pub(super) sx: f64,
    pub(super) sy: f64,
    pub(super) stx: f64,
    pub(super) sty: f64,
    pub(super) sxx: f64,
    pub(super) sxy: f64,
    pub(super) syy: f64,
    pub(super) sxxx: f64,
    pub(super) sxxy: f64,
    pub(super) sxyy: f64,
    pub(super) syyy: f64,
    pub(super) szz: f64,
    pub(super) lo: [f64; 2],
    pub(super) hi: [f64; 2],
    /// Smallest and largest valid frame (absolute).
    pub(super) first: usize,
    pub(super) last: usize,
    /// Frame of local time 0 (`n − 1`).
    pub(super) end: usize,
    /// Step lengths `aᵢ = ‖xᵢ₊₁ − xᵢ‖` of consecutive valid frames: count, Σa, Σa², range.
    pub(super) npairs: usize,
    pub(super) sa: f64,
    pub(super) saa: f64,
    pub(super) amin: f64,
    pub(super) amax: f64,
}

impl Acc2 {
    pub(super) fn reset(&mut self, end: usize, rx: f64, ry: f64) {
        *self = Acc2 {
            rx,
            ry,
            end,
            lo: [f64::INFINITY; 2],
            hi: [f64::NEG_INFINITY; 2],
            amin: f64::INFINITY,
            amax: f64::NEG_INFINITY,
            ..Acc2::default()
        };
    }

    #[inline(always)]
    pub(super) fn add(&mut self, i: usize, tau: f64, px: f64, py: f64, step: f64) {
        if step >= 0.0 && i < self.end {
            self.npairs += 1;
            self.sa += step;
            self.saa += step * step;
            self.amin = self.amin.min(step);
            self.amax = self.amax.max(step);
        }
        let (x, y) = (px - self.rx, py - self.ry);
        let (xx, yy, xy) = (x * x, y * y, x * y);
        let z = xx + yy;
        if self.count == 0 {
            self.last = i;
        }
        self.first = i;
        self.count += 1;
        self.sw += 1.0;
        self.st += tau;
        self.stt += tau * tau;
        self.sx += x;
        self.sy += y;
        self.stx += tau * x;
        self.sty += tau * y;
        self.sxx += xx;
        self.sxy += xy;
        self.syy += yy;
        self.sxxx += xx * x;
        self.sxxy += xx * y;
        self.sxyy += x * yy;
        self.syyy += yy * y;
        self.szz += z * z;
        self.lo[0] = self.lo[0].min(px);
        self.lo[1] = self.lo[1].min(py);
        self.hi[0] = self.hi[0].max(px);
        self.hi[1] = self.hi[1].max(py);
    }
}
