//! Step 1: keypoints (and frame thumbnails) from the input.
//!
//! For a video, a decoding thread feeds the pose model and keeps grey
//! thumbnails of every frame (and, when an overlay video is wanted and they
//! fit in memory, full-size copies); a second FFmpeg process writes reduced
//! JPEG copies for the report alongside, or, for a long video of which few
//! frames are kept, the decoding thread makes them
//! ([`COPY_ON_DECODER_MIN_STEP`]).
//!
//! With several people ([`crate::PoseParams::people`], the default for
//! BlazePose) every person is tracked; the track of the analysis is the
//! main person's (`mp_geom::People::main_person`, or the one asked for) over
//! the whole video. Each analysed person's frame signal is read from grey
//! thumbnails of their own box (a second decoding pass), not of the whole
//! frame, so that the people beside them stay out of it; the whole frame is
//! read only when nobody is found or the main person's box lies mostly
//! outside the picture (`crate::PoseParams::own_box_region`). Where a region
//! of the picture moves on its own and repeats more clearly than those
//! thumbnails, its cells are the frame signal instead
//! ([`crate::frame_signal`]); for a person, only a region inside their own
//! box. A video too long for 32 × 32 thumbnails within
//! [`mp_pose::MAX_SIGNAL_VALUES`] has them read at 16 × 16 (or fewer cells,
//! [`mp_pose::signal_side`]): an hour's frame signal in a quarter of the
//! memory; so are the other people's, when their frames together are that
//! many.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use mp_geom::{CancelToken, People, PersonId, Track};
use mp_pose::FrameSource;
use mp_pose::SessionParams;
use mp_pose::{decode_ahead, DecodeOptions, Frame, FrameCopies, MjpegOptions, MjpegStream};
use mp_pose::{extract_people, BlazePoseParams, MultiPose, MultiPoseParams, SharedLandmarks};
use mp_pose::{extract_track, open_estimator_with, ExtractOptions};
use mp_pose::{signal_side, Thumbnails};
use mp_pose::{ModelChoice, PoseEstimator};
use mp_pose::{VideoInfo, VideoReader};
use mp_report::{FrameStore, FrameStoreParams};

use crate::error::{PipelineError, Result};
use crate::frame_signal::{frame_signal, FrameChoice, PendingSignal};
use crate::input::Input;
use crate::params::{Params, PersonChoice};
use crate::pieces::{pose_people_in_pieces, pose_pieces};
use crate::progress::{check, Observer, Stage, StageTime, Timings};

/// Full-size frames kept in memory during the pose pass for the overlay
/// video, up to this many bytes; longer videos are decoded a second time.
pub(crate) const KEEP_FRAMES_BUDGET_BYTES: usize = 512 << 20;

/// Quality of the report's frame copies on FFmpeg's `-q:v` scale (2 best,
/// 31 worst). 4 gives about the PSNR of libjpeg quality 72 at full chroma
/// resolution (≈ 40 dB on the golf swing) in files about 25 % smaller.
pub(crate) const REPORT_JPEG_QSCALE: u32 = 4;

/// The report's reduced frames are made on the decoding thread, not by a
/// second FFmpeg process, when at most one frame in this many is kept
/// (videos over `16 × 1,200` frames, about 11 minutes at 30 fps): a copy
/// made here (reduced and encoded, about 8 ms for 640 × 360) costs as much
/// as FFmpeg decoding 8–16 frames, and the second process decodes every
/// frame of the video.
pub(crate) const COPY_ON_DECODER_MIN_STEP: usize = 16;

/// The frames of the overlay video.
pub struct OverlayFrames {
    /// The video (size, frame rate, path).
    pub info: VideoInfo,
    /// Full-size frames (YUV 4:2:0) kept during the pose pass; `None`:
    /// decode the video again.
    pub kept: Option<Vec<mp_pose::Yuv420Frame>>,
}

/// A pose model kept loaded between videos: the first video opens it, the
/// next ones with the same model and thread count reuse it (its tracking
/// state is reset for each video).
#[derive(Default)]
pub(crate) struct ModelSlot {
    loaded: Option<(
        ModelChoice,
        SessionParams,
        u64,
        Box<dyn PoseEstimator + Send>,
    )>,
    multi: Option<MultiPose>,
    /// A landmark model shared with other slots (a batch's jobs on a GPU),
    /// which the several-people estimator runs its crops through.
    shared: Option<SharedLandmarks>,
}

impl ModelSlot {
    /// A slot whose several-people estimator runs its landmark model
    /// through `shared`.
    pub(crate) fn with_shared(shared: Option<SharedLandmarks>) -> Self {
        ModelSlot {
            shared,
            ..ModelSlot::default()
        }
    }

    /// Forgets the loaded models (after a model panicked), keeping the shared one.
    pub(crate) fn reset(&mut self) {
        *self = ModelSlot::with_shared(self.shared.take());
    }

    /// The multi-person estimator for `params`, opened when not loaded yet
    /// (or loaded with other settings).
    fn get_multi(&mut self, params: &Params) -> Result<&mut MultiPose> {
        let lm = params.pose.model.landmark_model().ok_or_else(|| {
            PipelineError::param(
                "pose.model",
                "several people need BlazePose (full, lite or heavy)",
            )
        })?;
        let want = multi_params(lm, params.pose.session(), self.shared.clone(), params);
        if self.multi.as_ref().is_none_or(|m| *m.params() != want) {
            self.multi = Some(MultiPose::new(want)?);
        }
        self.multi
            .as_mut()
            .ok_or_else(|| PipelineError::stage("loading the pose model", "no model"))
    }

    /// The model for `params`, opened when not loaded yet (or loaded with other settings).
    fn get(&mut self, params: &Params) -> Result<&mut (dyn PoseEstimator + Send)> {
        let (model, session) = (params.pose.model, params.pose.session());
        let recover = params.pose.recover_s.to_bits();
        let fits = matches!(&self.loaded, Some((m, s, r, _)) if *m == model && *s == session && *r == recover);
        if !fits {
            let est = open_estimator_with(model, session.clone(), params.pose.recover_s)?;
            self.loaded = Some((model, session, recover, est));
        }
        match self.loaded.as_mut() {
            Some((_, _, _, est)) => Ok(est.as_mut()),
            None => Err(PipelineError::stage("loading the pose model", "no model")),
        }
    }
}

/// The several-people estimator's settings: landmark model `lm` in `session`.
pub(crate) fn multi_params(
    lm: mp_pose::LandmarkModelKind,
    session: SessionParams,
    shared: Option<SharedLandmarks>,
    params: &Params,
) -> MultiPoseParams {
    MultiPoseParams {
        pose: BlazePoseParams {
            model: lm,
            session,
            shared,
            ..Default::default()
        },
        people: params.pose.tracker.clone(),
    }
}

/// What step 1 produced.
pub struct Keypoints {
    /// The keypoints (COCO-17 unless all joints were asked for).
    pub track: Track,
    /// The frame signal, grey thumbnails as a unitless feature track: of the
    /// tracked person's own box when people are tracked and someone was
    /// found with a box mostly inside the picture, else of the whole frames
    /// — or, when more periodic, of the region of the picture that moves on
    /// its own (`crate::frame_signal`).
    pub thumbnails: Option<Track>,
    /// How the frame signal was chosen (for video).
    pub frame_choice: Option<FrameChoice>,
    /// Fraction of frames with a person (1 for a track).
    pub found_fraction: f64,
    /// Title of the report.
    pub title: String,
    /// Where the motion came from.
    pub description: String,
    /// Video frame size (width, height), when known.
    pub frame_size: Option<(usize, usize)>,
    /// Largest frame side used as the scale, when known.
    pub frame_px: Option<f64>,
    /// Name of the pose model, for video.
    pub model: Option<String>,
    /// Every person in the video, in the track's skeleton (several-people
    /// tracking); `None` for a track file and the single-person pipeline.
    pub people: Option<People>,
    /// The person `track` follows, when people are tracked and someone was found.
    pub person: Option<PersonId>,
    /// The people analysed besides `person`, each with grey thumbnails of
    /// their own box over their own frames.
    pub others: Vec<(PersonId, Option<Thumbnails>)>,
    /// A sentence for the user about the people in view (more than
    /// `max_people`), when there is one.
    pub warning: Option<String>,
    /// Reduced frame copies for the report.
    pub frames: Option<FrameStore>,
    /// Frames for the overlay video.
    pub overlay: Option<OverlayFrames>,
    /// A video's frame signal, not yet read ([`frame_signal`]).
    pub(crate) pending: Option<PendingSignal>,
}

impl Keypoints {
    /// Keypoints that come without the video's frames (a track file, a live
    /// run's people): no frame signal, frame copies or overlay, nobody else.
    fn without_frames(
        track: Track,
        title: String,
        description: String,
        frame_size: Option<(usize, usize)>,
        frame_px: Option<f64>,
    ) -> Self {
        Keypoints {
            found_fraction: mp_abstract::found_fraction(&track),
            track,
            thumbnails: None,
            frame_choice: None,
            title,
            description,
            frame_size,
            frame_px,
            model: None,
            people: None,
            person: None,
            others: Vec::new(),
            warning: None,
            frames: None,
            overlay: None,
            pending: None,
        }
    }
}

/// What the caller wants kept of a video besides the keypoints.
#[derive(Debug, Clone, Copy, Default)]
pub struct Keep {
    /// Reduced JPEG copies for the report.
    pub report_frames: bool,
    /// Frames for the overlay video.
    pub overlay: bool,
}

/// Keypoints of the input (see the module docs), with the stage timings.
pub fn keypoints(
    input: Input,
    params: &Params,
    keep: Keep,
    observer: &dyn Observer,
    cancel: &CancelToken,
) -> Result<(Keypoints, Vec<StageTime>)> {
    params.validate()?;
    let mut timings = Timings::new(observer);
    let kp = keypoints_timed(
        input,
        params,
        keep,
        &mut timings,
        cancel,
        &mut ModelSlot::default(),
    )?;
    Ok((kp, timings.stages))
}

/// [`keypoints`] with its frame signal read ([`frame_signal`]).
pub(crate) fn keypoints_timed(
    input: Input,
    params: &Params,
    keep: Keep,
    timings: &mut Timings<'_>,
    cancel: &CancelToken,
    slot: &mut ModelSlot,
) -> Result<Keypoints> {
    let mut kp = keypoints_pending(input, params, keep, timings, cancel, slot)?;
    if let Some(pending) = kp.pending.take() {
        frame_signal(&kp, pending, params, timings, cancel)?.apply(&mut kp);
    }
    Ok(kp)
}

/// The keypoints, a video's frame signal left to be read
/// ([`Keypoints::pending`], [`frame_signal`]).
pub(crate) fn keypoints_pending(
    input: Input,
    params: &Params,
    keep: Keep,
    timings: &mut Timings<'_>,
    cancel: &CancelToken,
    slot: &mut ModelSlot,
) -> Result<Keypoints> {
    match input {
        Input::Video { path } => from_video(&path, params, keep, timings, cancel, slot),
        Input::Track {
            mut track,
            title,
            description,
            frame_size,
            frame_px,
            ..
        } => {
            if let Some(n) = params.pose.max_frames {
                if n < track.n_frames() {
                    track = track.slice_frames(0, n.max(1))?;
                }
            }
            Ok(Keypoints::without_frames(
                track,
                title,
                description,
                frame_size,
                frame_px,
            ))
        }
        Input::People {
            people,
            skeleton,
            posed,
            title,
            description,
            frame_size,
            model,
        } => from_people(
            people,
            skeleton,
            &posed,
            params,
            title,
            description,
            frame_size,
            model,
        ),
    }
}

/// The keypoints of people found elsewhere (a live run): the choice of
/// people and the tracks of `mp run`, without thumbnails or frames.
#[allow(clippy::too_many_arguments)]
fn from_people(
    people: People,
    skeleton: mp_geom::Skeleton,
    posed: &[bool],
    params: &Params,
    title: String,
    description: String,
    frame_size: (usize, usize),
    model: String,
) -> Result<Keypoints> {
    let (n, fps) = (people.n_frames(), people.fps());
    let coco = |t: Track| coco17_unless_all(t, params);
    let empty = coco(Track::new(
        ndarray::Array3::zeros((n, skeleton.len(), 2)),
        Some(ndarray::Array2::zeros((n, skeleton.len()))),
        fps,
        mp_geom::Units::Pixels,
        skeleton,
    )?)?;
    let people = crate::pose_rate::fill_people(people, posed)?.map_tracks(coco)?;
    let (top, rest) = chosen_people(&people, params)?;
    let track = match top {
        Some(id) => people.full_track(id)?,
        None => empty,
    };
    let frame_px = Some(frame_size.0.max(frame_size.1) as f64);
    Ok(Keypoints {
        model: Some(model),
        people: Some(people),
        person: top,
        others: rest.into_iter().map(|id| (id, None)).collect(),
        ..Keypoints::without_frames(track, title, description, Some(frame_size), frame_px)
    })
}

/// `track` in COCO-17 where its skeleton maps to it, unless every joint
/// was asked for.
fn coco17_unless_all(t: Track, params: &Params) -> std::result::Result<Track, mp_geom::GeomError> {
    if !params.pose.all_joints && t.skeleton().name != "coco17" && t.skeleton().maps_to_coco17() {
        t.to_coco17()
    } else {
        Ok(t)
    }
}

fn from_video(
    path: &Path,
    params: &Params,
    keep: Keep,
    timings: &mut Timings<'_>,
    cancel: &CancelToken,
    slot: &mut ModelSlot,
) -> Result<Keypoints> {
    let max_frames = params.pose.max_frames;
    let reader = VideoReader::open(path)?;
    let info = reader.info().clone();
    let expected = match (info.frame_count, max_frames) {
        (Some(n), Some(m)) => Some(n.min(m)),
        (n, None) => n,
        (None, m) => m,
    };
    // Full-size frames are kept for the overlay when their count is known and they fit.
    let frame_bytes = mp_pose::Yuv420Frame::bytes(info.width, info.height);
    let keep_full = keep.overlay
        && expected.is_some_and(|n| n.saturating_mul(frame_bytes) <= KEEP_FRAMES_BUDGET_BYTES);
    let t0 = Instant::now();
    // The report's reduced frames: a long video's few on the decoding
    // thread, a short video's many by FFmpeg on its own thread.
    let store = keep
        .report_frames
        .then(|| {
            FrameStore::new(
                info.width,
                info.height,
                expected,
                &FrameStoreParams {
                    max_frames: params.output.report_frames,
                    ..FrameStoreParams::default()
                },
            )
        })
        .transpose()?;
    let (copies, jpegs) = match store {
        Some(store) if store.step >= COPY_ON_DECODER_MIN_STEP => {
            let encode = store.encoder();
            let copies = FrameCopies {
                step: store.step,
                first: 0,
                copy: Arc::new(move |at, f: &Frame| encode(at, &f.rgb).map_err(|e| e.to_string())),
            };
            (Some((copies, store)), None)
        }
        Some(store) => (
            None,
            Some(start_jpeg_copies(&info, max_frames, store, cancel.clone())?),
        ),
        None => (None, None),
    };
    let copy_options = copies.as_ref().map(|(c, _)| c.clone());
    // Whole-frame thumbnails at the side the expected length allows
    // (`signal_track` reduces them further if the video is longer).
    let side = signal_side(params.pose.thumbnail_size, expected.unwrap_or(0));
    let observer = timings.observer();
    let multi = params.pose.people && params.pose.model.landmark_model().is_some();
    // A long video is tracked in pieces side by side, each decoding its own frames.
    let pieces = if multi && !keep_full {
        pose_pieces(params, &info, expected, slot.shared.is_some())?
    } else {
        Vec::new()
    };
    let (ex, decoded) = if pieces.len() > 1 {
        drop(reader);
        observer.started(Stage::Pose, expected);
        let progress = |d| observer.progress(Stage::Pose, d);
        match pose_people_in_pieces(
            &info,
            &pieces,
            side,
            copy_options,
            params,
            cancel,
            &progress,
        ) {
            Ok((posed, decoded)) => (Ok(posed), decoded),
            Err(e) => (Err(e), mp_pose::Decoded::default()),
        }
    } else {
        let (source, decoder) = decode_ahead(
            reader,
            &DecodeOptions {
                limit: max_frames,
                keep_full,
                thumbnail_size: Some(side),
                copies: copy_options,
                ..DecodeOptions::default()
            },
            cancel.clone(),
        )?;
        observer.started(Stage::Pose, expected);
        let ex = if multi {
            pose_people(source, slot, params, |d| observer.progress(Stage::Pose, d))
        } else {
            pose_single(source, slot, params, |d| observer.progress(Stage::Pose, d))
        };
        // The frame source is gone once the pose pass returns, so the decoder stops too.
        let decoded = decoder
            .join()
            .map_err(|_| PipelineError::stage("decoding", "the decoding thread panicked"))?;
        (ex, decoded)
    };
    let wall = t0.elapsed();
    let jpegs = jpegs
        .map(|h| {
            h.join()
                .map_err(|_| PipelineError::stage("frame copies", "the JPEG thread panicked"))
        })
        .transpose()?;
    check(cancel)?;
    let posed = ex?;
    let n = posed.n_frames;
    timings.push(Stage::Decode, decoded.decode, n);
    let frames = match (jpegs, copies) {
        (Some(c), _) => {
            c.result?;
            timings.push(Stage::Jpeg, c.time, c.store.frames.len());
            Some(c.store)
        }
        (None, Some((_, mut store))) => {
            for (index, jpeg) in decoded.copies {
                store.push_jpeg(index, jpeg)?;
            }
            timings.push(Stage::Jpeg, decoded.copying, store.frames.len());
            Some(store)
        }
        (None, None) => None,
    };
    timings.push(Stage::Pose, wall, n);
    let coco = |t: Track| coco17_unless_all(t, params);
    let mut thumbs = decoded.thumbnails;
    thumbs.truncate(n * side * side);
    let whole_frame = if thumbs.len() == n * side * side && n > 0 {
        Some(Thumbnails::signal(thumbs, side, info.fps)?)
    } else {
        None
    };
    let (track, found, people, person, others) = match posed.people {
        None => {
            let track = coco(posed.track)?;
            (track, posed.found, None, None, Vec::new())
        }
        Some(people) => {
            let people = people.map_tracks(coco)?;
            let (top, rest) = chosen_people(&people, params)?;
            let track = match top {
                Some(id) => people.full_track(id)?,
                None => coco(posed.track)?,
            };
            let found = mp_abstract::found_fraction(&track);
            let others = rest.iter().map(|id| (*id, None)).collect();
            (track, found, Some(people), top, others)
        }
    };
    let overlay = keep.overlay.then(|| OverlayFrames {
        info: info.clone(),
        kept: decoded.kept.filter(|k| k.len() >= n),
    });
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(Keypoints {
        description: format!(
            "video {} · {}×{} at {:.2} fps · {} frames · {} ({} joints) · {}",
            name,
            info.width,
            info.height,
            info.fps,
            n,
            posed.model,
            track.n_joints(),
            match (&people, person) {
                (Some(p), Some(id)) => format!(
                    "{} {} tracked · person {id} found in {:.0}% of frames",
                    p.len(),
                    if p.len() == 1 { "person" } else { "people" },
                    100.0 * found
                ),
                (Some(_), None) => "nobody found".to_string(),
                (None, _) => format!("person found in {:.0}% of frames", 100.0 * found),
            }
        ),
        title: name,
        track,
        thumbnails: None,
        frame_choice: None,
        found_fraction: found,
        frame_size: Some((info.width, info.height)),
        frame_px: Some(info.width.max(info.height) as f64),
        model: Some(posed.model),
        people,
        person,
        others,
        warning: posed.warning,
        frames,
        overlay,
        pending: Some(PendingSignal {
            path: path.to_path_buf(),
            whole: whole_frame,
        }),
    })
}

/// What the pose pass gave.
pub(crate) struct Posed {
    /// The single-person track, or an empty track of the people's skeleton.
    track: Track,
    found: f64,
    people: Option<People>,
    n_frames: usize,
    model: String,
    warning: Option<String>,
}

/// The extraction options of the pose pass: all frames or the first
/// `max_frames`, the model on the frames of `params.pose.rate` at the
/// video's `fps`, no smoothing.
pub(crate) fn extract_options(params: &Params, fps: f64) -> ExtractOptions {
    ExtractOptions {
        max_frames: params.pose.max_frames,
        pose_every: params.pose.rate.stride(fps),
        ..Default::default()
    }
}

fn pose_single(
    source: FrameSource,
    slot: &mut ModelSlot,
    params: &Params,
    progress: impl Fn(usize),
) -> Result<Posed> {
    let fps = source.fps;
    let est = slot.get(params)?;
    let ex = extract_track(source, est, &extract_options(params, fps), |done, _| {
        progress(done)
    })?;
    Ok(Posed {
        n_frames: ex.track.n_frames(),
        found: ex.found_fraction(),
        track: crate::pose_rate::fill_track(&ex.track, &ex.posed)?,
        people: None,
        model: est.name().to_string(),
        warning: None,
    })
}

fn pose_people(
    source: FrameSource,
    slot: &mut ModelSlot,
    params: &Params,
    progress: impl Fn(usize),
) -> Result<Posed> {
    let fps = source.fps;
    let est = slot.get_multi(params)?;
    let ex = extract_people(source, est, &extract_options(params, fps), |done, _| {
        progress(done)
    })?;
    posed_people(ex, est.name(), est.skeleton(), fps)
}

/// What the several-people pass gave, with every skipped frame filled.
pub(crate) fn posed_people(
    ex: mp_pose::PeopleExtraction,
    name: &str,
    skeleton: mp_geom::Skeleton,
    fps: f64,
) -> Result<Posed> {
    let n = ex.people.n_frames();
    let empty = Track::new(
        ndarray::Array3::zeros((n, skeleton.len(), 2)),
        Some(ndarray::Array2::zeros((n, skeleton.len()))),
        fps,
        mp_geom::Units::Pixels,
        skeleton,
    )?;
    Ok(Posed {
        track: empty,
        found: ex.found_fraction(),
        n_frames: n,
        model: name.to_string(),
        warning: ex.warning(),
        people: Some(crate::pose_rate::fill_people(ex.people, &ex.posed)?),
    })
}

/// The person whose results are the top-level ones, and the others to analyse
/// ([`crate::PersonParams`]).
pub(crate) fn chosen_people(
    people: &People,
    params: &Params,
) -> Result<(Option<PersonId>, Vec<PersonId>)> {
    let main = people.main_person().map(|p| p.id);
    match params.person.choice {
        PersonChoice::Id(id) => {
            if people.get(id).is_none() {
                let ids: Vec<String> = people.people().iter().map(|p| p.id.to_string()).collect();
                return Err(PipelineError::param(
                    "person",
                    if ids.is_empty() {
                        format!("there is no person {id}: nobody was found in the video")
                    } else {
                        format!(
                            "there is no person {id}; the people found are {}",
                            ids.join(", ")
                        )
                    },
                ));
            }
            Ok((Some(id), Vec::new()))
        }
        PersonChoice::Main => Ok((main, Vec::new())),
        PersonChoice::All => {
            let min_frames = params.person.min_seen_s * people.fps();
            let rest = people
                .people()
                .iter()
                .filter(|p| Some(p.id) != main && p.frames_found() as f64 >= min_frames)
                .map(|p| p.id)
                .collect();
            Ok((main, rest))
        }
    }
}

/// What the JPEG thread hands back.
struct JpegCopies {
    store: FrameStore,
    result: Result<()>,
    time: std::time::Duration,
}

/// Reduced JPEG copies of the frames the store keeps, read on their own
/// thread from a second FFmpeg process.
fn start_jpeg_copies(
    info: &VideoInfo,
    limit: Option<usize>,
    mut store: FrameStore,
    cancel: CancelToken,
) -> Result<std::thread::JoinHandle<JpegCopies>> {
    let mut stream = MjpegStream::start(
        info,
        &MjpegOptions {
            step: store.step,
            size: Some(store.size),
            limit,
            qscale: REPORT_JPEG_QSCALE,
        },
    )?;
    let what = format!("frames of {}", info.path.display());
    std::thread::Builder::new()
        .name("jpeg".into())
        .spawn(move || {
            let t0 = Instant::now();
            let mut result = Ok(());
            if let Some(r) = stream.reader() {
                for k in 0.. {
                    if cancel.is_cancelled() {
                        break;
                    }
                    let index = k * store.step;
                    if limit.is_some_and(|n| index >= n) {
                        break;
                    }
                    match mp_report::read_jpeg(r, &what, k) {
                        Ok(Some(jpg)) => {
                            if let Err(e) = store.push_jpeg(index, jpg) {
                                result = Err(e.into());
                                break;
                            }
                        }
                        Ok(None) => break,
                        Err(e) => {
                            result = Err(e.into());
                            break;
                        }
                    }
                }
            }
            let (status, msg) = stream.finish();
            if result.is_ok() && store.frames.is_empty() && !cancel.is_cancelled() {
                result = Err(PipelineError::stage(
                    "keeping reduced frames for the report",
                    format!(
                        "ffmpeg wrote no JPEG frames for {what} ({status}){}",
                        if msg.is_empty() {
                            String::new()
                        } else {
                            format!(": {msg}")
                        }
                    ),
                ));
            }
            JpegCopies {
                store,
                result,
                time: t0.elapsed(),
            }
        })
        .map_err(|e| PipelineError::stage("starting the JPEG thread", e))
}
