//! Editing loops: change the iteration count (expand or contract a repetitive
//! section), drop or repeat one recorded iteration.

use crate::error::{AbstractError, Result};
use crate::model::AbstractProgram;

/// Sets the iteration count of loop `n` (0-based, program order). Recorded
/// iterations beyond the new count are dropped; new iterations execute the
/// body's distributions.
pub fn set_iterations(prog: &mut AbstractProgram, n: usize, iterations: usize) -> Result<()> {
    if iterations > 1_000_000 {
        return Err(AbstractError::param(
            "iterations",
            format!("{iterations} is absurdly large (max 1,000,000)"),
        ));
    }
    let l = prog.loop_mut(n)?;
    l.iterations = iterations;
    l.observed.truncate(iterations);
    Ok(())
}

/// Removes recorded iteration `i` of loop `n` (the loop runs one iteration fewer).
pub fn drop_iteration(prog: &mut AbstractProgram, n: usize, i: usize) -> Result<()> {
    let l = prog.loop_mut(n)?;
    if i >= l.iterations {
        return Err(AbstractError::NotFound(format!(
            "iteration {i} of loop {n} ({} iterations)",
            l.iterations
        )));
    }
    if i < l.observed.len() {
        l.observed.remove(i);
    }
    l.iterations -= 1;
    Ok(())
}

/// Repeats recorded iteration `i` of loop `n` right after itself (one iteration more).
pub fn repeat_iteration(prog: &mut AbstractProgram, n: usize, i: usize) -> Result<()> {
    let l = prog.loop_mut(n)?;
    if i >= l.iterations {
        return Err(AbstractError::NotFound(format!(
            "iteration {i} of loop {n} ({} iterations)",
            l.iterations
        )));
    }
    if i < l.observed.len() {
        let it = l.observed[i].clone();
        l.observed.insert(i + 1, it);
    }
    l.iterations += 1;
    Ok(())
}
