//! Execution: rendering a program as positions at any time resolution.
//!
//! The program's time axis is its frame index `f ∈ [0, T − 1]` (`T` = sum of
//! durations), fractional values allowed. Segment `i` owns frames
//! `b[i] ≤ f < b[i+1]`; at `t = f − b[i] ≤ duration − 1` its primitive is
//! evaluated at `t`. Between the last frame of one segment and the first of
//! the next (`duration − 1 < t < duration`) the [`Transition`] decides: a
//! linear blend of the two primitives' end and start (default), or the first
//! primitive extrapolated. At integer frames both give the primitive values.

use mp_geom::{Track, Units, MAX_FRAME_JOINTS};
use ndarray::Array3;
use serde::{Deserialize, Serialize};

use crate::error::{ConcreteError, Result};
use crate::program::Program;

/// What happens between the last frame of a segment and the first frame of the next.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum Transition {
    /// Linear blend from the segment's last frame to the next segment's first frame.
    #[default]
    Blend,
    /// The segment's primitive continued past its last frame.
    Extrapolate,
}

/// Parameters of [`Program::execute_with`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ExecParams {
    /// Output frame rate, finite and > 0; `None` = the program's own rate
    /// (one output frame per program frame).
    pub fps_out: Option<f64>,
    /// Between-segment behaviour.
    pub transition: Transition,
}

impl ExecParams {
    /// The most output frames one execution may produce for `joints`
    /// joints: [`mp_geom::MAX_FRAME_JOINTS`] output cells (frames × joints)
    /// divided by `joints` (at least 1). Larger requests (an absurd
    /// `fps_out`, a program of absurd durations) are a
    /// [`ConcreteError::TooLarge`] instead of an allocation failure.
    pub fn max_output_frames(joints: usize) -> usize {
        (MAX_FRAME_JOINTS / joints.max(1)).max(1)
    }

    /// Checks that `frames` output frames of `joints` joints (as `f64`, so that
    /// absurd values cannot overflow) fit [`ExecParams::max_output_frames`];
    /// the error names the parameter `name` and its `value`. Returns the frame count.
    pub fn check_output_frames(
        name: &'static str,
        value: impl std::fmt::Display,
        frames: f64,
        joints: usize,
    ) -> Result<usize> {
        let limit = Self::max_output_frames(joints);
        if frames.is_finite() && frames >= 0.0 && frames <= limit as f64 {
            return Ok(frames as usize);
        }
        Err(ConcreteError::TooLarge {
            name,
            value: value.to_string(),
            limit: format!(
                "it implies {frames:.0} output frames of {joints} joints, \
                 at most {limit} frames ({MAX_FRAME_JOINTS} frame·joints)"
            ),
        })
    }

    /// Checks every field: `fps_out`, when given, finite and > 0.
    pub fn validate(&self) -> Result<()> {
        if let Some(f) = self.fps_out {
            if !(f.is_finite() && f > 0.0) {
                return Err(ConcreteError::param(
                    "fps_out",
                    format!("must be finite and > 0, got {f}"),
                ));
            }
        }
        Ok(())
    }
}

impl Program {
    /// Positions of every joint at program frame `frame` (fractional), written
    /// into `out` (length `J·D`, joint-major). `boundaries` = [`Program::boundaries`].
    fn eval_into(
        &self,
        boundaries: &[usize],
        frame: f64,
        transition: Transition,
        out: &mut [f64],
    ) -> Result<()> {
        let total = boundaries.last().copied().unwrap_or(0);
        let last = total.saturating_sub(1) as f64;
        if !(frame.is_finite() && frame >= 0.0 && frame <= last + 1e-9) {
            return Err(ConcreteError::param(
                "frames",
                format!("frame {frame} is outside the program's range [0, {last}]"),
            ));
        }
        let frame = frame.min(last);
        // Segment i with b[i] ≤ frame < b[i+1].
        let i = boundaries
            .partition_point(|&b| (b as f64) <= frame)
            .saturating_sub(1)
            .min(self.segments.len().saturating_sub(1));
        let seg = &self.segments[i];
        let t = frame - boundaries[i] as f64;
        let end_t = (seg.duration_frames - 1) as f64;
        let d = self.dims;
        let blend = transition == Transition::Blend && t > end_t && i + 1 < self.segments.len();
        if blend {
            let a = t - end_t;
            let next = &self.segments[i + 1];
            let mut tmp = vec![0.0; d];
            for (j, (p, q)) in seg.primitives.iter().zip(&next.primitives).enumerate() {
                let o = &mut out[j * d..(j + 1) * d];
                p.eval_into(end_t, o);
                q.eval_into(0.0, &mut tmp);
                for k in 0..d {
                    o[k] = (1.0 - a) * o[k] + a * tmp[k];
                }
            }
        } else {
            for (j, p) in seg.primitives.iter().enumerate() {
                p.eval_into(t, &mut out[j * d..(j + 1) * d]);
            }
        }
        Ok(())
    }

    /// Positions `F × J × D` at the given program frames (fractional allowed,
    /// each in `[0, T − 1]`).
    pub fn sample_frames(&self, frames: &[f64], transition: Transition) -> Result<Array3<f64>> {
        self.validate()?;
        ExecParams::check_output_frames(
            "frames",
            frames.len(),
            frames.len() as f64,
            self.n_joints(),
        )?;
        let (j, d) = (self.n_joints(), self.dims);
        let b = self.boundaries();
        let mut out = Array3::zeros((frames.len(), j, d));
        let mut buf = vec![0.0; j * d];
        for (fi, &f) in frames.iter().enumerate() {
            self.eval_into(&b, f, transition, &mut buf)?;
            for ji in 0..j {
                for k in 0..d {
                    out[[fi, ji, k]] = buf[ji * d + k];
                }
            }
        }
        Ok(out)
    }

    /// Positions at times in seconds from the program's start.
    pub fn sample_times_s(&self, times_s: &[f64], transition: Transition) -> Result<Array3<f64>> {
        let frames: Vec<f64> = times_s.iter().map(|t| t * self.fps).collect();
        self.sample_frames(&frames, transition)
    }

    /// The track at the program's own frame rate (T frames, confidence 1).
    pub fn execute(&self) -> Result<Track> {
        self.execute_with(&ExecParams::default())
    }

    /// The track at `params.fps_out`: frames at times `k / fps_out` for all
    /// `k` with `k / fps_out ≤ (T − 1) / fps`.
    pub fn execute_with(&self, params: &ExecParams) -> Result<Track> {
        params.validate()?;
        self.validate()?;
        // The program's own fps is finite and > 0 (checked by `validate`).
        let fps_out = params.fps_out.unwrap_or(self.fps);
        let last = (self.n_frames() - 1) as f64;
        let ratio = self.fps / fps_out;
        let n_out_f = (last / ratio + 1e-9).floor() + 1.0;
        let n_out = match params.fps_out {
            Some(f) => ExecParams::check_output_frames("fps_out", f, n_out_f, self.n_joints())?,
            None => ExecParams::check_output_frames(
                "frames",
                self.n_frames(),
                n_out_f,
                self.n_joints(),
            )?,
        };
        let frames: Vec<f64> = (0..n_out).map(|k| (k as f64 * ratio).min(last)).collect();
        let pos = self.sample_frames(&frames, params.transition)?;
        let units: Units = self.units;
        Ok(Track::new(pos, None, fps_out, units, self.skeleton())?)
    }
}
