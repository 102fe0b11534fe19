//! Drawing skeletons on RGB frames, and contact sheets of several frames.

use mp_geom::Skeleton;

use crate::imageops::{crop_u8, Border, RgbView, Roi};

/// Style of a drawn skeleton.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrawStyle {
    /// Joints with confidence at or below this are not drawn. Default 0.5.
    pub min_confidence: f64,
    /// Bone colour (left side of the body gets this colour).
    pub left_rgb: [u8; 3],
    /// Right-side bones.
    pub right_rgb: [u8; 3],
    /// Bones in the middle (between left and right joints) and joints.
    pub center_rgb: [u8; 3],
    /// Line thickness in pixels. Default 2.
    pub thickness_px: f64,
    /// Joint dot radius in pixels. Default 3.
    pub radius_px: f64,
}

impl Default for DrawStyle {
    fn default() -> Self {
        DrawStyle {
            min_confidence: 0.5,
            left_rgb: [255, 140, 0],
            right_rgb: [0, 170, 255],
            center_rgb: [240, 240, 240],
            thickness_px: 2.0,
            radius_px: 3.0,
        }
    }
}

impl DrawStyle {
    /// Pixels of the frame's larger side per pixel of line thickness in
    /// [`Self::scaled_to`]: 300.
    pub const SIDE_PX_PER_THICKNESS_PX: f64 = 300.0;
    /// Pixels of the frame's larger side per pixel of joint radius in
    /// [`Self::scaled_to`]: 200.
    pub const SIDE_PX_PER_RADIUS_PX: f64 = 200.0;

    /// This style for a `width × height` frame: line thickness and joint
    /// radius grow with the frame's larger side
    /// ([`Self::SIDE_PX_PER_THICKNESS_PX`], [`Self::SIDE_PX_PER_RADIUS_PX`]),
    /// never below this style's own.
    pub fn scaled_to(self, width: usize, height: usize) -> Self {
        let side = width.max(height) as f64;
        DrawStyle {
            thickness_px: (side / Self::SIDE_PX_PER_THICKNESS_PX).max(self.thickness_px),
            radius_px: (side / Self::SIDE_PX_PER_RADIUS_PX).max(self.radius_px),
            ..self
        }
    }
}

/// A mutable RGB image.
pub struct Canvas<'a> {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// `height × width × 3` bytes.
    pub data: &'a mut [u8],
}

impl Canvas<'_> {
    fn put(&mut self, x: i64, y: i64, rgb: [u8; 3]) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let o = (y as usize * self.width + x as usize) * 3;
        if let Some(px) = self.data.get_mut(o..o + 3) {
            px.copy_from_slice(&rgb);
        }
    }

    /// Filled disc.
    pub fn disc(&mut self, cx: f64, cy: f64, r: f64, rgb: [u8; 3]) {
        if !(cx.is_finite() && cy.is_finite() && r.is_finite()) {
            return;
        }
        let (x0, x1) = ((cx - r).floor() as i64, (cx + r).ceil() as i64);
        let (y0, y1) = ((cy - r).floor() as i64, (cy + r).ceil() as i64);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (dx, dy) = (x as f64 - cx, y as f64 - cy);
                if dx * dx + dy * dy <= r * r {
                    self.put(x, y, rgb);
                }
            }
        }
    }

    /// Thick line segment.
    pub fn line(&mut self, a: [f64; 2], b: [f64; 2], thickness: f64, rgb: [u8; 3]) {
        if !a.iter().chain(b.iter()).all(|v| v.is_finite()) {
            return;
        }
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        // Long lines far outside the canvas are clipped by `put`; cap the step count.
        let steps = (len.min(4.0 * (self.width + self.height) as f64))
            .ceil()
            .max(1.0) as usize;
        let r = (thickness / 2.0).max(0.5);
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            self.disc(a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, r, rgb);
        }
    }
}

fn side(name: &str) -> i32 {
    if name.starts_with("left") || name.starts_with("l_") || name.starts_with("Left") {
        -1
    } else if name.starts_with("right") || name.starts_with("r_") || name.starts_with("Right") {
        1
    } else {
        0
    }
}

/// Draws one pose (`keypoints` and `confidence` in the skeleton's order).
pub fn draw_pose(
    canvas: &mut Canvas<'_>,
    skeleton: &Skeleton,
    keypoints: &[[f64; 2]],
    confidence: &[f64],
    style: &DrawStyle,
) {
    let ok = |k: usize| {
        confidence.get(k).is_some_and(|&c| c > style.min_confidence) && k < keypoints.len()
    };
    for &(a, b) in &skeleton.bones {
        if !(ok(a) && ok(b)) {
            continue;
        }
        let name = |k: usize| skeleton.joints.get(k).map(String::as_str).unwrap_or("");
        let s = side(name(a)) + side(name(b));
        let rgb = match s.signum() {
            -1 => style.left_rgb,
            1 => style.right_rgb,
            _ => style.center_rgb,
        };
        canvas.line(keypoints[a], keypoints[b], style.thickness_px, rgb);
    }
    for (k, p) in keypoints.iter().enumerate() {
        if ok(k) {
            canvas.disc(p[0], p[1], style.radius_px, style.center_rgb);
        }
    }
}

/// Scales an RGB image to `out_w × out_h` (bilinear).
pub fn resize(src: RgbView<'_>, out_w: usize, out_h: usize) -> Vec<u8> {
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

/// Layout of a contact sheet of evenly spaced frames of a video.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ContactSheetParams {
    /// Frames on the sheet. Default 12.
    pub frames: usize,
    /// Columns. Default 4.
    pub cols: usize,
    /// Width of each tile in pixels (the height keeps the frame's aspect).
    /// Default 320.
    pub tile_width_px: usize,
    /// Dark border between and around the tiles, pixels. Default 4.
    pub gap_px: usize,
}

impl Default for ContactSheetParams {
    fn default() -> Self {
        ContactSheetParams {
            frames: 12,
            cols: 4,
            tile_width_px: 320,
            gap_px: 4,
        }
    }
}

/// Tiles equally sized RGB images (`tile_w × tile_h`) into a grid of `cols`
/// columns with a `gap_px` dark border. Returns (pixels, width, height).
pub fn contact_sheet(
    tiles: &[Vec<u8>],
    tile_w: usize,
    tile_h: usize,
    cols: usize,
    gap_px: usize,
) -> (Vec<u8>, usize, usize) {
    let cols = cols.max(1).min(tiles.len().max(1));
    let rows = tiles.len().div_ceil(cols).max(1);
    let w = cols * tile_w + (cols + 1) * gap_px;
    let h = rows * tile_h + (rows + 1) * gap_px;
    let mut out = vec![24u8; w * h * 3];
    for (i, tile) in tiles.iter().enumerate() {
        if tile.len() != tile_w * tile_h * 3 {
            continue;
        }
        let (r, c) = (i / cols, i % cols);
        let x0 = gap_px + c * (tile_w + gap_px);
        let y0 = gap_px + r * (tile_h + gap_px);
        for y in 0..tile_h {
            let dst = ((y0 + y) * w + x0) * 3;
            let src = y * tile_w * 3;
            out[dst..dst + tile_w * 3].copy_from_slice(&tile[src..src + tile_w * 3]);
        }
    }
    (out, w, h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_only_confident_bones() {
        let sk = Skeleton::coco17();
        let mut buf = vec![0u8; 100 * 100 * 3];
        let mut kps = vec![[0.0, 0.0]; 17];
        let mut conf = vec![0.0; 17];
        // Left shoulder (5) to left elbow (7): confident.
        kps[5] = [10.0, 10.0];
        kps[7] = [90.0, 10.0];
        conf[5] = 0.9;
        conf[7] = 0.9;
        // Right shoulder (6) not confident.
        kps[6] = [10.0, 90.0];
        {
            let mut c = Canvas {
                width: 100,
                height: 100,
                data: &mut buf,
            };
            draw_pose(&mut c, &sk, &kps, &conf, &DrawStyle::default());
        }
        let at = |x: usize, y: usize| &buf[(y * 100 + x) * 3..(y * 100 + x) * 3 + 3];
        assert_eq!(at(50, 10), &DrawStyle::default().left_rgb);
        assert_eq!(at(10, 50), &[0, 0, 0]);
    }

    #[test]
    fn sheet_size() {
        let tiles = vec![vec![255u8; 4 * 3 * 3]; 5];
        let (px, w, h) = contact_sheet(&tiles, 4, 3, 2, 1);
        assert_eq!((w, h), (2 * 4 + 3, 3 * 3 + 4));
        assert_eq!(px.len(), w * h * 3);
        assert_eq!(px[(w + 1) * 3], 255);
    }

    #[test]
    fn resize_keeps_constant_images() {
        let img = vec![77u8; 10 * 6 * 3];
        let out = resize(
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
