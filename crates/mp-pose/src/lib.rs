//! # mp-pose — video to keypoints
//!
//! * `video`: frames from videos through the `ffmpeg`/`ffprobe` programs
//!   (streamed, one frame in memory) and from still images.
//! * `blazepose`: MediaPipe's BlazePose (person detector + GHUM landmark
//!   model, 33 keypoints, world coordinates in metres) with the same crop,
//!   tracking and filtering steps as MediaPipe's legacy Pose solution.
//! * `movenet`: MoveNet SinglePose Lightning (COCO-17, whole frame).
//! * `people`: several people per video: the detector over tiles of the
//!   frame, one landmark crop per person, a tracker that keeps each
//!   person's id and drops crops the detector does not confirm.
//! * [`pose::PoseEstimator`]: the trait both implement.
//! * [`extract_track`]: a whole video to an `mp_geom::Track` (pixels, and metres for
//!   BlazePose), frames without a person marked with confidence 0.
//! * `decode`: decoding on its own thread ahead of the pose model, and
//!   reduced JPEG copies of the frames from a second FFmpeg process.
//! * `thumbs`: grey thumbnails of whole frames (a feature track for
//!   counting repetitions where no person is found).
//!
//! ONNX Runtime is loaded at run time (`cargo xtask setup` installs it; see
//! `runtime`); the models come from `cargo xtask models`.
//!
//! ```no_run
//! use mp_pose::{extract_file, ExtractOptions, ModelChoice};
//! let out = extract_file("swing.mp4", ModelChoice::Full, &ExtractOptions::default(), |_, _| {})?;
//! println!("{} frames, {:.0}% with a pose", out.track.n_frames(), 100.0 * out.found_fraction());
//! # Ok::<(), mp_pose::PoseError>(())
//! ```

mod blazepose;
mod decode;
mod error;
mod extract;
mod filter;
mod imageops;
mod motion;
mod movenet;
mod people;
mod pose;
mod runtime;
mod thumbs;
mod video;

pub use blazepose::{BlazePose, BlazePoseParams, LandmarkModelKind, SharedLandmarks, SharedStats};
pub use error::PoseError;
pub use extract::{
    extract_file, extract_track, open_estimator, open_estimator_with, ExtractOptions, Extraction,
    ModelChoice, PoseSmoother, SmoothingParams,
};
pub use imageops::Roi;
pub use movenet::{MoveNet, MoveNetParams};
pub use mp_onnx::{OnnxError, SessionParams};
pub use people::{
    extract_people, join_pieces, piece_ranges, MultiPose, MultiPoseParams, PeopleExtraction,
    PeopleParams, PersonId, MIN_PIECE_S, PIECE_OVERLAP_S,
};
pub use pose::{Pose, PoseEstimator};
pub use runtime::ModelFile;
pub use video::{open_source, probe, read_image, Frame, FrameSource, VideoInfo, VideoReader};

pub use blazepose::detector::{roi_from_points, PoseDetector};
pub use blazepose::landmarks::{project, LandmarkModel};
pub use decode::{
    decode_ahead, CopyFn, DecodeOptions, Decoded, FrameCopies, MjpegOptions, MjpegStream,
};
pub use extract::is_posed_frame;
pub use imageops::{resize_rgb, RgbView};
pub use motion::{moving_regions, region_track, CellRegion, MotionEnergy};
pub use people::{PeopleCollector, TrackEvent, TrackedPose};
pub use runtime::{model_path, Device};
pub use thumbs::{
    grey_thumbnail_region, signal_side, thumbnail_track, Thumbnails, DEFAULT_THUMBNAIL_SIZE,
    MAX_SIGNAL_VALUES,
};
pub use video::{
    probe_bytes, PixelFormat, VideoReadOptions, VideoWriter, Yuv420Frame, Yuv420Frames, X264,
    X264_PRESETS,
};

#[cfg(test)]
mod tests;
