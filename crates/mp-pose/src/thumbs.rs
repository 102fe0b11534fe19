//! Cheap descriptors of whole frames: small grey-level thumbnails.
//!
//! A repetition shows in the pixels even where no person is found (a bar lift
//! in the dark, a body seen from too close): the thumbnails of a video form a
//! feature track ([`thumbnail_track`], unitless, one channel per cell) that the
//! periodicity analyses of `mp-abstract` read like joint positions.

use mp_geom::{Skeleton, Track, Units};
use ndarray::Array3;

use crate::error::{PoseError, Result};
use crate::video::Frame;

/// Default thumbnail side in cells (32 × 32 = 1,024 values per frame).
pub const DEFAULT_THUMBNAIL_SIZE: usize = 32;

/// The mean luma (BT.601 weights, 0–255) of each cell of a `size × size` grid
/// laid over the frame, row-major. Every pixel falls in exactly one cell
/// (cell `⌊x · size / width⌋`), so frames of any size work; frames smaller
/// than the grid leave some cells empty (0).
pub fn grey_thumbnail(frame: &Frame, size: usize) -> Result<Vec<f32>> {
    frame.validate()?;
    if size == 0 {
        return Err(PoseError::param("thumbnail size", "must be at least 1"));
    }
    let (w, h) = (frame.width, frame.height);
    let mut sum = vec![0.0f64; size * size];
    let mut count = vec![0u32; size * size];
    let col: Vec<usize> = (0..w).map(|x| x * size / w).collect();
    for y in 0..h {
        let row = (y * size / h) * size;
        let line = &frame.rgb[y * w * 3..(y + 1) * w * 3];
        for (x, px) in line.chunks_exact(3).enumerate() {
            let l = 0.299 * px[0] as f64 + 0.587 * px[1] as f64 + 0.114 * px[2] as f64;
            let c = row + col[x];
            sum[c] += l;
            count[c] += 1;
        }
    }
    Ok(sum
        .iter()
        .zip(&count)
        .map(|(&s, &n)| if n > 0 { (s / n as f64) as f32 } else { 0.0 })
        .collect())
}

/// Thumbnails of consecutive frames as a unitless feature track: `T` frames ×
/// `size` rows (the track's "joints", confidence 1) × `size` cells per row
/// (its dimensions), so the channels run row-major as in the thumbnail. Each
/// thumbnail is freed once copied: the track is built in the memory of one
/// copy (8 bytes per cell and frame).
pub fn thumbnail_track(thumbs: Vec<Vec<f32>>, size: usize, fps: f64) -> Result<Track> {
    let c = size * size;
    if thumbs.is_empty() {
        return Err(PoseError::param("thumbnails", "no frames"));
    }
    let mut a = Array3::<f64>::zeros((thumbs.len(), size, size));
    for (t, th) in thumbs.into_iter().enumerate() {
        if th.len() != c {
            return Err(PoseError::param(
                "thumbnails",
                format!(
                    "frame {t} has {} values, a {size}×{size} grid has {c}",
                    th.len()
                ),
            ));
        }
        for (k, &v) in th.iter().enumerate() {
            a[[t, k / size, k % size]] = v as f64;
        }
    }
    Ok(Track::new(
        a,
        None,
        fps,
        Units::Unitless,
        Skeleton::generic(size),
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: usize, h: usize, f: impl Fn(usize, usize) -> [u8; 3]) -> Frame {
        let mut rgb = Vec::with_capacity(w * h * 3);
        for y in 0..h {
            for x in 0..w {
                rgb.extend_from_slice(&f(x, y));
            }
        }
        Frame::new(0, 0.0, w, h, rgb).unwrap()
    }

    #[test]
    fn cells_average_their_pixels() {
        // Left half white, right half black, 4 × 2 grid cells of a 8 × 6 frame.
        let fr = frame(8, 6, |x, _| if x < 4 { [255; 3] } else { [0; 3] });
        let t = grey_thumbnail(&fr, 2).unwrap();
        assert_eq!(t.len(), 4);
        assert!((t[0] - 255.0).abs() < 1e-3 && (t[2] - 255.0).abs() < 1e-3);
        assert!(t[1].abs() < 1e-3 && t[3].abs() < 1e-3);
        // Luma weights: pure red is 0.299 · 255.
        let red = grey_thumbnail(&frame(5, 7, |_, _| [255, 0, 0]), 3).unwrap();
        assert!(red.iter().all(|&v| (v - 76.245).abs() < 1e-3), "{red:?}");
    }

    #[test]
    fn odd_sizes_and_bad_input() {
        let fr = frame(3, 2, |x, y| [(x * 50 + y * 10) as u8; 3]);
        let t = grey_thumbnail(&fr, 4).unwrap();
        assert_eq!(t.len(), 16);
        assert!(grey_thumbnail(&fr, 0).is_err());
        let tr = thumbnail_track(vec![t.clone(), t.clone()], 4, 30.0).unwrap();
        assert_eq!(tr.positions().dim(), (2, 4, 4));
        assert_eq!(tr.confidence().dim(), (2, 4));
        assert_eq!(tr.units(), Units::Unitless);
        // Row-major: cell k is row k / 4, column k % 4.
        for (k, &v) in t.iter().enumerate() {
            assert_eq!(tr.positions()[[1, k / 4, k % 4]], v as f64);
        }
        let err = thumbnail_track(vec![vec![0.0; 3]], 4, 30.0).unwrap_err();
        assert!(err.to_string().contains("frame 0 has 3 values"), "{err}");
        assert!(thumbnail_track(Vec::new(), 4, 30.0).is_err());
    }
}
