//! What a run reads: a video, a keypoint track file, or a track in memory.

use std::path::{Path, PathBuf};

use mp_geom::Track;

use crate::error::{PipelineError, Result};

/// The input of a run.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)]
#[non_exhaustive]
pub enum Input {
    /// A video, run through the pose model.
    Video {
        /// The file.
        path: PathBuf,
    },
    /// A keypoint track.
    Track {
        /// The keypoints.
        track: Track,
        /// Title of the report.
        title: String,
        /// Where the track came from (subtitle of the report).
        description: String,
        /// Video frame size (width, height) in pixels, when known (for drawing).
        frame_size: Option<(usize, usize)>,
        /// Largest frame side in pixels, used as the scale; `None`: the motion's extent.
        frame_px: Option<f64>,
        /// The file states no frame rate and none was given:
        /// [`mp_geom::DEFAULT_FPS`] was assumed.
        fps_assumed: bool,
    },
    /// Every person of a video, already found by the pose model and the
    /// tracker (a live run's): analysed as `mp run` analyses the people of
    /// a video, without its pictures.
    People {
        /// The people, in `skeleton`, pixels.
        people: mp_geom::People,
        /// The pose model's skeleton (of a video where nobody was found too).
        skeleton: mp_geom::Skeleton,
        /// Per frame, whether the pose model saw it; the frames it did not
        /// see (dropped, or skipped by the pose rate) are filled from the
        /// motion as `crate::pose_rate::fill_people` does.
        posed: Vec<bool>,
        /// Title of the report.
        title: String,
        /// Where the motion came from (subtitle of the report).
        description: String,
        /// Frame size (width, height) in pixels.
        frame_size: (usize, usize),
        /// The pose model's name.
        model: String,
    },
}

impl Input {
    /// File extensions read as videos; anything else is read as a keypoint track.
    pub const VIDEO_EXTENSIONS: [&str; 10] = [
        "mp4", "mov", "avi", "webm", "mkv", "m4v", "mpg", "mpeg", "wmv", "flv",
    ];

    /// Whether a path names a video by its extension.
    pub fn is_video(path: &Path) -> bool {
        path.extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .is_some_and(|e| Self::VIDEO_EXTENSIONS.contains(&e.as_str()))
    }

    /// A video or a track file, told apart by the extension
    /// ([`Input::VIDEO_EXTENSIONS`]); `frame_px` is the frame size to use as the scale
    /// of a track (ignored for videos, whose frame size is known; default for
    /// a track: the frame size its npz states, else the motion's extent).
    pub fn open(path: impl AsRef<Path>, frame_px: Option<f64>) -> Result<Self> {
        Self::open_with(path, frame_px, None)
    }

    /// [`Input::open`] with the frame rate of a track file: `Some` over
    /// what the file states; `None`, the file's own, or
    /// [`mp_geom::DEFAULT_FPS`] when it states none (then
    /// [`Input::fps_assumed`] is true and the description says so).
    /// Ignored for videos, whose rate is in the container.
    pub fn open_with(
        path: impl AsRef<Path>,
        frame_px: Option<f64>,
        fps: Option<f64>,
    ) -> Result<Self> {
        let path = path.as_ref();
        if !path.exists() {
            return Err(PipelineError::MissingInput(path.to_path_buf()));
        }
        if Self::is_video(path) {
            return Ok(Input::Video {
                path: path.to_path_buf(),
            });
        }
        let opts = mp_geom::ReadOptions {
            fps,
            ..Default::default()
        };
        let read =
            mp_geom::read_track_rated(path, &opts).map_err(|source| PipelineError::Track {
                path: path.to_path_buf(),
                extensions: Self::VIDEO_EXTENSIONS.join(", "),
                source,
            })?;
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let assumed = read.rate == mp_geom::RateSource::Assumed;
        // A track that states the video frame it is in (an npz of `mp run`
        // or `mp extract`) is scaled by it, as the video was.
        let frame_px = frame_px.or(read.frame_size.map(|(w, h)| w.max(h) as f64));
        let mut input = Self::from_track(read.track, &name, frame_px);
        if let Input::Track {
            description,
            frame_size,
            fps_assumed,
            ..
        } = &mut input
        {
            *frame_size = read.frame_size;
            *fps_assumed = assumed;
            if assumed {
                description.push_str(" (assumed: the file states no frame rate)");
            }
        }
        Ok(input)
    }

    /// Whether the frame rate of a track input was assumed
    /// ([`Input::open_with`]).
    pub fn fps_assumed(&self) -> bool {
        matches!(
            self,
            Input::Track {
                fps_assumed: true,
                ..
            }
        )
    }

    /// A track in memory; `name` titles the report.
    pub fn from_track(track: Track, name: &str, frame_px: Option<f64>) -> Self {
        Input::Track {
            description: describe_track(&track, name),
            title: name.to_string(),
            track,
            frame_size: None,
            frame_px,
            fps_assumed: false,
        }
    }

    /// A short name (the file name or the title).
    pub fn name(&self) -> String {
        match self {
            Input::Video { path } => path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            Input::Track { title, .. } | Input::People { title, .. } => title.clone(),
        }
    }
}

/// "keypoint track NAME · T frames × J joints (skeleton, 2D, px) at F fps".
pub(crate) fn describe_track(track: &Track, name: &str) -> String {
    format!(
        "keypoint track {} · {} frames × {} joints ({}, {}D, {}) at {} fps",
        name,
        track.n_frames(),
        track.n_joints(),
        track.skeleton().name,
        track.dims(),
        track.units().as_str(),
        mp_geom::fps_label(track.fps())
    )
}
