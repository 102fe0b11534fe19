//! Planar YUV 4:2:0 frames: how H.264 stores most videos, half the bytes of
//! RGB. A video decoded to YUV and encoded again from it passes through
//! FFmpeg's pipes without a colour conversion on either side; drawing on such
//! a frame blends a premultiplied RGBA layer into its planes
//! ([`Yuv420Frame::blend_layer`]).
//!
//! The colours are ITU-R BT.601 at limited range (luma 16–235, chroma
//! 16–240), what FFmpeg converts RGB to and from by default.

use crate::error::{PoseError, Result};

/// How a frame's pixels lie in a pipe to or from FFmpeg.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelFormat {
    /// 3 bytes a pixel: R, G, B.
    Rgb24,
    /// Planar: the luma plane, then the two chroma planes (U, V) at half the
    /// width and height, rounded up ([`Yuv420Frame`]).
    Yuv420p,
}

impl PixelFormat {
    /// Bytes of one `width × height` frame.
    pub fn frame_bytes(self, width: usize, height: usize) -> usize {
        match self {
            PixelFormat::Rgb24 => width * height * 3,
            PixelFormat::Yuv420p => Yuv420Frame::bytes(width, height),
        }
    }

    /// FFmpeg's name of the format (`-pix_fmt`).
    pub fn ffmpeg_name(self) -> &'static str {
        match self {
            PixelFormat::Rgb24 => "rgb24",
            PixelFormat::Yuv420p => "yuv420p",
        }
    }

    /// The format's name in messages.
    pub(crate) fn label(self) -> &'static str {
        match self {
            PixelFormat::Rgb24 => "RGB",
            PixelFormat::Yuv420p => "YUV 4:2:0",
        }
    }
}

/// Luma of an RGB colour (0–255 each), BT.601 limited range, without the
/// offset of 16.
fn luma(r: f32, g: f32, b: f32) -> f32 {
    (65.481 * r + 128.553 * g + 24.966 * b) / 255.0
}

/// The two chroma values of an RGB colour, without the offset of 128.
fn chroma(r: f32, g: f32, b: f32) -> (f32, f32) {
    (
        (-37.797 * r - 74.203 * g + 112.0 * b) / 255.0,
        (112.0 * r - 93.786 * g - 18.214 * b) / 255.0,
    )
}

fn to_u8(v: f32) -> u8 {
    v.round().clamp(0.0, 255.0) as u8
}

/// One frame in planar YUV 4:2:0 (FFmpeg's `yuv420p`): `width × height`
/// luma bytes, then the U and the V plane, each `⌈width/2⌉ × ⌈height/2⌉`.
#[derive(Debug, Clone, PartialEq)]
pub struct Yuv420Frame {
    /// Index of the frame in the video (0-based).
    pub index: usize,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The three planes, one after the other.
    pub data: Vec<u8>,
}

impl Yuv420Frame {
    /// Size of each chroma plane: half the frame's, rounded up.
    pub fn chroma_size(width: usize, height: usize) -> (usize, usize) {
        (width.div_ceil(2), height.div_ceil(2))
    }

    /// Bytes of a `width × height` frame.
    pub fn bytes(width: usize, height: usize) -> usize {
        let (cw, ch) = Self::chroma_size(width, height);
        width * height + 2 * cw * ch
    }

    /// Builds a frame, checking that `data` holds [`Self::bytes`] bytes.
    pub fn new(index: usize, width: usize, height: usize, data: Vec<u8>) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(PoseError::BadFrame {
                frame: index,
                reason: format!("empty frame ({width}×{height})"),
            });
        }
        let need = Self::bytes(width, height);
        if data.len() != need {
            return Err(PoseError::BadFrame {
                frame: index,
                reason: format!(
                    "buffer has {} bytes, {width}×{height} YUV 4:2:0 needs {need}",
                    data.len()
                ),
            });
        }
        Ok(Yuv420Frame {
            index,
            width,
            height,
            data,
        })
    }

    /// An RGB frame (`height × width × 3` bytes) in YUV 4:2:0: each chroma
    /// value from the mean colour of the 2 × 2 pixels it covers.
    pub fn from_rgb(index: usize, width: usize, height: usize, rgb: &[u8]) -> Result<Self> {
        if rgb.len() != width * height * 3 {
            return Err(PoseError::BadFrame {
                frame: index,
                reason: format!(
                    "buffer has {} bytes, {width}×{height} RGB needs {}",
                    rgb.len(),
                    width * height * 3
                ),
            });
        }
        let mut f = Self::new(index, width, height, vec![0; Self::bytes(width, height)])?;
        let (cw, ch) = Self::chroma_size(width, height);
        let (y, uv) = f.data.split_at_mut(width * height);
        let (u, v) = uv.split_at_mut(cw * ch);
        for (dst, px) in y.iter_mut().zip(rgb.chunks_exact(3)) {
            *dst = to_u8(16.0 + luma(px[0].into(), px[1].into(), px[2].into()));
        }
        for cy in 0..ch {
            for cx in 0..cw {
                let mut sum = [0.0f32; 3];
                let mut k = 0.0f32;
                for yy in 2 * cy..(2 * cy + 2).min(height) {
                    for xx in 2 * cx..(2 * cx + 2).min(width) {
                        let p = &rgb[(yy * width + xx) * 3..][..3];
                        for c in 0..3 {
                            sum[c] += f32::from(p[c]);
                        }
                        k += 1.0;
                    }
                }
                let (cu, cv) = chroma(sum[0] / k, sum[1] / k, sum[2] / k);
                u[cy * cw + cx] = to_u8(128.0 + cu);
                v[cy * cw + cx] = to_u8(128.0 + cv);
            }
        }
        Ok(f)
    }

    /// The frame as RGB bytes (`height × width × 3`), each pixel with the
    /// chroma of its 2 × 2 block.
    pub fn to_rgb(&self) -> Vec<u8> {
        let (w, h) = (self.width, self.height);
        let (cw, ch) = Self::chroma_size(w, h);
        let (y, uv) = self.data.split_at(w * h);
        let (u, v) = uv.split_at(cw * ch);
        let mut out = Vec::with_capacity(w * h * 3);
        for yy in 0..h {
            for xx in 0..w {
                let l = 1.164_383 * (f32::from(y[yy * w + xx]) - 16.0);
                let c = (yy / 2) * cw + xx / 2;
                let (cu, cv) = (f32::from(u[c]) - 128.0, f32::from(v[c]) - 128.0);
                out.push(to_u8(l + 1.596_027 * cv));
                out.push(to_u8(l - 0.391_762 * cu - 0.812_968 * cv));
                out.push(to_u8(l + 2.017_232 * cu));
            }
        }
        out
    }

    /// Draws a layer onto the frame: `layer` is premultiplied RGBA of the
    /// frame's size (e.g. a `tiny_skia::Pixmap`'s bytes), and only its pixels
    /// inside `rect` (`[x0, y0, x1, y1)`, clipped to the frame and widened to
    /// whole 2 × 2 blocks) are read; each chroma value takes the mean of its
    /// block's colour and coverage. Those pixels of the layer are then
    /// cleared to transparent, so the layer is ready for the next frame.
    pub fn blend_layer(&mut self, layer: &mut [u8], rect: [usize; 4]) -> Result<()> {
        let (w, h) = (self.width, self.height);
        if layer.len() != w * h * 4 {
            return Err(PoseError::BadFrame {
                frame: self.index,
                reason: format!(
                    "a layer of {} bytes on a {w}×{h} frame (RGBA needs {})",
                    layer.len(),
                    w * h * 4
                ),
            });
        }
        let x0 = rect[0].min(w) & !1;
        let y0 = rect[1].min(h) & !1;
        let x1 = rect[2].min(w);
        let y1 = rect[3].min(h);
        if x1 <= x0 || y1 <= y0 {
            return Ok(());
        }
        let (cw, ch) = Self::chroma_size(w, h);
        let (yp, uv) = self.data.split_at_mut(w * h);
        let (up, vp) = uv.split_at_mut(cw * ch);
        for cy in y0 / 2..y1.div_ceil(2) {
            for cx in x0 / 2..x1.div_ceil(2) {
                // The block's coverage and premultiplied colour, summed.
                let (mut a_sum, mut rgb_sum, mut n) = (0.0f32, [0.0f32; 3], 0.0f32);
                for yy in 2 * cy..(2 * cy + 2).min(h) {
                    for xx in 2 * cx..(2 * cx + 2).min(w) {
                        n += 1.0;
                        let px = &mut layer[(yy * w + xx) * 4..][..4];
                        if px[3] == 0 {
                            continue;
                        }
                        let a = f32::from(px[3]) / 255.0;
                        let (r, g, b) = (f32::from(px[0]), f32::from(px[1]), f32::from(px[2]));
                        let l = &mut yp[yy * w + xx];
                        *l = to_u8(f32::from(*l) * (1.0 - a) + 16.0 * a + luma(r, g, b));
                        a_sum += a;
                        rgb_sum[0] += r;
                        rgb_sum[1] += g;
                        rgb_sum[2] += b;
                        px.fill(0);
                    }
                }
                if a_sum == 0.0 {
                    continue;
                }
                let a = a_sum / n;
                let (du, dv) = chroma(rgb_sum[0] / n, rgb_sum[1] / n, rgb_sum[2] / n);
                let c = cy * cw + cx;
                up[c] = to_u8(f32::from(up[c]) * (1.0 - a) + 128.0 * a + du);
                vp[c] = to_u8(f32::from(vp[c]) * (1.0 - a) + 128.0 * a + dv);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn worst(a: &[u8], b: &[u8]) -> u8 {
        a.iter().zip(b).map(|(p, q)| p.abs_diff(*q)).max().unwrap()
    }

    /// Flat colours go to YUV and back within a grey level or two; odd
    /// sizes give chroma planes rounded up.
    #[test]
    fn rgb_round_trips_through_yuv() {
        for (w, h) in [(4usize, 2usize), (5, 3)] {
            assert_eq!(
                Yuv420Frame::bytes(w, h),
                w * h + 2 * w.div_ceil(2) * h.div_ceil(2)
            );
            for colour in [[0u8, 0, 0], [255, 255, 255], [200, 40, 90], [30, 160, 220]] {
                let rgb: Vec<u8> = (0..w * h).flat_map(|_| colour).collect();
                let f = Yuv420Frame::from_rgb(7, w, h, &rgb).unwrap();
                assert_eq!(f.data.len(), PixelFormat::Yuv420p.frame_bytes(w, h));
                assert!(worst(&f.to_rgb(), &rgb) <= 2, "{colour:?} at {w}×{h}");
            }
        }
        // Black and white at the ends of the limited range.
        let f = Yuv420Frame::from_rgb(0, 2, 2, &[255; 12]).unwrap();
        assert_eq!(&f.data[..4], &[235; 4]);
        assert_eq!(&f.data[4..], &[128, 128]);
        assert!(Yuv420Frame::from_rgb(0, 2, 2, &[0; 11]).is_err());
        assert!(Yuv420Frame::new(0, 2, 2, vec![0; 5]).is_err());
        assert!(Yuv420Frame::new(0, 0, 2, vec![]).is_err());
    }

    /// An opaque pixel of the layer takes the frame's luma to its colour's;
    /// a transparent one leaves it; half coverage lands half way; the
    /// chroma of a block is its pixels' mean; the layer is cleared after.
    #[test]
    fn a_layer_blends_into_the_planes_and_is_cleared() {
        let (w, h) = (4usize, 2usize);
        let grey = vec![128u8; w * h * 3];
        let mut f = Yuv420Frame::from_rgb(0, w, h, &grey).unwrap();
        let before = f.clone();
        let mut layer = vec![0u8; w * h * 4];
        // Pixel (0, 0) opaque red; pixel (3, 1) half-covered white (premultiplied).
        layer[..4].copy_from_slice(&[255, 0, 0, 255]);
        layer[(w + 3) * 4..][..4].copy_from_slice(&[128, 128, 128, 128]);
        f.blend_layer(&mut layer, [0, 0, w, h]).unwrap();
        assert!(layer.iter().all(|&v| v == 0), "the layer is cleared");
        let red = Yuv420Frame::from_rgb(0, 1, 1, &[255, 0, 0]).unwrap();
        assert!(f.data[0].abs_diff(red.data[0]) <= 1);
        assert_eq!(&f.data[1..w + 3], &before.data[1..w + 3]);
        let white_half = (f32::from(before.data[w + 3]) + 235.0) / 2.0;
        assert!((f32::from(f.data[w + 3]) - white_half).abs() <= 1.0);
        // Block 0 is a quarter red: its V moves a quarter of the way to red's.
        let (u0, v0) = (w * h, w * h + 2);
        let v_quarter = (3.0 * f32::from(before.data[v0]) + f32::from(red.data[2])) / 4.0;
        assert!((f32::from(f.data[v0]) - v_quarter).abs() <= 1.0);
        assert!(f.data[u0] < before.data[u0]);
        // Outside the rectangle nothing is read or changed.
        let mut g = before.clone();
        let mut layer = vec![255u8; w * h * 4];
        g.blend_layer(&mut layer, [2, 0, 4, 2]).unwrap();
        assert_eq!(&g.data[..2], &before.data[..2]);
        assert_eq!(&layer[..8], &[255; 8]);
        assert!(layer[8..16].iter().all(|&v| v == 0));
        assert!(g.blend_layer(&mut [0u8; 3], [0, 0, 1, 1]).is_err());
    }
}
