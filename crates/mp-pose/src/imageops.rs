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
    if src.width == 0
        || src.height == 0
        || src.data.len() < src.width * src.height * 3
        || out.is_empty()
    {
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
    let source = Source {
        data: src.data,
        w: src.width as i64,
        h: src.height as i64,
        stride: src.width * 3,
        border,
    };
    let lim = (1u64 << 30) as f64;
    // Each row's source points in fixed point (1/32 pixel), computed for the
    // whole row first where they fit in 32 bits (the same values as
    // `round_fixed`, without a branch per pixel), then blended.
    let (mut xs, mut ys) = (vec![0i32; out_w], vec![0i32; out_w]);
    for (i, row) in out.chunks_exact_mut(out_w * 3).enumerate() {
        let fi = i as f64;
        let row_x = x0 + b * fi;
        let row_y = y0 + e * fi;
        if fixed_row(row_x, a, &mut xs) && fixed_row(row_y, d, &mut ys) {
            #[cfg(target_arch = "x86_64")]
            {
                if mp_geom::has_avx2() {
                    // SAFETY: the CPU has AVX2 (checked just above), the only
                    // requirement of a `target_feature(enable = "avx2")` function.
                    unsafe { source.blend_row_avx2(&xs, &ys, row) };
                    continue;
                }
            }
            for ((&xq, &yq), dst) in xs.iter().zip(&ys).zip(row.chunks_exact_mut(3)) {
                source.blend(i64::from(xq), i64::from(yq), dst);
            }
        } else {
            for (j, dst) in row.chunks_exact_mut(3).enumerate() {
                let fj = j as f64;
                let sx = (row_x + a * fj).clamp(-lim, lim);
                let sy = (row_y + d * fj).clamp(-lim, lim);
                let xq = round_fixed(sx * INTER_TAB as f64);
                let yq = round_fixed(sy * INTER_TAB as f64);
                source.blend(xq, yq, dst);
            }
        }
    }
}

/// The image a crop reads: its pixels, size and what lies outside.
struct Source<'a> {
    data: &'a [u8],
    w: i64,
    h: i64,
    stride: usize,
    border: Border,
}

/// Half of the weights' sum (1,024), for rounding.
const ROUND: i64 = 1 << (2 * INTER_BITS - 1);

impl Source<'_> {
    /// Byte offset of pixel `(xi, yi)`, or `None` for black outside.
    #[inline(always)]
    fn pixel(&self, xi: i64, yi: i64) -> Option<usize> {
        match self.border {
            Border::Replicate => {
                let xc = xi.clamp(0, self.w - 1) as usize;
                let yc = yi.clamp(0, self.h - 1) as usize;
                Some(yc * self.stride + xc * 3)
            }
            Border::Zero => {
                if xi < 0 || yi < 0 || xi >= self.w || yi >= self.h {
                    None
                } else {
                    Some(yi as usize * self.stride + xi as usize * 3)
                }
            }
        }
    }

    /// The bilinear value at fixed-point source point `(xq, yq)` (1/32
    /// pixel) into `dst` (3 bytes).
    #[inline(always)]
    fn blend(&self, xq: i64, yq: i64, dst: &mut [u8]) {
        let (xi, yi) = (xq >> INTER_BITS, yq >> INTER_BITS);
        let (fx, fy) = (xq & (INTER_TAB - 1), yq & (INTER_TAB - 1));
        let w00 = (INTER_TAB - fx) * (INTER_TAB - fy);
        let w01 = fx * (INTER_TAB - fy);
        let w10 = (INTER_TAB - fx) * fy;
        let w11 = fx * fy;
        if xi >= 0 && yi >= 0 && xi + 1 < self.w && yi + 1 < self.h {
            // All four neighbours inside: the two pixels of each row as
            // one slice (two bounds checks, not twelve), in 32 bits
            // (the weights sum to 1,024: at most 261,120 a channel).
            let (data, stride) = (self.data, self.stride);
            let k00 = yi as usize * stride + xi as usize * 3;
            let (top, bottom) = (&data[k00..k00 + 6], &data[k00 + stride..k00 + stride + 6]);
            let (w00, w01, w10, w11) = (w00 as i32, w01 as i32, w10 as i32, w11 as i32);
            for ch in 0..3 {
                let acc = w00 * i32::from(top[ch])
                    + w01 * i32::from(top[3 + ch])
                    + w10 * i32::from(bottom[ch])
                    + w11 * i32::from(bottom[3 + ch]);
                dst[ch] = ((acc + ROUND as i32) >> (2 * INTER_BITS)) as u8;
            }
            return;
        }
        let p00 = self.pixel(xi, yi);
        let p01 = self.pixel(xi + 1, yi);
        let p10 = self.pixel(xi, yi + 1);
        let p11 = self.pixel(xi + 1, yi + 1);
        for (ch, d) in dst.iter_mut().enumerate() {
            let g = |p: Option<usize>| p.map_or(0, |k| self.data[k + ch] as i64);
            let acc = w00 * g(p00) + w01 * g(p01) + w10 * g(p10) + w11 * g(p11);
            *d = ((acc + ROUND) >> (2 * INTER_BITS)).clamp(0, 255) as u8;
        }
    }

    /// [`Source::blend`] for a row of fixed-point points, a pixel whose four
    /// neighbours lie inside in one SSE multiply-add per row of neighbours:
    /// each row's two pixels loaded together (8 bytes), their channels
    /// paired (`r0 r1 g0 g1 b0 b1` as 16-bit values) and weighted by
    /// `pmaddwd` — the same integer sums as the scalar code.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn blend_row_avx2(&self, xs: &[i32], ys: &[i32], row: &mut [u8]) {
        use std::arch::x86_64::*;
        let (data, stride) = (self.data, self.stride);
        // Channel c of the left pixel and of the right one side by side,
        // zero-extended to 16 bits; the last two pairs zero.
        let pairs = _mm_setr_epi8(0, -1, 3, -1, 1, -1, 4, -1, 2, -1, 5, -1, -1, -1, -1, -1);
        let round = _mm_set1_epi32(ROUND as i32);
        for ((&xq, &yq), dst) in xs.iter().zip(ys).zip(row.chunks_exact_mut(3)) {
            let (xi, yi) = (xq >> INTER_BITS, yq >> INTER_BITS);
            let inside =
                xi >= 0 && yi >= 0 && i64::from(xi) + 1 < self.w && i64::from(yi) + 1 < self.h;
            let k00 = if inside {
                yi as usize * stride + xi as usize * 3
            } else {
                usize::MAX
            };
            // Eight bytes from each row (the two pixels and two more): the
            // last pixels of the image go the scalar way.
            if !inside || k00 + stride + 8 > data.len() {
                self.blend(i64::from(xq), i64::from(yq), dst);
                continue;
            }
            let (fx, fy) = (xq & (INTER_TAB as i32 - 1), yq & (INTER_TAB as i32 - 1));
            let t = INTER_TAB as i32;
            let (w00, w01) = ((t - fx) * (t - fy), fx * (t - fy));
            let (w10, w11) = ((t - fx) * fy, fx * fy);
            let top: [u8; 8] = data[k00..k00 + 8].try_into().unwrap_or_default();
            let bottom: [u8; 8] = data[k00 + stride..k00 + stride + 8]
                .try_into()
                .unwrap_or_default();
            let top = _mm_shuffle_epi8(_mm_set_epi64x(0, i64::from_le_bytes(top)), pairs);
            let bottom = _mm_shuffle_epi8(_mm_set_epi64x(0, i64::from_le_bytes(bottom)), pairs);
            let acc = _mm_add_epi32(
                _mm_madd_epi16(top, _mm_set1_epi32(w00 | (w01 << 16))),
                _mm_madd_epi16(bottom, _mm_set1_epi32(w10 | (w11 << 16))),
            );
            let v = _mm_srai_epi32::<{ 2 * INTER_BITS as i32 }>(_mm_add_epi32(acc, round));
            let v16 = _mm_packs_epi32(v, v);
            let bytes = _mm_cvtsi128_si32(_mm_packus_epi16(v16, v16)).to_le_bytes();
            dst.copy_from_slice(&bytes[..3]);
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
    // `j` through 32 bits (a row is far shorter), which converts on lanes;
    // the same values as `j as f64`.
    for (j, o) in (0i32..).zip(out.iter_mut()) {
        let v = (start + step * f64::from(j)).clamp(-lim, lim) * INTER_TAB as f64;
        let t = v + 0.5 + SHIFT;
        let i = t.trunc();
        let half = i * 0.5;
        let tie_to_odd = i == t && half != half.trunc();
        let q = i - SHIFT - if tie_to_odd { 1.0 } else { 0.0 };
        // SAFETY: `q` is an integer within ±2³⁰ + 1: the caller checked that
        // every coordinate lies within ±2²⁵ pixels (`fixed_row`).
        *o = unsafe { q.to_int_unchecked::<i32>() };
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

    /// A row blended on several lanes gives the bytes of the pixel-by-pixel
    /// blend: points inside, on the last row and column, and outside (both
    /// borders).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn a_row_blended_on_lanes_is_the_scalar_row() {
        if !mp_geom::has_avx2() {
            return;
        }
        let (w, h) = (37usize, 23usize);
        let data: Vec<u8> = (0..w * h * 3)
            .map(|i| ((i * 131 + i / 7) % 256) as u8)
            .collect();
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: i32| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % n as u64) as i32
        };
        let span = 32 * (w as i32 + 4);
        let xs: Vec<i32> = (0..500).map(|_| next(span) - 64).collect();
        let ys: Vec<i32> = (0..500).map(|_| next(32 * (h as i32 + 4)) - 64).collect();
        for border in [Border::Zero, Border::Replicate] {
            let source = Source {
                data: &data,
                w: w as i64,
                h: h as i64,
                stride: w * 3,
                border,
            };
            let mut lanes = vec![0u8; 500 * 3];
            // SAFETY: the CPU has AVX2 (checked above).
            unsafe { source.blend_row_avx2(&xs, &ys, &mut lanes) };
            let mut scalar = vec![0u8; 500 * 3];
            for ((&x, &y), dst) in xs.iter().zip(&ys).zip(scalar.chunks_exact_mut(3)) {
                source.blend(i64::from(x), i64::from(y), dst);
            }
            assert_eq!(lanes, scalar, "{border:?}");
        }
    }

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
        // An empty output size gives an empty image.
        let view = RgbView {
            width: 10,
            height: 6,
            data: &img,
        };
        assert!(resize_rgb(view, 0, 3).is_empty());
        assert!(resize_rgb(view, 4, 0).is_empty());
    }
}
