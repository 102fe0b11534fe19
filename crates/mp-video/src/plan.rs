//! Output videos as plans over the source's frames, rendered while the
//! source streams, and written atomically.
//!
//! A [`Plan`] lists the output frames, each a source frame or a blend of
//! two. [`Plan::render`] decodes the source once, front to back, and keeps only
//! the frames that a later output frame still needs (a repeated iteration,
//! a cross-fade), so memory is bounded by what the plan reuses, not by the
//! video's length; a plan that would hold more than
//! [`RenderParams::memory_budget_bytes`] at once is an error before anything
//! is written.

use std::collections::HashMap;
use std::path::Path;

use mp_pose::{VideoReader, VideoWriter};

use crate::error::{Result, VideoError};

/// One output frame: source frame `a`, blended with source frame `b` by
/// weight `w` (`out = (1 − w)·a + w·b`; `w = 0` copies `a`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanFrame {
    /// First source frame.
    pub a: usize,
    /// Second source frame.
    pub b: usize,
    /// Weight of `b`, in `[0, 1]`.
    pub w: f32,
}

impl PlanFrame {
    /// A copy of source frame `i`.
    pub fn copy(i: usize) -> Self {
        PlanFrame { a: i, b: i, w: 0.0 }
    }

    /// A blend of `a` and `b` with weight `w` on `b`.
    pub fn blend(a: usize, b: usize, w: f32) -> Self {
        PlanFrame {
            a,
            b,
            w: w.clamp(0.0, 1.0),
        }
    }

    fn sources(&self) -> (usize, Option<usize>) {
        if self.w <= 0.0 || self.a == self.b {
            (self.a, None)
        } else if self.w >= 1.0 {
            (self.b, None)
        } else {
            (self.a, Some(self.b))
        }
    }
}

/// The frames of an output video.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Plan {
    /// Output frames in order.
    pub frames: Vec<PlanFrame>,
}

impl Plan {
    /// Source frames `range` copied in order.
    pub fn push_range(&mut self, range: std::ops::Range<usize>) {
        self.frames.extend(range.map(PlanFrame::copy));
    }

    /// Number of output frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether the plan has no frame.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The largest source frame used.
    pub fn max_source(&self) -> Option<usize> {
        self.frames
            .iter()
            .map(|f| {
                let (a, b) = f.sources();
                b.map_or(a, |b| a.max(b))
            })
            .max()
    }

    /// Most source frames held at once when rendered (the cache's peak).
    pub fn peak_frames(&self) -> usize {
        let last = self.last_uses();
        // A frame is held from when it is read (when the output first needs a
        // frame at or after it) until its last use.
        let mut events: Vec<(usize, i64)> = Vec::new();
        let mut read_upto = 0usize;
        for (i, f) in self.frames.iter().enumerate() {
            let (a, b) = f.sources();
            let need = b.map_or(a, |b| a.max(b)) + 1;
            while read_upto < need {
                if let Some(&l) = last.get(&read_upto) {
                    events.push((i, 1));
                    events.push((l + 1, -1));
                }
                read_upto += 1;
            }
        }
        events.sort();
        let (mut cur, mut peak) = (0i64, 0i64);
        for (_, d) in events {
            cur += d;
            peak = peak.max(cur);
        }
        peak.max(0) as usize
    }

    /// Renders the plan from the video at `path`, handing each output frame
    /// (RGB bytes) to `sink` in order. Returns the number of frames produced.
    pub fn render(
        &self,
        path: &Path,
        params: &RenderParams,
        mut sink: impl FnMut(&[u8]) -> Result<()>,
    ) -> Result<usize> {
        let mut reader = VideoReader::open(path)?;
        let info = reader.info().clone();
        let frame_bytes = info.width * info.height * 3;
        let peak = self.peak_frames();
        if peak.saturating_mul(frame_bytes) > params.memory_budget_bytes {
            return Err(VideoError::Memory {
                frames: peak,
                mb: peak.saturating_mul(frame_bytes) >> 20,
                budget_mb: params.memory_budget_bytes >> 20,
            });
        }
        let last = self.last_uses();
        let mut cache: HashMap<usize, Vec<u8>> = HashMap::new();
        let mut next_read = 0usize;
        for (i, f) in self.frames.iter().enumerate() {
            let (a, b) = f.sources();
            let need = b.map_or(a, |b| a.max(b));
            while next_read <= need {
                let frame = reader.next().ok_or_else(|| {
                    VideoError::Edit(format!(
                        "{} has {next_read} frames, the output needs frame {need}",
                        path.display()
                    ))
                })??;
                if last.contains_key(&next_read) {
                    cache.insert(next_read, frame.rgb);
                }
                next_read += 1;
            }
            let fa = cache
                .get(&a)
                .ok_or_else(|| VideoError::Edit(format!("frame {a} is not held")))?;
            match b {
                None => sink(fa)?,
                Some(b) => {
                    let fb = cache
                        .get(&b)
                        .ok_or_else(|| VideoError::Edit(format!("frame {b} is not held")))?;
                    sink(&blend(fa, fb, f.w))?
                }
            }
            for s in [Some(a), b].into_iter().flatten() {
                if last.get(&s) == Some(&i) {
                    cache.remove(&s);
                }
            }
        }
        Ok(self.len())
    }

    fn last_uses(&self) -> HashMap<usize, usize> {
        let mut last = HashMap::new();
        for (i, f) in self.frames.iter().enumerate() {
            let (a, b) = f.sources();
            last.insert(a, i);
            if let Some(b) = b {
                last.insert(b, i);
            }
        }
        last
    }
}

/// Parameters of [`Plan::render`].
#[derive(Debug, Clone, PartialEq)]
pub struct RenderParams {
    /// Most bytes of source frames held at once. Default 1 GiB.
    pub memory_budget_bytes: usize,
    /// x264 preset of the output. Default `veryfast`.
    pub preset: &'static str,
}

impl Default for RenderParams {
    fn default() -> Self {
        RenderParams {
            memory_budget_bytes: 1 << 30,
            preset: "veryfast",
        }
    }
}

/// `(1 − w)·a + w·b`, per byte.
pub fn blend(a: &[u8], b: &[u8], w: f32) -> Vec<u8> {
    let w = w.clamp(0.0, 1.0);
    a.iter()
        .zip(b)
        .map(|(&x, &y)| ((1.0 - w) * x as f32 + w * y as f32).round() as u8)
        .collect()
}

/// Renders `plan` from `input` into the video file `output` at `fps`
/// (written atomically). Returns the number of frames written.
pub(crate) fn render_to_file(
    input: &Path,
    plan: &Plan,
    output: &Path,
    fps: f64,
    params: &RenderParams,
) -> Result<usize> {
    let info = mp_pose::probe(input)?;
    let mut out = AtomicVideo::create(output, info.width, info.height, fps, params.preset)?;
    plan.render(input, params, |rgb| out.write(rgb))?;
    out.finish()
}

/// A video written to a temporary file in the output's folder and renamed
/// onto the output when finished; dropped unfinished, the temporary file is
/// removed and the output is left as it was.
pub struct AtomicVideo {
    writer: Option<VideoWriter>,
    file: Option<mp_geom::PartialFile>,
}

impl AtomicVideo {
    /// Starts the encoder (H.264; `preset` one of `mp_pose::X264_PRESETS`).
    pub fn create(
        target: &Path,
        width: usize,
        height: usize,
        fps: f64,
        preset: &str,
    ) -> Result<Self> {
        // Registered, so an interrupted process removes it (see `mp_geom::PartialFile`).
        let file = mp_geom::PartialFile::new(target)?;
        let writer = VideoWriter::create_with_preset(file.path(), width, height, fps, preset)?;
        Ok(AtomicVideo {
            writer: Some(writer),
            file: Some(file),
        })
    }

    /// Appends one RGB frame.
    pub fn write(&mut self, rgb: &[u8]) -> Result<()> {
        match self.writer.as_mut() {
            Some(w) => Ok(w.write(rgb)?),
            None => Err(VideoError::Edit("the encoder is closed".into())),
        }
    }

    /// Finishes encoding and renames the file onto the target; returns the
    /// number of frames written.
    pub fn finish(mut self) -> Result<usize> {
        let (Some(writer), Some(file)) = (self.writer.take(), self.file.take()) else {
            return Err(VideoError::Edit("the encoder is closed".into()));
        };
        let n = writer.finish()?;
        file.commit()?;
        Ok(n)
    }
}

impl Drop for AtomicVideo {
    fn drop(&mut self) {
        // The encoder stops before its temporary file is removed.
        drop(self.writer.take());
        drop(self.file.take());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_counts_reused_frames() {
        let mut p = Plan::default();
        p.push_range(0..10);
        assert_eq!(p.peak_frames(), 1);
        p.push_range(5..10);
        assert_eq!(p.peak_frames(), 5);
        let mut q = Plan::default();
        q.frames.push(PlanFrame::blend(0, 3, 0.5));
        assert_eq!(q.peak_frames(), 2);
        assert_eq!(q.max_source(), Some(3));
    }

    #[test]
    fn blend_weights() {
        assert_eq!(blend(&[0, 100], &[100, 200], 0.5), vec![50, 150]);
        assert_eq!(blend(&[0], &[100], 0.0), vec![0]);
    }
}
