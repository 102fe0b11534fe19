//! Whole videos to tracks: runs an estimator over every frame and collects
//! the keypoints into `mp_geom::Track`s (pixels, and metres where the model
//! gives world coordinates). Frames without a person get confidence 0 for
//! every joint; no keypoint is ever invented.

use std::path::Path;
use std::time::Instant;

use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array2, Array3};

use crate::blazepose::{BlazePose, BlazePoseParams, LandmarkModelKind};
use crate::error::{PoseError, Result};
use crate::filter::{LowPass, OneEuroParams, PointsFilter};
use crate::movenet::{MoveNet, MoveNetParams};
use crate::pose::{Pose, PoseEstimator};
use crate::runtime::SessionParams;
use crate::video::{open_source, Frame, FrameSource};

/// Which model to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum ModelChoice {
    /// BlazePose with the full landmark model. Default.
    #[default]
    Full,
    /// BlazePose with the lite landmark model.
    Lite,
    /// BlazePose with the heavy landmark model (if its ONNX file is present).
    Heavy,
    /// MoveNet SinglePose Lightning (COCO-17, no tracking, no world coordinates).
    MoveNet,
}

impl ModelChoice {
    /// Parses `full`, `lite`, `heavy`, `movenet`.
    pub fn parse(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "full" => Ok(ModelChoice::Full),
            "lite" => Ok(ModelChoice::Lite),
            "heavy" => Ok(ModelChoice::Heavy),
            "movenet" | "movenet-lightning" => Ok(ModelChoice::MoveNet),
            other => Err(PoseError::param(
                "model",
                format!("unknown model `{other}` (expected full, lite, heavy or movenet)"),
            )),
        }
    }
    /// The BlazePose landmark model of this choice; `None` for MoveNet.
    pub fn landmark_model(self) -> Option<LandmarkModelKind> {
        match self {
            ModelChoice::Full => Some(LandmarkModelKind::Full),
            ModelChoice::Lite => Some(LandmarkModelKind::Lite),
            ModelChoice::Heavy => Some(LandmarkModelKind::Heavy),
            ModelChoice::MoveNet => None,
        }
    }
    /// Short name.
    pub fn as_str(self) -> &'static str {
        match self {
            ModelChoice::Full => "full",
            ModelChoice::Lite => "lite",
            ModelChoice::Heavy => "heavy",
            ModelChoice::MoveNet => "movenet",
        }
    }
}

/// Opens the estimator for a model choice with default parameters and the
/// given session settings.
pub fn open_estimator(
    model: ModelChoice,
    session: SessionParams,
) -> Result<Box<dyn PoseEstimator + Send>> {
    open_estimator_with(model, session, BlazePoseParams::default().recover_s)
}

/// [`open_estimator`] with BlazePose's recovery after a lost person
/// ([`BlazePoseParams::recover_s`], seconds; MoveNet has no tracking and
/// ignores it).
pub fn open_estimator_with(
    model: ModelChoice,
    session: SessionParams,
    recover_s: f64,
) -> Result<Box<dyn PoseEstimator + Send>> {
    let Some(lm) = model.landmark_model() else {
        return Ok(Box::new(MoveNet::new(MoveNetParams {
            session,
            ..Default::default()
        })?));
    };
    Ok(Box::new(BlazePose::new(BlazePoseParams {
        model: lm,
        session,
        recover_s,
        ..Default::default()
    })?))
}

/// Optional output smoothing, as MediaPipe's `smooth_landmarks=True`:
/// visibility low-pass, One-Euro on image keypoints (scaled by the person's
/// size) and on world keypoints. Filters restart after a frame without a person.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothingParams {
    /// Image keypoints filter. Default (0.05, 80, 1).
    pub keypoints: OneEuroParams,
    /// World keypoints filter. Default (0.1, 40, 1, no value scaling).
    pub world: OneEuroParams,
    /// α of the visibility low-pass. Default 0.1.
    pub visibility_alpha: f64,
}

impl Default for SmoothingParams {
    fn default() -> Self {
        SmoothingParams {
            keypoints: OneEuroParams::LANDMARKS,
            world: OneEuroParams::WORLD_LANDMARKS,
            visibility_alpha: 0.1,
        }
    }
}

impl SmoothingParams {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        self.keypoints.validate("smoothing.keypoints")?;
        self.world.validate("smoothing.world")?;
        if !(self.visibility_alpha.is_finite()
            && self.visibility_alpha > 0.0
            && self.visibility_alpha <= 1.0)
        {
            return Err(PoseError::param(
                "smoothing.visibility_alpha",
                format!("must be in (0, 1], got {}", self.visibility_alpha),
            ));
        }
        Ok(())
    }
}

/// Stateful smoother of successive poses.
#[derive(Debug, Clone)]
pub struct PoseSmoother {
    params: SmoothingParams,
    keypoints: PointsFilter,
    world: PointsFilter,
    visibility: Vec<LowPass>,
}

impl PoseSmoother {
    /// A fresh smoother.
    pub fn new(params: SmoothingParams) -> Result<Self> {
        params.validate()?;
        Ok(PoseSmoother {
            keypoints: PointsFilter::new(params.keypoints),
            world: PointsFilter::new(params.world),
            visibility: Vec::new(),
            params,
        })
    }

    /// Forgets all state (call on a frame without a person).
    pub fn reset(&mut self) {
        self.keypoints.reset();
        self.world.reset();
        self.visibility.clear();
    }

    /// Smooths a pose observed at `time_s` in place.
    pub fn apply(&mut self, time_s: f64, pose: &mut Pose) {
        let t = (time_s * 1e9).round() as i64;
        if self.visibility.len() != pose.visibility.len() {
            self.visibility = vec![LowPass::default(); pose.visibility.len()];
        }
        for (v, f) in pose.visibility.iter_mut().zip(self.visibility.iter_mut()) {
            *v = f.apply(*v, self.params.visibility_alpha);
        }
        let mut pts: Vec<[f64; 3]> = pose
            .keypoints_px
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let z = pose
                    .depth_px
                    .as_ref()
                    .and_then(|d| d.get(k))
                    .copied()
                    .unwrap_or(0.0);
                [p[0], p[1], z]
            })
            .collect();
        self.keypoints.apply(t, pose.object_scale_px, &mut pts);
        for (k, p) in pts.iter().enumerate() {
            if let Some(kp) = pose.keypoints_px.get_mut(k) {
                *kp = [p[0], p[1]];
            }
            if let Some(d) = pose.depth_px.as_mut().and_then(|d| d.get_mut(k)) {
                *d = p[2];
            }
        }
        if let Some(w) = pose.world_m.as_mut() {
            self.world.apply(t, 1.0, w);
        }
    }
}

/// Options of [`extract_track`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExtractOptions {
    /// Output smoothing; `None` (default) = off.
    pub smoothing: Option<SmoothingParams>,
    /// Stop after this many frames (`None` = all).
    pub max_frames: Option<usize>,
    /// Time between frames used by the smoothing filters instead of the
    /// frames' timestamps (MediaPipe's Python API uses 1/30 s).
    pub fixed_frame_interval_s: Option<f64>,
    /// The pose model runs on every `pose_every`-th frame (0, 2k, …) and on
    /// the last one, when the number of frames is known; the frames between
    /// get no pose here (the caller fills them: `mp_pipeline::pose_rate`).
    /// 0 or 1 (default): every frame.
    pub pose_every: usize,
}

/// Whether frame `index` is one the pose model runs on ([`ExtractOptions::pose_every`]):
/// every `every`-th frame from the first, and the last of `total` frames.
pub fn is_posed_frame(index: usize, every: usize, total: Option<usize>) -> bool {
    every <= 1 || index.is_multiple_of(every) || total.is_some_and(|n| index + 1 == n)
}

/// Result of running an estimator over a video.
#[derive(Debug, Clone)]
pub struct Extraction {
    /// Keypoints in pixels (`T × J × 2`), confidence = visibility, the video's fps.
    pub track: Track,
    /// World keypoints in metres (`T × J × 3`), when the model gives them.
    pub world: Option<Track>,
    /// Relative depth per keypoint (`T × J`, pixels; 0 where missing), when the model gives it.
    pub depth_px: Option<Array2<f64>>,
    /// Per-keypoint presence (`T × J`; 0 where no pose).
    pub presence: Array2<f64>,
    /// Whether each frame has a pose.
    pub found: Vec<bool>,
    /// Whether the pose model ran on each frame ([`ExtractOptions::pose_every`]).
    pub posed: Vec<bool>,
    /// Whether the detector ran on each frame (BlazePose).
    pub detector_ran: Vec<bool>,
    /// Milliseconds spent in the estimator per posed frame (no decoding).
    pub estimate_ms: Vec<f64>,
    /// Milliseconds for the whole run, decoding included.
    pub total_ms: f64,
    /// Frame size.
    pub width: usize,
    /// Frame size.
    pub height: usize,
}

impl Extraction {
    /// Frames per second of the estimator alone (median per-frame time).
    pub fn estimator_fps(&self) -> f64 {
        median_fps(&self.estimate_ms)
    }
    /// Fraction of the posed frames with a pose.
    pub fn found_fraction(&self) -> f64 {
        posed_fraction(&self.found, &self.posed)
    }
}

/// Fraction of the posed frames (`posed`) where `found` holds; 0 without any.
pub(crate) fn posed_fraction(found: &[bool], posed: &[bool]) -> f64 {
    let (mut n, mut k) = (0usize, 0usize);
    for (i, f) in found.iter().enumerate() {
        if posed.get(i).copied().unwrap_or(true) {
            n += 1;
            k += usize::from(*f);
        }
    }
    if n == 0 {
        0.0
    } else {
        k as f64 / n as f64
    }
}

/// Frames per second from per-frame milliseconds: 1000 over the median (0
/// without frames or time).
pub(crate) fn median_fps(ms: &[f64]) -> f64 {
    let mut v = ms.to_vec();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let med = v[v.len() / 2];
    if med > 0.0 {
        1000.0 / med
    } else {
        0.0
    }
}

/// Runs `estimator` over the frames of `source` (every frame, or those
/// [`ExtractOptions::pose_every`] names). `progress(done, total)` is called
/// after each frame.
pub fn extract_track(
    mut source: FrameSource,
    estimator: &mut dyn PoseEstimator,
    options: &ExtractOptions,
    mut progress: impl FnMut(usize, Option<usize>),
) -> Result<Extraction> {
    if let Some(s) = &options.smoothing {
        s.validate()?;
    }
    if let Some(dt) = options.fixed_frame_interval_s {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(PoseError::param(
                "fixed_frame_interval_s",
                format!("must be > 0, got {dt}"),
            ));
        }
    }
    estimator.reset();
    let mut smoother = options.smoothing.map(PoseSmoother::new).transpose()?;
    let skeleton: Skeleton = estimator.skeleton();
    let j = skeleton.len();
    let total = match (source.frame_count, options.max_frames) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, None) => a,
        (None, b) => b,
    };
    let start = Instant::now();
    let mut poses: Vec<Option<Pose>> = Vec::new();
    let mut posed = Vec::new();
    let mut estimate_ms = Vec::new();
    let mut done = 0usize;
    while options.max_frames.is_none_or(|m| done < m) {
        let Some(frame) = source.frames.next() else {
            break;
        };
        let frame: Frame = frame?;
        if !is_posed_frame(done, options.pose_every, total) {
            poses.push(None);
            posed.push(false);
            done += 1;
            progress(done, total);
            continue;
        }
        posed.push(true);
        let t0 = Instant::now();
        let mut pose = estimator.estimate(&frame)?;
        estimate_ms.push(t0.elapsed().as_secs_f64() * 1000.0);
        if let Some(sm) = smoother.as_mut() {
            match pose.as_mut() {
                Some(p) => {
                    let t = match options.fixed_frame_interval_s {
                        Some(dt) => (frame.index as f64 + 1.0) * dt,
                        None => frame.timestamp_s,
                    };
                    sm.apply(t, p)
                }
                None => sm.reset(),
            }
        }
        if let Some(p) = &pose {
            if p.keypoints_px.len() != j || p.visibility.len() != j {
                return Err(PoseError::BadFrame {
                    frame: frame.index,
                    reason: format!(
                        "{} returned {} keypoints, its skeleton has {j}",
                        estimator.name(),
                        p.keypoints_px.len()
                    ),
                });
            }
        }
        poses.push(pose);
        done += 1;
        progress(done, total);
    }
    let total_ms = start.elapsed().as_secs_f64() * 1000.0;
    let t = poses.len();
    if t == 0 {
        return Err(PoseError::Video {
            path: Path::new("(input)").to_path_buf(),
            reason: "no frames".into(),
        });
    }
    let has_world = estimator.has_world();
    let mut pos = Array3::<f64>::zeros((t, j, 2));
    let mut conf = Array2::<f64>::zeros((t, j));
    let mut presence = Array2::<f64>::zeros((t, j));
    let mut world = Array3::<f64>::zeros((t, j, 3));
    let mut world_conf = Array2::<f64>::zeros((t, j));
    let mut depth = Array2::<f64>::zeros((t, j));
    let mut has_depth = false;
    let mut found = Vec::with_capacity(t);
    let mut detector_ran = Vec::with_capacity(t);
    for (ti, p) in poses.iter().enumerate() {
        found.push(p.is_some());
        detector_ran.push(p.as_ref().is_some_and(|p| p.detector_ran));
        let Some(p) = p else { continue };
        for k in 0..j {
            let finite = p.keypoints_px[k].iter().all(|v| v.is_finite());
            if !finite {
                continue;
            }
            pos[[ti, k, 0]] = p.keypoints_px[k][0];
            pos[[ti, k, 1]] = p.keypoints_px[k][1];
            conf[[ti, k]] = p.visibility[k];
            presence[[ti, k]] = p.presence.get(k).copied().unwrap_or(0.0);
            if let Some(d) = p.depth_px.as_ref().and_then(|d| d.get(k)) {
                depth[[ti, k]] = *d;
                has_depth = true;
            }
            if let Some(w) = p.world_m.as_ref().and_then(|w| w.get(k)) {
                world[[ti, k, 0]] = w[0];
                world[[ti, k, 1]] = w[1];
                world[[ti, k, 2]] = w[2];
                world_conf[[ti, k]] = p.visibility[k];
            }
        }
    }
    let track = Track::new(pos, Some(conf), source.fps, Units::Pixels, skeleton.clone())?;
    let world = if has_world {
        Some(Track::new(
            world,
            Some(world_conf),
            source.fps,
            Units::Metres,
            skeleton,
        )?)
    } else {
        None
    };
    Ok(Extraction {
        track,
        world,
        depth_px: has_depth.then_some(depth),
        presence,
        found,
        posed,
        detector_ran,
        estimate_ms,
        total_ms,
        width: source.width,
        height: source.height,
    })
}

/// Opens a video or image and runs a model over it (default parameters).
pub fn extract_file(
    path: impl AsRef<Path>,
    model: ModelChoice,
    options: &ExtractOptions,
    progress: impl FnMut(usize, Option<usize>),
) -> Result<Extraction> {
    let source = open_source(path.as_ref())?;
    let mut est = open_estimator(model, SessionParams::default())?;
    extract_track(source, est.as_mut(), options, progress)
}
