//! The warp: backward displacement fields (smooth or per bone), body masks,
//! bilinear sampling, and the in-between frame.

use rayon::prelude::*;

use super::guide::{Controls, Guide, Segment};
use super::{Frames, InterpParams, Warp};
use crate::error::Result;
use crate::plan::blend;

/// The backward displacement field of a bone warp on a grid of step `g`:
/// each bone maps a target pixel to the source frame (the position along
/// the bone scaled with it, the distance across kept on the source bone's
/// normal; a bone of no length translates), and the bones' maps are
/// blended with weights `1 / (d² + ε²)²` of the distance `d` to each bone at
/// the target pose.
pub(super) fn bone_field(
    bones: &[(Segment, Segment)],
    eps: f64,
    g: usize,
    w: usize,
    h: usize,
) -> Vec<[f32; 2]> {
    let gw = (w - 1) / g + 2;
    let gh = (h - 1) / g + 2;
    let e2 = eps * eps;
    (0..gw * gh)
        .into_par_iter()
        .map(|idx| {
            let (x, y) = (((idx % gw) * g) as f64, ((idx / gw) * g) as f64);
            let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
            for ((t0, t1), (s0, s1)) in bones {
                let (dx, dy) = (t1[0] - t0[0], t1[1] - t0[1]);
                let l2 = dx * dx + dy * dy;
                let (ex, ey) = (s1[0] - s0[0], s1[1] - s0[1]);
                let m2 = ex * ex + ey * ey;
                let (src, dist2) = if l2 < 1.0 || m2 < 1.0 {
                    // A point (or a bone seen end-on): translate with its middle.
                    let (cx, cy) = ((t0[0] + t1[0]) / 2.0, (t0[1] + t1[1]) / 2.0);
                    let (ox, oy) = ((s0[0] + s1[0]) / 2.0 - cx, (s0[1] + s1[1]) / 2.0 - cy);
                    let tc = if l2 > 0.0 {
                        (((x - t0[0]) * dx + (y - t0[1]) * dy) / l2).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let (px, py) = (t0[0] + tc * dx - x, t0[1] + tc * dy - y);
                    ([x + ox, y + oy], px * px + py * py)
                } else {
                    let l = l2.sqrt();
                    let m = m2.sqrt();
                    let u = ((x - t0[0]) * dx + (y - t0[1]) * dy) / l2;
                    // Signed distance across the bone, in pixels.
                    let v = ((x - t0[0]) * -dy + (y - t0[1]) * dx) / l;
                    let src = [s0[0] + u * ex + v * -ey / m, s0[1] + u * ey + v * ex / m];
                    let uc = u.clamp(0.0, 1.0);
                    let (px, py) = (t0[0] + uc * dx - x, t0[1] + uc * dy - y);
                    (src, px * px + py * py)
                };
                let wt = 1.0 / (dist2 + e2).powi(2);
                sx += wt * (src[0] - x);
                sy += wt * (src[1] - y);
                sw += wt;
            }
            if sw > 0.0 {
                [(sx / sw) as f32, (sy / sw) as f32]
            } else {
                [0.0, 0.0]
            }
        })
        .collect()
}

/// A soft body mask on the grid: 1 within `r` of a segment, fading to 0 at `2r`.
pub(super) fn body_mask(segs: &[Segment], r: f64, g: usize, w: usize, h: usize) -> Vec<f32> {
    let gw = (w - 1) / g + 2;
    let gh = (h - 1) / g + 2;
    (0..gw * gh)
        .into_par_iter()
        .map(|idx| {
            let (x, y) = (((idx % gw) * g) as f64, ((idx / gw) * g) as f64);
            let mut best = f64::INFINITY;
            for (p, q) in segs {
                let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
                let l2 = dx * dx + dy * dy;
                let t = if l2 > 0.0 {
                    (((x - p[0]) * dx + (y - p[1]) * dy) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let (cx, cy) = (p[0] + t * dx - x, p[1] + t * dy - y);
                best = best.min(cx * cx + cy * cy);
            }
            ((2.0 * r - best.sqrt()) / r).clamp(0.0, 1.0) as f32
        })
        .collect()
}

/// The displacement field of `controls` on a grid of step `g` covering the frame.
pub(super) fn field(
    controls: &[([f64; 2], [f64; 2])],
    sigma: f64,
    decay: f64,
    g: usize,
    w: usize,
    h: usize,
) -> (Vec<[f32; 2]>, usize, usize) {
    let gw = (w - 1) / g + 2;
    let gh = (h - 1) / g + 2;
    let inv = 1.0 / (2.0 * sigma * sigma);
    let w0 = (-decay * decay / 2.0).exp();
    let cut = (decay + 2.0) * sigma;
    let cut2 = cut * cut;
    let f: Vec<[f32; 2]> = (0..gw * gh)
        .into_par_iter()
        .map(|idx| {
            let (x, y) = (((idx % gw) * g) as f64, ((idx / gw) * g) as f64);
            let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
            for (t, u) in controls {
                let d2 = (x - t[0]).powi(2) + (y - t[1]).powi(2);
                if d2 > cut2 {
                    continue;
                }
                let wt = (-d2 * inv).exp();
                sx += wt * u[0];
                sy += wt * u[1];
                sw += wt;
            }
            let den = sw + w0;
            [(sx / den) as f32, (sy / den) as f32]
        })
        .collect();
    (f, gw, gh)
}

/// Bilinear sample of a grid of step `g` (`gw` columns) at pixel `(x, y)`.
#[inline]
pub(super) fn grid_at<T: Copy>(
    f: &[T],
    gw: usize,
    g: f32,
    x: usize,
    y: usize,
    lerp: impl Fn(T, T, T, T, f32, f32) -> T,
) -> T {
    let (gx, gy) = (x as f32 / g, y as f32 / g);
    let (x0, y0) = (gx.floor() as usize, gy.floor() as usize);
    let (tx, ty) = (gx - x0 as f32, gy - y0 as f32);
    lerp(
        f[y0 * gw + x0],
        f[y0 * gw + x0 + 1],
        f[(y0 + 1) * gw + x0],
        f[(y0 + 1) * gw + x0 + 1],
        tx,
        ty,
    )
}

pub(super) fn lerp1(a: f32, b: f32, c: f32, d: f32, tx: f32, ty: f32) -> f32 {
    (1.0 - ty) * ((1.0 - tx) * a + tx * b) + ty * ((1.0 - tx) * c + tx * d)
}

pub(super) fn lerp2(
    a: [f32; 2],
    b: [f32; 2],
    c: [f32; 2],
    d: [f32; 2],
    tx: f32,
    ty: f32,
) -> [f32; 2] {
    [
        lerp1(a[0], b[0], c[0], d[0], tx, ty),
        lerp1(a[1], b[1], c[1], d[1], tx, ty),
    ]
}

/// Bilinear sample of RGB `src` at `(sx, sy)` (clamped to the frame).
#[inline]
pub(super) fn sample(src: &[u8], w: usize, h: usize, sx: f32, sy: f32, out: &mut [f32; 3]) {
    let sx = sx.clamp(0.0, (w - 1) as f32);
    let sy = sy.clamp(0.0, (h - 1) as f32);
    let (ix, iy) = (sx.floor() as usize, sy.floor() as usize);
    let (fx, fy) = (sx - ix as f32, sy - iy as f32);
    let (ix1, iy1) = ((ix + 1).min(w - 1), (iy + 1).min(h - 1));
    for (ch, o) in out.iter_mut().enumerate() {
        let p = |xx: usize, yy: usize| src[(yy * w + xx) * 3 + ch] as f32;
        *o = (1.0 - fy) * ((1.0 - fx) * p(ix, iy) + fx * p(ix1, iy))
            + fy * ((1.0 - fx) * p(ix, iy1) + fx * p(ix1, iy1));
    }
}

/// The two backward displacement fields and the three body masks of one
/// in-between frame, on the grid of step [`InterpParams::grid`].
pub(super) struct Fields {
    pub(super) fa: Vec<[f32; 2]>,
    pub(super) fb: Vec<[f32; 2]>,
    pub(super) mt: Vec<f32>,
    pub(super) ma: Vec<f32>,
    pub(super) mb: Vec<f32>,
    /// Columns of the grid.
    pub(super) gw: usize,
    /// Grid step in pixels.
    pub(super) gf: f32,
}

pub(super) fn fields(c: &Controls, params: &InterpParams, width: usize, height: usize) -> Fields {
    let g = params.grid;
    let d = params.decay_sigmas;
    let cells = ((width - 1) / g + 2) * ((height - 1) / g + 2);
    let warp_field = |pts: &[([f64; 2], [f64; 2])], bones: &[(Segment, Segment)]| match params.warp
    {
        Warp::Field if !pts.is_empty() => field(pts, c.sigma, d, g, width, height).0,
        Warp::Bones if !bones.is_empty() => bone_field(bones, 0.5 * c.radius, g, width, height),
        _ => vec![[0.0f32; 2]; cells],
    };
    Fields {
        fa: warp_field(&c.a, &c.bone_a),
        fb: warp_field(&c.b, &c.bone_b),
        mt: body_mask(&c.seg_t, c.radius, g, width, height),
        ma: body_mask(&c.seg_a, c.radius, g, width, height),
        mb: body_mask(&c.seg_b, c.radius, g, width, height),
        gw: (width - 1) / g + 2,
        gf: g as f32,
    }
}

impl Fields {
    /// The pixel `(x, y)` of the in-between frame as each of the two frames
    /// warped shows it (`pa` from `a`, `pb` from `b`).
    pub(super) fn sample_both(
        &self,
        frames: &Frames<'_>,
        x: usize,
        y: usize,
        pa: &mut [f32; 3],
        pb: &mut [f32; 3],
    ) {
        let (width, height) = frames.size;
        let ua = grid_at(&self.fa, self.gw, self.gf, x, y, lerp2);
        let ub = grid_at(&self.fb, self.gw, self.gf, x, y, lerp2);
        let (xf, yf) = (x as f32, y as f32);
        sample(frames.a, width, height, xf + ua[0], yf + ua[1], pa);
        sample(frames.b, width, height, xf + ub[0], yf + ub[1], pb);
    }
}

/// The frame between `a` (frame `i`) and `b` (frame `i + 1`) at `i + w`.
///
/// Inside the body at the target pose, both frames warped towards it and
/// blended; elsewhere the background: each frame's own pixels, weighted by
/// time and left out where that frame shows the person.
pub(super) fn between(
    guide: Option<&Guide>,
    frames: &Frames<'_>,
    i: usize,
    w: f64,
    params: &InterpParams,
    support: Option<&[bool]>,
) -> Result<Vec<u8>> {
    let (a, b) = (frames.a, frames.b);
    let (width, height) = frames.size;
    let ctl = match guide {
        Some(g) => g.controls(i, w, params, support)?,
        None => None,
    };
    let Some(c) = ctl else {
        return Ok(blend(a, b, w as f32));
    };
    let f = fields(&c, params, width, height);
    let (mt, ma, mb, gw, gf) = (&f.mt, &f.ma, &f.mb, f.gw, f.gf);
    // Weights of the two warped frames inside the body.
    let (pwa, pwb) = {
        let p = params.blend_power;
        let (x, y) = ((1.0 - w).powf(p), w.powf(p));
        ((x / (x + y)) as f32, (y / (x + y)) as f32)
    };
    let wf = w as f32;
    let ww = params.warp_weight as f32;
    let tau = params.agree_tau as f32;
    let mut out = vec![0u8; a.len()];
    out.par_chunks_mut(width * 3)
        .enumerate()
        .for_each(|(y, row)| {
            let (mut pa, mut pb) = ([0.0f32; 3], [0.0f32; 3]);
            for x in 0..width {
                let m_t = grid_at(mt, gw, gf, x, y, lerp1);
                let m_a = grid_at(ma, gw, gf, x, y, lerp1);
                let m_b = grid_at(mb, gw, gf, x, y, lerp1);
                // Background: each frame where it does not show the person.
                let mut ba = (1.0 - wf) * (1.0 - m_a);
                let mut bb = wf * (1.0 - m_b);
                if ba + bb < 1e-3 {
                    ba = 1.0 - wf;
                    bb = wf;
                }
                let (ba, bb) = (ba / (ba + bb), bb / (ba + bb));
                let p = (y * width + x) * 3;
                let mut bg = [0.0f32; 3];
                for ch in 0..3 {
                    bg[ch] = ba * a[p + ch] as f32 + bb * b[p + ch] as f32;
                }
                if m_t > 0.0 {
                    f.sample_both(frames, x, y, &mut pa, &mut pb);
                    let ww = if tau > 0.0 {
                        let dd =
                            ((pa[0] - pb[0]).abs() + (pa[1] - pb[1]).abs() + (pa[2] - pb[2]).abs())
                                / 3.0
                                / tau;
                        ww * (-dd * dd).exp()
                    } else {
                        ww
                    };
                    for ch in 0..3 {
                        let lin = (1.0 - wf) * a[p + ch] as f32 + wf * b[p + ch] as f32;
                        let person = ww * (pwa * pa[ch] + pwb * pb[ch]) + (1.0 - ww) * lin;
                        bg[ch] = m_t * person + (1.0 - m_t) * bg[ch];
                    }
                }
                for ch in 0..3 {
                    row[x * 3 + ch] = bg[ch].round().clamp(0.0, 255.0) as u8;
                }
            }
        });
    Ok(out)
}
