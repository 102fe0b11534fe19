//! Video frames kept for the pictures and the report: reduced in size and
//! stored as JPEG, so memory stays small whatever the video's length.

use image::imageops::FilterType;

use crate::error::{ReportError, Result};
use crate::raster::{decode_rgb, encode_jpeg};

/// Parameters of a [`FrameStore`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameStoreParams {
    /// Longest side of a stored frame in pixels (frames are only reduced). Default 480.
    pub max_side_px: usize,
    /// JPEG quality, 1–100. Default 72.
    pub jpeg_quality: u8,
    /// At most this many frames are kept; longer videos keep every k-th frame. Default 1200.
    pub max_frames: usize,
}

impl Default for FrameStoreParams {
    fn default() -> Self {
        FrameStoreParams {
            max_side_px: 480,
            jpeg_quality: 72,
            max_frames: 1200,
        }
    }
}

impl FrameStoreParams {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        if self.max_side_px < 16 {
            return Err(ReportError::param(
                "max_side_px",
                format!("must be ≥ 16, got {}", self.max_side_px),
            ));
        }
        if !(1..=100).contains(&self.jpeg_quality) {
            return Err(ReportError::param(
                "jpeg_quality",
                format!("must be in 1..=100, got {}", self.jpeg_quality),
            ));
        }
        if self.max_frames == 0 {
            return Err(ReportError::param("max_frames", "must be ≥ 1"));
        }
        Ok(())
    }
}

/// Reduced JPEG copies of a video's frames.
#[derive(Debug, Clone)]
pub struct FrameStore {
    /// Size of the original frames.
    pub source_size: (usize, usize),
    /// Size of the stored frames.
    pub size: (usize, usize),
    /// Every `step`-th frame is kept.
    pub step: usize,
    /// (frame index, JPEG bytes), in frame order.
    pub frames: Vec<(usize, Vec<u8>)>,
    quality: u8,
}

impl FrameStore {
    /// A store for frames of `width × height`; `expected_frames` (when known)
    /// decides how many are kept.
    pub fn new(
        width: usize,
        height: usize,
        expected_frames: Option<usize>,
        params: &FrameStoreParams,
    ) -> Result<Self> {
        params.validate()?;
        if width == 0 || height == 0 {
            return Err(ReportError::Mismatch(format!(
                "empty frame size {width}×{height}"
            )));
        }
        let s = params.max_side_px as f64 / width.max(height) as f64;
        // Frames within 10 % of the size are kept as they are (no resampling).
        let s = if s >= 0.9 { 1.0 } else { s };
        let size = (
            ((width as f64 * s).round() as usize).max(1),
            ((height as f64 * s).round() as usize).max(1),
        );
        let step = expected_frames.map_or(1, |n| n.div_ceil(params.max_frames).max(1));
        Ok(FrameStore {
            source_size: (width, height),
            size,
            step,
            frames: Vec::new(),
            quality: params.jpeg_quality,
        })
    }

    /// Stored pixels per original pixel.
    pub fn scale(&self) -> f64 {
        self.size.0 as f64 / self.source_size.0 as f64
    }

    /// Keeps frame `index` (RGB, original size) when it falls on the step.
    pub fn push(&mut self, index: usize, rgb: &[u8]) -> Result<()> {
        if !index.is_multiple_of(self.step) {
            return Ok(());
        }
        let (w, h) = self.source_size;
        let img = image::RgbImage::from_raw(w as u32, h as u32, rgb.to_vec()).ok_or_else(|| {
            ReportError::Image {
                what: format!("frame {index}"),
                reason: format!("{} bytes for a {w}×{h} RGB frame", rgb.len()),
            }
        })?;
        let small = if self.size == self.source_size {
            img
        } else {
            image::imageops::resize(
                &img,
                self.size.0 as u32,
                self.size.1 as u32,
                FilterType::Triangle,
            )
        };
        let jpg = encode_jpeg(small.as_raw(), self.size.0, self.size.1, self.quality)?;
        self.frames.push((index, jpg));
        Ok(())
    }

    /// Position in [`FrameStore::frames`] of the stored frame nearest at or before `index`.
    pub fn nearest(&self, index: usize) -> Option<usize> {
        if self.frames.is_empty() {
            return None;
        }
        let p = self.frames.partition_point(|(i, _)| *i <= index);
        Some(p.saturating_sub(1))
    }

    /// Decoded RGB of stored frame `pos` (a position in [`FrameStore::frames`]).
    pub fn rgb(&self, pos: usize) -> Result<Vec<u8>> {
        let (index, jpg) = self
            .frames
            .get(pos)
            .ok_or_else(|| ReportError::Mismatch(format!("no stored frame at position {pos}")))?;
        let (rgb, w, h) = decode_rgb(jpg, &format!("frame {index}"))?;
        if (w, h) != self.size {
            return Err(ReportError::Mismatch(format!(
                "stored frame {index} is {w}×{h}, expected {}×{}",
                self.size.0, self.size.1
            )));
        }
        Ok(rgb)
    }

    /// Total bytes of the stored JPEGs.
    pub fn bytes(&self) -> usize {
        self.frames.iter().map(|(_, j)| j.len()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_reduced_and_subsampled() {
        let p = FrameStoreParams {
            max_side_px: 50,
            max_frames: 5,
            ..Default::default()
        };
        let mut s = FrameStore::new(100, 60, Some(10), &p).unwrap();
        assert_eq!(s.size, (50, 30));
        assert_eq!(s.step, 2);
        let rgb = vec![200u8; 100 * 60 * 3];
        for i in 0..10 {
            s.push(i, &rgb).unwrap();
        }
        assert_eq!(s.frames.len(), 5);
        assert_eq!(s.nearest(3), Some(1));
        assert_eq!(s.nearest(100), Some(4));
        let back = s.rgb(0).unwrap();
        assert_eq!(back.len(), 50 * 30 * 3);
        assert!(s.push(0, &rgb[..10]).is_err());
        assert!(s.rgb(9).is_err());
    }
}
