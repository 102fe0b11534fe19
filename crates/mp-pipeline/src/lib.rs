//! # mp-pipeline — the whole analysis of a video or a keypoint track
//!
//! One library function per job, used by the `mp` binary, the evaluations
//! (`cargo xtask eval`) and the Python package alike, so that what is
//! measured is what a user runs:
//!
//! 1. [`keypoints()`]: video → FFmpeg decoding (own thread, with grey frame
//!    thumbnails) → pose model → `Track`; or a track file.
//! 2. [`concrete_program`]: segmentation and primitive fits.
//! 3. [`analyse_track`]: abstract program and loops.
//! 4. [`count`]: repetition intervals and counts from the keypoints and, for
//!    video, the frame thumbnails (where no person is found, the frames count).
//! 5. [`run`]: all of the above into an output folder, with pictures, an
//!    overlay video and the report (`report.html` and its folder `report/`;
//!    where nobody is found, a page with the frames and the counts).
//! 6. [`Analyser`]: many inputs with one set of parameters, the pose model
//!    kept loaded between videos.
//! 7. [`batch()`]: [`run`] over a folder or a list of inputs, several at
//!    once, each into its own folder, with a resumable `manifest.jsonl`.
//! 8. [`extract()`]: a video or still image → keypoints (everyone in view,
//!    or one person, or BlazePose's world coordinates) to write as a track
//!    file (`mp extract`).
//!
//! [`Params::default()`] holds the libraries' defaults, validated once; an
//! [`Observer`] receives progress and stage timings, and a
//! [`CancelToken`] stops a run between steps (a cancelled run leaves only
//! complete files in its output folder).
//!
//! ```no_run
//! use mp_geom::CancelToken;
//! use mp_pipeline::{analyse_input, Input, Params, Silent};
//! let input = Input::open("squats.mp4", None)?;
//! let out = analyse_input(input, &Params::default(), &Silent, &CancelToken::new())?;
//! println!("{} repetitions ({})", out.counts.total, out.counts.method.as_str());
//! # Ok::<(), mp_pipeline::PipelineError>(())
//! ```

mod analysis;
mod batch;
mod error;
mod extract;
mod fit_options;
mod frame_signal;
mod input;
mod keypoints;
mod output;
mod params;
mod pieces;
mod pose_rate;
mod progress;
mod report_people;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

pub use analysis::{analyse_track, concrete_program, count, count_frames};
pub use batch::{
    batch, batch_items, BatchError, BatchObserver, BatchParams, BatchSummary, ItemReport,
    ItemStatus, SharedModel,
};
pub use error::PipelineError;
use error::Result;
pub use extract::{extract, ExtractParams, Extracted, ExtractedPoses};
pub use fit_options::FitOptions;
pub use frame_signal::FrameChoice;
pub use input::Input;
use keypoints::ModelSlot;
pub use keypoints::{keypoints, Keep, Keypoints};
use mp_abstract::{Analysis, Counts};
use mp_geom::CancelToken;
pub use params::{OutputParams, Params, PersonChoice, PersonParams, PoseParams};
pub use pose_rate::PoseRate;
pub use progress::{peak_resident_bytes, Observer, Silent, Stage, StageTime};

use mp_report::Analysed;
use mp_report::{Card, OutputDir};
use progress::{check, Timings};

/// One person's results (several-people tracking).
#[derive(Debug, Clone)]
pub struct PersonOutcome {
    /// The person's id.
    pub id: mp_geom::PersonId,
    /// Whether this person's results are the top-level ones.
    pub main: bool,
    /// First and last video frame where the person was tracked.
    pub first_frame: usize,
    /// Last video frame (inclusive).
    pub last_frame: usize,
    /// Frames with a pose.
    pub frames_found: usize,
    /// Mean box `[x0, y0, x1, y1]` in pixels.
    pub mean_box: Option<[f64; 4]>,
    /// Video frame of the analysis' first frame: 0 for the main person
    /// (analysed over the whole video), `first_frame` for the others
    /// (analysed over their own frames).
    pub offset: usize,
    /// Programs and loops (frames from `offset`); `None` when the person was
    /// not analysed (seen too briefly) or had no pose.
    pub analysis: Option<Analysis>,
    /// Repetition counts in video frames; `None` when not analysed.
    pub counts: Option<Counts>,
}

/// What an analysis produced.
pub struct Outcome {
    /// The keypoints (the track, thumbnails, where they came from).
    pub keypoints: Keypoints,
    /// Programs and loops; `None` when no person was found in any frame (the
    /// counts then come from the frames alone).
    pub analysis: Option<Analysis>,
    /// Repetition counts.
    pub counts: Counts,
    /// Every person tracked (several-people tracking; empty for a track file
    /// and the single-person pipeline), in id order.
    pub people: Vec<PersonOutcome>,
    /// Time per stage.
    pub stages: Vec<StageTime>,
    /// Wall time of the whole run.
    pub total: Duration,
}

impl Outcome {
    /// Duration of the motion in seconds.
    pub fn motion_s(&self) -> f64 {
        self.keypoints.track.n_frames() as f64 / self.keypoints.track.fps()
    }
}

/// What [`run`] produced.
pub struct RunSummary {
    /// The analysis (its frame copies and frame thumbnails are released).
    pub outcome: Outcome,
    /// The report page, when one was written (whenever the report was asked
    /// for, also where nobody was found).
    pub report: Option<PathBuf>,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
}

/// Steps 1–4 without writing anything: keypoints, programs, counts.
pub fn analyse_input(
    input: Input,
    params: &Params,
    observer: &dyn Observer,
    cancel: &CancelToken,
) -> Result<Outcome> {
    params.validate()?;
    analyse_with(input, params, observer, cancel, &mut ModelSlot::default())
}

/// [`analyse_input`] with validated parameters and the caller's pose model.
fn analyse_with(
    input: Input,
    params: &Params,
    observer: &dyn Observer,
    cancel: &CancelToken,
    slot: &mut ModelSlot,
) -> Result<Outcome> {
    let start = Instant::now();
    let mut timings = Timings::new(observer);
    let kp =
        keypoints::keypoints_timed(input, params, Keep::default(), &mut timings, cancel, slot)?;
    finish_analysis(kp, params, &mut timings, cancel, start)
}

/// Runs many inputs with one set of parameters, keeping the pose model
/// loaded between videos (a worker of a batch, a Ray actor). One analyser
/// runs one input at a time; use one per thread.
pub struct Analyser {
    params: Params,
    slot: ModelSlot,
}

impl Analyser {
    /// An analyser with validated parameters; the pose model is loaded with the first video.
    pub fn new(params: Params) -> Result<Self> {
        params.validate()?;
        Ok(Analyser {
            params,
            slot: ModelSlot::default(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// As [`analyse_input`].
    pub fn analyse(
        &mut self,
        input: Input,
        observer: &dyn Observer,
        cancel: &CancelToken,
    ) -> Result<Outcome> {
        analyse_with(input, &self.params, observer, cancel, &mut self.slot)
    }

    /// As [`run`].
    pub fn run(
        &mut self,
        input: Input,
        out_dir: &Path,
        observer: &dyn Observer,
        cancel: &CancelToken,
    ) -> Result<RunSummary> {
        run_with(
            input,
            out_dir,
            &self.params,
            observer,
            cancel,
            &mut self.slot,
        )
    }
}

fn finish_analysis(
    kp: Keypoints,
    params: &Params,
    timings: &mut Timings<'_>,
    cancel: &CancelToken,
    start: Instant,
) -> Result<Outcome> {
    Ok(finish_with_overlay(kp, params, timings, cancel, start, None)?.0)
}

/// The overlay video of a run into a folder, encoded beside the frame
/// signal, the counts and the people: it reads only the keypoints and the
/// main person's program.
struct OverlayJob<'a> {
    out: &'a OutputDir,
    src: keypoints::OverlayFrames,
    observer: &'a dyn Observer,
}

/// The overlay's staged file and its encoding time.
type Encoded = (PathBuf, Duration);

/// The analysis after the keypoints: the programs, then (a video's frame
/// signal still to read) the boxes' thumbnails and the frame signal, the
/// counts and the other people — with the overlay video (`overlay`, when
/// there is a program to draw) encoded on its own thread beside them, since
/// it needs only the main person's program. Also gives the main program
/// executed when the overlay drew it.
fn finish_with_overlay(
    mut kp: Keypoints,
    params: &Params,
    timings: &mut Timings<'_>,
    cancel: &CancelToken,
    start: Instant,
    overlay: Option<OverlayJob<'_>>,
) -> Result<(Outcome, Option<mp_geom::Track>, Option<Encoded>)> {
    let n = kp.track.n_frames();
    if n < 2 {
        return Err(PipelineError::TooShort(n));
    }
    let analysis = if kp.track.valid_count() > 0 {
        Some(analysis::analyse(
            &kp.track,
            kp.frame_px,
            params,
            timings,
            cancel,
        )?)
    } else {
        None
    };
    let executed = match (&analysis, &overlay) {
        (Some(an), Some(_)) => Some(
            an.concrete
                .execute()
                .map_err(|e| PipelineError::stage("executing the program", e))?,
        ),
        _ => None,
    };
    let pending = kp.pending.take();
    let kp_ref = &kp;
    // Set when the rest of the run fails: the overlay stops at its next frame.
    let stop = std::sync::atomic::AtomicBool::new(false);
    let (rest, encoded) = std::thread::scope(|s| {
        let handle = match (overlay, executed.as_ref()) {
            (Some(job), Some(executed)) => {
                job.observer.started(Stage::Overlay, Some(n));
                let others = output::other_people(kp_ref);
                let stop = &stop;
                Some(s.spawn(move || {
                    let t0 = Instant::now();
                    output::encode_overlay(
                        job.out,
                        job.src,
                        &kp_ref.track,
                        executed,
                        &others,
                        &|d| job.observer.progress(Stage::Overlay, d),
                        stop,
                    )
                    .map(|staged| (staged, t0.elapsed()))
                }))
            }
            _ => None,
        };
        let rest = (|| -> Result<_> {
            let signal = pending
                .map(|p| frame_signal::frame_signal(kp_ref, p, params, timings, cancel))
                .transpose()?;
            let thumbnails = match &signal {
                Some(s) => s.thumbnails.as_ref(),
                None => kp_ref.thumbnails.as_ref(),
            };
            let counts = analysis::count_timed(&kp_ref.track, thumbnails, params, timings)?;
            check(cancel)?;
            let others = signal.as_ref().map_or(&kp_ref.others, |s| &s.others);
            let people = people_outcomes(
                kp_ref,
                others,
                analysis.as_ref(),
                &counts,
                params,
                timings,
                cancel,
            )?;
            Ok((signal, counts, people))
        })();
        if rest.is_err() {
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        }
        let encoded = handle.map(|h| {
            h.join()
                .map_err(|_| PipelineError::stage("overlay video", "the overlay thread panicked"))
                .and_then(|r| r)
        });
        (rest, encoded)
    });
    let (signal, counts, people) = rest?;
    let encoded = encoded.transpose()?;
    if let Some(s) = signal {
        s.apply(&mut kp);
    }
    let outcome = Outcome {
        keypoints: kp,
        analysis,
        counts,
        people,
        stages: std::mem::take(&mut timings.stages),
        total: start.elapsed(),
    };
    Ok((outcome, executed, encoded))
}

/// Every tracked person's entry: the main person's from the top-level
/// results, the other analysed people's from their own frames (in parallel).
fn people_outcomes(
    kp: &Keypoints,
    others: &[(mp_geom::PersonId, Option<mp_pose::Thumbnails>)],
    analysis: Option<&Analysis>,
    counts: &Counts,
    params: &Params,
    timings: &mut Timings<'_>,
    cancel: &CancelToken,
) -> Result<Vec<PersonOutcome>> {
    use rayon::prelude::*;
    let Some(people) = &kp.people else {
        return Ok(Vec::new());
    };
    let n = people.n_frames();
    let frame_px = kp.frame_px;
    let t0 = Instant::now();
    let analysed: Vec<(mp_geom::PersonId, Option<Analysis>, Counts)> = others
        .par_iter()
        .map(|(id, thumbs)| {
            let p = people.get(*id).ok_or_else(|| {
                PipelineError::stage("analysing people", format!("no person {id}"))
            })?;
            let track = &p.track;
            if cancel.is_cancelled() || track.n_frames() < 2 {
                return Ok(None);
            }
            let an = if track.valid_count() > 0 {
                Some(analysis::analyse(
                    track,
                    frame_px,
                    params,
                    &mut Timings::new(&Silent),
                    cancel,
                )?)
            } else {
                None
            };
            // Their thumbnails become a track (8 bytes a cell) only now,
            // one person per thread at a time.
            let thumbs = thumbs.as_ref().map(|t| t.track()).transpose()?;
            let c = analysis::count(track, thumbs.as_ref(), params)?;
            Ok(Some((*id, an, c.shifted(p.first_frame, n))))
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect();
    check(cancel)?;
    if !others.is_empty() {
        timings.push(Stage::People, t0.elapsed(), n);
    }
    let out = people
        .people()
        .iter()
        .map(|p| {
            let main = kp.person == Some(p.id);
            let (offset, an, c) = if main {
                (0, analysis.cloned(), Some(counts.clone()))
            } else {
                match analysed.iter().find(|a| a.0 == p.id) {
                    Some((_, an, c)) => (p.first_frame, an.clone(), Some(c.clone())),
                    None => (p.first_frame, None, None),
                }
            };
            PersonOutcome {
                id: p.id,
                main,
                first_frame: p.first_frame,
                last_frame: p.last_frame(),
                frames_found: p.frames_found(),
                mean_box: p.mean_box(),
                offset,
                analysis: an,
                counts: c,
            }
        })
        .collect();
    Ok(out)
}

/// The whole pipeline into `out_dir`: `track.npz`, `program.txt/.json`,
/// `abstract.txt/.json`, `loops.json`, and (see [`OutputParams`]) `plots/`,
/// `timeline.svg/.png`, `contact_sheet.png`, `overlay.mp4` for video, the
/// report's folder `report/` and `report.html`, written last. Where nobody
/// was found there are no programs and no pictures, and the page shows the
/// frames, the repetitions counted from them and a notice. The overlay video
/// is encoded on its own thread as soon as the main person's program is
/// fitted, beside the boxes' pass, the counting and the other people.
pub fn run(
    input: Input,
    out_dir: &Path,
    params: &Params,
    observer: &dyn Observer,
    cancel: &CancelToken,
) -> Result<RunSummary> {
    params.validate()?;
    run_with(
        input,
        out_dir,
        params,
        observer,
        cancel,
        &mut ModelSlot::default(),
    )
}

/// [`run`] with validated parameters and the caller's pose model.
pub(crate) fn run_with(
    input: Input,
    out_dir: &Path,
    params: &Params,
    observer: &dyn Observer,
    cancel: &CancelToken,
    slot: &mut ModelSlot,
) -> Result<RunSummary> {
    let start = Instant::now();
    let mut timings = Timings::new(observer);
    let keep = Keep {
        report_frames: params.output.report,
        overlay: params.output.overlay_video,
    };
    let mut kp = keypoints::keypoints_pending(input, params, keep, &mut timings, cancel, slot)?;
    let frames = kp.frames.take();
    // The overlay video goes with the report, when there is a program to draw.
    let overlay_src = kp
        .overlay
        .take()
        .filter(|_| params.output.overlay_video && params.output.report);
    // The output folder is created once there is something to write: with
    // an overlay video, before the counting it is encoded beside.
    let early = overlay_src
        .as_ref()
        .filter(|_| kp.track.n_frames() >= 2 && kp.track.valid_count() > 0)
        .map(|_| OutputDir::create_with_cancel(out_dir, cancel.clone()))
        .transpose()
        .map_err(PipelineError::from_report)?;
    let job = early
        .as_ref()
        .zip(overlay_src)
        .map(|(out, src)| OverlayJob { out, src, observer });
    let (mut outcome, executed, encoded) =
        finish_with_overlay(kp, params, &mut timings, cancel, start, job)?;
    // The frame signals (8 bytes per thumbnail cell and frame: up to 256 MiB
    // each, `mp_pose::MAX_SIGNAL_VALUES`) have been counted and are written
    // nowhere: they are freed before the pictures and the page.
    outcome.keypoints.thumbnails = None;
    for (_, thumbnails) in &mut outcome.keypoints.others {
        *thumbnails = None;
    }
    let out = match early {
        Some(out) => out,
        None => OutputDir::create_with_cancel(out_dir, cancel.clone())
            .map_err(PipelineError::from_report)?,
    };
    let track = &outcome.keypoints.track;
    let mut files = output::write_analysis(&out, &outcome)?;
    let mut report = None;
    let n = track.n_frames();
    let kp = &outcome.keypoints;
    match (outcome.analysis.as_ref(), params.output.report) {
        (_, false) => {}
        (Some(an), true) => {
            let executed = match executed {
                Some(e) => e,
                None => an
                    .concrete
                    .execute()
                    .map_err(|e| PipelineError::stage("executing the program", e))?,
            };
            let intervals = outcome.counts.repetitive_intervals();
            let analysed = Analysed {
                track,
                program: &an.concrete,
                executed: &executed,
                abstract_program: &an.program,
                intervals: &intervals,
                program_loops: &an.intervals,
                frames: frames.as_ref(),
                frame_size: kp.frame_size,
                title: &kp.title,
            };
            let pictures = pictures_and_page(
                &out,
                Some(&analysed),
                &outcome,
                frames.as_ref(),
                encoded.is_some(),
                observer,
            );
            let (pic_files, pic_time, page, page_time) = pictures?;
            files.extend(pic_files);
            timings.push(Stage::Pictures, pic_time, n);
            if let Some((staged, t)) = encoded {
                out.commit(&staged, "overlay.mp4")
                    .map_err(PipelineError::from_report)?;
                files.push("overlay.mp4".into());
                timings.push(Stage::Overlay, t, n);
            }
            report = Some(write_page(
                &out,
                page,
                page_time,
                &mut files,
                &mut timings,
                n,
            )?);
        }
        // Nobody was found: the page shows the frames and the repetitions
        // counted from them, and says so.
        (None, true) => {
            let (_, _, page, page_time) =
                pictures_and_page(&out, None, &outcome, frames.as_ref(), false, observer)?;
            report = Some(write_page(
                &out,
                page,
                page_time,
                &mut files,
                &mut timings,
                n,
            )?);
        }
    }
    check(cancel)?;
    // What an earlier run into the same folder wrote and this one did not
    // (another input's people, plots or overlay) does not stay beside it.
    files.push(mp_report::RUN_FILES.into());
    out.replace_previous_run(&files)
        .map_err(PipelineError::from_report)?;
    drop(out);
    outcome.stages.extend(std::mem::take(&mut timings.stages));
    outcome.total = start.elapsed();
    Ok(RunSummary {
        outcome,
        report,
        files,
    })
}

/// Writes the report page, last: when it exists, everything it links to
/// and loads does too.
fn write_page(
    out: &OutputDir,
    page: mp_report::ReportPage,
    page_time: Duration,
    files: &mut Vec<String>,
    timings: &mut Timings<'_>,
    n: usize,
) -> Result<PathBuf> {
    let t_write = Instant::now();
    files.extend(page.files.iter().cloned());
    let path = page.write(out).map_err(PipelineError::from_report)?;
    files.push(mp_report::PAGE.into());
    timings.push(Stage::Report, page_time + t_write.elapsed(), n);
    Ok(path)
}

/// The pictures (when there is a program), then the report's folder and page
/// (the page not yet written): picture files, their time, the page, its time.
fn pictures_and_page(
    out: &OutputDir,
    a: Option<&Analysed<'_>>,
    outcome: &Outcome,
    frames: Option<&mp_report::FrameStore>,
    with_overlay: bool,
    observer: &dyn Observer,
) -> Result<(Vec<String>, Duration, mp_report::ReportPage, Duration)> {
    let kp = &outcome.keypoints;
    let t_pic = Instant::now();
    let pic_files = match a {
        Some(a) => {
            observer.started(Stage::Pictures, Some(a.program.n_joints() + 2));
            let done = std::sync::atomic::AtomicUsize::new(0);
            mp_report::write_pictures(out, a, &|| {
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                observer.progress(Stage::Pictures, d);
            })
            .map_err(PipelineError::from_report)?
        }
        None => Vec::new(),
    };
    let pic_time = t_pic.elapsed();
    let t_rep = Instant::now();
    observer.started(Stage::Report, None);
    let mut linked: Vec<String> = if a.is_some() {
        [
            "program.txt",
            "program.json",
            "abstract.txt",
            "abstract.json",
            "loops.json",
            "track.npz",
            "timeline.svg",
            "contact_sheet.png",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    } else {
        vec!["loops.json".into(), "track.npz".into()]
    };
    if with_overlay {
        linked.push("overlay.mp4".into());
    }
    linked.extend(
        pic_files
            .iter()
            .filter(|f| f.starts_with("plots/") && f.ends_with(".svg"))
            .cloned(),
    );
    let people = &outcome.people;
    for p in people.iter().filter(|p| !p.main && p.analysis.is_some()) {
        linked.push(format!("people/{}/program.txt", p.id));
        linked.push(format!("people/{}/abstract.txt", p.id));
    }
    let mut cards = Vec::new();
    if let Some(model) = &kp.model {
        cards.push(Card::new(
            "pose",
            format!("{:.0}%", 100.0 * kp.found_fraction),
            format!("of frames with a person · {model}"),
        ));
    }
    cards.extend(report_people::people_card(people));
    let n = kp.track.n_frames();
    let notice = a.is_none().then(|| match &kp.model {
        Some(model) => format!(
            "No person was found in this video: the pose model ({model}) examined its {n} frames and found nobody, so there is no program; the repetitions are counted from the frames alone."
        ),
        None => format!(
            "No person was found in this recording: none of its {n} frames holds a keypoint, so there is no program."
        ),
    });
    let views = report_people::people_views(kp, people, n)?;
    let executed;
    let main = mp_report::PersonPage {
        id: kp.person.filter(|_| !people.is_empty()),
        label: views
            .as_ref()
            .map_or_else(|| "the person".to_string(), |v| v.main_label()),
        colour: None,
        offset: 0,
        track: &kp.track,
        program: match (a, outcome.analysis.as_ref()) {
            (Some(a), Some(an)) => {
                executed = a.executed;
                Some(mp_report::ProgramView {
                    concrete: &an.concrete,
                    executed,
                    abstract_program: &an.program,
                    loops: &an.intervals,
                })
            }
            _ => None,
        },
        repetitions: outcome.counts.intervals.clone(),
    };
    let mut everyone = vec![main];
    if let Some(v) = &views {
        everyone.extend(v.pages()?);
    }
    let input = mp_report::ReportInput {
        title: &kp.title,
        subtitle: &kp.description,
        people: everyone,
        counts: &outcome.counts,
        frames,
        notice,
        cards,
        files: &linked,
        strip: views.as_ref().map(|v| v.rows.clone()),
    };
    let page = mp_report::write_report(out, &input).map_err(PipelineError::from_report)?;
    Ok((pic_files, pic_time, page, t_rep.elapsed()))
}
