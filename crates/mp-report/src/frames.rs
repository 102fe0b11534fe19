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
        let jpg = self.encoder()(index, rgb)?;
        self.frames.push((index, jpg));
        Ok(())
    }

    /// What [`FrameStore::push`] keeps of a frame — frame `index` (RGB,
    /// original size) reduced to the store's size and encoded as JPEG — as
    /// a function that may run on another thread (e.g. the one decoding
    /// the video); [`FrameStore::push_jpeg`] then keeps its result.
    pub fn encoder(&self) -> impl Fn(usize, &[u8]) -> Result<Vec<u8>> + Send + Sync + 'static {
        let ((w, h), size, quality) = (self.source_size, self.size, self.quality);
        move |index, rgb| {
            // The frame read in place (no copy of its pixels).
            let img =
                image::ImageBuffer::<image::Rgb<u8>, &[u8]>::from_raw(w as u32, h as u32, rgb)
                    .ok_or_else(|| ReportError::Image {
                        what: format!("frame {index}"),
                        reason: format!("{} bytes for a {w}×{h} RGB frame", rgb.len()),
                    })?;
            if size == (w, h) {
                return encode_jpeg(rgb, w, h, quality);
            }
            let small =
                image::imageops::resize(&img, size.0 as u32, size.1 as u32, FilterType::Triangle);
            encode_jpeg(small.as_raw(), size.0, size.1, quality)
        }
    }

    /// Whether frame `index` is one the store keeps (it falls on the step).
    pub fn wants(&self, index: usize) -> bool {
        index.is_multiple_of(self.step)
    }

    /// Keeps frame `index` from a JPEG made elsewhere (e.g. by FFmpeg's
    /// `mjpeg` encoder) at [`FrameStore::size`]; frames off the step are
    /// skipped. The JPEG's size is checked against the store's.
    pub fn push_jpeg(&mut self, index: usize, jpeg: Vec<u8>) -> Result<()> {
        if !self.wants(index) {
            return Ok(());
        }
        let what = || format!("frame {index}");
        let (w, h) = jpeg_size(&jpeg).ok_or_else(|| ReportError::Image {
            what: what(),
            reason: "not a baseline or progressive JPEG (no frame header)".into(),
        })?;
        if (w, h) != self.size {
            return Err(ReportError::Image {
                what: what(),
                reason: format!(
                    "JPEG is {w}×{h}, the store keeps {}×{}",
                    self.size.0, self.size.1
                ),
            });
        }
        if self.frames.last().is_some_and(|(last, _)| *last >= index) {
            return Err(ReportError::Mismatch(format!(
                "frame {index} stored out of order"
            )));
        }
        self.frames.push((index, jpeg));
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

/// Width and height from a JPEG's frame header (SOF0–SOF15 except DHT,
/// JPG and DAC), or `None` when there is none before the first scan.
pub fn jpeg_size(jpeg: &[u8]) -> Option<(usize, usize)> {
    if jpeg.get(..2) != Some(&[0xFF, 0xD8][..]) {
        return None;
    }
    let mut i = 2;
    while i + 4 <= jpeg.len() {
        if jpeg[i] != 0xFF {
            return None;
        }
        let marker = jpeg[i + 1];
        if marker == 0xFF {
            i += 1;
            continue;
        }
        let len = u16::from_be_bytes([jpeg[i + 2], jpeg[i + 3]]) as usize;
        if (0xC0..=0xCF).contains(&marker) && !matches!(marker, 0xC4 | 0xC8 | 0xCC) {
            let h = u16::from_be_bytes([*jpeg.get(i + 5)?, *jpeg.get(i + 6)?]) as usize;
            let w = u16::from_be_bytes([*jpeg.get(i + 7)?, *jpeg.get(i + 8)?]) as usize;
            return Some((w, h));
        }
        if marker == 0xDA || len < 2 {
            return None;
        }
        i += 2 + len;
    }
    None
}

/// Reads the next JPEG from a stream of JPEG files written back to back
/// (FFmpeg's `image2pipe` output): from its start-of-image marker through
/// its end-of-image marker, following segment lengths and skipping over
/// entropy-coded data. `Ok(None)` at the end of the stream; a stream that
/// ends inside a JPEG, or bytes that are not a JPEG, are an error naming
/// `what` and the image's position in the stream (`number`).
pub fn read_jpeg(
    r: &mut impl std::io::BufRead,
    what: &str,
    number: usize,
) -> Result<Option<Vec<u8>>> {
    let bad = |reason: String| ReportError::Image {
        what: format!("{what}, image {number}"),
        reason,
    };
    let io = |e: std::io::Error| bad(e.to_string());
    let mut out = Vec::new();
    // Start of image, or the end of the stream.
    let mut soi = [0u8; 2];
    let mut got = 0;
    while got < 2 {
        let n = r.read(&mut soi[got..]).map_err(io)?;
        if n == 0 {
            break;
        }
        got += n;
    }
    match got {
        0 => return Ok(None),
        2 if soi == [0xFF, 0xD8] => out.extend_from_slice(&soi),
        _ => return Err(bad("not a JPEG (no start-of-image marker)".into())),
    }
    let truncated = || bad("the stream ends inside the image".into());
    let byte = |r: &mut dyn std::io::BufRead, out: &mut Vec<u8>| -> Result<u8> {
        let mut b = [0u8; 1];
        r.read_exact(&mut b).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                truncated()
            } else {
                io(e)
            }
        })?;
        out.push(b[0]);
        Ok(b[0])
    };
    // `pending`: a marker byte already read while scanning entropy-coded data.
    let mut pending: Option<u8> = None;
    loop {
        let marker = match pending.take() {
            Some(m) => m,
            None => {
                if byte(r, &mut out)? != 0xFF {
                    return Err(bad("expected a marker".into()));
                }
                let mut m = byte(r, &mut out)?;
                while m == 0xFF {
                    m = byte(r, &mut out)?;
                }
                m
            }
        };
        match marker {
            0xD9 => return Ok(Some(out)),
            0xD0..=0xD7 | 0x01 => continue,
            _ => {}
        }
        let hi = byte(r, &mut out)?;
        let lo = byte(r, &mut out)?;
        let len = u16::from_be_bytes([hi, lo]) as usize;
        if len < 2 {
            return Err(bad(format!("segment 0xFF{marker:02X} has length {len}")));
        }
        let start = out.len();
        out.resize(start + len - 2, 0);
        r.read_exact(&mut out[start..]).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                truncated()
            } else {
                io(e)
            }
        })?;
        if marker != 0xDA {
            continue;
        }
        // Entropy-coded data: up to the next marker that is not a stuffed
        // zero or a restart marker.
        loop {
            let buf = r.fill_buf().map_err(io)?;
            if buf.is_empty() {
                return Err(truncated());
            }
            match buf.iter().position(|&b| b == 0xFF) {
                None => {
                    let n = buf.len();
                    out.extend_from_slice(buf);
                    r.consume(n);
                }
                Some(p) => {
                    out.extend_from_slice(&buf[..p]);
                    r.consume(p);
                    byte(r, &mut out)?; // the 0xFF
                    let mut m = byte(r, &mut out)?;
                    while m == 0xFF {
                        m = byte(r, &mut out)?;
                    }
                    if m == 0x00 || (0xD0..=0xD7).contains(&m) {
                        continue;
                    }
                    pending = Some(m);
                    break;
                }
            }
        }
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

    fn test_jpeg(w: usize, h: usize, shade: u8) -> Vec<u8> {
        let rgb: Vec<u8> = (0..w * h * 3)
            .map(|i| shade.wrapping_add((i % 251) as u8))
            .collect();
        encode_jpeg(&rgb, w, h, 80).unwrap()
    }

    #[test]
    fn jpeg_stream_splits_into_the_images() {
        let a = test_jpeg(40, 30, 0);
        let b = test_jpeg(17, 9, 90);
        assert_eq!(jpeg_size(&a), Some((40, 30)));
        assert_eq!(jpeg_size(&b), Some((17, 9)));
        assert_eq!(jpeg_size(&a[2..]), None);
        let mut stream = a.clone();
        stream.extend_from_slice(&b);
        stream.extend_from_slice(&a);
        // A small buffer makes the reader cross buffer ends inside segments and scans.
        let mut r = std::io::BufReader::with_capacity(7, &stream[..]);
        let got: Vec<Vec<u8>> = (0..)
            .map_while(|k| read_jpeg(&mut r, "test", k).unwrap())
            .collect();
        assert_eq!(got, vec![a.clone(), b.clone(), a.clone()]);
        // Truncated: an error naming the stream and the image.
        let cut = &stream[..a.len() + b.len() / 2];
        let mut r = std::io::BufReader::new(cut);
        assert!(read_jpeg(&mut r, "test", 0).unwrap().is_some());
        let e = read_jpeg(&mut r, "frames of x.mp4", 1).unwrap_err();
        assert!(e.to_string().contains("x.mp4, image 1"), "{e}");
        // Not a JPEG.
        let mut r = std::io::BufReader::new(&b"GIF89a"[..]);
        assert!(read_jpeg(&mut r, "test", 0).is_err());
    }

    #[test]
    fn store_takes_ready_jpegs_on_its_step() {
        let p = FrameStoreParams {
            max_side_px: 40,
            max_frames: 2,
            ..Default::default()
        };
        let mut s = FrameStore::new(40, 30, Some(4), &p).unwrap();
        assert_eq!((s.size, s.step), ((40, 30), 2));
        for i in 0..4 {
            s.push_jpeg(i, test_jpeg(40, 30, i as u8)).unwrap();
        }
        assert_eq!(
            s.frames.iter().map(|(i, _)| *i).collect::<Vec<_>>(),
            vec![0, 2]
        );
        assert_eq!(s.rgb(1).unwrap().len(), 40 * 30 * 3);
        // Wrong size, out of order, not a JPEG.
        assert!(s.push_jpeg(4, test_jpeg(20, 30, 0)).is_err());
        assert!(s.push_jpeg(2, test_jpeg(40, 30, 0)).is_err());
        assert!(s.push_jpeg(6, vec![1, 2, 3]).is_err());
    }
}
