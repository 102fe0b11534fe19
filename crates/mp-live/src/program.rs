//! The online concrete program of one person.
//!
//! The person's poses wait in a buffer of stream frames not yet committed.
//! Every `program_every_s` seconds of stream time the buffer is segmented
//! with the offline synthesis ([`mp_pipeline::concrete_program`]: the
//! keypoints, scale, λ, primitives and C0 refit of `mp run` and `mp fit`),
//! and its leading segments that can no longer change are **committed**:
//!
//! - a segment is *stable* when its end lies at least `program_lag_s` before
//!   the buffer's last frame and both its boundaries were boundaries of the
//!   previous segmentation too; the leading stable segments are committed;
//! - when the buffer reaches `program_max_lag_s`, every leading segment that
//!   ends `program_lag_s` before the buffer's end is committed whether
//!   stable or not (at least the first one), so the buffer, and the delay of
//!   a segment, are bounded whatever the motion;
//! - at the end of the stream (or when the person leaves), and before a gap
//!   in the person's poses longer than `max_gap_s`, the rest is segmented
//!   once more and committed whole.
//!
//! Committed frames leave the buffer: it never holds more than
//! `program_max_lag_s` of frames plus one filled gap ([`OnlineProgram::max_buffer`]).
//! The committed segments tile the person's frames (the stream frames from
//! their first pose to their last, with the holes of gaps longer than
//! `max_gap_s`) without overlap; each keeps the primitives the segmentation
//! of its buffer gave it.

use mp_concrete::{NumberFormat, Program, Segment};
use mp_geom::{Primitive, Skeleton, Track};

use crate::poses::Poses;
use crate::{LiveError, LiveParams, Result};

/// One committed segment of a person's program.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramSegment {
    /// The person's segment number, from 0.
    pub index: usize,
    /// First stream frame.
    pub start_frame: usize,
    /// One past the last stream frame.
    pub end_frame: usize,
    /// Committed because the buffer was full (not yet stable).
    pub forced: bool,
    /// One primitive per joint, in the order of [`OnlineProgram::joints`].
    pub segment: Segment,
}

impl ProgramSegment {
    /// A short description: how many joints follow each kind of primitive,
    /// e.g. `"9 stationary, 5 lines, 3 splines"`.
    pub fn summary(&self) -> String {
        let mut n = [0usize; 4];
        for p in &self.segment.primitives {
            let k = match p {
                Primitive::Stationary { .. } => 0,
                Primitive::Line { .. } => 1,
                Primitive::Circle { .. } => 2,
                _ => 3,
            };
            n[k] += 1;
        }
        let names = [
            ("stationary", "stationary"),
            ("line", "lines"),
            ("circle", "circles"),
            ("spline", "splines"),
        ];
        let parts: Vec<String> = n
            .iter()
            .zip(names)
            .filter(|(c, _)| **c > 0)
            .map(|(c, (one, many))| format!("{c} {}", if *c == 1 { one } else { many }))
            .collect();
        parts.join(", ")
    }

    /// The segment in the DSL of `mp fit` (two decimals): one line per joint,
    /// `name: statement`.
    pub fn dsl(&self, joints: &[String]) -> String {
        let nf = NumberFormat::Fixed(NumberFormat::PRETTY_DECIMALS);
        let lines: Vec<String> = (0..self.segment.primitives.len())
            .filter_map(|j| {
                let name = joints.get(j).map(String::as_str).unwrap_or("?");
                let statement = self.segment.dsl_statement(j, nf)?;
                Some(format!("{name}: {statement}"))
            })
            .collect();
        lines.join("\n")
    }

    /// The program made of `segments` (consecutive, in order) with the header
    /// of `like` (frame rate, units, joints, continuity).
    pub fn concatenate(like: &Program, segments: &[ProgramSegment]) -> Result<Program> {
        for w in segments.windows(2) {
            if w[1].start_frame != w[0].end_frame {
                return Err(LiveError::Param {
                    name: "segments",
                    reason: format!(
                        "segment {} starts at frame {}, not where segment {} ends ({})",
                        w[1].index, w[1].start_frame, w[0].index, w[0].end_frame
                    ),
                });
            }
        }
        Ok(Program {
            segments: segments.iter().map(|s| s.segment.clone()).collect(),
            ..like.clone()
        })
    }
}

/// See the module docs.
pub struct OnlineProgram {
    frame_px: Option<f64>,
    every: usize,
    lag: usize,
    max_frames: usize,
    rows: Poses,
    /// Boundaries (stream frames) of the last segmentation.
    previous: Vec<usize>,
    last_segmented: Option<usize>,
    next_index: usize,
    joints: Vec<String>,
    longest: usize,
}

impl OnlineProgram {
    /// The program of poses in `skeleton` at `fps` frames per second, seen
    /// in a frame whose largest side is `frame_px` pixels (`mp run`'s scale;
    /// `None`: the scale of each buffer's own extent). Programs are fitted to
    /// COCO-17 unless `params.analysis.pose.all_joints` (as `mp run`).
    pub fn new(fps: f64, skeleton: Skeleton, frame_px: Option<f64>, params: &LiveParams) -> Self {
        let frames = |s: f64| (s * fps).round().max(1.0) as usize;
        let rows = Poses::new(fps, skeleton, params);
        let joints = rows.joints();
        let lag = (params.program_lag_s * fps).round() as usize;
        OnlineProgram {
            frame_px,
            every: frames(params.program_every_s),
            lag,
            max_frames: frames(params.program_max_lag_s).max(lag + 2),
            rows,
            previous: Vec::new(),
            last_segmented: None,
            next_index: 0,
            joints,
            longest: 0,
        }
    }

    /// The joints of the segments' primitives, in order.
    pub fn joints(&self) -> &[String] {
        &self.joints
    }

    /// Stream frames in the buffer now.
    pub fn buffer_len(&self) -> usize {
        self.rows.len()
    }

    /// The most stream frames the buffer ever held.
    pub fn longest_buffer(&self) -> usize {
        self.longest
    }

    /// The most stream frames the buffer may hold: `program_max_lag_s` of
    /// frames, plus a filled gap of up to `max_gap_s` pushed at once.
    pub fn max_buffer(&self) -> usize {
        self.max_frames + self.rows.max_gap()
    }

    /// Segments committed so far.
    pub fn committed(&self) -> usize {
        self.next_index
    }

    /// Adds the pose of stream frame `frame` (after the previous one) and
    /// returns the segments committed by it: a gap of up to `max_gap_s`
    /// since the previous pose is filled by linear interpolation; before a
    /// longer one the buffer is committed whole.
    pub fn push(
        &mut self,
        frame: usize,
        points: Vec<[f64; 2]>,
        conf: Vec<f64>,
        params: &LiveParams,
    ) -> Result<Vec<ProgramSegment>> {
        let mut out = Vec::new();
        if self.rows.breaks_at(frame) {
            out = self.finish(params)?;
        }
        self.rows.push(frame, points, conf);
        self.longest = self.longest.max(self.rows.len());
        Ok(out)
    }

    /// Takes back the poses after stream frame `frame` (the tracker took
    /// them back); frames committed already stay.
    pub fn retract_after(&mut self, frame: usize) {
        self.rows.retract_after(frame);
    }

    /// Whether the buffer is due to be segmented again.
    pub fn due(&self) -> bool {
        match (self.rows.last_frame(), self.last_segmented) {
            (None, _) => false,
            _ if self.rows.len() >= self.max_frames => true,
            (Some(_), None) => self.rows.len() >= self.every,
            (Some(b), Some(c)) => b >= c + self.every,
        }
    }

    /// Segments the buffer when due and returns the segments newly committed.
    pub fn update(&mut self, params: &LiveParams) -> Result<Vec<ProgramSegment>> {
        if !self.due() {
            return Ok(Vec::new());
        }
        self.segment_buffer(params, false)
    }

    /// Segments the buffer once more and commits it whole (the end of the
    /// stream, or the person left).
    pub fn finish(&mut self, params: &LiveParams) -> Result<Vec<ProgramSegment>> {
        let out = self.segment_buffer(params, true)?;
        self.rows.clear();
        self.previous.clear();
        self.last_segmented = None;
        Ok(out)
    }

    fn segment_buffer(&mut self, params: &LiveParams, last: bool) -> Result<Vec<ProgramSegment>> {
        let Some(track) = self.rows.track()? else {
            return Ok(Vec::new());
        };
        let first = self.rows.span().map_or(0, |s| s.0);
        let end = first + track.n_frames();
        self.last_segmented = Some(end - 1);
        let min_conf = params.analysis.analysis.synth.min_confidence;
        if !track.confidence().iter().any(|&c| c > min_conf) {
            // Nothing observed: no program; the frames wait for an observed
            // one, or go at the end.
            if last || self.rows.len() >= self.max_frames {
                self.rows.clear();
            }
            return Ok(Vec::new());
        }
        let segments: Vec<(usize, usize, Segment)> = if track.n_frames() < 2 {
            vec![(first, end, stationary(&track))]
        } else {
            let syn = mp_pipeline::concrete_program(&track, self.frame_px, &params.analysis)?;
            let b = syn.program.boundaries();
            syn.program
                .segments
                .into_iter()
                .zip(b.windows(2))
                .map(|(s, w)| (first + w[0], first + w[1], s))
                .collect()
        };
        let mut take = 0;
        let mut forced = 0;
        if last {
            take = segments.len();
        } else {
            for (s, e, _) in &segments {
                let stable = self.previous.windows(2).any(|w| w[0] == *s && w[1] == *e);
                if e + self.lag <= end && stable {
                    take += 1;
                } else {
                    break;
                }
            }
            if end - segments.get(take).map_or(end, |s| s.0) >= self.max_frames {
                let cut = end.saturating_sub(self.lag);
                forced = segments[take..]
                    .iter()
                    .take_while(|s| s.1 <= cut)
                    .count()
                    .max(1);
                take = (take + forced).min(segments.len());
            }
        }
        self.previous = segments.iter().map(|s| s.0).chain([end]).collect();
        let n_stable = take - forced.min(take);
        let mut out = Vec::with_capacity(take);
        for (k, (s, e, segment)) in segments.into_iter().take(take).enumerate() {
            self.rows.forget_before(e);
            out.push(ProgramSegment {
                index: self.next_index,
                start_frame: s,
                end_frame: e,
                forced: !last && k >= n_stable,
                segment,
            });
            self.next_index += 1;
        }
        Ok(out)
    }
}

/// The one-frame program of a one-frame track: every joint stationary.
fn stationary(track: &Track) -> Segment {
    let pos = track.positions();
    Segment {
        duration_frames: 1,
        primitives: (0..track.n_joints())
            .map(|j| Primitive::Stationary {
                point: (0..track.dims()).map(|d| pos[[0, j, d]]).collect(),
            })
            .collect(),
    }
}
