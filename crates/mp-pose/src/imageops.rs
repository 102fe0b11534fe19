//! Image operations of the pipelines: rotated-rectangle crops (affine warp,
//! bilinear, border replicate or zero) and letterboxing.
//!
//! Sampling follows the convention of OpenCV's `warpPerspective` on 8-bit
//! images, which is what MediaPipe's CPU image-to-tensor step uses: pixel
//! centres sit at integer coordinates, the rectangle's corners map to the
//! output's outer corners (output pixel `j` samples the rectangle at
//! `u = j / out_width`), source coordinates are rounded to 1/32 pixel, and the
//! bilinear blend is done in integers and rounded back to 8 bits.

/// A borrowed RGB image (row-major, 3 bytes per pixel).
#[derive(Debug, Clone, Copy)]
pub struct RgbView<'a> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `height × width × 3` bytes.
    pub data: &'a [u8],
}

/// A rotated rectangle in image pixels: the region a crop is taken from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Roi {
    /// Centre, x (pixels).
    pub center_x_px: f64,
    /// Centre, y (pixels).
    pub center_y_px: f64,
    /// Width before rotation (pixels).
    pub width_px: f64,
    /// Height before rotation (pixels).
    pub height_px: f64,
    /// Rotation in radians (image coordinates, y down: positive turns x towards y).
    pub rotation_rad: f64,
}

impl Roi {
    /// The square around a whole `width × height` frame (the longer side),
    /// centred: the letterbox region.
    pub fn letterbox(width: usize, height: usize) -> Roi {
        let s = width.max(height) as f64;
        Roi {
            center_x_px: width as f64 / 2.0,
            center_y_px: height as f64 / 2.0,
            width_px: s,
            height_px: s,
            rotation_rad: 0.0,
        }
    }

    /// Image point of the rectangle's normalised coordinates `(u, v)`
    /// (`(0, 0)` = top-left corner before rotation, `(1, 1)` = bottom-right).
    pub fn to_image(&self, u: f64, v: f64) -> (f64, f64) {
        let (s, c) = self.rotation_rad.sin_cos();
        let dx = (u - 0.5) * self.width_px;
        let dy = (v - 0.5) * self.height_px;
        (
            self.center_x_px + c * dx - s * dy,
            self.center_y_px + s * dx + c * dy,
        )
    }

    /// Whether all values are finite and the size is positive.
    pub fn is_valid(&self) -> bool {
        [
            self.center_x_px,
            self.center_y_px,
            self.width_px,
            self.height_px,
            self.rotation_rad,
        ]
        .iter()
        .all(|v| v.is_finite())
            && self.width_px > 0.0
            && self.height_px > 0.0
    }
}

/// What a crop reads outside the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub(crate) enum Border {
    /// The nearest edge pixel.
    Replicate,
    /// Black.
    Zero,
}

const INTER_BITS: i64 = 5;
const INTER_TAB: i64 = 1 << INTER_BITS;

/// Rounds to the nearest integer, ties to even (as OpenCV's `cvRound`), for
/// |v| < 2^40. A float-to-int cast of a positive value truncates, so the value
/// is shifted into the positive range first: this avoids a library call per
/// pixel on targets without SSE4.1.
#[inline(always)]
fn round_fixed(v: f64) -> i64 {
    const SHIFT: i64 = 1 << 40;
    let t = v + 0.5 + SHIFT as f64;
    let mut i = t as i64;
    if i as f64 == t && i & 1 == 1 {
        // Exactly halfway: round to the even neighbour.
        i -= 1;
    }
    i - SHIFT
}

/// Crops the rotated rectangle `roi` of `src` into an `out_w × out_h` RGB
/// image (written to `out`, resized as needed).
pub(crate) fn crop_u8(
    src: RgbView<'_>,
    roi: &Roi,
    out_w: usize,
    out_h: usize,
    border: Border,
    out: &mut Vec<u8>,
) {
    out.clear();
    out.resize(out_w * out_h * 3, 0);
    if src.width == 0 || src.height == 0 || src.data.len() < src.width * src.height * 3 {
        return;
    }
    // Affine map output pixel (j, i) -> source point.
    let (s, c) = roi.rotation_rad.sin_cos();
    let sx_u = roi.width_px / out_w as f64; // source step per output column, along the rectangle's x axis
    let sy_v = roi.height_px / out_h as f64;
    let a = c * sx_u; // d src_x / d j
    let b = -s * sy_v; // d src_x / d i
    let d = s * sx_u; // d src_y / d j
    let e = c * sy_v; // d src_y / d i
    let (x0, y0) = roi.to_image(0.0, 0.0);
    let (w, h) = (src.width as i64, src.height as i64);
    let data = src.data;
    let stride = src.width * 3;
    let pixel = |xi: i64, yi: i64| -> Option<usize> {
        match border {
            Border::Replicate => {
                let xc = xi.clamp(0, w - 1) as usize;
                let yc = yi.clamp(0, h - 1) as usize;
                Some(yc * stride + xc * 3)
            }
            Border::Zero => {
                if xi < 0 || yi < 0 || xi >= w || yi >= h {
                    None
                } else {
                    Some(yi as usize * stride + xi as usize * 3)
                }
            }
        }
    };
    let lim = (1u64 << 30) as f64;
    // Each row's source points in fixed point (1/32 pixel), computed for the
    // whole row first where they fit in 32 bits (the same values as
    // `round_fixed`, without a branch per pixel), then blended.
    let (mut xs, mut ys) = (vec![0i32; out_w], vec![0i32; out_w]);
    for i in 0..out_h {
        let fi = i as f64;
        let row_x = x0 + b * fi;
        let row_y = y0 + e * fi;
        let fixed = fixed_row(row_x, a, &mut xs) && fixed_row(row_y, d, &mut ys);
        for j in 0..out_w {
            let (xq, yq) = if fixed {
                (i64::from(xs[j]), i64::from(ys[j]))
            } else {
                let fj = j as f64;
                let sx = (row_x + a * fj).clamp(-lim, lim);
                let sy = (row_y + d * fj).clamp(-lim, lim);
                (
                    round_fixed(sx * INTER_TAB as f64),
                    round_fixed(sy * INTER_TAB as f64),
                )
            };
            let xi = xq >> INTER_BITS;
            let yi = yq >> INTER_BITS;
            let fx = xq & (INTER_TAB - 1);
            let fy = yq & (INTER_TAB - 1);
            let w00 = (INTER_TAB - fx) * (INTER_TAB - fy);
            let w01 = fx * (INTER_TAB - fy);
            let w10 = (INTER_TAB - fx) * fy;
            let w11 = fx * fy;
            let o = (i * out_w + j) * 3;
            const ROUND: i64 = 1 << (2 * INTER_BITS - 1);
            if xi >= 0 && yi >= 0 && xi + 1 < w && yi + 1 < h {
                // All four neighbours inside: the two pixels of each row as
                // one slice (two bounds checks, not twelve), in 32 bits
                // (the weights sum to 1,024: at most 261,120 a channel).
                let k00 = yi as usize * stride + xi as usize * 3;
                let (top, bottom) = (&data[k00..k00 + 6], &data[k00 + stride..k00 + stride + 6]);
                let (w00, w01, w10, w11) = (w00 as i32, w01 as i32, w10 as i32, w11 as i32);
                let dst = &mut out[o..o + 3];
                for ch in 0..3 {
                    let acc = w00 * i32::from(top[ch])
                        + w01 * i32::from(top[3 + ch])
                        + w10 * i32::from(bottom[ch])
                        + w11 * i32::from(bottom[3 + ch]);
                    dst[ch] = ((acc + ROUND as i32) >> (2 * INTER_BITS)) as u8;
                }
                continue;
            }
            let p00 = pixel(xi, yi);
            let p01 = pixel(xi + 1, yi);
            let p10 = pixel(xi, yi + 1);
            let p11 = pixel(xi + 1, yi + 1);
            for ch in 0..3 {
                let g = |p: Option<usize>| p.map_or(0, |k| data[k + ch] as i64);
                let acc = w00 * g(p00) + w01 * g(p01) + w10 * g(p10) + w11 * g(p11);
                out[o + ch] = ((acc + ROUND) >> (2 * INTER_BITS)).clamp(0, 255) as u8;
            }
        }
    }
}

/// Source coordinates of a row of output pixels, `start + step · j` for
/// each `j`, in fixed point (`round_fixed(v · 32)`) into `out`; false (and
/// `out` unspecified) when a coordinate lies beyond ±2²⁵ pixels, where the
/// fixed-point value might not fit in 32 bits (the caller then computes
/// them one by one).
fn fixed_row(start: f64, step: f64, out: &mut [i32]) -> bool {
    const FAR: f64 = (1u64 << 25) as f64;
    let last = out.len().saturating_sub(1) as f64;
    // Affine in `j`: the ends bound every value.
    let ends = [start, start + step * last];
    if !ends.iter().all(|v| v.is_finite() && v.abs() < FAR) {
        return false;
    }
    #[cfg(target_arch = "x86_64")]
    {
        if mp_geom::has_avx2() {
            // SAFETY: the CPU has AVX2 (checked just above), the only
            // requirement of a `target_feature(enable = "avx2")` function.
            unsafe { fixed_row_avx2(start, step, out) };
            return true;
        }
    }
    fixed_row_body(start, step, out);
    true
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn fixed_row_avx2(start: f64, step: f64, out: &mut [i32]) {
    fixed_row_body(start, step, out)
}

/// [`round_fixed`] of `(start + step · j) · 32` for every `j`, as branch-free
/// arithmetic the compiler can run on several lanes: the truncation, the
/// test for an exact half and the parity all in `f64` (every value an
/// integer below 2⁴¹, so exact), then the conversion of a value known to
/// fit in 32 bits.
#[inline(always)]
fn fixed_row_body(start: f64, step: f64, out: &mut [i32]) {
    const SHIFT: f64 = (1u64 << 40) as f64;
    let lim = (1u64 << 30) as f64;
    for (j, o) in out.iter_mut().enumerate() {
        let v = (start + step * j as f64).clamp(-lim, lim) * INTER_TAB as f64;
        let t = v + 0.5 + SHIFT;
        let i = t.trunc();
        let half = i * 0.5;
        let tie_to_odd = i == t && half != half.trunc();
        let q = i - SHIFT - if tie_to_odd { 1.0 } else { 0.0 };
        *o = q as i32;
    }
}

/// Converts 8-bit values to `f32` as `v · scale + offset`.
pub fn to_f32(src: &[u8], scale: f32, offset: f32, out: &mut Vec<f32>) {
    out.clear();
    extend_f32(src, scale, offset, out);
}

/// [`to_f32`] appending to `out` (several images laid end to end).
pub(crate) fn extend_f32(src: &[u8], scale: f32, offset: f32, out: &mut Vec<f32>) {
    out.extend(src.iter().map(|&v| v as f32 * scale + offset));
}

/// Scales an RGB image to `out_w × out_h` (bilinear).
pub fn resize_rgb(src: RgbView<'_>, out_w: usize, out_h: usize) -> Vec<u8> {
    let roi = Roi {
        center_x_px: src.width as f64 / 2.0 - 0.5 + 0.5 * src.width as f64 / out_w as f64,
        center_y_px: src.height as f64 / 2.0 - 0.5 + 0.5 * src.height as f64 / out_h as f64,
        width_px: src.width as f64,
        height_px: src.height as f64,
        rotation_rad: 0.0,
    };
    let mut out = Vec::new();
    crop_u8(src, &roi, out_w, out_h, Border::Replicate, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row's fixed-point coordinates are `round_fixed`'s, ties (exact
    /// halves of 1/32 pixel) and negative points included; far points are
    /// left to the pixel-by-pixel path.
    #[test]
    fn fixed_rows_round_as_round_fixed() {
        let mut out = vec![0i32; 257];
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut cases = vec![
            (2.5 / 32.0, 1.0 / 32.0),
            (-3.0 / 64.0, 0.5 / 32.0),
            (-700.0, 1.0),
        ];
        for _ in 0..2000 {
            cases.push(((next() - 0.5) * 2000.0, (next() - 0.5) * 4.0));
        }
        for (start, step) in cases {
            assert!(fixed_row(start, step, &mut out));
            for (j, &q) in out.iter().enumerate() {
                let lim = (1u64 << 30) as f64;
                let v = (start + step * j as f64).clamp(-lim, lim);
                assert_eq!(
                    i64::from(q),
                    round_fixed(v * INTER_TAB as f64),
                    "{start} + {step} · {j}"
                );
            }
        }
        assert!(!fixed_row(1e9, 1.0, &mut out));
        assert!(!fixed_row(0.0, f64::NAN, &mut out));
    }

    fn gradient(w: usize, h: usize) -> Vec<u8> {
        let mut v = vec![0u8; w * h * 3];
        for y in 0..h {
            for x in 0..w {
                let o = (y * w + x) * 3;
                v[o] = (x * 10) as u8;
                v[o + 1] = (y * 10) as u8;
                v[o + 2] = 7;
            }
        }
        v
    }

    #[test]
    fn identity_crop_reproduces_the_image() {
        // A ROI whose corners are the image's outer corners maps output
        // pixel j onto source pixel j exactly (u = j / w).
        let (w, h) = (8, 6);
        let img = gradient(w, h);
        let roi = Roi {
            center_x_px: w as f64 / 2.0,
            center_y_px: h as f64 / 2.0,
            width_px: w as f64,
            height_px: h as f64,
            rotation_rad: 0.0,
        };
        let mut out = Vec::new();
        let view = RgbView {
            width: w,
            height: h,
            data: &img,
        };
        crop_u8(view, &roi, w, h, Border::Zero, &mut out);
        assert_eq!(out, img);
    }

    #[test]
    fn bilinear_midpoint_and_borders() {
        let img = vec![0, 0, 0, 100, 100, 100]; // 2×1: black, grey
        let view = RgbView {
            width: 2,
            height: 1,
            data: &img,
        };
        // One output pixel sampling x = 0.5: halfway.
        let roi = Roi {
            center_x_px: 1.0,
            center_y_px: 0.5,
            width_px: 1.0,
            height_px: 1.0,
            rotation_rad: 0.0,
        };
        let mut out = Vec::new();
        crop_u8(view, &roi, 1, 1, Border::Replicate, &mut out);
        assert_eq!(out, vec![50, 50, 50]);
        // Far outside: replicate gives the edge, zero gives black.
        let far = Roi {
            center_x_px: 50.5,
            center_y_px: 0.5,
            width_px: 1.0,
            height_px: 1.0,
            rotation_rad: 0.0,
        };
        crop_u8(view, &far, 1, 1, Border::Replicate, &mut out);
        assert_eq!(out, vec![100, 100, 100]);
        crop_u8(view, &far, 1, 1, Border::Zero, &mut out);
        assert_eq!(out, vec![0, 0, 0]);
    }

    #[test]
    fn rotation_by_quarter_turn_moves_columns_to_rows() {
        let (w, h) = (5, 5);
        let img = gradient(w, h);
        let view = RgbView {
            width: w,
            height: h,
            data: &img,
        };
        let roi = Roi {
            center_x_px: 2.0,
            center_y_px: 2.0,
            width_px: 5.0,
            height_px: 5.0,
            rotation_rad: std::f64::consts::FRAC_PI_2,
        };
        let mut out = Vec::new();
        crop_u8(view, &roi, w, h, Border::Replicate, &mut out);
        // Output (j, i) samples source point centre + R(90°)·(j − 2.5, i − 2.5) = (2 − (i − 2.5), 2 + (j − 2.5)).
        // Output column j advances along the source's y axis.
        for i in 0..h {
            for j in 1..w {
                let g_prev = out[(i * w + j - 1) * 3 + 1] as i32;
                let g = out[(i * w + j) * 3 + 1] as i32;
                assert!(g >= g_prev, "green (source y) must grow along output rows");
            }
        }
    }

    #[test]
    fn rounding_is_to_nearest_with_ties_to_even() {
        for (v, want) in [
            (0.4, 0),
            (0.5, 0),
            (1.5, 2),
            (2.5, 2),
            (-0.5, 0),
            (-1.5, -2),
            (-2.6, -3),
            (7.49, 7),
        ] {
            assert_eq!(round_fixed(v), want, "{v}");
            assert_eq!(round_fixed(v), v.round_ties_even() as i64);
        }
    }

    #[test]
    fn letterbox_is_a_centred_square() {
        let r = Roi::letterbox(640, 360);
        assert_eq!((r.width_px, r.height_px), (640.0, 640.0));
        let (x, y) = r.to_image(0.0, 0.0);
        assert_eq!((x, y), (0.0, -140.0));
    }

    #[test]
    fn resize_keeps_constant_images() {
        let img = vec![77u8; 10 * 6 * 3];
        let out = resize_rgb(
            RgbView {
                width: 10,
                height: 6,
                data: &img,
            },
            5,
            3,
        );
        assert!(out.iter().all(|&v| v == 77));
    }
}
