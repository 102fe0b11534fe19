//! BlazePose: person detector + GHUM landmark model with tracking, as in
//! MediaPipe's legacy Pose solution.
//!
//! Per frame: when no crop region is carried over from the previous frame,
//! the detector runs and the best detection's keypoints 0/1 give the region
//! (centre = hip centre, side = 2·|kp1 − kp0|·1.25, rotated so the body points
//! up). The landmark model runs on that rotated 256×256 crop; a pose presence
//! below 0.5 means no person (and the detector runs on the next frame).
//! Otherwise the two auxiliary landmarks (33, 34), smoothed by a One-Euro
//! filter (min_cutoff 0.01, beta 10, derivate_cutoff 1, scaled by the size of
//! the person), give the next frame's region.

pub mod detector;
pub mod landmarks;
mod shared;

use std::path::PathBuf;

use mp_geom::Skeleton;

use crate::error::{PoseError, Result};
use crate::filter::{OneEuroParams, PointsFilter};
use crate::imageops::{RgbView, Roi};
use crate::pose::{Pose, PoseEstimator};
use crate::runtime::{self, ModelFile, SessionParams};
use crate::video::Frame;

pub use detector::{DetectorParams, PoseDetector};
pub use landmarks::{LandmarkModel, LandmarkModelKind, LandmarkOutput, RefineParams};
pub use shared::{SharedLandmarks, SharedStats};

/// Index of the first auxiliary landmark (crop centre for tracking).
pub(crate) const AUX_CENTER: usize = 33;
/// Index of the second auxiliary landmark (crop scale/rotation point).
pub(crate) const AUX_SCALE: usize = 34;

/// Parameters of the BlazePose pipeline; defaults are MediaPipe's
/// (`model_complexity=1`, `min_detection_confidence=0.5`,
/// `min_tracking_confidence=0.5`).
#[derive(Debug, Clone, PartialEq)]
pub struct BlazePoseParams {
    /// Landmark model. Default [`LandmarkModelKind::Full`].
    pub model: LandmarkModelKind,
    /// Detector decoding (score 0.5, NMS IoU 0.3).
    pub detector: DetectorParams,
    /// Pose presence below which a frame has no person. Default 0.5.
    pub min_presence: f32,
    /// Scale of the crop around the body (side = 2·|kp1 − kp0|·scale). Default 1.25.
    pub roi_scale: f64,
    /// Heatmap refinement (on, 7×7, 0.5).
    pub refine: RefineParams,
    /// Carry the crop region from frame to frame (video). Default true;
    /// false runs the detector on every frame (still images).
    pub tracking: bool,
    /// Recovery after the tracked person is lost (video, seconds). When the
    /// carried region no longer holds a person, the detector runs on the
    /// same frame instead of the next one; when it finds no one, the region
    /// of the last pose is tried again, for up to `recover_s` seconds after
    /// that pose. Default 0: MediaPipe's behaviour (no pose on the frame
    /// where tracking fails, the detector alone from the next frame). Worth
    /// it on low frame rates, where the next frame is far away in time.
    pub recover_s: f64,
    /// One-Euro filter of the auxiliary landmarks that place the next crop.
    pub aux_filter: OneEuroParams,
    /// Time between frames for the filters: `None` (default) uses each
    /// frame's timestamp; `Some(dt)` uses `index · dt` (MediaPipe's Python
    /// API always assumes 1/30 s).
    pub fixed_frame_interval_s: Option<f64>,
    /// ONNX Runtime session settings.
    pub session: SessionParams,
    /// Folder of the ONNX files; `None` = the usual search (see `runtime::model_dirs`).
    pub model_dir: Option<PathBuf>,
    /// A landmark model shared with estimators on other threads, run there
    /// instead of one of this estimator's own (its `model` must be this
    /// one's; its refinement and session are its own). Default `None`.
    pub shared: Option<SharedLandmarks>,
}

impl Default for BlazePoseParams {
    fn default() -> Self {
        BlazePoseParams {
            model: LandmarkModelKind::Full,
            detector: DetectorParams::default(),
            min_presence: 0.5,
            roi_scale: 1.25,
            refine: RefineParams::default(),
            tracking: true,
            recover_s: 0.0,
            aux_filter: OneEuroParams::AUX_LANDMARKS,
            fixed_frame_interval_s: None,
            session: SessionParams::default(),
            model_dir: None,
            shared: None,
        }
    }
}

impl BlazePoseParams {
    /// The landmark model: the shared one's, else one of its own.
    pub(crate) fn landmark_model(&self) -> Result<LandmarkModel> {
        match &self.shared {
            Some(shared) => shared.model_for(self.model),
            None => self.own_landmark_model(),
        }
    }

    /// A landmark model of its own: its model, refinement and session.
    pub(crate) fn own_landmark_model(&self) -> Result<LandmarkModel> {
        LandmarkModel::open(
            &self.model_path(self.model.file())?,
            self.model,
            self.refine,
            &self.session,
        )
    }

    /// Checks every value.
    pub fn validate(&self) -> Result<()> {
        self.detector.validate()?;
        self.refine.validate()?;
        self.session.validate()?;
        self.aux_filter.validate("aux_filter")?;
        if !(self.min_presence.is_finite() && (0.0..=1.0).contains(&self.min_presence)) {
            return Err(PoseError::param(
                "min_presence",
                format!("must be in [0, 1], got {}", self.min_presence),
            ));
        }
        if !(self.roi_scale.is_finite() && self.roi_scale > 0.0) {
            return Err(PoseError::param(
                "roi_scale",
                format!("must be > 0, got {}", self.roi_scale),
            ));
        }
        if !(self.recover_s.is_finite() && self.recover_s >= 0.0) {
            return Err(PoseError::param(
                "recover_s",
                format!(
                    "must be a finite number of seconds ≥ 0, got {}",
                    self.recover_s
                ),
            ));
        }
        if let Some(dt) = self.fixed_frame_interval_s {
            if !(dt.is_finite() && dt > 0.0) {
                return Err(PoseError::param(
                    "fixed_frame_interval_s",
                    format!("must be > 0, got {dt}"),
                ));
            }
        }
        Ok(())
    }

    /// The file the estimators open for `file` ([`runtime::run_model_path`],
    /// or in `model_dir` the first of [`ModelFile::run_files`]).
    pub(crate) fn model_path(&self, file: ModelFile) -> Result<PathBuf> {
        match &self.model_dir {
            Some(d) => file
                .run_files()
                .into_iter()
                .map(|f| d.join(f))
                .find(|p| p.is_file())
                .ok_or_else(|| PoseError::ModelMissing {
                    file: file.file_name().into(),
                    searched: d.display().to_string(),
                }),
            None => runtime::run_model_path(file),
        }
    }
}

/// The BlazePose estimator (detector + landmarks + tracking).
pub struct BlazePose {
    params: BlazePoseParams,
    detector: PoseDetector,
    landmarks: LandmarkModel,
    name: String,
    next_roi: Option<Roi>,
    /// Time and region of the last frame with a pose.
    last_found: Option<(f64, Roi)>,
    aux_filter: PointsFilter,
    frame_size: Option<(usize, usize)>,
}

/// Diagnostics of the last processed frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FrameDiagnostics {
    /// Whether the detector ran.
    pub detector_ran: bool,
    /// Best detection score when it ran and found someone.
    pub detection_score: Option<f64>,
    /// Crop region used for the landmark model.
    pub roi: Option<Roi>,
    /// Pose presence from the landmark model.
    pub presence: Option<f32>,
    /// Region carried to the next frame.
    pub next_roi: Option<Roi>,
}

impl BlazePose {
    /// Opens the detector and landmark models.
    pub fn new(params: BlazePoseParams) -> Result<Self> {
        params.validate()?;
        let det_path = params.model_path(ModelFile::PoseDetection)?;
        let detector = PoseDetector::open(&det_path, params.detector, &params.session)?;
        let landmarks = params.landmark_model()?;
        Ok(BlazePose {
            name: format!("blazepose-{}", params.model.as_str()),
            aux_filter: PointsFilter::new(params.aux_filter),
            params,
            detector,
            landmarks,
            next_roi: None,
            last_found: None,
            frame_size: None,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &BlazePoseParams {
        &self.params
    }

    /// The detector, for running it alone.
    pub fn detector_mut(&mut self) -> &mut PoseDetector {
        &mut self.detector
    }

    /// The landmark model, for running it alone.
    pub fn landmarks_mut(&mut self) -> &mut LandmarkModel {
        &mut self.landmarks
    }

    fn time_ns(&self, frame: &Frame) -> i64 {
        let t = match self.params.fixed_frame_interval_s {
            // MediaPipe's first packet is one interval after zero.
            Some(dt) => (frame.index as f64 + 1.0) * dt,
            None => frame.timestamp_s,
        };
        (t * 1e9).round() as i64
    }

    fn time_s(&self, frame: &Frame) -> f64 {
        self.time_ns(frame) as f64 * 1e-9
    }

    fn lose(&mut self) {
        self.next_roi = None;
        self.aux_filter.reset();
    }

    /// The landmark model on `roi`, kept when the pose presence reaches
    /// `min_presence`.
    fn landmarks_in(
        &mut self,
        image: RgbView<'_>,
        roi: Roi,
        diag: &mut FrameDiagnostics,
    ) -> Result<Option<(Roi, LandmarkOutput)>> {
        if !roi.is_valid() {
            return Ok(None);
        }
        diag.roi = Some(roi);
        let out = self.landmarks.run(image, &roi)?;
        diag.presence = Some(out.pose_presence);
        if out.pose_presence.is_nan() || out.pose_presence < self.params.min_presence {
            return Ok(None);
        }
        Ok(Some((roi, out)))
    }

    /// The detector's best region, when it finds someone.
    fn detect(&mut self, image: RgbView<'_>, diag: &mut FrameDiagnostics) -> Result<Option<Roi>> {
        diag.detector_ran = true;
        let dets = self.detector.detect(image)?;
        Ok(dets.first().map(|best| {
            diag.detection_score = Some(best.score);
            detector::roi_from_points(
                best.keypoints_px[0],
                best.keypoints_px[1],
                self.params.roi_scale,
            )
        }))
    }

    /// Finds the person in `frame`: the carried region, else the detector's,
    /// else (within `recover_s` of the last pose) the region of the last pose.
    fn locate(
        &mut self,
        frame: &Frame,
        diag: &mut FrameDiagnostics,
    ) -> Result<Option<(Roi, LandmarkOutput)>> {
        let image = frame.view();
        let recover = self.params.tracking && self.params.recover_s > 0.0;
        let carried = if self.params.tracking {
            self.next_roi.take()
        } else {
            None
        };
        if let Some(roi) = carried {
            if let Some(found) = self.landmarks_in(image, roi, diag)? {
                return Ok(Some(found));
            }
            if !recover {
                // MediaPipe: the detector runs from the next frame on.
                return Ok(None);
            }
            // Lost: the next region starts a new track.
            self.aux_filter.reset();
        }
        if let Some(roi) = self.detect(image, diag)? {
            if let Some(found) = self.landmarks_in(image, roi, diag)? {
                return Ok(Some(found));
            }
        }
        if recover {
            if let Some((t_last, roi)) = self.last_found {
                let age = self.time_s(frame) - t_last;
                if age.is_finite() && (0.0..=self.params.recover_s).contains(&age) {
                    return self.landmarks_in(image, roi, diag);
                }
            }
        }
        Ok(None)
    }

    /// Processes one frame; also returns what happened (detector, regions).
    pub fn process(&mut self, frame: &Frame) -> Result<(Option<Pose>, FrameDiagnostics)> {
        frame.validate()?;
        let size = (frame.width, frame.height);
        if self.frame_size != Some(size) {
            self.lose();
            self.last_found = None;
            self.frame_size = Some(size);
        }
        let mut diag = FrameDiagnostics::default();
        let Some((roi, out)) = self.locate(frame, &mut diag)? else {
            self.lose();
            return Ok((None, diag));
        };
        diag.roi = Some(roi);
        self.last_found = Some((self.time_s(frame), roi));
        let t = self.time_ns(frame);
        let (mut pose, next) = pose_in_roi(
            &self.name,
            roi,
            &out,
            &mut self.aux_filter,
            t,
            self.params.roi_scale,
        )?;
        pose.detector_ran = diag.detector_ran;
        if self.params.tracking && next.is_valid() {
            self.next_roi = Some(next);
            diag.next_roi = Some(next);
        } else {
            self.next_roi = None;
        }
        Ok((Some(pose), diag))
    }
}

impl PoseEstimator for BlazePose {
    fn name(&self) -> &str {
        &self.name
    }
    fn skeleton(&self) -> Skeleton {
        Skeleton::blazepose33()
    }
    fn has_world(&self) -> bool {
        true
    }
    fn estimate(&mut self, frame: &Frame) -> Result<Option<Pose>> {
        self.process(frame).map(|(p, _)| p)
    }
    fn reset(&mut self) {
        self.lose();
        self.last_found = None;
        self.frame_size = None;
    }
}

/// The pose of a landmark output computed in `roi` (keypoints in image
/// pixels, depth, visibility, presence, world coordinates), and the region
/// for the next frame placed by the two auxiliary landmarks after the
/// One-Euro `aux_filter` (at `time_ns`, scaled by the person's size).
pub(crate) fn pose_in_roi(
    model: &str,
    roi: Roi,
    out: &LandmarkOutput,
    aux_filter: &mut PointsFilter,
    time_ns: i64,
    roi_scale: f64,
) -> Result<(Pose, Roi)> {
    let mut keypoints = Vec::with_capacity(landmarks::NUM_BODY);
    let mut depth = Vec::with_capacity(landmarks::NUM_BODY);
    let mut visibility = Vec::with_capacity(landmarks::NUM_BODY);
    let mut presence = Vec::with_capacity(landmarks::NUM_BODY);
    let mut world = Vec::with_capacity(landmarks::NUM_BODY);
    for k in 0..landmarks::NUM_BODY {
        let (Some(lm), Some(w)) = (out.landmarks.get(k), out.world.get(k)) else {
            return Err(PoseError::Contract {
                model: model.to_string(),
                reason: format!("landmark {k} missing from the model output"),
            });
        };
        let (p, z) = landmarks::project(&roi, lm);
        keypoints.push(p);
        depth.push(z);
        visibility.push(lm.visibility as f64);
        presence.push(lm.presence as f64);
        world.push(landmarks::rotate_world(&roi, w));
    }
    // Auxiliary landmarks -> next crop.
    let aux = |k: usize| -> Result<[f64; 3]> {
        let lm = out.landmarks.get(k).ok_or_else(|| PoseError::Contract {
            model: model.to_string(),
            reason: format!("auxiliary landmark {k} missing from the model output"),
        })?;
        let (p, z) = landmarks::project(&roi, lm);
        Ok([p[0], p[1], z])
    };
    let mut aux_pts = [aux(AUX_CENTER)?, aux(AUX_SCALE)?];
    let dx = aux_pts[1][0] - aux_pts[0][0];
    let dy = aux_pts[1][1] - aux_pts[0][1];
    // Size of the unscaled region from the raw auxiliary points: (width + height) / 2.
    let object_scale = 2.0 * (dx * dx + dy * dy).sqrt();
    aux_filter.apply(time_ns, object_scale, &mut aux_pts);
    let next = detector::roi_from_points(
        [aux_pts[0][0], aux_pts[0][1]],
        [aux_pts[1][0], aux_pts[1][1]],
        roi_scale,
    );
    let pose = Pose {
        keypoints_px: keypoints,
        depth_px: Some(depth),
        visibility,
        presence,
        world_m: Some(world),
        score: out.pose_presence as f64,
        object_scale_px: object_scale,
        roi: Some(roi),
        detector_ran: false,
    };
    Ok((pose, next))
}
