//! Steps 2–4: concrete program, abstract program and loops, repetition
//! counts. `mp fit`, `mp abstract`, `mp loops` and `mp run` all call these,
//! so the same track with the same parameters gives the same program and
//! the same counts whichever command made them.

use std::time::Instant;

use mp_abstract::{count_signals, Analysis, Counts};
use mp_concrete::{Program, Synthesis};
use mp_geom::{CancelToken, Track};

use crate::error::{PipelineError, Result};
use crate::params::Params;
use crate::progress::{check, Observer, Silent, Stage, Timings};

/// Step 2: the concrete program of a track seen in a frame whose largest side
/// is `frame_px` pixels (`None`: the scale comes from the motion's extent).
pub fn concrete_program(
    track: &Track,
    frame_px: Option<f64>,
    params: &Params,
) -> Result<Synthesis> {
    params.validate()?;
    Program::synthesize_detailed(track, &params.synth_for(frame_px))
        .map_err(|e| PipelineError::stage("fitting the concrete program", e))
}

/// Steps 2–3: concrete program, abstract program, loops (as intervals).
pub fn analyse_track(track: &Track, frame_px: Option<f64>, params: &Params) -> Result<Analysis> {
    analyse(
        track,
        frame_px,
        params,
        &mut Timings::new(&Silent),
        &CancelToken::new(),
    )
}

pub(crate) fn analyse(
    track: &Track,
    frame_px: Option<f64>,
    params: &Params,
    timings: &mut Timings<'_>,
    cancel: &CancelToken,
) -> Result<Analysis> {
    if track.n_frames() < 2 {
        return Err(PipelineError::TooShort(track.n_frames()));
    }
    let obs: &dyn Observer = timings.observer();
    obs.started(Stage::Concrete, None);
    let t0 = Instant::now();
    let syn = concrete_program(track, frame_px, params)?;
    timings.push(Stage::Concrete, t0.elapsed(), track.n_frames());
    check(cancel)?;
    obs.started(Stage::Abstract, None);
    let t1 = Instant::now();
    let an = mp_abstract::Analysis::from_synthesis(syn, &params.analysis.loops)
        .map_err(|e| PipelineError::stage("finding loops (abstract program)", e))?;
    timings.push(Stage::Abstract, t1.elapsed(), track.n_frames());
    check(cancel)?;
    Ok(an)
}

/// Step 4: repetition counts from the keypoints and, for video, the frame
/// thumbnails (see `mp_abstract::count`).
pub fn count(track: &Track, thumbnails: Option<&Track>, params: &Params) -> Result<Counts> {
    params.validate()?;
    Ok(count_signals(Some(track), thumbnails, &params.count)?)
}

/// The repetitions of a recording counted from its frames alone (nobody in
/// it): the frame signal chosen from the whole-frame thumbnails `whole` as
/// `mp run` chooses it (`choose_frame_signal`), counted as `mp run` counts
/// frames. `mp live` counts the scene with it until a person's repetitions are.
pub fn count_frames(whole: mp_pose::Thumbnails, params: &Params) -> Result<Counts> {
    params.validate()?;
    let (signal, _) = crate::frame_signal::choose_frame_signal(whole, None, params)?;
    Ok(count_signals(None, Some(&signal), &params.count)?)
}

pub(crate) fn count_timed(
    track: &Track,
    thumbnails: Option<&Track>,
    params: &Params,
    timings: &mut Timings<'_>,
) -> Result<Counts> {
    timings.observer().started(Stage::Count, None);
    let t0 = Instant::now();
    let c = count(track, thumbnails, params)?;
    timings.push(Stage::Count, t0.elapsed(), track.n_frames());
    Ok(c)
}
