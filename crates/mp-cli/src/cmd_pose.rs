//! `mp extract` (video → keypoint track) and `mp overlay` (skeleton drawn on
//! the video: a contact sheet PNG or an MP4).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use mp_geom::CancelToken;
use mp_geom::Units;
use mp_pipeline::{ExtractParams, ExtractedPoses};
use mp_pose::ModelChoice;
use mp_pose::SessionParams;
use mp_pose::{open_source, VideoWriter};
use mp_report::{
    contact_sheet, draw_skeleton, frame_tile, ContactSheetParams, SkeletonStyle, Tile, View,
};
use mp_report::{pixmap_to_png, pixmap_to_rgb, rgb_to_pixmap};

/// Arguments of `mp extract`.
#[derive(clap::Args, Debug)]
pub struct ExtractArgs {
    /// Input video (anything FFmpeg decodes) or still image (.png, .jpg).
    pub video: PathBuf,
    /// Output track (.npz, .json, .mpt, .csv, .parquet or .pose; .c3d and .bvh with --world); with several people, npz, JSON, .mpt, .parquet and .pose hold everyone (the npz's single-track arrays hold the main person), CSV the main person.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Pose model: full, lite (BlazePose-33) or movenet (COCO-17).
    #[arg(long, default_value = ModelChoice::default().as_str())]
    pub model: String,
    /// Write BlazePose's world coordinates (metres, hip-centred, 3D) instead of pixels.
    #[arg(long)]
    pub world: bool,
    /// One-Euro smoothing of the keypoints (MediaPipe's `smooth_landmarks`).
    #[arg(long)]
    pub smooth: bool,
    /// Keep all of the pose model's joints (BlazePose: 33) instead of the COCO-17 body joints `mp run` analyses (world coordinates, `--world`, always keep all 33).
    #[arg(long)]
    pub all_joints: bool,
    /// ONNX Runtime threads.
    #[arg(long, default_value_t = SessionParams::default().intra_threads)]
    pub threads: usize,
    /// BlazePose, video: after the tracked person is lost, the detector runs
    /// on the same frame and, when it finds no one, the region of the last
    /// pose is tried again for this many seconds (0: MediaPipe's tracking).
    #[arg(long, value_name = "SECONDS", default_value_t = mp_pose::BlazePoseParams::default().recover_s)]
    pub recover: f64,
    /// Only the first N frames.
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Follow one person with MediaPipe's single-person pipeline instead of
    /// tracking everyone in view (BlazePose, video; `--world`, MoveNet and
    /// still images are always single-person).
    #[arg(long)]
    pub single_person: bool,
    /// Most people tracked at once.
    #[arg(long, default_value_t = mp_pose::PeopleParams::default().max_people)]
    pub max_people: usize,
    /// How often the pose model runs: all (every frame), auto (12 poses a second: every second frame at 24–30 fps), or N poses a second; the frames between are filled from the motion
    #[arg(long, value_name = "N|auto|all", default_value_t = mp_pipeline::Params::default().pose.rate.label())]
    pub pose_fps: String,
    /// Where the pose model runs: auto (the GPU where ONNX Runtime's CUDA build and a GPU are there, else the CPU), cpu, cuda or cuda:N.
    #[arg(long, default_value_t = mp_pipeline::Params::default().pose.device.label())]
    pub device: String,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

fn pose_err(e: mp_pose::PoseError) -> anyhow::Error {
    anyhow::anyhow!("{e}")
}

/// ` (pose model on N of M frames)` when it skipped some, else nothing.
fn posed_note(posed: &[bool]) -> String {
    let n = posed.iter().filter(|&&p| p).count();
    if n == posed.len() {
        String::new()
    } else {
        format!(" (pose model on {n} of {} frames)", posed.len())
    }
}

/// `mp extract`'s settings as the library's parameters.
fn extract_params(a: &ExtractArgs) -> Result<(mp_pipeline::Params, ExtractParams)> {
    let mut params = mp_pipeline::Params::default();
    let pose = &mut params.pose;
    pose.model = ModelChoice::parse(&a.model).map_err(pose_err)?;
    pose.rate = mp_pipeline::PoseRate::parse(&a.pose_fps)?;
    pose.device = mp_pose::Device::parse(&a.device).map_err(|e| anyhow::anyhow!("{e}"))?;
    pose.threads = a.threads;
    pose.recover_s = a.recover;
    pose.max_frames = a.max_frames;
    pose.all_joints = a.all_joints;
    pose.people = !a.single_person;
    pose.tracker.max_people = a.max_people;
    let what = if a.world {
        ExtractParams::world(a.smooth)
    } else {
        ExtractParams::pixels(a.smooth)
    };
    Ok((params, what))
}

/// `mp extract`: keypoints of a video or image written as a track.
pub fn extract_cmd(a: &ExtractArgs) -> Result<()> {
    crate::track_arg::refuse_track_for_extract(&a.video)?;
    let (params, what) = extract_params(a)?;
    what.check_output(&a.output)?;
    let bars = crate::progress::Bars::new(a.quiet);
    let ex = mp_pipeline::extract(&a.video, &params, what, &bars, &CancelToken::new())
        .with_context(|| format!("extracting keypoints from {}", a.video.display()))?;
    drop(bars);
    ex.write(&a.output)
        .with_context(|| format!("writing {}", a.output.display()))?;
    if let Some(w) = &ex.warning {
        eprintln!("note: {w}");
    }
    if a.quiet {
        return Ok(());
    }
    match &ex.poses {
        ExtractedPoses::One(track) => println!(
            "{}: {} frames at {:.3} fps{}, pose in {:.1}% ({} joints, {}), {:.1} frames/s → {}",
            a.video.display(),
            track.n_frames(),
            track.fps(),
            posed_note(&ex.posed),
            100.0 * ex.found_fraction,
            track.n_joints(),
            track.units().as_str(),
            ex.model_fps,
            a.output.display()
        ),
        ExtractedPoses::People(people) => {
            println!(
                "{}: {} frames at {:.3} fps{}, {} {} tracked (someone in {:.1}% of frames), {:.1} frames/s → {}",
                a.video.display(),
                people.n_frames(),
                people.fps(),
                posed_note(&ex.posed),
                people.len(),
                if people.len() == 1 { "person" } else { "people" },
                100.0 * ex.found_fraction,
                ex.model_fps,
                a.output.display()
            );
            for p in people.people() {
                println!(
                    "  person {}{}: frames {}–{} (found in {})",
                    p.id,
                    if people.main_person().map(|m| m.id) == Some(p.id) {
                        " (main)"
                    } else {
                        ""
                    },
                    p.first_frame,
                    p.last_frame(),
                    p.frames_found()
                );
            }
        }
        _ => {}
    }
    Ok(())
}

/// Arguments of `mp overlay`.
#[derive(clap::Args, Debug)]
pub struct OverlayArgs {
    /// The video the track was extracted from.
    pub video: PathBuf,
    /// Keypoint track in pixels (npz, npy, json, csv, mpt, or an OpenPose folder), drawn frame by frame.
    pub track: PathBuf,
    /// Output: .png (contact sheet of evenly spaced frames) or .mp4 (every frame).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Frames on the contact sheet.
    #[arg(long, default_value_t = ContactSheetParams::default().frames)]
    pub frames: usize,
    /// Columns of the contact sheet.
    #[arg(long, default_value_t = ContactSheetParams::default().cols)]
    pub cols: usize,
    /// Width of each contact-sheet tile in pixels.
    #[arg(long, default_value_t = ContactSheetParams::default().tile_width_px)]
    pub tile_width: u32,
    /// Joints with confidence at or below this are not drawn.
    #[arg(long, default_value_t = SkeletonStyle::default().min_confidence)]
    pub min_confidence: f64,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `mp overlay`: a track's skeleton drawn on its video, as a contact sheet
/// (`.png`) or a video (`.mp4`, `.mkv`, `.mov`), with the renderer of
/// `mp run`'s overlay video and report.
pub fn overlay_cmd(a: &OverlayArgs) -> Result<()> {
    let track =
        mp_geom::read_track(&a.track).with_context(|| format!("reading {}", a.track.display()))?;
    if track.units() != Units::Pixels || track.dims() != 2 {
        bail!(
            "{}: overlay needs a 2D track in pixels, this one is {}D in {}",
            a.track.display(),
            track.dims(),
            track.units().as_str()
        );
    }
    let mut source = open_source(&a.video).map_err(pose_err)?;
    let (w, h) = (source.width, source.height);
    let ext = extension(&a.output);
    match ext.as_str() {
        "png" => {
            if a.frames == 0 || a.tile_width == 0 {
                bail!("--frames and --tile-width must be ≥ 1");
            }
            let style = SkeletonStyle {
                min_confidence: a.min_confidence,
                ..SkeletonStyle::default()
            };
            let n = source
                .frame_count
                .unwrap_or(track.n_frames())
                .min(track.n_frames())
                .max(1);
            let k = a.frames.min(n);
            let wanted: Vec<usize> = (0..k)
                .map(|i| if k == 1 { 0 } else { i * (n - 1) / (k - 1) })
                .collect();
            let mut tiles = Vec::new();
            for frame in source.frames.by_ref() {
                let f = frame.map_err(pose_err)?;
                if !wanted.contains(&f.index) {
                    if f.index > *wanted.last().unwrap_or(&0) {
                        break;
                    }
                    continue;
                }
                let pixmap = frame_tile(&f.rgb, (w, h), a.tile_width, |tile, view| {
                    draw_skeleton(tile, &track, f.index, view, &style);
                })?;
                let secs = f.index as f64 / track.fps();
                tiles.push(Tile {
                    pixmap,
                    caption: format!("frame {} · {secs:.2} s", f.index),
                });
            }
            if tiles.is_empty() {
                bail!("{}: no frames decoded", a.video.display());
            }
            let title = a
                .video
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let sheet = contact_sheet(&tiles, a.cols, &format!("{title} — keypoints"))?;
            let png = pixmap_to_png("contact sheet", &sheet)?;
            mp_geom::write_atomic(&a.output, &png)
                .with_context(|| format!("writing {}", a.output.display()))?;
            if !a.quiet {
                println!(
                    "{}: contact sheet of {} frames ({}×{})",
                    a.output.display(),
                    tiles.len(),
                    sheet.width(),
                    sheet.height()
                );
            }
        }
        "mp4" | "mkv" | "mov" => {
            let style = SkeletonStyle {
                min_confidence: a.min_confidence,
                ..SkeletonStyle::for_frame(w, h)
            };
            let view = View::frame(1.0);
            let mut writer = VideoWriter::create(&a.output, w, h, source.fps).map_err(pose_err)?;
            let pb = crate::progress::bar(source.frame_count, "overlay", a.quiet);
            for frame in source.frames.by_ref() {
                let f = frame.map_err(pose_err)?;
                let mut pm = rgb_to_pixmap(&f.rgb, w, h)?;
                draw_skeleton(&mut pm, &track, f.index, &view, &style);
                writer.write(&pixmap_to_rgb(&pm)).map_err(pose_err)?;
                pb.inc(1);
            }
            pb.finish_and_clear();
            let n = writer.finish().map_err(pose_err)?;
            if !a.quiet {
                println!("{}: {n} frames", a.output.display());
            }
        }
        other => bail!(
            "{}: output must be .png or .mp4, not `.{other}`",
            a.output.display()
        ),
    }
    Ok(())
}

fn extension(p: &Path) -> String {
    p.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}
