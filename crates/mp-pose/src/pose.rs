//! The seam between pose models: one frame in, at most one pose out.

use mp_geom::Skeleton;

use crate::error::Result;
use crate::imageops::Roi;
use crate::video::Frame;

/// The pose of one person in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose {
    /// Keypoints in image pixels `(x, y)`, in the estimator's skeleton order.
    pub keypoints_px: Vec<[f64; 2]>,
    /// Relative depth per keypoint on the scale of x (pixels; smaller = closer
    /// to the camera), where the model gives one.
    pub depth_px: Option<Vec<f64>>,
    /// Per-keypoint confidence in `[0, 1]` (BlazePose: visibility; MoveNet: score).
    pub visibility: Vec<f64>,
    /// Per-keypoint presence in `[0, 1]` (BlazePose; equals `visibility` otherwise).
    pub presence: Vec<f64>,
    /// World coordinates in metres, origin at the hip centre, y down (BlazePose).
    pub world_m: Option<Vec<[f64; 3]>>,
    /// Whole-pose score (BlazePose: pose presence; MoveNet: mean keypoint score).
    pub score: f64,
    /// Size of the person in pixels, used to scale smoothing filters.
    pub object_scale_px: f64,
    /// The region the keypoints were computed in (BlazePose crop), if any.
    pub roi: Option<Roi>,
    /// Whether the person detector ran for this frame.
    pub detector_ran: bool,
}

impl Pose {
    /// Number of keypoints.
    pub fn len(&self) -> usize {
        self.keypoints_px.len()
    }
    /// Whether the pose has no keypoints.
    pub fn is_empty(&self) -> bool {
        self.keypoints_px.is_empty()
    }
}

/// A single-person pose estimator working frame by frame.
///
/// Implementations may keep state between frames (tracking); [`reset`]
/// forgets it, e.g. before a new video.
///
/// [`reset`]: PoseEstimator::reset
pub trait PoseEstimator {
    /// Short name (`blazepose-full`, `movenet-lightning`, …).
    fn name(&self) -> &str;
    /// The skeleton of the keypoints [`estimate`](PoseEstimator::estimate) returns.
    fn skeleton(&self) -> Skeleton;
    /// Whether [`Pose::world_m`] is filled.
    fn has_world(&self) -> bool;
    /// The pose in this frame, or `None` when no person was found. Frames
    /// must come in order; a frame whose size differs from the previous one
    /// restarts tracking.
    fn estimate(&mut self, frame: &Frame) -> Result<Option<Pose>>;
    /// Forgets any state carried between frames.
    fn reset(&mut self);
}
