//! Live analysis: frames are read from a file or a stream (standard input)
//! as they arrive, every person in view is tracked with the pose model and
//! tracker of `mp run`, and each person's repetitions are counted online, in
//! memory bounded whatever the stream's length.
//!
//! - `source`: the frames, decoded by FFmpeg on a thread of their own; when
//!   the pose model falls behind a live source, only the newest frame waits
//!   and the others are dropped (and counted).
//! - `counter`: the online repetition counter of one person: a sliding
//!   window of their recent keypoints, counted again every half second with
//!   the offline counting, turned into a running total that only grows.
//! - `program`: the online concrete program of one person: a buffer of
//!   their frames not yet committed, segmented again every second with the
//!   offline synthesis, whose leading segments are committed once stable.
//! - [`watch`]: the loop over the frames, reporting [`Event`]s.
//! - `record`: with [`LiveParams::out`], every pose kept in a spool file
//!   and, when the stream ends, `mp run`'s files written from them.
//!
//! ```no_run
//! use mp_live::{watch, Event, LiveParams, LiveSource};
//! use mp_geom::CancelToken;
//!
//! // A file read at its own speed (`mp live squats.mp4 --realtime`), each
//! // repetition printed once it is confirmed.
//! let params = LiveParams { realtime: true, ..LiveParams::default() };
//! let mut print = |e: &Event| {
//!     if let Event::Rep { person, count, .. } = e {
//!         println!("person {person}: {count}");
//!     }
//! };
//! let source = LiveSource::File("squats.mp4".into());
//! let summary = watch(&source, &params, &CancelToken::new(), &mut print)?;
//! println!("{} frames", summary.frames);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod counter;
mod follow;
mod poses;
mod program;
mod record;
mod run;
mod scene;
mod source;

use std::collections::BTreeMap;

use mp_pose::Frame;
use serde::Serialize;

pub use counter::{OnlineCounter, Repetition};
pub use program::{OnlineProgram, ProgramSegment};
pub use run::watch;
pub use source::LiveSource;

/// Why a live run stopped early.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LiveError {
    /// The source cannot be opened or decoded.
    #[error("{0}")]
    Source(String),
    /// No frame came for longer than the stall timeout.
    #[error("the stream stalled: no frame for {0:.1} s")]
    Stalled(f64),
    /// The pose model or the tracker failed.
    #[error(transparent)]
    Pose(#[from] mp_pose::PoseError),
    /// Counting failed.
    #[error(transparent)]
    Pipeline(#[from] mp_pipeline::PipelineError),
    /// A keypoint track could not be built.
    #[error(transparent)]
    Geom(#[from] mp_geom::GeomError),
    /// The output folder cannot be written.
    #[error("{0}")]
    Output(String),
    /// A parameter is out of range.
    #[error("invalid parameter {name}: {reason}")]
    Param {
        /// The parameter.
        name: &'static str,
        /// Why.
        reason: String,
    },
}

/// The result of this crate's fallible functions.
pub(crate) type Result<T> = std::result::Result<T, LiveError>;

/// Parameters of a live run. The pose model, the tracker and the counting
/// are `mp run`'s ([`mp_pipeline::Params`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LiveParams {
    /// Pose model, tracker and counting. Default `mp run`'s.
    pub analysis: mp_pipeline::Params,
    /// Seconds of each person's recent keypoints that are counted. Default 20.
    pub window_s: f64,
    /// Seconds of stream time between two countings of a window. Default 0.5.
    pub count_every_s: f64,
    /// A repetition is reported once its end lies this many of its periods
    /// before the window's last frame. Default 0.5.
    pub confirm_periods: f64,
    /// Countings of a window less confident than this (`Counts::confidence`)
    /// report nothing until the end of the stream. Default 0.5.
    pub min_confidence: f64,
    /// Gaps in a person's poses up to this many seconds (dropped frames) are
    /// filled by linear interpolation. Default 0.25.
    pub max_gap_s: f64,
    /// Seconds of stream time between two status reports. Default 2.
    pub status_every_s: f64,
    /// Seconds without a frame after which the stream counts as stalled. Default 10.
    pub stall_timeout_s: f64,
    /// Stop after this many seconds of stream time. Default none.
    pub duration_s: Option<f64>,
    /// Read a file at its own speed, as a camera would deliver it. Default false.
    pub realtime: bool,
    /// Drop frames when the pose model falls behind: `None` (default) drops
    /// them for live sources (standard input, `realtime`) and analyses every
    /// frame of a file read as fast as possible.
    pub drop_late: Option<bool>,
    /// Seconds of decoded frames that may wait for the pose model, so that a
    /// frame that costs more than the rest (a search of the detector, the
    /// counting of a window) delays the next ones instead of losing them.
    /// When the queue is full, a new frame of a live source pushes out the
    /// oldest one waiting (dropped). At least one frame, at most 256 MiB.
    /// Default 0.5.
    pub queue_s: f64,
    /// Each confirmed person's concrete program, reported segment by segment
    /// ([`Event::Segment`]). Default false (segmentation costs CPU).
    pub program: bool,
    /// Seconds of stream time between two segmentations of a person's
    /// uncommitted frames. Default 1.
    pub program_every_s: f64,
    /// A stable segment is committed once its end lies this many seconds
    /// before the last frame. Default 2.
    pub program_lag_s: f64,
    /// Uncommitted frames are committed, stable or not, once they span this
    /// many seconds (more than `program_lag_s`). Default 10.
    pub program_max_lag_s: f64,
    /// A folder into which, when the stream ends (its end, `duration_s`, a
    /// cancel or an error), the files `mp run` writes are written from the
    /// poses of the whole stream, with the people numbered as the events
    /// numbered them: `track.npz`, programs, `loops.json`, per-person
    /// folders, plots and the report page (without frames: the stream is
    /// not kept). Meanwhile the poses wait in a spool file in the folder, so
    /// memory stays flat. Default none.
    pub out: Option<std::path::PathBuf>,
}

impl Default for LiveParams {
    fn default() -> Self {
        LiveParams {
            analysis: mp_pipeline::Params::default(),
            window_s: 20.0,
            count_every_s: 0.5,
            confirm_periods: 0.5,
            min_confidence: 0.5,
            max_gap_s: 0.25,
            status_every_s: 2.0,
            stall_timeout_s: 10.0,
            duration_s: None,
            realtime: false,
            drop_late: None,
            queue_s: 0.5,
            program: false,
            program_every_s: 1.0,
            program_lag_s: 2.0,
            program_max_lag_s: 10.0,
            out: None,
        }
    }
}

impl LiveParams {
    /// Checks every value.
    pub fn validate(&self) -> Result<()> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(LiveError::Param {
                    name,
                    reason: format!("must be a positive number of seconds, got {v}"),
                })
            }
        };
        positive("window_s", self.window_s)?;
        positive("count_every_s", self.count_every_s)?;
        positive("status_every_s", self.status_every_s)?;
        positive("stall_timeout_s", self.stall_timeout_s)?;
        positive("program_every_s", self.program_every_s)?;
        positive("program_lag_s", self.program_lag_s)?;
        positive("program_max_lag_s", self.program_max_lag_s)?;
        if self.program_max_lag_s <= self.program_lag_s {
            return Err(LiveError::Param {
                name: "program_max_lag_s",
                reason: format!(
                    "must be more than program_lag_s ({}), got {}",
                    self.program_lag_s, self.program_max_lag_s
                ),
            });
        }
        if let Some(d) = self.duration_s {
            positive("duration_s", d)?;
        }
        if !(self.confirm_periods.is_finite() && self.confirm_periods >= 0.0) {
            return Err(LiveError::Param {
                name: "confirm_periods",
                reason: format!("must be ≥ 0, got {}", self.confirm_periods),
            });
        }
        if !(0.0..=1.0).contains(&self.min_confidence) {
            return Err(LiveError::Param {
                name: "min_confidence",
                reason: format!("must be in 0..1, got {}", self.min_confidence),
            });
        }
        if !(self.queue_s.is_finite() && self.queue_s >= 0.0) {
            return Err(LiveError::Param {
                name: "queue_s",
                reason: format!("must be ≥ 0 seconds, got {}", self.queue_s),
            });
        }
        if !(self.max_gap_s.is_finite() && self.max_gap_s >= 0.0) {
            return Err(LiveError::Param {
                name: "max_gap_s",
                reason: format!("must be ≥ 0, got {}", self.max_gap_s),
            });
        }
        self.analysis.validate()?;
        Ok(())
    }
}

/// What a live run reports, in order. As JSON (`serde_json`), each is an
/// object whose `type` names the variant (`rep`, `segment`, `enter`,
/// `leave`, `status`, `reconnect`, `summary`, `error`).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Event {
    /// A person's repetition, once confirmed.
    Rep {
        /// The person.
        person: u32,
        /// The person's running total, this repetition included.
        count: usize,
        /// Stream time of the repetition's first frame, seconds.
        start: f64,
        /// Stream time of its end, seconds.
        end: f64,
        /// Stream time of the frame on which it was reported, seconds.
        t: f64,
    },
    /// A segment of a person's concrete program, once committed
    /// (`crate::program`); with `LiveParams::program` only.
    Segment {
        /// The person.
        person: u32,
        /// The person's segment number, from 0 (it rises by one each time).
        index: usize,
        /// Stream time of the segment's first frame, seconds.
        start: f64,
        /// Stream time one frame past its last frame, seconds (the next
        /// segment's `start`; as a repetition's `end`).
        end: f64,
        /// Stream time of the frame on which it was reported, seconds.
        t: f64,
        /// How many joints follow each kind of primitive, e.g. `"9 stationary, 5 lines, 3 splines"`.
        summary: String,
        /// Committed because the person's uncommitted frames reached
        /// `program_max_lag_s`, before the segment was stable.
        forced: bool,
        /// The segment's primitives in the DSL of `mp fit`, one line per
        /// joint: `name: statement`.
        program: String,
    },
    /// A person's track was confirmed.
    Enter {
        /// The person.
        person: u32,
        /// Stream time, seconds.
        t: f64,
    },
    /// A person is gone for good.
    Leave {
        /// The person.
        person: u32,
        /// Stream time, seconds.
        t: f64,
    },
    /// How the run keeps up.
    Status {
        /// Stream time of the last frame analysed, seconds.
        t: f64,
        /// Frames analysed per second since the previous status.
        fps: f64,
        /// Frames analysed so far.
        frames: usize,
        /// Of them, frames the pose model ran on (all of them unless the
        /// pose rate, `analysis.pose.rate`, skips some).
        posed: usize,
        /// Frames dropped so far (the pose model was behind).
        dropped: usize,
        /// Seconds the last frame analysed is behind the source.
        delay: f64,
    },
    /// A network source could not be reached or broke off, and is tried again.
    Reconnect {
        /// 1 for the first new try in a row.
        attempt: u32,
        /// Why.
        reason: String,
        /// Stream time, seconds.
        t: f64,
    },
    /// Why the run stopped early.
    Error {
        /// The message.
        message: String,
    },
    /// The end of the run (always the last event).
    Summary(Summary),
}

impl Event {
    /// The person id of the scene's repetitions (the people tracker numbers
    /// people from 1).
    pub const SCENE: u32 = 0;
}

/// Where a live run reports what it finds: every [`Event`], and every
/// analysed frame with the poses on it (for drawing or keeping them; the
/// default ignores frames). A closure `|e: &Event| …` is a sink of events.
pub trait Sink {
    /// An event, as it happens.
    fn event(&mut self, event: &Event);
    /// A frame once analysed, after the events it caused.
    fn frame(&mut self, _frame: &LiveFrame<'_>) {}
}

impl<F: FnMut(&Event)> Sink for F {
    fn event(&mut self, event: &Event) {
        self(event)
    }
}

/// An analysed frame and what was found on it.
#[derive(Debug, Clone, Copy)]
pub struct LiveFrame<'a> {
    /// The frame (RGB).
    pub frame: &'a Frame,
    /// The confirmed people on it.
    pub people: &'a [PersonPose],
    /// Every confirmed person's running total of repetitions, by id.
    pub totals: &'a BTreeMap<u32, usize>,
}

/// One confirmed person's pose on a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PersonPose {
    /// The person.
    pub id: u32,
    /// Keypoints in image pixels `(x, y)`, in the pose model's skeleton order.
    pub keypoints_px: Vec<[f64; 2]>,
    /// Per-keypoint visibility in `[0, 1]`.
    pub visibility: Vec<f64>,
}

/// The totals at the end of a run.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Summary {
    /// Frames analysed.
    pub frames: usize,
    /// Of them, frames the pose model ran on (all of them unless the pose
    /// rate, `analysis.pose.rate`, skips some).
    pub posed: usize,
    /// Frames dropped.
    pub dropped: usize,
    /// Stream time of the last frame analysed, seconds.
    pub t: f64,
    /// Every person confirmed, by id.
    pub people: Vec<PersonTotal>,
    /// The folder `LiveParams::out` into which `mp run`'s files were
    /// written, once they were.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub out: Option<String>,
}

/// One person's total.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PersonTotal {
    /// The person.
    pub id: u32,
    /// Repetitions reported.
    pub total_repetitions: usize,
}
