//! Progress of a run: the stages, their timings, and the observer that a
//! caller (a progress bar, a GUI, a batch manifest) passes in.

use std::time::Duration;

use mp_geom::CancelToken;

use crate::error::{PipelineError, Result};

/// The stages of a run, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Stage {
    /// Video decoding (FFmpeg), on its own thread alongside the pose model.
    Decode,
    /// Reduced JPEG copies of the frames for the report, alongside the pose model.
    Jpeg,
    /// Pose model loading and inference.
    Pose,
    /// Concrete program: segmentation and primitive fits.
    Concrete,
    /// Abstract program and loops.
    Abstract,
    /// Repetition counting.
    Count,
    /// Programs and counts of the other people in view (in parallel).
    People,
    /// Grey thumbnails of each analysed person's own box (a second decoding pass).
    Boxes,
    /// Where the picture moves on its own, and the frame signal counting reads.
    Motion,
    /// Plots, timeline and contact sheet.
    Pictures,
    /// Overlay video.
    Overlay,
    /// The report page.
    Report,
}

impl Stage {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Decode => "decode",
            Stage::Jpeg => "jpeg",
            Stage::Pose => "pose",
            Stage::Concrete => "concrete",
            Stage::Abstract => "abstract",
            Stage::Count => "count",
            Stage::People => "people",
            Stage::Boxes => "boxes",
            Stage::Motion => "motion",
            Stage::Pictures => "pictures",
            Stage::Overlay => "overlay",
            Stage::Report => "report",
        }
    }

    /// What the stage covers and what it runs alongside.
    pub fn note(self) -> &'static str {
        match self {
            Stage::Decode => "FFmpeg rgb24 pipe and frame thumbnails, own thread alongside pose",
            Stage::Jpeg => "reduced JPEG copies for the report: FFmpeg mjpeg alongside pose (long videos: on the decoding thread)",
            Stage::Pose => "model loading + inference (waits on decoding included)",
            Stage::Concrete => "segmentation and primitive fits",
            Stage::Abstract => "abstract program and loops",
            Stage::Count => "repetition intervals and counts",
            Stage::People => "programs and counts of the other people, in parallel",
            Stage::Boxes => "second FFmpeg pass: grey thumbnails of each person's own box",
            Stage::Motion => "motion energy of the thumbnails (camera motion discounted) and the periodicity of the regions where it gathers",
            Stage::Pictures => "plots (SVG + PNG), timeline, contact sheet",
            Stage::Overlay => "own thread, alongside boxes, counting and people; drawn into YUV frames + H.264",
            Stage::Report => "the page, its frames as JPEG files and its data in chunks (report/)",
        }
    }
}

/// Time spent in one stage.
#[derive(Debug, Clone, PartialEq)]
pub struct StageTime {
    /// The stage.
    pub stage: Stage,
    /// Wall time.
    pub time: Duration,
    /// Frames processed by the stage (for frames per second).
    pub frames: usize,
    /// The process's peak resident set when the stage ended, bytes (where
    /// the system tells it: Linux); the stage where it rises is the one
    /// that needed the memory (or a stage running beside it).
    pub peak_bytes: Option<u64>,
}

impl StageTime {
    /// A stage's time, with the process's peak resident set now.
    pub fn now(stage: Stage, time: Duration, frames: usize) -> Self {
        StageTime {
            stage,
            time,
            frames,
            peak_bytes: peak_resident_bytes(),
        }
    }
}

/// The process's peak resident set so far (`VmHWM` of `/proc/self/status`),
/// bytes; `None` where the system does not tell it.
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Receives the progress of a run. Every method has an empty default; the
/// methods may be called from several threads at once.
pub trait Observer: Sync {
    /// A stage starts; `total` is its number of steps when known.
    fn started(&self, _stage: Stage, _total: Option<usize>) {}
    /// `done` steps of a stage are finished.
    fn progress(&self, _stage: Stage, _done: usize) {}
    /// A stage is finished.
    fn finished(&self, _time: &StageTime) {}
}

/// An observer that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Observer for Silent {}

/// `Err(PipelineError::Cancelled)` once `cancel` is cancelled.
pub fn check(cancel: &CancelToken) -> Result<()> {
    if cancel.is_cancelled() {
        Err(PipelineError::Cancelled)
    } else {
        Ok(())
    }
}

/// Stage timings collected during a run, each also reported to the observer.
pub(crate) struct Timings<'a> {
    pub(crate) stages: Vec<StageTime>,
    observer: &'a dyn Observer,
}

impl<'a> Timings<'a> {
    pub(crate) fn new(observer: &'a dyn Observer) -> Self {
        Timings {
            stages: Vec::new(),
            observer,
        }
    }

    pub(crate) fn observer(&self) -> &'a dyn Observer {
        self.observer
    }

    pub(crate) fn push(&mut self, stage: Stage, time: Duration, frames: usize) {
        let t = StageTime::now(stage, time, frames);
        self.observer.finished(&t);
        self.stages.push(t);
    }
}
