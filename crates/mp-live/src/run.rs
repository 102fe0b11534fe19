//! The live loop: frames from the [`crate::source`], every person tracked
//! with BlazePose and the people tracker (`mp run`'s), each confirmed
//! person's repetitions counted online (`counter`), the picture's
//! (`scene`) until a person's are, and, with `LiveParams::program`, their
//! concrete program ([`crate::program`]).

use std::collections::{BTreeMap, HashMap};
use std::time::{Duration, Instant};

use mp_geom::CancelToken;
use mp_pose::TrackEvent;
use mp_pose::{BlazePoseParams, MultiPose, MultiPoseParams, VideoInfo};

use crate::counter::{OnlineCounter, Repetition};
use crate::program::{OnlineProgram, ProgramSegment};
use crate::record::Recorder;
use crate::scene::SceneCounter;
use crate::source::{self, LiveSource, Taken};
use crate::{
    Event, LiveError, LiveFrame, LiveParams, PersonPose, PersonTotal, Result, Sink, Summary,
};

/// One track of the tracker: its person id once confirmed, its counter,
/// its program (and its segments committed before it was confirmed).
struct Tracked {
    id: Option<u32>,
    counter: OnlineCounter,
    program: Option<OnlineProgram>,
    segments: Vec<ProgramSegment>,
}

impl Tracked {
    fn new(info: &VideoInfo, skeleton: &mp_geom::Skeleton, params: &LiveParams) -> Self {
        let frame_px = Some(info.width.max(info.height) as f64);
        Tracked {
            id: None,
            counter: OnlineCounter::new(info.fps, skeleton.clone(), params),
            program: params
                .program
                .then(|| OnlineProgram::new(info.fps, skeleton.clone(), frame_px, params)),
            segments: Vec::new(),
        }
    }

    /// The program's segments committed since the last call: every one
    /// left when `last` (the end of the stream, or the person left).
    fn segments(&mut self, params: &LiveParams, last: bool) -> Result<Vec<ProgramSegment>> {
        if let Some(p) = &mut self.program {
            let more = if last {
                p.finish(params)?
            } else {
                p.update(params)?
            };
            self.segments.extend(more);
        }
        Ok(std::mem::take(&mut self.segments))
    }
}

/// The state of a run, kept apart from the loop so that the summary can be
/// written whatever stopped it.
struct State {
    fps: f64,
    frames: usize,
    posed: usize,
    dropped: usize,
    t: f64,
    tracks: HashMap<u64, Tracked>,
    totals: BTreeMap<u32, usize>,
    /// The spool of every pose, with `LiveParams::out`.
    recorder: Option<Recorder>,
    /// The stream's frame size, the pose model's skeleton and name, once known.
    stream: Option<((usize, usize), mp_geom::Skeleton, String)>,
    /// The output folder, once written.
    out: Option<String>,
    /// The scene's counter, until a person's first repetition.
    scene: Option<SceneCounter>,
}

impl State {
    fn summary(&self) -> Summary {
        Summary {
            out: self.out.clone(),
            frames: self.frames,
            posed: self.posed,
            dropped: self.dropped,
            t: self.t,
            people: self
                .totals
                .iter()
                .map(|(id, n)| PersonTotal {
                    id: *id,
                    total_repetitions: *n,
                })
                .collect(),
        }
    }

    fn report_segments(
        &self,
        id: u32,
        tr: &Tracked,
        segs: Vec<ProgramSegment>,
        sink: &mut dyn Sink,
    ) {
        let joints = tr.program.as_ref().map_or(&[][..], |p| p.joints());
        for s in segs {
            sink.event(&Event::Segment {
                person: id,
                index: s.index,
                start: s.start_frame as f64 / self.fps,
                end: s.end_frame as f64 / self.fps,
                t: self.t,
                summary: s.summary(),
                forced: s.forced,
                program: s.dsl(joints),
            });
        }
    }

    /// Reports `reps`, the new repetitions of person `id` (track `key`).
    /// The first person whose repetitions are counted while the scene still
    /// is takes over the scene's that are theirs ([`SceneCounter::before`]):
    /// those come first in their running total, and their counter (when
    /// still tracked) goes on after them.
    fn report_person(&mut self, id: u32, key: u64, reps: Vec<Repetition>, sink: &mut dyn Sink) {
        let earlier = match (reps.first(), &self.scene) {
            (Some(first), Some(scene)) if first.count == 1 => scene.before(first),
            _ => Vec::new(),
        };
        if let Some(tr) = self.tracks.get_mut(&key) {
            tr.counter.add_earlier(earlier.len());
        }
        self.report(id, with_earlier(earlier, reps), sink);
    }

    fn report(&mut self, id: u32, reps: Vec<Repetition>, sink: &mut dyn Sink) {
        if id != Event::SCENE && !reps.is_empty() {
            // A person's repetitions are counted: the scene's count stops where it is.
            self.scene = None;
        }
        for r in reps {
            self.totals.insert(id, r.count);
            sink.event(&Event::Rep {
                person: id,
                count: r.count,
                start: r.start_frame as f64 / self.fps,
                end: r.end_frame as f64 / self.fps,
                t: self.t,
            });
        }
    }
}

/// `earlier` (the scene's repetitions a person takes over) as the first of
/// `reps`, the person's own, which follow them in the running total.
fn with_earlier(earlier: Vec<Repetition>, mut reps: Vec<Repetition>) -> Vec<Repetition> {
    let k = earlier.len();
    for r in &mut reps {
        r.count += k;
    }
    let mut all: Vec<Repetition> = earlier
        .into_iter()
        .enumerate()
        .map(|(i, r)| Repetition { count: i + 1, ..r })
        .collect();
    all.append(&mut reps);
    all
}

/// Runs the live analysis of `source` until it ends, `cancel` is set or
/// `params.duration_s` of stream time have passed, reporting every
/// [`Event`] to `sink` as it happens (a closure `|e: &Event| …` is a
/// [`Sink`]), and every analysed frame with the poses found on it; the last
/// event is always the [`Event::Summary`] (after an [`Event::Error`] when
/// the run stopped on an error). Returns the summary, or the error that
/// stopped the run.
pub fn watch(
    source: &LiveSource,
    params: &LiveParams,
    cancel: &CancelToken,
    sink: &mut dyn Sink,
) -> Result<Summary> {
    let mut state = State {
        fps: 30.0,
        frames: 0,
        posed: 0,
        dropped: 0,
        t: 0.0,
        tracks: HashMap::new(),
        totals: BTreeMap::new(),
        recorder: None,
        stream: None,
        out: None,
        scene: None,
    };
    let result = run_inner(source, params, cancel, &mut state, sink);
    if let Err(e) = &result {
        sink.event(&Event::Error {
            message: e.to_string(),
        });
    }
    // The output folder, whatever stopped the run (after an error, from the
    // frames analysed before it).
    let written = match state.recorder.take() {
        Some(rec) => write_out(rec, source, params, &state),
        None => Ok(None),
    };
    let result = match written {
        Ok(out) => {
            state.out = out;
            result
        }
        Err(e) => {
            sink.event(&Event::Error {
                message: e.to_string(),
            });
            result.and(Err(e))
        }
    };
    let summary = state.summary();
    sink.event(&Event::Summary(summary.clone()));
    result.map(|()| summary)
}

fn run_inner(
    source: &LiveSource,
    params: &LiveParams,
    cancel: &CancelToken,
    state: &mut State,
    sink: &mut dyn Sink,
) -> Result<()> {
    params.validate()?;
    if let Some(dir) = &params.out {
        state.recorder = Some(Recorder::create(dir)?);
    }
    let pose = &params.analysis.pose;
    let model = pose
        .model
        .landmark_model()
        .ok_or_else(|| LiveError::Param {
            name: "analysis.pose.model",
            reason: "live analysis needs BlazePose (full, lite or heavy)".into(),
        })?;
    let mut multi = MultiPose::new(MultiPoseParams {
        pose: BlazePoseParams {
            model,
            session: pose.session(),
            ..Default::default()
        },
        people: pose.tracker.clone(),
    })?;
    let stall = Duration::from_secs_f64(params.stall_timeout_s);
    let drop_late = params
        .drop_late
        .unwrap_or_else(|| source.is_live(params.realtime));
    let (slot, info) = source::start(
        source,
        params.realtime,
        stall,
        drop_late,
        params.queue_s,
        &mut |r| {
            sink.event(&Event::Reconnect {
                attempt: r.attempt,
                reason: r.reason,
                t: 0.0,
            })
        },
    )?;
    let result = analyse_frames(
        &slot, &info, &mut multi, params, cancel, stall, drop_late, state, sink,
    );
    slot.stop();
    state.dropped = slot.dropped();
    result
}

#[allow(clippy::too_many_arguments)]
fn analyse_frames(
    slot: &source::Slot,
    info: &VideoInfo,
    multi: &mut MultiPose,
    params: &LiveParams,
    cancel: &CancelToken,
    stall: Duration,
    live: bool,
    state: &mut State,
    sink: &mut dyn Sink,
) -> Result<()> {
    state.fps = info.fps;
    let skeleton = multi.skeleton();
    state.stream = Some((
        (info.width, info.height),
        skeleton.clone(),
        multi.name().to_string(),
    ));
    let mut started: Option<(Instant, f64)> = None;
    let mut last_status = (0.0, 0usize, Instant::now());
    let poll = Duration::from_millis(200);
    let mut waited = Duration::ZERO;
    // The pose rate: the model runs on a frame at least `stride` frames
    // after the last one it ran on (dropped frames count towards it).
    let stride = params.analysis.pose.rate.stride(info.fps);
    let mut next_pose = 0usize;
    let mut shown: Vec<PersonPose> = Vec::new();
    state.scene = Some(SceneCounter::new(info.fps, params));
    loop {
        if cancel.is_cancelled() {
            break;
        }
        for r in slot.take_reconnects() {
            sink.event(&Event::Reconnect {
                attempt: r.attempt,
                reason: r.reason,
                t: state.t,
            });
        }
        let frame = match slot.take(poll) {
            Taken::Frame(f) => f,
            Taken::Ended(Ok(())) => break,
            Taken::Ended(Err(e)) => return Err(LiveError::Source(e)),
            Taken::Stalled if slot.is_reconnecting() => {
                waited = Duration::ZERO;
                continue;
            }
            Taken::Stalled => {
                waited += poll;
                if waited >= stall {
                    return Err(LiveError::Stalled(stall.as_secs_f64()));
                }
                continue;
            }
        };
        waited = Duration::ZERO;
        if params.duration_s.is_some_and(|d| frame.timestamp_s > d) {
            break;
        }
        let start = *started.get_or_insert((Instant::now(), frame.timestamp_s));
        state.t = frame.timestamp_s;
        state.frames += 1;
        if let Some(scene) = &mut state.scene {
            let whole = [0.0, 0.0, frame.width as f64, frame.height as f64];
            let thumb = mp_pose::grey_thumbnail_region(&frame, scene.thumbnail_size(), whole)?;
            scene.push(frame.index, thumb);
            let reps = scene.update(params)?;
            state.report(Event::SCENE, reps, sink);
        }
        if frame.index < next_pose {
            // Skipped by the pose rate: the people's poses on it are filled
            // from the frames around it; the page shows the last ones.
            if let Some(rec) = &mut state.recorder {
                rec.skipped(frame.index);
            }
            sink.frame(&LiveFrame {
                frame: &frame,
                people: &shown,
                totals: &state.totals,
            });
            continue;
        }
        next_pose = frame.index + stride;
        state.posed += 1;
        let r = multi.process(&frame)?;
        if let Some(rec) = &mut state.recorder {
            rec.frame(frame.index, &r.poses, &r.events)?;
        }
        let people: Vec<PersonPose> = r
            .poses
            .iter()
            .filter_map(|tp| {
                Some(PersonPose {
                    id: tp.id?,
                    keypoints_px: tp.pose.keypoints_px.clone(),
                    visibility: tp.pose.visibility.clone(),
                })
            })
            .collect();
        for tp in r.poses {
            let tr = state
                .tracks
                .entry(tp.key)
                .or_insert_with(|| Tracked::new(info, &skeleton, params));
            if let Some(p) = &mut tr.program {
                let (pts, vis) = (tp.pose.keypoints_px.clone(), tp.pose.visibility.clone());
                tr.segments.extend(p.push(frame.index, pts, vis, params)?);
            }
            tr.counter
                .push(frame.index, tp.pose.keypoints_px, tp.pose.visibility);
        }
        for e in r.events {
            match e {
                TrackEvent::Confirmed { key, id, .. } => {
                    let tr = state
                        .tracks
                        .entry(key)
                        .or_insert_with(|| Tracked::new(info, &skeleton, params));
                    tr.id = Some(id);
                    state.totals.entry(id).or_insert(0);
                    sink.event(&Event::Enter {
                        person: id,
                        t: state.t,
                    });
                }
                TrackEvent::Dropped { key, keep_until } => {
                    if let Some(tr) = state.tracks.get_mut(&key) {
                        tr.counter.retract_after(keep_until);
                        if let Some(p) = &mut tr.program {
                            p.retract_after(keep_until);
                        }
                    }
                }
                TrackEvent::Ended { key } => {
                    if let Some(mut tr) = state.tracks.remove(&key) {
                        if let Some(id) = tr.id {
                            let reps = tr.counter.finish(params)?;
                            state.report_person(id, key, reps, sink);
                            let segs = tr.segments(params, true)?;
                            state.report_segments(id, &tr, segs, sink);
                            sink.event(&Event::Leave {
                                person: id,
                                t: state.t,
                            });
                        }
                    }
                }
            }
        }
        let mut due = Vec::new();
        for (key, tr) in state.tracks.iter_mut() {
            if let Some(id) = tr.id {
                let reps = tr.counter.update(params)?;
                let segs = tr.segments(params, false)?;
                if !reps.is_empty() || !segs.is_empty() {
                    due.push((id, *key, reps, segs));
                }
            }
        }
        due.sort_by_key(|d| d.0);
        for (id, key, reps, segs) in due {
            state.report_person(id, key, reps, sink);
            if let Some(tr) = state.tracks.get(&key) {
                state.report_segments(id, tr, segs, sink);
            }
        }
        sink.frame(&LiveFrame {
            frame: &frame,
            people: &people,
            totals: &state.totals,
        });
        shown = people;
        if state.t - last_status.0 >= params.status_every_s {
            let now = Instant::now();
            let secs = now.duration_since(last_status.2).as_secs_f64();
            let fps = (state.frames - last_status.1) as f64 / secs.max(1e-9);
            // Live: how far the frame is behind the source's clock (started
            // with the first frame); a file read as fast as possible: behind
            // the newest frame decoded.
            let delay = if live {
                now.duration_since(start.0).as_secs_f64() - (state.t - start.1)
            } else {
                slot.newest_s() - state.t
            };
            sink.event(&Event::Status {
                t: state.t,
                fps,
                frames: state.frames,
                posed: state.posed,
                dropped: slot.dropped(),
                delay: delay.max(0.0),
            });
            last_status = (state.t, state.frames, now);
        }
    }
    // The end: every person still in view is counted once more, then the
    // scene, when still no person's repetition was counted.
    let mut rest = Vec::new();
    for (key, tr) in state.tracks.iter_mut() {
        if let Some(id) = tr.id {
            rest.push((
                id,
                *key,
                tr.counter.finish(params)?,
                tr.segments(params, true)?,
            ));
        }
    }
    rest.sort_by_key(|r| r.0);
    for (id, key, reps, segs) in rest {
        state.report_person(id, key, reps, sink);
        if let Some(tr) = state.tracks.get(&key) {
            state.report_segments(id, tr, segs, sink);
        }
    }
    if let Some(mut scene) = state.scene.take() {
        let reps = scene.finish(params)?;
        state.report(Event::SCENE, reps, sink);
    }
    Ok(())
}

/// `mp run`'s files in `params.out`, from the poses `rec` kept; the folder
/// written, or `None` when no frame came.
fn write_out(
    rec: Recorder,
    source: &LiveSource,
    params: &LiveParams,
    state: &State,
) -> Result<Option<String>> {
    let (Some(dir), Some((frame_size, skeleton, model))) = (&params.out, &state.stream) else {
        // The source never gave a frame.
        rec.discard();
        return Ok(None);
    };
    if rec.frames() == 0 {
        rec.discard();
        return Ok(None);
    }
    let n = rec.frames();
    let (people, posed) = rec.people(state.fps, skeleton)?;
    let title = source.name();
    let description = format!(
        "live {title} · {}×{} at {} fps · {n} frames ({} analysed, {} dropped) · {model}",
        frame_size.0,
        frame_size.1,
        mp_geom::fps_label(state.fps),
        state.frames,
        state.dropped,
    );
    let input = mp_pipeline::Input::People {
        people,
        skeleton: skeleton.clone(),
        posed,
        title,
        description,
        frame_size: *frame_size,
        model: model.clone(),
    };
    // A cancel of the stream ends the stream, not the writing of its results.
    mp_pipeline::run(
        input,
        dir,
        &params.analysis,
        &mp_pipeline::Silent,
        &mp_geom::CancelToken::new(),
    )?;
    Ok(Some(dir.display().to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rep(count: usize, start_frame: usize, end_frame: usize) -> Repetition {
        Repetition {
            count,
            start_frame,
            end_frame,
        }
    }

    #[test]
    fn repetitions_taken_over_come_first_in_the_running_total() {
        let all = with_earlier(
            vec![rep(1, 0, 93)],
            vec![rep(1, 118, 204), rep(2, 204, 290)],
        );
        assert_eq!(all, vec![rep(1, 0, 93), rep(2, 118, 204), rep(3, 204, 290)]);
        assert_eq!(
            with_earlier(Vec::new(), vec![rep(1, 5, 9)]),
            vec![rep(1, 5, 9)]
        );
    }
}
