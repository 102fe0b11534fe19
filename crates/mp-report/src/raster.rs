//! SVG → PNG with resvg (pure Rust), and PNG/JPEG encoding of RGB buffers.
//!
//! Text uses the system fonts (DejaVu Sans on Debian, installed by
//! `scripts/setup.sh`), loaded once per process. Without any font the
//! pictures still render, only without labels.

use std::sync::{Arc, OnceLock};

use resvg::tiny_skia::{Pixmap, Transform};
use resvg::usvg;

use crate::error::{ReportError, Result};

/// The family the pictures' text uses.
const SANS_FAMILY: &str = "DejaVu Sans";

/// At most this many bytes of font files are held in memory (the text
/// family's files always are).
pub(crate) const FONT_MEMORY_BUDGET_BYTES: u64 = 32 << 20;

fn fonts() -> Arc<usvg::fontdb::Database> {
    static FONTS: OnceLock<Arc<usvg::fontdb::Database>> = OnceLock::new();
    FONTS
        .get_or_init(|| {
            let mut db = usvg::fontdb::Database::new();
            db.load_system_fonts();
            let mut db = fonts_in_memory(&db, FONT_MEMORY_BUDGET_BYTES);
            db.set_sans_serif_family(SANS_FAMILY);
            Arc::new(db)
        })
        .clone()
}

/// A copy of `db` whose faces read their data from memory instead of from
/// their files: a file-backed face is read from disk again every time a
/// glyph is drawn, which made text the slowest part of every picture. The
/// text family's files come first; other files are copied while the total
/// stays within `budget_bytes`, the rest stay file-backed.
fn fonts_in_memory(db: &usvg::fontdb::Database, budget_bytes: u64) -> usvg::fontdb::Database {
    use std::collections::HashMap;
    use std::path::PathBuf;
    use usvg::fontdb::{Database, Source, ID};
    type Data = Arc<dyn AsRef<[u8]> + Sync + Send>;
    let is_sans = |f: &usvg::fontdb::FaceInfo| f.families.iter().any(|(n, _)| n == SANS_FAMILY);
    // Which files to read: the text family's first, then the others in order.
    let mut order: Vec<(bool, PathBuf)> = Vec::new();
    for f in db.faces() {
        if let Source::File(path) = &f.source {
            order.push((!is_sans(f), path.clone()));
        }
    }
    order.sort_by_key(|(other, _)| *other);
    let mut data: HashMap<PathBuf, Data> = HashMap::new();
    let mut used = 0u64;
    for (other, path) in order {
        if data.contains_key(&path) {
            continue;
        }
        let Ok(meta) = std::fs::metadata(&path) else {
            continue;
        };
        if other && used + meta.len() > budget_bytes {
            continue;
        }
        if let Ok(bytes) = std::fs::read(&path) {
            used += bytes.len() as u64;
            data.insert(path, Arc::new(bytes));
        }
    }
    let mut out = Database::new();
    for f in db.faces() {
        let mut f = f.clone();
        if let Source::File(path) = &f.source {
            if let Some(d) = data.get(path) {
                f.source = Source::Binary(d.clone());
            }
        }
        f.id = ID::dummy();
        out.push_face_info(f);
    }
    out
}

fn parse(name: &str, svg: &str) -> Result<usvg::Tree> {
    let opt = usvg::Options {
        fontdb: fonts(),
        font_family: "DejaVu Sans".into(),
        ..usvg::Options::default()
    };
    usvg::Tree::from_str(svg, &opt).map_err(|e| ReportError::Render {
        name: name.to_string(),
        reason: e.to_string(),
    })
}

/// Rasterises an SVG document at `scale` × its size into a new pixmap.
pub fn svg_to_pixmap(name: &str, svg: &str, scale: f32) -> Result<Pixmap> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(ReportError::param(
            "scale",
            format!("must be > 0, got {scale}"),
        ));
    }
    let tree = parse(name, svg)?;
    let size = tree.size();
    let (w, h) = (
        (size.width() * scale).ceil().max(1.0) as u32,
        (size.height() * scale).ceil().max(1.0) as u32,
    );
    let mut pixmap = Pixmap::new(w, h).ok_or_else(|| ReportError::Render {
        name: name.to_string(),
        reason: format!("cannot allocate a {w}×{h} picture"),
    })?;
    resvg::render(
        &tree,
        Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    Ok(pixmap)
}

/// Draws an SVG document over an existing pixmap (same coordinate system).
pub(crate) fn render_svg_onto(name: &str, svg: &str, pixmap: &mut Pixmap) -> Result<()> {
    let tree = parse(name, svg)?;
    resvg::render(&tree, Transform::identity(), &mut pixmap.as_mut());
    Ok(())
}

/// Rasterises an SVG document to PNG bytes at `scale` × its size.
pub(crate) fn svg_to_png(name: &str, svg: &str, scale: f32) -> Result<Vec<u8>> {
    let pixmap = svg_to_pixmap(name, svg, scale)?;
    pixmap_to_png(name, &pixmap)
}

/// Encodes a pixmap as PNG with fast compression: 8-bit RGB when every
/// pixel is opaque, 8-bit RGBA (colours un-premultiplied) otherwise.
pub fn pixmap_to_png(name: &str, p: &Pixmap) -> Result<Vec<u8>> {
    let opaque = p.pixels().iter().all(|px| px.alpha() == 255);
    let (w, h) = (p.width(), p.height());
    let (bytes, colour) = if opaque {
        (pixmap_to_rgb(p), image::ExtendedColorType::Rgb8)
    } else {
        let mut out = Vec::with_capacity(p.pixels().len() * 4);
        for px in p.pixels() {
            let c = px.demultiply();
            out.extend_from_slice(&[c.red(), c.green(), c.blue(), c.alpha()]);
        }
        (out, image::ExtendedColorType::Rgba8)
    };
    let mut out = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new_with_quality(
            &mut out,
            image::codecs::png::CompressionType::Fast,
            image::codecs::png::FilterType::Adaptive,
        ),
        &bytes,
        w,
        h,
        colour,
    )
    .map_err(|e| ReportError::Image {
        what: name.to_string(),
        reason: e.to_string(),
    })?;
    Ok(out)
}

/// Pixmap (premultiplied RGBA) → RGB bytes (alpha composited over black).
pub fn pixmap_to_rgb(p: &Pixmap) -> Vec<u8> {
    let mut out = Vec::with_capacity((p.width() * p.height() * 3) as usize);
    for px in p.pixels() {
        // Premultiplied: the colour channels are already scaled by alpha.
        out.extend_from_slice(&[px.red(), px.green(), px.blue()]);
    }
    out
}

/// RGB bytes → an opaque pixmap.
pub fn rgb_to_pixmap(rgb: &[u8], width: usize, height: usize) -> Result<Pixmap> {
    if rgb.len() != width * height * 3 {
        return Err(ReportError::Mismatch(format!(
            "RGB buffer of {} bytes for a {width}×{height} image",
            rgb.len()
        )));
    }
    let mut p = Pixmap::new(width as u32, height as u32).ok_or_else(|| {
        ReportError::Mismatch(format!("cannot allocate a {width}×{height} picture"))
    })?;
    for (dst, src) in p.data_mut().chunks_exact_mut(4).zip(rgb.chunks_exact(3)) {
        dst.copy_from_slice(&[src[0], src[1], src[2], 255]);
    }
    Ok(p)
}

/// Encodes RGB bytes as PNG.
#[cfg(test)]
fn encode_png(rgb: &[u8], width: usize, height: usize) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image_checked(rgb, width, height)
        .map_err(|reason| ReportError::Image {
            what: "PNG".into(),
            reason,
        })?;
    Ok(out)
}

/// Encodes RGB bytes as JPEG at `quality` (1–100).
pub fn encode_jpeg(rgb: &[u8], width: usize, height: usize, quality: u8) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, quality.clamp(1, 100))
        .write_image_checked(rgb, width, height)
        .map_err(|reason| ReportError::Image {
            what: "JPEG".into(),
            reason,
        })?;
    Ok(out)
}

/// Decodes a JPEG or PNG into RGB bytes, width and height.
pub(crate) fn decode_rgb(bytes: &[u8], what: &str) -> Result<(Vec<u8>, usize, usize)> {
    let img = image::load_from_memory(bytes).map_err(|e| ReportError::Image {
        what: what.to_string(),
        reason: e.to_string(),
    })?;
    let rgb = img.to_rgb8();
    let (w, h) = (rgb.width() as usize, rgb.height() as usize);
    Ok((rgb.into_raw(), w, h))
}

trait WriteChecked {
    fn write_image_checked(
        self,
        rgb: &[u8],
        width: usize,
        height: usize,
    ) -> std::result::Result<(), String>;
}

impl<E: image::ImageEncoder> WriteChecked for E {
    fn write_image_checked(
        self,
        rgb: &[u8],
        width: usize,
        height: usize,
    ) -> std::result::Result<(), String> {
        if rgb.len() != width * height * 3 {
            return Err(format!(
                "{} bytes for a {width}×{height} RGB image",
                rgb.len()
            ));
        }
        let (w, h) = (
            u32::try_from(width).map_err(|e| e.to_string())?,
            u32::try_from(height).map_err(|e| e.to_string())?,
        );
        self.write_image(rgb, w, h, image::ExtendedColorType::Rgb8)
            .map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_rasterises_with_colours() {
        let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" width="20" height="10"><rect width="10" height="10" fill="#ff0000"/><rect x="10" width="10" height="10" fill="#0000ff"/></svg>"##;
        let p = svg_to_pixmap("t", svg, 2.0).unwrap();
        assert_eq!((p.width(), p.height()), (40, 20));
        let left = p.pixel(5, 5).unwrap();
        let right = p.pixel(35, 5).unwrap();
        assert_eq!((left.red(), left.blue()), (255, 0));
        assert_eq!((right.red(), right.blue()), (0, 255));
        let png = svg_to_png("t", svg, 1.0).unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }

    #[test]
    fn png_keeps_colours_and_transparency() {
        let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" width="20" height="10"><rect width="10" height="10" fill="#ff0000"/><rect x="10" width="10" height="10" fill="#0000ff" fill-opacity="0.5"/></svg>"##;
        let p = svg_to_pixmap("t", svg, 1.0).unwrap();
        let img = image::load_from_memory(&pixmap_to_png("t", &p).unwrap())
            .unwrap()
            .to_rgba8();
        assert_eq!(img.dimensions(), (20, 10));
        assert_eq!(img.get_pixel(5, 5).0, [255, 0, 0, 255]);
        let half = img.get_pixel(15, 5).0;
        assert_eq!((half[0], half[1]), (0, 0));
        assert!(half[2] >= 254 && (126..=129).contains(&half[3]), "{half:?}");
        // Opaque pictures are written without an alpha channel.
        let opaque = svg_to_pixmap(
            "o",
            r##"<svg xmlns="http://www.w3.org/2000/svg" width="4" height="4"><rect width="4" height="4" fill="#00ff00"/></svg>"##,
            1.0,
        )
        .unwrap();
        let back = image::load_from_memory(&pixmap_to_png("o", &opaque).unwrap()).unwrap();
        assert_eq!(back.color(), image::ColorType::Rgb8);
        assert_eq!(back.to_rgb8().get_pixel(1, 1).0, [0, 255, 0]);
    }

    #[test]
    fn bad_svg_names_the_picture() {
        let e = svg_to_png("timeline", "<svg", 1.0).unwrap_err();
        assert!(e.to_string().contains("timeline"), "{e}");
    }

    #[test]
    fn jpeg_round_trip_keeps_size() {
        let rgb = vec![128u8; 8 * 6 * 3];
        let jpg = encode_jpeg(&rgb, 8, 6, 80).unwrap();
        let (back, w, h) = decode_rgb(&jpg, "x").unwrap();
        assert_eq!((w, h), (8, 6));
        assert!(back.iter().all(|&v| (v as i32 - 128).abs() <= 3));
        assert!(encode_png(&rgb, 8, 5).is_err());
    }
}
