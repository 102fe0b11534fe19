//! Cheap descriptors of whole frames: small grey-level thumbnails.
//!
//! A repetition shows in the pixels even where no person is found (a bar lift
//! in the dark, a body seen from too close): the thumbnails of a video form a
//! feature track ([`thumbnail_track`], unitless, one channel per cell) that the
//! periodicity analyses of `mp-abstract` read like joint positions.

use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array3, ArrayView3};

use crate::error::{PoseError, Result};
use crate::video::Frame;

/// Default thumbnail side in cells (32 × 32 = 1,024 values per frame).
pub const DEFAULT_THUMBNAIL_SIZE: usize = 32;

/// Most values a frame signal holds over a whole video: 2²⁵ (256 MiB as the
/// 64-bit floats of a [`Track`]). 32 × 32 thumbnails fit for 32,768 frames
/// (18 minutes at 30 fps); a longer video's are read at 16 × 16 (to 73
/// minutes), 8 × 8 beyond ([`signal_side`]), so that an hour's frame signal
/// takes 229 MB instead of 917 MB.
pub const MAX_SIGNAL_VALUES: usize = 1 << 25;

/// The side at which the thumbnails of `frames` frames are kept, asked for at
/// `size`: `size` halved (rounding up) until `frames × side²` is at most
/// [`MAX_SIGNAL_VALUES`] or the side is 1. A halved side's cells are the
/// pixels of 2 × 2 cells of the asked side (`grey_thumbnail_region` gives
/// pixel `x` the cell `⌊x · side / width⌋`).
pub fn signal_side(size: usize, frames: usize) -> usize {
    let mut side = size.max(1);
    while side > 1 && frames.saturating_mul(side * side) > MAX_SIGNAL_VALUES {
        side = side.div_ceil(2);
    }
    side
}

/// A `size × size` thumbnail as `side × side` cells, each the mean of the
/// cells `c` with `⌊c · side / size⌋` equal to it (row and column).
fn pooled(th: &[f32], size: usize, side: usize) -> Vec<f32> {
    let mut sum = vec![0.0f64; side * side];
    let mut count = vec![0u32; side * side];
    for (k, &v) in th.iter().enumerate() {
        let (r, c) = (k / size * side / size, k % size * side / size);
        sum[r * side + c] += v as f64;
        count[r * side + c] += 1;
    }
    sum.iter()
        .zip(&count)
        .map(|(&s, &n)| (s / n.max(1) as f64) as f32)
        .collect()
}

/// The mean luma (BT.601 weights, 0–255) of each cell of a `size × size` grid
/// laid over the frame, row-major. Every pixel falls in exactly one cell
/// (cell `⌊x · size / width⌋`), so frames of any size work; frames smaller
/// than the grid leave some cells empty (0).
pub fn grey_thumbnail(frame: &Frame, size: usize) -> Result<Vec<f32>> {
    let (w, h) = (frame.width as f64, frame.height as f64);
    grey_thumbnail_region(frame, size, [0.0, 0.0, w, h])
}

/// `grey_thumbnail` of one region of the frame, `[x0, y0, x1, y1]` in
/// pixels (clamped to the frame): a person's own box, so that the pixels of
/// the people beside them stay out of their signal. A region with no pixel in
/// the frame gives zeros.
pub fn grey_thumbnail_region(frame: &Frame, size: usize, region: [f64; 4]) -> Result<Vec<f32>> {
    frame.validate()?;
    if size == 0 {
        return Err(PoseError::param("thumbnail size", "must be at least 1"));
    }
    if region.iter().any(|v| !v.is_finite()) {
        return Err(PoseError::param(
            "thumbnail region",
            format!("must be finite, got {region:?}"),
        ));
    }
    let (w, h) = (frame.width, frame.height);
    let clamp = |v: f64, n: usize| (v.round().max(0.0) as usize).min(n);
    let (x0, x1) = (clamp(region[0], w), clamp(region[2], w));
    let (y0, y1) = (clamp(region[1], h), clamp(region[3], h));
    let mut sum = vec![0.0f64; size * size];
    let mut count = vec![0u32; size * size];
    if x1 > x0 && y1 > y0 {
        let (rw, rh) = (x1 - x0, y1 - y0);
        let col: Vec<usize> = (0..rw).map(|x| x * size / rw).collect();
        for y in y0..y1 {
            let row = ((y - y0) * size / rh) * size;
            let line = &frame.rgb[(y * w + x0) * 3..(y * w + x1) * 3];
            for (x, px) in line.chunks_exact(3).enumerate() {
                let l = 0.299 * px[0] as f64 + 0.587 * px[1] as f64 + 0.114 * px[2] as f64;
                let c = row + col[x];
                sum[c] += l;
                count[c] += 1;
            }
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
/// (its dimensions), so the channels run row-major as in the thumbnail (8
/// bytes per cell and frame). Where a long video's thumbnails are gathered,
/// gather them in one buffer and use [`Thumbnails::from_flat`].
pub fn thumbnail_track(thumbs: Vec<Vec<f32>>, size: usize, fps: f64) -> Result<Track> {
    let c = size * size;
    if let Some((t, th)) = thumbs.iter().enumerate().find(|(_, th)| th.len() != c) {
        return Err(PoseError::param(
            "thumbnails",
            format!(
                "frame {t} has {} values, a {size}×{size} grid has {c}",
                th.len()
            ),
        ));
    }
    Thumbnails::from_flat(thumbs.concat(), size, fps)?.track()
}

/// Grey thumbnails of consecutive frames, `frames × side × side` cells, as
/// 4-byte floats: half the bytes of the unitless feature track that counting
/// reads ([`Thumbnails::track`], 8 bytes a cell), which is made only when a
/// signal is read from them. An hour's 16 × 16 thumbnails are held in
/// 115 MB instead of 229 MB until then.
#[derive(Debug, Clone, PartialEq)]
pub struct Thumbnails {
    values: Array3<f32>,
    fps: f64,
}

impl Thumbnails {
    /// Thumbnails laid out as `frames × side × side` (e.g. written frame by
    /// frame); at least one frame, square, finite, at a positive frame rate.
    pub fn new(values: Array3<f32>, fps: f64) -> Result<Self> {
        let (n, rows, cols) = values.dim();
        if n == 0 || rows == 0 {
            return Err(PoseError::param("thumbnails", "no frames"));
        }
        if rows != cols {
            return Err(PoseError::param(
                "thumbnails",
                format!("cells must form a square grid, got {rows}×{cols}"),
            ));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(PoseError::param("fps", format!("must be > 0, got {fps}")));
        }
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(PoseError::param(
                "thumbnails",
                format!("a cell holds {v}, not a grey level"),
            ));
        }
        Ok(Thumbnails { values, fps })
    }

    /// Thumbnails held one after the other in one buffer, `size × size`
    /// values a frame.
    pub fn from_flat(values: Vec<f32>, size: usize, fps: f64) -> Result<Self> {
        let c = size * size;
        if values.is_empty() || c == 0 {
            return Err(PoseError::param("thumbnails", "no frames"));
        }
        if !values.len().is_multiple_of(c) {
            return Err(PoseError::param(
                "thumbnails",
                format!(
                    "{} values are not whole {size}×{size} grids of {c}",
                    values.len()
                ),
            ));
        }
        let n = values.len() / c;
        let a = Array3::from_shape_vec((n, size, size), values)
            .map_err(|e| PoseError::param("thumbnails", e.to_string()))?;
        Self::new(a, fps)
    }

    /// A video's frame signal: [`Thumbnails::from_flat`], first reduced to
    /// [`signal_side`] cells a side where the thumbnails hold more than
    /// [`MAX_SIGNAL_VALUES`] values (each cell the mean of the cells it
    /// covers; for a video whose length was not known when it was read).
    pub fn signal(values: Vec<f32>, size: usize, fps: f64) -> Result<Self> {
        let c = size * size;
        let frames = values.len().checked_div(c).unwrap_or(0);
        let side = signal_side(size, frames);
        if side == size || values.len() != frames * c {
            return Self::from_flat(values, size, fps);
        }
        let mut reduced = Vec::with_capacity(frames * side * side);
        for th in values.chunks_exact(c) {
            reduced.extend(pooled(th, size, side));
        }
        drop(values);
        Self::from_flat(reduced, side, fps)
    }

    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.values.dim().0
    }

    /// Cells a side.
    pub fn side(&self) -> usize {
        self.values.dim().1
    }

    /// Frames per second.
    pub fn fps(&self) -> f64 {
        self.fps
    }

    /// The cells, `frames × side × side`.
    pub fn values(&self) -> ArrayView3<'_, f32> {
        self.values.view()
    }

    /// The thumbnails as a unitless feature track: `frames` × `side` rows
    /// (the track's "joints", confidence 1) × `side` cells per row (its
    /// dimensions), so the channels run row-major as in the thumbnail.
    pub fn track(&self) -> Result<Track> {
        Ok(Track::new(
            self.values.mapv(f64::from),
            None,
            self.fps,
            Units::Unitless,
            Skeleton::generic(self.side()),
        )?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_video_s_signal_is_kept_within_its_budget() {
        assert_eq!(signal_side(32, 0), 32);
        assert_eq!(signal_side(32, 32_768), 32);
        assert_eq!(signal_side(32, 32_769), 16);
        assert_eq!(signal_side(32, 111_975), 16);
        assert_eq!(signal_side(32, 131_073), 8);
        assert_eq!(signal_side(31, 40_000), 16);
        assert_eq!(signal_side(1, usize::MAX), 1);
        for n in [1usize, 5_000, 40_000, 200_000, 10_000_000] {
            let side = signal_side(32, n);
            assert!(
                n * side * side <= MAX_SIGNAL_VALUES || side == 1,
                "{n}: {side}"
            );
        }
    }

    #[test]
    fn pooled_cells_are_the_means_of_the_cells_they_cover() {
        // 4 × 4 cells k = 0..16 pooled to 2 × 2: the top-left cell covers
        // 0, 1, 4, 5.
        let th: Vec<f32> = (0..16).map(|k| k as f32).collect();
        assert_eq!(pooled(&th, 4, 2), vec![2.5, 4.5, 10.5, 12.5]);
        // A frame's 16-cell thumbnail equals its 32-cell one pooled, up to
        // the cells' unequal pixel counts (here 20 × 11.25 px).
        let (w, h) = (640usize, 360usize);
        let rgb: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let v = ((i % w) * 255 / w + (i / w) * 97 % 255) as u8;
                [v, v, v]
            })
            .collect();
        let frame = Frame {
            index: 0,
            timestamp_s: 0.0,
            width: w,
            height: h,
            rgb,
        };
        let fine = grey_thumbnail(&frame, 32).unwrap();
        let coarse = grey_thumbnail(&frame, 16).unwrap();
        let p = pooled(&fine, 32, 16);
        for (a, b) in p.iter().zip(&coarse) {
            assert!((a - b).abs() < 1.0, "{a} vs {b}");
        }
        let signal = Thumbnails::signal(fine.repeat(40_000), 32, 30.0).unwrap();
        assert_eq!((signal.n_frames(), signal.side()), (40_000, 16));
        assert_eq!(signal.values()[[7, 0, 1]], p[1]);
        let track = signal.track().unwrap();
        assert_eq!(
            (track.n_frames(), track.n_joints(), track.dims()),
            (40_000, 16, 16)
        );
        assert_eq!(track.positions()[[7, 0, 1]], f64::from(p[1]));
    }

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
    fn a_region_reads_only_its_own_pixels() {
        // Left half white, right half black: the right half's thumbnail is black,
        // the whole frame's region equals the whole-frame thumbnail.
        let fr = frame(8, 6, |x, _| if x < 4 { [255; 3] } else { [0; 3] });
        let right = grey_thumbnail_region(&fr, 2, [4.0, 0.0, 8.0, 6.0]).unwrap();
        assert!(right.iter().all(|v| v.abs() < 1e-3), "{right:?}");
        let whole = grey_thumbnail_region(&fr, 2, [-10.0, -10.0, 100.0, 100.0]).unwrap();
        assert_eq!(whole, grey_thumbnail(&fr, 2).unwrap());
        let outside = grey_thumbnail_region(&fr, 2, [20.0, 20.0, 30.0, 30.0]).unwrap();
        assert_eq!(outside, vec![0.0; 4]);
        assert!(grey_thumbnail_region(&fr, 2, [f64::NAN, 0.0, 1.0, 1.0]).is_err());
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
        // Thumbnails that are no square grid of grey levels are refused.
        assert!(Thumbnails::new(Array3::zeros((2, 3, 4)), 30.0).is_err());
        assert!(Thumbnails::new(Array3::zeros((0, 3, 3)), 30.0).is_err());
        assert!(Thumbnails::new(Array3::zeros((2, 3, 3)), 0.0).is_err());
        assert!(Thumbnails::new(Array3::from_elem((2, 3, 3), f32::NAN), 30.0).is_err());
        assert!(Thumbnails::from_flat(vec![0.0; 17], 4, 30.0).is_err());
    }
}
