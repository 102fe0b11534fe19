//! Skeletons drawn on frames (or on a blank canvas) with anti-aliased
//! lines, and contact sheets of several frames with labels.

use mp_geom::{Skeleton, Track, Units};
use resvg::tiny_skia::{
    Color, FillRule, FilterQuality, Paint, PathBuilder, Pixmap, PixmapPaint, Stroke, Transform,
};

use crate::error::{ReportError, Result};
use crate::raster::render_svg_onto;
use crate::style::{self, bone_rgb};
use crate::svg::{Anchor, Svg};

/// Maps track coordinates (first two dimensions) to picture pixels:
/// `px = x·scale + dx`, `py = ±y·scale + dy` (minus when `flip_y`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Picture pixels per track unit.
    pub scale: f64,
    /// Horizontal offset, picture pixels.
    pub dx: f64,
    /// Vertical offset, picture pixels.
    pub dy: f64,
    /// Whether the track's y axis points up (metres) rather than down (image pixels).
    pub flip_y: bool,
}

impl View {
    /// The view of a frame of the video the keypoints came from, shown `scale` × its size.
    pub fn frame(scale: f64) -> Self {
        View {
            scale,
            dx: 0.0,
            dy: 0.0,
            flip_y: false,
        }
    }

    /// A view that fits every valid position of `tracks` into `width × height`
    /// with `margin_px` on each side (y flipped unless the units are pixels).
    pub fn fit(tracks: &[&Track], width: f64, height: f64, margin_px: f64) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut flip_y = false;
        for t in tracks {
            flip_y |= t.units() != Units::Pixels;
            if t.dims() < 2 {
                continue;
            }
            if let Some((a, b)) = t.bounds() {
                for k in 0..2 {
                    if a[k].is_finite() && b[k].is_finite() {
                        lo[k] = lo[k].min(a[k]);
                        hi[k] = hi[k].max(b[k]);
                    }
                }
            }
        }
        if !(lo[0].is_finite() && lo[1].is_finite()) {
            return View::frame(1.0);
        }
        let (w, h) = ((hi[0] - lo[0]).max(1e-9), (hi[1] - lo[1]).max(1e-9));
        let scale = ((width - 2.0 * margin_px) / w)
            .min((height - 2.0 * margin_px) / h)
            .max(1e-9);
        let cx = (lo[0] + hi[0]) / 2.0;
        let cy = (lo[1] + hi[1]) / 2.0;
        let dx = width / 2.0 - cx * scale;
        let dy = if flip_y {
            height / 2.0 + cy * scale
        } else {
            height / 2.0 - cy * scale
        };
        View {
            scale,
            dx,
            dy,
            flip_y,
        }
    }

    /// Picture position of a track point.
    pub fn apply(&self, x: f64, y: f64) -> (f32, f32) {
        let px = x * self.scale + self.dx;
        let py = if self.flip_y {
            -y * self.scale + self.dy
        } else {
            y * self.scale + self.dy
        };
        (px as f32, py as f32)
    }

    /// This view shown `s` × larger.
    pub fn scaled(&self, s: f64) -> Self {
        View {
            scale: self.scale * s,
            dx: self.dx * s,
            dy: self.dy * s,
            flip_y: self.flip_y,
        }
    }
}

/// How a skeleton is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkeletonStyle {
    /// Joints at or below this confidence are left out. Default 0.3.
    pub min_confidence: f64,
    /// Bone width in pixels. Default 3.
    pub line_width_px: f32,
    /// Joint dot radius in pixels. Default 3.5.
    pub dot_radius_px: f32,
    /// One colour for every bone (e.g. the program's), or `None` for left/right colours.
    pub color: Option<[u8; 3]>,
    /// Opacity in [0, 1]. Default 1.
    pub opacity: f32,
}

impl Default for SkeletonStyle {
    fn default() -> Self {
        SkeletonStyle {
            min_confidence: 0.3,
            line_width_px: 3.0,
            dot_radius_px: 3.5,
            color: None,
            opacity: 1.0,
        }
    }
}

impl SkeletonStyle {
    /// The style of an executed program's skeleton: thinner, one colour.
    pub fn program() -> Self {
        SkeletonStyle {
            min_confidence: 0.0,
            line_width_px: 2.0,
            dot_radius_px: 2.5,
            color: Some(style::SKELETON_PROGRAM),
            opacity: 0.95,
        }
    }

    /// How much thicker skeletons are drawn on a `width × height` video
    /// frame: its larger side / 512, at least 0.6.
    pub fn frame_scale(width: usize, height: usize) -> f32 {
        (width.max(height) as f32 / 512.0).max(0.6)
    }

    /// The keypoints' style on a `width × height` video frame
    /// ([`Self::frame_scale`]).
    pub fn for_frame(width: usize, height: usize) -> Self {
        SkeletonStyle::default().scaled(Self::frame_scale(width, height))
    }

    /// The same style `s` × thicker.
    pub fn scaled(&self, s: f32) -> Self {
        SkeletonStyle {
            line_width_px: self.line_width_px * s,
            dot_radius_px: self.dot_radius_px * s,
            ..*self
        }
    }
}

fn paint(rgb: [u8; 3], opacity: f32) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color(Color::from_rgba8(
        rgb[0],
        rgb[1],
        rgb[2],
        (opacity.clamp(0.0, 1.0) * 255.0) as u8,
    ));
    p.anti_alias = true;
    p
}

/// Draws frame `t` of `track` onto `pixmap` through `view`; returns the
/// area it may have painted, as [`draw_pose`] does.
pub fn draw_skeleton(
    pixmap: &mut Pixmap,
    track: &Track,
    t: usize,
    view: &View,
    st: &SkeletonStyle,
) -> Option<[f32; 4]> {
    if t >= track.n_frames() || track.dims() < 2 {
        return None;
    }
    let (pos, conf) = (track.positions(), track.confidence());
    let points: Vec<[f64; 2]> = (0..track.n_joints())
        .map(|k| [pos[[t, k, 0]], pos[[t, k, 1]]])
        .collect();
    let confidence: Vec<f64> = conf.row(t).to_vec();
    draw_pose(pixmap, track.skeleton(), &points, &confidence, view, st)
}

/// Draws one pose (`points` and `confidence` in the skeleton's joint
/// order) onto `pixmap` through `view`: the one skeleton renderer of the
/// workspace (reports, overlay videos, `mp overlay`, the live page).
/// Returns the area it may have painted, `[x0, y0, x1, y1]` in picture
/// pixels (the joints drawn, widened by the strokes, dots and their
/// anti-aliasing; not clipped to the picture), or `None` when no joint was
/// drawn.
pub fn draw_pose(
    pixmap: &mut Pixmap,
    sk: &Skeleton,
    points: &[[f64; 2]],
    confidence: &[f64],
    view: &View,
    st: &SkeletonStyle,
) -> Option<[f32; 4]> {
    let j = points.len().min(confidence.len());
    let ok = |k: usize| {
        k < j
            && confidence[k] > st.min_confidence
            && points[k][0].is_finite()
            && points[k][1].is_finite()
    };
    let at = |k: usize| view.apply(points[k][0], points[k][1]);
    let stroke = Stroke {
        width: st.line_width_px,
        line_cap: resvg::tiny_skia::LineCap::Round,
        ..Stroke::default()
    };
    // Dark outline under the bones so they read on any background.
    let mut outline = PathBuilder::new();
    let mut by_colour: Vec<([u8; 3], PathBuilder)> = Vec::new();
    for &(a, b) in &sk.bones {
        if !(ok(a) && ok(b)) {
            continue;
        }
        let (pa, pb) = (at(a), at(b));
        let rgb = st.color.unwrap_or_else(|| {
            bone_rgb(
                sk.joints.get(a).map(String::as_str).unwrap_or(""),
                sk.joints.get(b).map(String::as_str).unwrap_or(""),
            )
        });
        outline.move_to(pa.0, pa.1);
        outline.line_to(pb.0, pb.1);
        let pbld = match by_colour.iter_mut().find(|(c, _)| *c == rgb) {
            Some((_, p)) => p,
            None => {
                by_colour.push((rgb, PathBuilder::new()));
                let last = by_colour.len() - 1;
                &mut by_colour[last].1
            }
        };
        pbld.move_to(pa.0, pa.1);
        pbld.line_to(pb.0, pb.1);
    }
    if let Some(path) = outline.finish() {
        let s = Stroke {
            width: st.line_width_px + 2.0,
            ..stroke.clone()
        };
        pixmap.stroke_path(
            &path,
            &paint([15, 23, 42], 0.55 * st.opacity),
            &s,
            Transform::identity(),
            None,
        );
    }
    for (rgb, pb) in by_colour {
        if let Some(path) = pb.finish() {
            pixmap.stroke_path(
                &path,
                &paint(rgb, st.opacity),
                &stroke,
                Transform::identity(),
                None,
            );
        }
    }
    let dot_rgb = st.color.unwrap_or(style::SKELETON_CENTER);
    let mut dots = PathBuilder::new();
    let mut area: Option<[f32; 4]> = None;
    for k in 0..j {
        if ok(k) {
            let p = at(k);
            dots.push_circle(p.0, p.1, st.dot_radius_px);
            let a = area.get_or_insert([p.0, p.1, p.0, p.1]);
            *a = [a[0].min(p.0), a[1].min(p.1), a[2].max(p.0), a[3].max(p.1)];
        }
    }
    if let Some(path) = dots.finish() {
        pixmap.fill_path(
            &path,
            &paint(dot_rgb, st.opacity),
            FillRule::Winding,
            Transform::identity(),
            None,
        );
        let s = Stroke {
            width: 1.0,
            ..Stroke::default()
        };
        pixmap.stroke_path(
            &path,
            &paint([15, 23, 42], 0.6 * st.opacity),
            &s,
            Transform::identity(),
            None,
        );
    }
    // Half the outline's width (or a dot and its rim), and a pixel of
    // anti-aliasing beyond.
    let reach = (st.line_width_px / 2.0 + 1.0).max(st.dot_radius_px + 0.5) + 1.5;
    area.map(|a| [a[0] - reach, a[1] - reach, a[2] + reach, a[3] + reach])
}

/// A blank dark canvas with a faint grid, for tracks without video.
pub(crate) fn blank_canvas(width: u32, height: u32) -> Result<Pixmap> {
    let mut p = Pixmap::new(width.max(1), height.max(1)).ok_or_else(|| {
        ReportError::Mismatch(format!("cannot allocate a {width}×{height} picture"))
    })?;
    p.fill(Color::from_rgba8(15, 23, 42, 255));
    let mut grid = PathBuilder::new();
    let step = 40.0;
    let mut x = step;
    while x < width as f32 {
        grid.move_to(x, 0.0);
        grid.line_to(x, height as f32);
        x += step;
    }
    let mut y = step;
    while y < height as f32 {
        grid.move_to(0.0, y);
        grid.line_to(width as f32, y);
        y += step;
    }
    if let Some(path) = grid.finish() {
        let s = Stroke {
            width: 1.0,
            ..Stroke::default()
        };
        p.stroke_path(
            &path,
            &paint([51, 65, 85], 0.6),
            &s,
            Transform::identity(),
            None,
        );
    }
    Ok(p)
}

/// Draws `src` scaled to fill `dst` (bilinear).
pub(crate) fn blit_scaled(dst: &mut Pixmap, src: &Pixmap) {
    let sx = dst.width() as f32 / src.width().max(1) as f32;
    let sy = dst.height() as f32 / src.height().max(1) as f32;
    let pp = PixmapPaint {
        quality: FilterQuality::Bilinear,
        ..PixmapPaint::default()
    };
    dst.draw_pixmap(0, 0, src.as_ref(), &pp, Transform::from_scale(sx, sy), None);
}

/// A `tile_w`-pixel-wide tile of the RGB frame `rgb` (`size` = width,
/// height), with `draw` drawing on it through the view that maps the
/// frame's pixels onto the tile (skeletons are drawn after scaling, so
/// their lines stay sharp).
pub fn frame_tile(
    rgb: &[u8],
    size: (usize, usize),
    tile_w: u32,
    draw: impl FnOnce(&mut Pixmap, &View),
) -> Result<Pixmap> {
    let (w, h) = size;
    let tile_h = ((h as f64 / w.max(1) as f64) * tile_w as f64)
        .round()
        .max(1.0) as u32;
    let frame = crate::raster::rgb_to_pixmap(rgb, w, h)?;
    let mut tile = blank_canvas(tile_w, tile_h)?;
    blit_scaled(&mut tile, &frame);
    draw(&mut tile, &View::frame(tile_w as f64 / w.max(1) as f64));
    Ok(tile)
}

/// Layout of a contact sheet of evenly spaced frames of a video
/// (`mp overlay … -o sheet.png`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ContactSheetParams {
    /// Frames on the sheet. Default 12.
    pub frames: usize,
    /// Columns. Default 4.
    pub cols: usize,
    /// Width of each tile in pixels (the height keeps the frame's aspect).
    /// Default 320.
    pub tile_width_px: u32,
}

impl Default for ContactSheetParams {
    fn default() -> Self {
        ContactSheetParams {
            frames: 12,
            cols: 4,
            tile_width_px: 320,
        }
    }
}

/// One tile of a contact sheet: a finished picture and its caption.
pub struct Tile {
    /// The picture (all tiles the same size).
    pub pixmap: Pixmap,
    /// Caption shown in the tile's corner.
    pub caption: String,
}

/// Tiles pictures into a grid of `cols` columns under a title.
pub fn contact_sheet(tiles: &[Tile], cols: usize, title: &str) -> Result<Pixmap> {
    let first = tiles
        .first()
        .ok_or_else(|| ReportError::Mismatch("a contact sheet needs at least one frame".into()))?;
    let (tw, th) = (first.pixmap.width(), first.pixmap.height());
    if tiles
        .iter()
        .any(|t| t.pixmap.width() != tw || t.pixmap.height() != th)
    {
        return Err(ReportError::Mismatch(
            "contact-sheet tiles differ in size".into(),
        ));
    }
    let cols = cols.clamp(1, tiles.len()) as u32;
    let rows = (tiles.len() as u32).div_ceil(cols);
    let gap = 8u32;
    let head = 40u32;
    let w = cols * tw + (cols + 1) * gap;
    let h = head + rows * th + (rows + 1) * gap;
    let mut sheet = Pixmap::new(w, h)
        .ok_or_else(|| ReportError::Mismatch(format!("cannot allocate a {w}×{h} contact sheet")))?;
    sheet.fill(Color::from_rgba8(15, 23, 42, 255));
    let mut labels = Svg::new(w as f64, h as f64, "none");
    labels.text(
        gap as f64 + 2.0,
        27.0,
        title,
        17.0,
        "#f8fafc",
        Anchor::Start,
        r#"font-weight="bold""#,
    );
    for (i, t) in tiles.iter().enumerate() {
        let (r, c) = (i as u32 / cols, i as u32 % cols);
        let x = gap + c * (tw + gap);
        let y = head + gap + r * (th + gap);
        sheet.draw_pixmap(
            x as i32,
            y as i32,
            t.pixmap.as_ref(),
            &PixmapPaint::default(),
            Transform::identity(),
            None,
        );
        let cw = 7.2 * t.caption.chars().count() as f64 + 12.0;
        labels.rect(
            x as f64 + 6.0,
            y as f64 + 6.0,
            cw,
            20.0,
            "#0f172a",
            r#"fill-opacity="0.72" rx="4""#,
        );
        labels.text(
            x as f64 + 12.0,
            y as f64 + 20.5,
            &t.caption,
            12.0,
            "#f8fafc",
            Anchor::Start,
            "",
        );
    }
    render_svg_onto("contact sheet labels", &labels.finish(), &mut sheet)?;
    Ok(sheet)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::{Array2, Array3};

    fn two_joint_track() -> Track {
        let mut pos = Array3::zeros((1, 2, 2));
        pos[[0, 0, 0]] = 10.0;
        pos[[0, 0, 1]] = 50.0;
        pos[[0, 1, 0]] = 90.0;
        pos[[0, 1, 1]] = 50.0;
        let sk = Skeleton::custom(
            "two",
            vec!["left_a".into(), "left_b".into()],
            vec![(0, 1)],
            None,
        );
        Track::new(pos, Some(Array2::ones((1, 2))), 30.0, Units::Pixels, sk).unwrap()
    }

    #[test]
    fn bone_is_drawn_in_side_colour() {
        let t = two_joint_track();
        let mut p = Pixmap::new(100, 100).unwrap();
        draw_skeleton(&mut p, &t, 0, &View::frame(1.0), &SkeletonStyle::default());
        let px = p.pixel(50, 50).unwrap();
        assert_eq!([px.red(), px.green(), px.blue()], style::SKELETON_LEFT);
        assert_eq!(p.pixel(50, 10).unwrap().alpha(), 0);
        // Out of range frames draw nothing.
        let mut q = Pixmap::new(100, 100).unwrap();
        draw_skeleton(&mut q, &t, 3, &View::frame(1.0), &SkeletonStyle::default());
        assert!(q.pixels().iter().all(|c| c.alpha() == 0));
    }

    #[test]
    fn fit_view_centres_the_motion() {
        let t = two_joint_track();
        let v = View::fit(&[&t], 200.0, 100.0, 10.0);
        let (a, b) = (v.apply(10.0, 50.0), v.apply(90.0, 50.0));
        assert!(
            (a.0 - 10.0).abs() < 1e-3 && (b.0 - 190.0).abs() < 1e-3,
            "{a:?} {b:?}"
        );
        assert!((a.1 - 50.0).abs() < 1e-3);
    }

    #[test]
    fn sheet_layout() {
        let tiles: Vec<Tile> = (0..5)
            .map(|i| Tile {
                pixmap: blank_canvas(40, 30).unwrap(),
                caption: format!("frame {i}"),
            })
            .collect();
        let s = contact_sheet(&tiles, 3, "t").unwrap();
        assert_eq!(
            (s.width(), s.height()),
            (3 * 40 + 4 * 8, 40 + 2 * 30 + 3 * 8)
        );
        assert!(contact_sheet(&[], 3, "t").is_err());
    }
}
