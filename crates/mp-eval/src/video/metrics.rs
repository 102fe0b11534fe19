//! Image quality: PSNR and SSIM of RGB frames, on the whole frame or a box.
//!
//! * PSNR: `10·log10(255² / MSE)` over the RGB bytes; identical frames give
//!   [`PSNR_CAP_DB`].
//! * SSIM (Wang et al. 2004): on luma (BT.601), Gaussian window σ = 1.5
//!   truncated at 11 × 11, `C1 = (0.01·255)²`, `C2 = (0.03·255)²`, the mean
//!   of the SSIM map over the pixels.

use mp_geom::Track;

use mp_video::VideoError;

/// PSNR reported for identical frames (no error at all).
pub const PSNR_CAP_DB: f64 = 100.0;

/// A pixel rectangle `[x0, x1) × [y0, y1)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelBox {
    /// Left.
    pub x0: usize,
    /// Top.
    pub y0: usize,
    /// Right (exclusive).
    pub x1: usize,
    /// Bottom (exclusive).
    pub y1: usize,
}

impl PixelBox {
    /// The whole frame.
    pub fn full(width: usize, height: usize) -> Self {
        PixelBox {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// The box around the joints of frame `t` with confidence above
    /// `min_conf`, grown by `margin` (a fraction of its larger side) and
    /// clipped to the frame; `None` when fewer than two joints are seen.
    pub fn around_pose(
        track: &Track,
        t: usize,
        min_conf: f64,
        margin: f64,
        width: usize,
        height: usize,
    ) -> Option<Self> {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut n = 0;
        for j in 0..track.n_joints() {
            if !track.is_valid(t, j, min_conf) {
                continue;
            }
            let p = track.point(t, j);
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
            n += 1;
        }
        if n < 2 {
            return None;
        }
        let m = margin * (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let clip = |v: f64, max: usize| v.max(0.0).min(max as f64) as usize;
        let b = PixelBox {
            x0: clip(lo[0] - m, width),
            y0: clip(lo[1] - m, height),
            x1: clip(hi[0] + m + 1.0, width),
            y1: clip(hi[1] + m + 1.0, height),
        };
        (b.x1 > b.x0 + 1 && b.y1 > b.y0 + 1).then_some(b)
    }

    fn width(&self) -> usize {
        self.x1 - self.x0
    }

    fn height(&self) -> usize {
        self.y1 - self.y0
    }
}

fn check(a: &[u8], b: &[u8], width: usize, height: usize, r: &PixelBox) -> Result<(), VideoError> {
    if a.len() != width * height * 3 || b.len() != a.len() {
        return Err(VideoError::param(
            "frame",
            format!(
                "frames of {} and {} bytes, {width}×{height} RGB needs {}",
                a.len(),
                b.len(),
                width * height * 3
            ),
        ));
    }
    if r.x1 > width || r.y1 > height || r.x0 >= r.x1 || r.y0 >= r.y1 {
        return Err(VideoError::param(
            "box",
            format!("{r:?} is empty or outside the {width}×{height} frame"),
        ));
    }
    Ok(())
}

/// PSNR (dB) of `a` against `b` (RGB, `width × height`) inside `r`.
pub fn psnr(
    a: &[u8],
    b: &[u8],
    width: usize,
    height: usize,
    r: &PixelBox,
) -> Result<f64, VideoError> {
    check(a, b, width, height, r)?;
    let mut se = 0.0f64;
    for y in r.y0..r.y1 {
        let row = (y * width + r.x0) * 3..(y * width + r.x1) * 3;
        se += a[row.clone()]
            .iter()
            .zip(&b[row])
            .map(|(&x, &y)| {
                let d = x as f64 - y as f64;
                d * d
            })
            .sum::<f64>();
    }
    let mse = se / (r.width() * r.height() * 3) as f64;
    if mse <= 0.0 {
        return Ok(PSNR_CAP_DB);
    }
    Ok((10.0 * (255.0f64 * 255.0 / mse).log10()).min(PSNR_CAP_DB))
}

fn luma(rgb: &[u8], width: usize, r: &PixelBox) -> Vec<f32> {
    let mut out = Vec::with_capacity(r.width() * r.height());
    for y in r.y0..r.y1 {
        for x in r.x0..r.x1 {
            let i = (y * width + x) * 3;
            out.push(0.299 * rgb[i] as f32 + 0.587 * rgb[i + 1] as f32 + 0.114 * rgb[i + 2] as f32);
        }
    }
    out
}

fn gaussian_kernel() -> Vec<f32> {
    let k: Vec<f32> = (-5i32..=5)
        .map(|i| (-(i * i) as f32 / (2.0 * 1.5 * 1.5)).exp())
        .collect();
    let s: f32 = k.iter().sum();
    k.into_iter().map(|v| v / s).collect()
}

/// Separable Gaussian filter with clamped borders.
fn blur(src: &[f32], w: usize, h: usize, k: &[f32]) -> Vec<f32> {
    let r = (k.len() / 2) as isize;
    let mut tmp = vec![0.0f32; src.len()];
    for y in 0..h {
        for x in 0..w {
            let mut s = 0.0;
            for (i, kv) in k.iter().enumerate() {
                let xx = (x as isize + i as isize - r).clamp(0, w as isize - 1) as usize;
                s += kv * src[y * w + xx];
            }
            tmp[y * w + x] = s;
        }
    }
    let mut out = vec![0.0f32; src.len()];
    for y in 0..h {
        for x in 0..w {
            let mut s = 0.0;
            for (i, kv) in k.iter().enumerate() {
                let yy = (y as isize + i as isize - r).clamp(0, h as isize - 1) as usize;
                s += kv * tmp[yy * w + x];
            }
            out[y * w + x] = s;
        }
    }
    out
}

/// SSIM of `a` against `b` (RGB, `width × height`) inside `r`, on luma.
pub fn ssim(
    a: &[u8],
    b: &[u8],
    width: usize,
    height: usize,
    r: &PixelBox,
) -> Result<f64, VideoError> {
    check(a, b, width, height, r)?;
    let (w, h) = (r.width(), r.height());
    let x = luma(a, width, r);
    let y = luma(b, width, r);
    let k = gaussian_kernel();
    let xx: Vec<f32> = x.iter().map(|v| v * v).collect();
    let yy: Vec<f32> = y.iter().map(|v| v * v).collect();
    let xy: Vec<f32> = x.iter().zip(&y).map(|(p, q)| p * q).collect();
    let (mx, my) = (blur(&x, w, h, &k), blur(&y, w, h, &k));
    let (sxx, syy, sxy) = (
        blur(&xx, w, h, &k),
        blur(&yy, w, h, &k),
        blur(&xy, w, h, &k),
    );
    let (c1, c2) = ((0.01f64 * 255.0).powi(2), (0.03f64 * 255.0).powi(2));
    let mut total = 0.0f64;
    for i in 0..w * h {
        let (mx, my) = (mx[i] as f64, my[i] as f64);
        let vx = (sxx[i] as f64 - mx * mx).max(0.0);
        let vy = (syy[i] as f64 - my * my).max(0.0);
        let cxy = sxy[i] as f64 - mx * my;
        total +=
            ((2.0 * mx * my + c1) * (2.0 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
    }
    Ok(total / (w * h) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noise(w: usize, h: usize, seed: u32) -> Vec<u8> {
        let mut s = seed;
        (0..w * h * 3)
            .map(|_| {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (s >> 24) as u8
            })
            .collect()
    }

    #[test]
    fn identical_frames_are_perfect() {
        let a = noise(20, 16, 1);
        let r = PixelBox::full(20, 16);
        assert_eq!(psnr(&a, &a, 20, 16, &r).unwrap(), PSNR_CAP_DB);
        assert!((ssim(&a, &a, 20, 16, &r).unwrap() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn psnr_of_a_constant_offset() {
        let a = vec![100u8; 8 * 8 * 3];
        let b = vec![110u8; 8 * 8 * 3];
        let r = PixelBox::full(8, 8);
        let expect = 10.0 * (255.0f64 * 255.0 / 100.0).log10();
        assert!((psnr(&a, &b, 8, 8, &r).unwrap() - expect).abs() < 1e-9);
    }

    #[test]
    fn ssim_drops_with_noise_and_boxes_are_checked() {
        let a = noise(32, 32, 1);
        let b = noise(32, 32, 2);
        let r = PixelBox::full(32, 32);
        assert!(ssim(&a, &b, 32, 32, &r).unwrap() < 0.2);
        let outside = PixelBox {
            x0: 0,
            y0: 0,
            x1: 40,
            y1: 10,
        };
        assert!(psnr(&a, &b, 32, 32, &outside).is_err());
    }
}
