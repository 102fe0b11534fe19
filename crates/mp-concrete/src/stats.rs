//! How well and how compactly a program represents a track (paper §4.1).

use std::collections::BTreeMap;

use mp_geom::Poses;
use mp_geom::{GeomError, Track};
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
    /// Free parameters of the program ([`Program::n_params`]: in a C0
    /// program the start pose of a segment is the previous one's end, so it
    /// is not counted again).
    pub params_program: usize,
    /// Numbers written for the program ([`Program::n_numbers`]: every
    /// primitive's parameters and the durations, continuity or not).
    #[serde(default)]
    pub numbers_program: usize,
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

impl Program {
    /// Statistics of the program against `track` (same frames, joints and dimensions).
    pub fn stats(&self, track: &Track) -> Result<ProgramStats> {
        self.validate()?;
        check_compatible(self, track)?;
        let exec = self.execute_with(&ExecParams::default())?;
        let kd = mp_geom::kd(&exec, track).map_err(|e| match e {
            GeomError::NoData(_) => ConcreteError::Track("no observed keypoint to compare".into()),
            e => e.into(),
        })?;
        // Largest adjacent-frame jump: of the observed joints of the track, of
        // every joint of the program (0 for a single frame).
        let jump = |p: Poses<'_>| -> Result<f64> {
            if track.n_frames() < 2 {
                return Ok(0.0);
            }
            match mp_geom::max_adjacent_jump(p) {
                Err(GeomError::NoData(_)) => Ok(0.0),
                r => Ok(r?),
            }
        };
        let kinds = self
            .kind_counts()
            .into_iter()
            .map(|(k, n)| (k.as_str().to_string(), n))
            .collect();
        Ok(ProgramStats {
            n_frames: track.n_frames(),
            n_joints: track.n_joints(),
            dims: track.dims(),
            n_segments: self.n_segments(),
            kinds,
            params_program: self.n_params(),
            numbers_program: self.n_numbers(),
            params_raw: track.n_frames() * track.n_joints() * track.dims(),
            kd,
            max_jump_raw: jump(track.into())?,
            max_jump_program: jump(exec.positions().into())?,
        })
    }
}
