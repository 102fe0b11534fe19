//! Several people in one video: BlazePose's detector and landmark model
//! around a person tracker.
//!
//! Per frame ([`MultiPose::process`]):
//!
//! 1. every tracked person's carried crop goes through the landmark model
//!    (MediaPipe's tracking, one crop per person);
//! 2. the detector searches a few tiles of the frame ([`tiles`]: the whole
//!    frame, squares of its shorter side, squares of half of it; every tile
//!    once per [`PeopleParams::search_cycle_s`], or per
//!    [`PeopleParams::tracked_cycle_s`] while every track is confirmed), and
//!    the crop of any person it has not seen for [`PeopleParams::recheck_s`];
//! 3. the [`tracker`] assigns the detections to the people, starts new
//!    tracks, brings lost ones back under their id and drops crops the
//!    detector does not confirm.
//!
//! [`extract_people`] runs this over a video into an `mp_geom::People`. The
//! single-person estimator ([`crate::BlazePose`], MediaPipe's pipeline)
//! remains for one person and is the reference of the keypoint evaluation.

pub mod extract;
pub mod pieces;
pub mod tiles;
pub mod tracker;

use mp_geom::Skeleton;

use crate::blazepose::{
    self, detector, BlazePoseParams, LandmarkModel, LandmarkOutput, PoseDetector,
};
use crate::error::{PoseError, Result};
use crate::filter::PointsFilter;
use crate::imageops::{RgbView, Roi};
use crate::pose::Pose;
use crate::runtime::ModelFile;
use crate::video::Frame;

pub use extract::{extract_people, PeopleCollector, PeopleExtraction};
pub use pieces::{join_pieces, piece_ranges, MIN_PIECE_S, PIECE_OVERLAP_S};
pub use tracker::{
    Candidate, FrameResult, PeopleParams, PersonId, Seen, Sensors, TrackEvent, TrackedPose, Tracker,
};

/// Parameters of the multi-person estimator.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MultiPoseParams {
    /// The models, the crop and the filters (BlazePose's; its `tracking` and
    /// `recover_s` are the single-person pipeline's and are not used here).
    pub pose: BlazePoseParams,
    /// The tracker.
    pub people: PeopleParams,
}

impl MultiPoseParams {
    /// Checks every value.
    pub fn validate(&self) -> Result<()> {
        self.pose.validate()?;
        self.people.validate()
    }
}

/// What one frame gave.
pub(crate) type PeopleFrame = FrameResult<Pose>;

/// BlazePose for several people (see the module docs).
pub struct MultiPose {
    params: MultiPoseParams,
    detector: PoseDetector,
    landmarks: LandmarkModel,
    tracker: Option<Tracker>,
    frame_size: Option<(usize, usize)>,
    name: String,
}

impl MultiPose {
    /// Opens the detector and landmark models.
    pub fn new(params: MultiPoseParams) -> Result<Self> {
        params.validate()?;
        let det_path = params.pose.model_path(ModelFile::PoseDetection)?;
        let detector = PoseDetector::open(&det_path, params.pose.detector, &params.pose.session)?;
        let landmarks = params.pose.landmark_model()?;
        Ok(MultiPose {
            name: format!("blazepose-{}-people", params.pose.model.as_str()),
            params,
            detector,
            landmarks,
            tracker: None,
            frame_size: None,
        })
    }

    /// Short name (`blazepose-full-people`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The parameters.
    pub fn params(&self) -> &MultiPoseParams {
        &self.params
    }

    /// The skeleton of the poses (BlazePose-33).
    pub fn skeleton(&self) -> Skeleton {
        Skeleton::blazepose33()
    }

    /// The tracker of the current video (after its first frame).
    pub fn tracker(&self) -> Option<&Tracker> {
        self.tracker.as_ref()
    }

    /// Forgets every person (before a new video).
    pub fn reset(&mut self) {
        self.tracker = None;
        self.frame_size = None;
    }

    /// Processes the next frame of the video. A frame of another size than
    /// the previous one starts the tracking afresh.
    pub fn process(&mut self, frame: &Frame) -> Result<PeopleFrame> {
        frame.validate()?;
        let size = (frame.width, frame.height);
        if self.frame_size != Some(size) || self.tracker.is_none() {
            let p = &self.params.people;
            let tiles = tiles::tile_regions(
                frame.width,
                frame.height,
                &p.tile_sides,
                p.tile_overlap,
                p.min_tile_px,
            );
            self.tracker = Some(Tracker::new(p.clone(), self.params.pose.aux_filter, tiles)?);
            self.frame_size = Some(size);
        }
        let t = frame.timestamp_s;
        let mut sensors = BlazeSensors {
            image: frame.view(),
            detector: &mut self.detector,
            landmarks: &mut self.landmarks,
            min_presence: self.params.pose.min_presence,
            roi_scale: self.params.pose.roi_scale,
            time_ns: (t * 1e9).round() as i64,
            name: &self.name,
        };
        match self.tracker.as_mut() {
            Some(tr) => {
                let mut r = tr.step(t, &mut sensors)?;
                if r.detector_runs > 0 {
                    for p in &mut r.poses {
                        p.pose.detector_ran = true;
                    }
                }
                Ok(r)
            }
            None => Ok(FrameResult {
                poses: Vec::new(),
                events: Vec::new(),
                detector_runs: 0,
            }),
        }
    }
}

/// The models on the current frame.
struct BlazeSensors<'a> {
    image: RgbView<'a>,
    detector: &'a mut PoseDetector,
    landmarks: &'a mut LandmarkModel,
    min_presence: f32,
    roi_scale: f64,
    time_ns: i64,
    name: &'a str,
}

impl BlazeSensors<'_> {
    /// The pose in `roi` from the landmark model's output, if a person is there.
    fn seen(
        &self,
        roi: &Roi,
        out: &LandmarkOutput,
        filter: &mut PointsFilter,
    ) -> Result<Option<Seen<Pose>>> {
        if out.pose_presence.is_nan() || out.pose_presence < self.min_presence {
            return Ok(None);
        }
        let (pose, next) =
            blazepose::pose_in_roi(self.name, *roi, out, filter, self.time_ns, self.roi_scale)?;
        Ok(Some(Seen {
            pose,
            next_roi: next.is_valid().then_some(next),
        }))
    }
}

impl Sensors for BlazeSensors<'_> {
    type Pose = Pose;

    fn landmarks(&mut self, roi: &Roi, filter: &mut PointsFilter) -> Result<Option<Seen<Pose>>> {
        if !roi.is_valid() {
            return Ok(None);
        }
        let out = self.landmarks.run(self.image, roi)?;
        self.seen(roi, &out, filter)
    }

    fn landmarks_many(
        &mut self,
        jobs: &mut [(Roi, &mut PointsFilter)],
    ) -> Result<Vec<Option<Seen<Pose>>>> {
        let valid: Vec<Roi> = jobs
            .iter()
            .filter(|(roi, _)| roi.is_valid())
            .map(|(roi, _)| *roi)
            .collect();
        let mut outs = self.landmarks.run_many(self.image, &valid)?.into_iter();
        let mut seen = Vec::with_capacity(jobs.len());
        for (roi, filter) in jobs.iter_mut() {
            if !roi.is_valid() {
                seen.push(None);
                continue;
            }
            let out = outs.next().ok_or_else(|| PoseError::Contract {
                model: self.name.to_string(),
                reason: format!("fewer results than the {} crops", valid.len()),
            })?;
            seen.push(self.seen(roi, &out, filter)?);
        }
        Ok(seen)
    }

    fn detect(&mut self, region: &Roi) -> Result<Vec<Candidate>> {
        let dets = self.detector.detect_in(self.image, region)?;
        Ok(dets
            .into_iter()
            .map(|d| Candidate {
                score: d.score,
                roi: detector::roi_from_points(
                    d.keypoints_px[0],
                    d.keypoints_px[1],
                    self.roi_scale,
                ),
            })
            .filter(|c| c.roi.is_valid())
            .collect())
    }
}
