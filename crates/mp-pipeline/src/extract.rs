//! Keypoints of a video or a still image as a track file: what `mp extract`
//! and the Python `extract` do, in one call.
//!
//! [`extract`] reads the frames, runs the pose model of
//! [`PoseParams`](crate::PoseParams) (every person in view on a video with
//! BlazePose, unless `people` is off; one person on a still image, with
//! MoveNet, and for world coordinates), fills the frames the pose rate
//! skipped ([`crate::pose_rate`]) and keeps the COCO-17 body joints unless
//! `all_joints` is set. [`Extracted::write`] writes the result in the format
//! of the file's extension.

use std::path::Path;

use mp_geom::{CancelToken, People, Track};
use mp_pose::open_source;
use mp_pose::{open_estimator_with, ExtractOptions, SmoothingParams};

use crate::error::{PipelineError, Result};
use crate::input::Input;
use crate::params::Params;
use crate::pose_rate::{fill_people, fill_track};
use crate::progress::{check, Observer, Stage, StageTime};

/// What [`extract`] makes beyond [`Params`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct ExtractParams {
    /// One-Euro smoothing of the keypoints (MediaPipe's `smooth_landmarks`).
    /// Default off.
    pub smooth: bool,
    /// BlazePose's world coordinates (metres, hip-centred, 3D, the model's
    /// 33 landmarks) of one person instead of pixels. Default off.
    pub world: bool,
}

impl ExtractParams {
    /// Pixel keypoints, smoothed or not.
    pub fn pixels(smooth: bool) -> Self {
        ExtractParams {
            smooth,
            world: false,
        }
    }

    /// BlazePose's world coordinates, smoothed or not.
    pub fn world(smooth: bool) -> Self {
        ExtractParams {
            smooth,
            world: true,
        }
    }

    /// Whether the track file `path` can hold what these parameters
    /// extract: a 3D format (`.c3d`, `.bvh`) needs world coordinates. Check
    /// it before [`extract`] to fail before the pose model runs.
    pub fn check_output(&self, path: &Path) -> Result<()> {
        if !self.world && mp_geom::needs_3d(path) {
            return Err(PipelineError::param(
                "output",
                format!(
                    "{} holds 3D motion and keypoints are 2D pixels: extract BlazePose's world \
                     coordinates (metres) for it (`mp extract --world`, `extract(world=True)`), \
                     or write .npz, .csv, .parquet or .pose",
                    path.display()
                ),
            ));
        }
        Ok(())
    }
}

/// The keypoints [`extract`] found.
#[derive(Debug, Clone)]
#[non_exhaustive]
#[allow(clippy::large_enum_variant)] // one per extraction, moved once
pub enum ExtractedPoses {
    /// One person: a still image, MoveNet, the single-person pipeline or
    /// world coordinates.
    One(Track),
    /// Everyone tracked in a video, with their ids.
    People(People),
}

/// The result of [`extract`].
#[derive(Debug, Clone)]
pub struct Extracted {
    /// The keypoints.
    pub poses: ExtractedPoses,
    /// The frame (width, height) the pixel keypoints are in; `None` for
    /// world coordinates.
    pub frame: Option<(usize, usize)>,
    /// Per frame: whether the pose model ran on it (the others were filled).
    pub posed: Vec<bool>,
    /// Fraction of the frames with someone found.
    pub found_fraction: f64,
    /// Frames per second through the pose model (decoding excluded).
    pub model_fps: f64,
    /// Something the user should know about the run (e.g. more people in
    /// view than were tracked).
    pub warning: Option<String>,
}

impl Extracted {
    /// The track of one person: the only one, or the main person of a
    /// video with several. An error when nobody was found.
    pub fn main_track(&self) -> Result<Track> {
        match &self.poses {
            ExtractedPoses::One(t) => Ok(t.clone()),
            ExtractedPoses::People(p) => Ok(p.main_track()?),
        }
    }

    /// Writes the keypoints to `path` in the format of its extension
    /// (`mp_geom::write_track`); a format that holds several people
    /// gets everyone, another the main person. Pixels keep the frame they
    /// are in. Refuses a 3D format for pixel keypoints.
    pub fn write(&self, path: &Path) -> Result<()> {
        ExtractParams {
            world: self.frame.is_none(),
            ..ExtractParams::default()
        }
        .check_output(path)?;
        match &self.poses {
            ExtractedPoses::People(p) if mp_geom::holds_people(path) => {
                mp_geom::write_people_framed(path, p, self.frame)?
            }
            ExtractedPoses::People(_) => mp_geom::write_track(path, &self.main_track()?)?,
            ExtractedPoses::One(t) => mp_geom::write_track_framed(path, t, self.frame)?,
        }
        Ok(())
    }
}

/// Keypoints of the video or still image at `path` with the pose settings
/// of `params.pose` (model, threads, device, people, tracker, rate,
/// `max_frames`, `all_joints`, `recover_s`). Progress goes to `observer` as
/// [`Stage::Pose`]; `cancel` is checked before the model starts.
pub fn extract(
    path: &Path,
    params: &Params,
    what: ExtractParams,
    observer: &dyn Observer,
    cancel: &CancelToken,
) -> Result<Extracted> {
    params.validate()?;
    let pose = &params.pose;
    if what.world && pose.model.landmark_model().is_none() {
        return Err(PipelineError::param(
            "world",
            "world coordinates need a BlazePose model (full, lite or heavy); MoveNet has none \
             (`mp extract --world --model full`)",
        ));
    }
    if !path.exists() {
        return Err(PipelineError::MissingInput(path.to_path_buf()));
    }
    let source = open_source(path)?;
    let options = ExtractOptions {
        smoothing: what.smooth.then(SmoothingParams::default),
        max_frames: pose.max_frames,
        pose_every: pose.rate.stride(source.fps),
        ..ExtractOptions::default()
    };
    let total = match (source.frame_count, pose.max_frames) {
        (Some(n), Some(m)) => Some(n.min(m)),
        (n, None) => n,
        (None, m) => m,
    };
    check(cancel)?;
    let started = std::time::Instant::now();
    observer.started(Stage::Pose, total);
    let finished =
        |frames: usize| observer.finished(&StageTime::now(Stage::Pose, started.elapsed(), frames));
    let several = pose.people && !what.world && Input::is_video(path);
    if let (true, Some(lm)) = (several, pose.model.landmark_model()) {
        let mut est = mp_pose::MultiPose::new(mp_pose::MultiPoseParams {
            pose: mp_pose::BlazePoseParams {
                model: lm,
                session: pose.session(),
                recover_s: pose.recover_s,
                ..Default::default()
            },
            people: pose.tracker.clone(),
        })?;
        let ex = mp_pose::extract_people(source, &mut est, &options, |done, _| {
            observer.progress(Stage::Pose, done)
        })?;
        finished(ex.posed.len());
        let (found_fraction, model_fps, warning) =
            (ex.found_fraction(), ex.estimator_fps(), ex.warning());
        let people = fill_people(ex.people, &ex.posed)?;
        let people = if pose.all_joints {
            people
        } else {
            people.map_tracks(|t| t.to_coco17())?
        };
        return Ok(Extracted {
            poses: ExtractedPoses::People(people),
            frame: Some((ex.width, ex.height)),
            found_fraction,
            model_fps,
            warning,
            posed: ex.posed,
        });
    }
    let mut est = open_estimator_with(pose.model, pose.session(), pose.recover_s)?;
    let ex = mp_pose::extract_track(source, est.as_mut(), &options, |done, _| {
        observer.progress(Stage::Pose, done)
    })?;
    finished(ex.posed.len());
    let track = if what.world {
        ex.world.as_ref().ok_or_else(|| PipelineError::Stage {
            stage: "extract".into(),
            message: "the model gave no world coordinates".into(),
        })?
    } else {
        &ex.track
    };
    let mut track = fill_track(track, &ex.posed)?;
    if !pose.all_joints && !what.world && track.skeleton().name != "coco17" {
        track = track.to_coco17()?;
    }
    Ok(Extracted {
        poses: ExtractedPoses::One(track),
        // Pixels keep the frame they are in (the scale of their programs);
        // world coordinates are metres.
        frame: (!what.world).then_some((ex.width, ex.height)),
        found_fraction: ex.found_fraction(),
        model_fps: ex.estimator_fps(),
        warning: None,
        posed: ex.posed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Silent;

    #[test]
    fn pixels_are_refused_for_a_3d_format_before_anything_runs() {
        let e = ExtractParams::pixels(false)
            .check_output(Path::new("out.bvh"))
            .unwrap_err();
        assert!(e.to_string().contains("2D pixels"), "{e}");
        ExtractParams::world(false)
            .check_output(Path::new("out.bvh"))
            .unwrap();
        ExtractParams::pixels(true)
            .check_output(Path::new("out.npz"))
            .unwrap();
    }

    #[test]
    fn movenet_has_no_world_coordinates_and_a_missing_file_is_named() {
        let mut params = Params::default();
        params.pose.model = mp_pose::ModelChoice::MoveNet;
        let cancel = CancelToken::new();
        let e = extract(
            Path::new("nowhere.mp4"),
            &params,
            ExtractParams::world(false),
            &Silent,
            &cancel,
        )
        .unwrap_err();
        assert!(e.to_string().contains("MoveNet has none"), "{e}");
        let e = extract(
            Path::new("nowhere.mp4"),
            &Params::default(),
            ExtractParams::default(),
            &Silent,
            &cancel,
        )
        .unwrap_err();
        assert!(matches!(e, PipelineError::MissingInput(_)), "{e}");
    }
}
