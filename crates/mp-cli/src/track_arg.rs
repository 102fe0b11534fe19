//! What a command is given as its input: the frame rate of a track
//! (`--fps`), a warning when a rate is assumed, and advice that names the
//! right command when the file is not what the command reads.

use std::path::Path;

use anyhow::{bail, Context, Result};
use clap::Args;
use mp_geom::Track;
use mp_geom::{read_track_rated, RateSource, ReadOptions, TrackRead, DEFAULT_FPS};
use mp_pipeline::Input;

/// The frame-rate option of every command that reads a track.
#[derive(Args, Debug, Clone, Default)]
pub struct RateOpt {
    /// Frame rate of a track input, frames per second, over what the file states. Default: the file's (npz, JSON, mpt, BVH, a CSV `time` column); 30, with a warning, for a file that states none (npy, CSV without `time`, OpenPose/AlphaPose JSON)
    #[arg(long, value_name = "FPS")]
    pub fps: Option<f64>,
}

/// Still-image extensions `mp extract` reads.
const IMAGE_EXTENSIONS: [&str; 7] = ["png", "jpg", "jpeg", "bmp", "webp", "tif", "tiff"];

/// Extensions of keypoint tracks.
pub const TRACK_EXTENSIONS: [&str; 9] = mp_geom::TRACK_EXTENSIONS;

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

/// Whether a path names a still image by its extension.
pub fn is_image(path: &Path) -> bool {
    IMAGE_EXTENSIONS.contains(&extension(path).as_str())
}

/// Whether a path names a keypoint track by its extension.
pub fn is_track_file(path: &Path) -> bool {
    TRACK_EXTENSIONS.contains(&extension(path).as_str())
}

/// The warning printed when a track's frame rate was assumed.
pub fn warn_assumed(path: &Path) {
    eprintln!(
        "warning: {} states no frame rate: {DEFAULT_FPS} fps assumed (give --fps)",
        path.display()
    );
}

/// Refuses a video or an image given where a keypoint track is read, naming
/// the commands that take it.
fn refuse_pictures(path: &Path) -> Result<()> {
    let p = path.display();
    if Input::is_video(path) {
        bail!(
            "{p} is a video, not a keypoint track: `mp extract {p} -o track.npz` writes its \
             keypoints, `mp run {p} --out DIR` analyses it whole"
        );
    }
    if is_image(path) {
        bail!(
            "{p} is an image, not a keypoint track: `mp extract {p} -o pose.json` writes its \
             keypoints"
        );
    }
    Ok(())
}

/// Reads the keypoint track a command is given, at the rate of `rate`
/// (warning when 30 fps is assumed), with the frame size its file states; a
/// video or an image gets advice instead.
pub fn read_track_file(path: &Path, rate: &RateOpt) -> Result<TrackRead> {
    refuse_pictures(path)?;
    let opts = ReadOptions {
        fps: rate.fps,
        ..Default::default()
    };
    let read =
        read_track_rated(path, &opts).with_context(|| format!("reading {}", path.display()))?;
    if read.rate == RateSource::Assumed {
        warn_assumed(path);
    }
    Ok(read)
}

/// [`read_track_file`]'s track alone.
pub fn read_track(path: &Path, rate: &RateOpt) -> Result<Track> {
    read_track_file(path, rate).map(|r| r.track)
}

/// The frame size (largest side, pixels) a track is scaled by: `given`
/// (`--frame-size`), else the one its file states (the npz of `mp run` and
/// `mp extract`), else `None` (the motion's extent).
pub fn frame_px(read: &TrackRead, given: Option<f64>) -> Option<f64> {
    given.or(read.frame_size.map(|(w, h)| w.max(h) as f64))
}

/// Opens the input of `mp run` / `mp loops` (a video or a keypoint track),
/// with advice for a still image and for a folder that holds no OpenPose
/// frames (a folder of videos is `mp batch`'s).
pub fn open_input(path: &Path, frame_px: Option<f64>, rate: &RateOpt) -> Result<Input> {
    let p = path.display();
    if is_image(path) {
        bail!(
            "{p} is a still image: `mp extract {p} -o pose.json` writes its keypoints; `mp run` \
             takes a video or a keypoint track"
        );
    }
    if path.is_dir() && !holds_openpose_frames(path) {
        bail!(
            "{p} is a folder without OpenPose *_keypoints.json frames: `mp batch {p} --out DIR` \
             runs every video and track in a folder"
        );
    }
    let input = Input::open_with(path, frame_px, rate.fps)?;
    if input.fps_assumed() {
        warn_assumed(path);
    }
    Ok(input)
}

fn holds_openpose_frames(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|entries| {
        entries.flatten().any(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.ends_with("_keypoints.json") || name.ends_with(".json")
        })
    })
}

/// Refuses an output folder that names an existing file.
pub fn check_out_dir(out: &Path) -> Result<()> {
    if out.exists() && !out.is_dir() {
        bail!(
            "--out names the folder to write into, but {} is a file",
            out.display()
        );
    }
    Ok(())
}

/// Refuses a keypoint track given to `mp extract`, which reads videos and
/// images.
pub fn refuse_track_for_extract(path: &Path) -> Result<()> {
    if is_track_file(path) && !Input::is_video(path) {
        let p = path.display();
        bail!(
            "{p} is already a keypoint track: give it to `mp run {p} --out DIR` or `mp fit {p} -o \
             program.txt` directly; `mp extract` reads videos and images"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_are_told_apart_by_extension() {
        assert!(is_image(Path::new("a/photo.JPG")));
        assert!(!is_image(Path::new("clip.mp4")));
        assert!(is_track_file(Path::new("motion.bvh")));
        for f in ["take.c3d", "keypoints.parquet", "signs.pose"] {
            assert!(is_track_file(Path::new(f)), "{f}");
        }
        assert!(!is_track_file(Path::new("clip.mov")));
    }

    #[test]
    fn a_video_given_as_a_track_names_the_commands_that_take_it() {
        let e = read_track(Path::new("clip.mp4"), &RateOpt::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("mp extract clip.mp4") && e.contains("mp run clip.mp4"),
            "{e}"
        );
        let e = refuse_track_for_extract(Path::new("motion.bvh"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("already a keypoint track"), "{e}");
    }
}
