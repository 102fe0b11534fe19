//! Step 1: keypoints (and frame thumbnails) from the input.
//!
//! For a video, a decoding thread feeds the pose model and keeps grey
//! thumbnails of every frame (and, when an overlay video is wanted and they
//! fit in memory, full-size copies); a second FFmpeg process writes reduced
//! JPEG copies for the report alongside.

use std::path::Path;
use std::time::Instant;

use mp_geom::{CancelToken, Track};
use mp_pose::decode::{decode_ahead, DecodeOptions, MjpegOptions, MjpegStream};
use mp_pose::extract::{extract, open_estimator_with, ExtractOptions};
use mp_pose::thumbs::thumbnail_track;
use mp_pose::video::{VideoInfo, VideoReader};
use mp_pose::SessionParams;
use mp_pose::{ModelChoice, PoseEstimator};
use mp_report::{FrameStore, FrameStoreParams};

use crate::error::{PipelineError, Result};
use crate::input::Input;
use crate::params::Params;
use crate::progress::{check, Observer, Stage, StageTime, Timings};

/// Full-size frames kept in memory during the pose pass for the overlay
/// video, up to this many bytes; longer videos are decoded a second time.
pub const KEEP_FRAMES_BUDGET_BYTES: usize = 512 << 20;

/// Quality of the report's frame copies on FFmpeg's `-q:v` scale (2 best,
/// 31 worst). 4 gives about the PSNR of libjpeg quality 72 at full chroma
/// resolution (≈ 40 dB on the golf swing) in files about 25 % smaller.
pub const REPORT_JPEG_QSCALE: u32 = 4;

/// The frames of the overlay video.
pub struct OverlayFrames {
    /// The video (size, frame rate, path).
    pub info: VideoInfo,
    /// Full-size RGB frames kept during the pose pass; `None`: decode the video again.
    pub kept: Option<Vec<Vec<u8>>>,
}

/// A pose model kept loaded between videos: the first video opens it, the
/// next ones with the same model and thread count reuse it (its tracking
/// state is reset for each video).
#[derive(Default)]
pub struct ModelSlot {
    loaded: Option<(ModelChoice, usize, u64, Box<dyn PoseEstimator + Send>)>,
}

impl ModelSlot {
    /// The model for `params`, opened when not loaded yet (or loaded with other settings).
    fn get(&mut self, params: &Params) -> Result<&mut (dyn PoseEstimator + Send)> {
        let (model, threads) = (params.pose.model, params.pose.threads.max(1));
        let recover = params.pose.recover_s.to_bits();
        let fits = matches!(&self.loaded, Some((m, t, r, _)) if *m == model && *t == threads && *r == recover);
        if !fits {
            let est = open_estimator_with(
                model,
                SessionParams {
                    intra_threads: threads,
                    ..Default::default()
                },
                params.pose.recover_s,
            )?;
            self.loaded = Some((model, threads, recover, est));
        }
        match self.loaded.as_mut() {
            Some((_, _, _, est)) => Ok(est.as_mut()),
            None => Err(PipelineError::stage("loading the pose model", "no model")),
        }
    }
}

/// What step 1 produced.
pub struct Keypoints {
    /// The keypoints (COCO-17 unless all joints were asked for).
    pub track: Track,
    /// Grey thumbnails of the video frames as a unitless feature track.
    pub thumbnails: Option<Track>,
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
    /// Reduced frame copies for the report.
    pub frames: Option<FrameStore>,
    /// Frames for the overlay video.
    pub overlay: Option<OverlayFrames>,
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

pub(crate) fn keypoints_timed(
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
        } => {
            if let Some(n) = params.pose.max_frames {
                if n < track.n_frames() {
                    track = track.slice_frames(0, n.max(1))?;
                }
            }
            Ok(Keypoints {
                found_fraction: mp_abstract::count::found_fraction(&track),
                track,
                thumbnails: None,
                title,
                description,
                frame_size,
                frame_px,
                model: None,
                frames: None,
                overlay: None,
            })
        }
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
    let frame_bytes = info.width * info.height * 3;
    let keep_full = keep.overlay
        && expected.is_some_and(|n| n.saturating_mul(frame_bytes) <= KEEP_FRAMES_BUDGET_BYTES);
    let t0 = Instant::now();
    let jpegs = if keep.report_frames {
        let store = FrameStore::new(
            info.width,
            info.height,
            expected,
            &FrameStoreParams::default(),
        )?;
        Some(start_jpeg_copies(&info, max_frames, store, cancel.clone())?)
    } else {
        None
    };
    let (source, decoder) = decode_ahead(
        reader,
        &DecodeOptions {
            limit: max_frames,
            keep_full,
            thumbnail_size: Some(params.pose.thumbnail_size),
            ..DecodeOptions::default()
        },
        cancel.clone(),
    )?;
    let observer = timings.observer();
    observer.started(Stage::Pose, expected);
    let ex = slot.get(params).and_then(|est| {
        let ex = extract(
            source,
            est,
            &ExtractOptions {
                max_frames,
                ..Default::default()
            },
            |done, _| observer.progress(Stage::Pose, done),
        )?;
        Ok((ex, est.name().to_string()))
    });
    // The frame source is gone once `extract` returns, so the decoder stops too.
    let decoded = decoder
        .join()
        .map_err(|_| PipelineError::stage("decoding", "the decoding thread panicked"))?;
    let wall = t0.elapsed();
    let copies = jpegs
        .map(|h| {
            h.join()
                .map_err(|_| PipelineError::stage("frame copies", "the JPEG thread panicked"))
        })
        .transpose()?;
    check(cancel)?;
    let (ex, model_name) = ex?;
    let n = ex.track.n_frames();
    timings.push(Stage::Decode, decoded.decode, n);
    let frames = match copies {
        Some(c) => {
            c.result?;
            timings.push(Stage::Jpeg, c.time, c.store.frames.len());
            Some(c.store)
        }
        None => None,
    };
    timings.push(Stage::Pose, wall, n);
    let found = ex.found_fraction();
    let mut track = ex.track;
    if !params.pose.all_joints
        && track.skeleton().name != "coco17"
        && track.skeleton().maps_to_coco17()
    {
        track = track.to_coco17()?;
    }
    let mut thumbs = decoded.thumbnails;
    thumbs.truncate(n);
    let thumbnails = if thumbs.len() == n && n > 0 {
        Some(thumbnail_track(
            thumbs,
            params.pose.thumbnail_size,
            info.fps,
        )?)
    } else {
        None
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
            "video {} · {}×{} at {:.2} fps · {} frames · {} ({} joints) · person found in {:.0}% of frames",
            name,
            info.width,
            info.height,
            info.fps,
            n,
            model_name,
            track.n_joints(),
            100.0 * found
        ),
        title: name,
        track,
        thumbnails,
        found_fraction: found,
        frame_size: Some((info.width, info.height)),
        frame_px: Some(info.width.max(info.height) as f64),
        model: Some(model_name),
        frames,
        overlay,
    })
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
                    match mp_report::frames::read_jpeg(r, &what, k) {
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
