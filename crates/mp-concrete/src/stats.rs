//! How well and how compactly a program represents a track (paper §4.1).

use std::collections::BTreeMap;

use mp_geom::Track;
use ndarray::ArrayView3;
use serde::{Deserialize, Serialize};

use crate::error::{ConcreteError, Result};
use crate::exec::ExecParams;
use crate::program::Program;

/// Size and accuracy of a program against the track it encodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProgramStats {
    /// Frames T.
    pub n_frames: usize,
    /// Joints J.
    pub n_joints: usize,
    /// Dimensions D.
    pub dims: usize,
    /// Segments (= primitives per joint; the paper's "primitives per video").
    pub n_segments: usize,
    /// Primitives by kind over all joints.
    pub kinds: BTreeMap<String, usize>,
    /// Free parameters of the program ([`Program::n_params`]).
    pub params_program: usize,
    /// Numbers in the raw track: `T · J · D`.
    pub params_raw: usize,
    /// Keypoint difference: mean Euclidean distance between the executed
    /// program and the track over observed (frame, joint) entries (track units).
    pub kd: f64,
    /// Largest distance a joint moves between two adjacent frames in the
    /// track (both frames observed), track units.
    pub max_jump_raw: f64,
    /// The same for the executed program.
    pub max_jump_program: f64,
}

/// Mean Euclidean distance between `a` and `b` (`T × J × D`) over entries
/// with `conf > min_conf` (`T × J`); `None` when there is none.
pub fn keypoint_difference(
    a: ArrayView3<'_, f64>,
    b: ArrayView3<'_, f64>,
    conf: ndarray::ArrayView2<'_, f64>,
    min_conf: f64,
) -> Option<f64> {
    let (t, j, d) = a.dim();
    let (mut sum, mut n) = (0.0, 0usize);
    for ti in 0..t {
        for ji in 0..j {
            if conf[[ti, ji]] > min_conf {
                let mut s = 0.0;
                for k in 0..d {
                    let e = a[[ti, ji, k]] - b[[ti, ji, k]];
                    s += e * e;
                }
                sum += s.sqrt();
                n += 1;
            }
        }
    }
    (n > 0).then(|| sum / n as f64)
}

/// Largest adjacent-frame displacement of any joint, counting only pairs of
/// frames where both have `conf > min_conf` (all pairs when `conf` is `None`).
pub fn max_adjacent_jump(
    pos: ArrayView3<'_, f64>,
    conf: Option<ndarray::ArrayView2<'_, f64>>,
    min_conf: f64,
) -> f64 {
    let (t, j, d) = pos.dim();
    let mut best = 0.0f64;
    for ti in 1..t {
        for ji in 0..j {
            if let Some(c) = conf {
                if !(c[[ti - 1, ji]] > min_conf && c[[ti, ji]] > min_conf) {
                    continue;
                }
            }
            let mut s = 0.0;
            for k in 0..d {
                let e = pos[[ti, ji, k]] - pos[[ti - 1, ji, k]];
                s += e * e;
            }
            best = best.max(s.sqrt());
        }
    }
    best
}

fn check_compatible(program: &Program, track: &Track) -> Result<()> {
    if program.n_frames() != track.n_frames()
        || program.n_joints() != track.n_joints()
        || program.dims != track.dims()
    {
        return Err(ConcreteError::Program(format!(
            "program covers {} frames × {} joints × {} dims, track has {} × {} × {}",
            program.n_frames(),
            program.n_joints(),
            program.dims,
            track.n_frames(),
            track.n_joints(),
            track.dims()
        )));
    }
    Ok(())
}

/// Statistics of `program` against `track` (same frames, joints and dimensions).
pub fn program_stats(program: &Program, track: &Track) -> Result<ProgramStats> {
    program.validate()?;
    check_compatible(program, track)?;
    let exec = program.execute_with(&ExecParams::default())?;
    let kd = keypoint_difference(exec.positions(), track.positions(), track.confidence(), 0.0)
        .ok_or_else(|| ConcreteError::Track("no observed keypoint to compare".into()))?;
    let kinds = program
        .kind_counts()
        .into_iter()
        .map(|(k, n)| (k.as_str().to_string(), n))
        .collect();
    Ok(ProgramStats {
        n_frames: track.n_frames(),
        n_joints: track.n_joints(),
        dims: track.dims(),
        n_segments: program.n_segments(),
        kinds,
        params_program: program.n_params(),
        params_raw: track.n_frames() * track.n_joints() * track.dims(),
        kd,
        max_jump_raw: max_adjacent_jump(track.positions(), Some(track.confidence()), 0.0),
        max_jump_program: max_adjacent_jump(exec.positions(), None, 0.0),
    })
}
