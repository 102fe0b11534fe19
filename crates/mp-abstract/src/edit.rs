//! Editing loops: change the iteration count (expand or contract a repetitive
//! section), drop or repeat one recorded iteration.

use crate::error::{AbstractError, Result};
use crate::exec::{check_output_frames, output_frames_bound, LoopReplay};
use crate::model::{AbstractProgram, Loop};

/// The largest iteration count [`AbstractProgram::set_iterations`] accepts, whatever the body:
/// one million. The program's output must also fit
/// [`mp_geom::MAX_FRAME_JOINTS`] (frames × joints) when sampled,
/// which is usually the tighter bound.
pub const MAX_ITERATIONS: usize = 1_000_000;

impl AbstractProgram {
    /// Sets the iteration count of loop `n` (0-based, program order). Recorded
    /// iterations beyond the new count are dropped; new iterations execute the
    /// body's distributions. Counts above `MAX_ITERATIONS`, or whose execution
    /// (at the longest body durations) would exceed
    /// [`mp_geom::MAX_FRAME_JOINTS`], are an error naming `iterations`;
    /// the program is then unchanged.
    pub fn set_iterations(&mut self, n: usize, iterations: usize) -> Result<()> {
        if iterations > MAX_ITERATIONS {
            return Err(AbstractError::param(
                "iterations",
                format!("{iterations} is too large: at most {MAX_ITERATIONS} iterations"),
            ));
        }
        let l = self.loop_mut(n)?;
        let old = l.iterations;
        l.iterations = iterations;
        let bound = output_frames_bound(self, LoopReplay::Mean, true);
        if let Err(e) = check_output_frames(self, bound) {
            self.loop_mut(n)?.iterations = old;
            return Err(e);
        }
        let l = self.loop_mut(n)?;
        l.observed.truncate(iterations);
        Ok(())
    }

    /// Removes recorded iteration `i` of loop `n` (the loop runs one iteration fewer).
    pub fn drop_iteration(&mut self, n: usize, i: usize) -> Result<()> {
        let l = iteration_of(self, n, i)?;
        if i < l.observed.len() {
            l.observed.remove(i);
        }
        l.iterations -= 1;
        Ok(())
    }

    /// Repeats recorded iteration `i` of loop `n` right after itself (one iteration more).
    pub fn repeat_iteration(&mut self, n: usize, i: usize) -> Result<()> {
        let l = iteration_of(self, n, i)?;
        if i < l.observed.len() {
            let it = l.observed[i].clone();
            l.observed.insert(i + 1, it);
        }
        l.iterations += 1;
        Ok(())
    }
}

/// Loop `n`, when it has an iteration `i`.
fn iteration_of(prog: &mut AbstractProgram, n: usize, i: usize) -> Result<&mut Loop> {
    let l = prog.loop_mut(n)?;
    if i >= l.iterations {
        return Err(AbstractError::NotFound(format!(
            "iteration {i} of loop {n} ({} iterations)",
            l.iterations
        )));
    }
    Ok(l)
}
