//! `mp run`: a video or a keypoint track in, programs, loops, pictures and a
//! report out.
//!
//! Steps: keypoints (FFmpeg decoding + pose model, or a track file) →
//! concrete program → abstract program and loops → pictures (trajectory
//! plots, timeline, contact sheet, overlay video) → `report.html`. Every
//! file goes through the output folder's staging area
//! ([`mp_report::OutputDir`]), so Ctrl-C leaves only complete files.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::sync::Once;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use mp_abstract::dsl::{print_with, PrintOptions};
use mp_abstract::{AbstractParams, Analysis, LoopParams};
use mp_concrete::{synthesize_detailed, Scale, SynthParams, UnobservedJoints};
use mp_geom::Track;
use mp_pose::extract::{extract, open_estimator, ExtractOptions, ModelChoice};
use mp_pose::video::{Frame, FrameSource, VideoInfo, VideoReader, VideoWriter};
use mp_pose::SessionParams;
use mp_report::draw::{
    blank_canvas, blit_scaled, contact_sheet, draw_skeleton, SkeletonStyle, Tile, View,
};
use mp_report::outdir::{check_interrupt, emergency_cleanup, interrupted, request_interrupt};
use mp_report::raster::{pixmap_to_png, pixmap_to_rgb, rgb_to_pixmap, svg_to_png};
use mp_report::{
    joint_trajectory_svg, report_html, standard_cards, timeline_svg, Card, FrameStore,
    FrameStoreParams, OutputDir, PlotParams, ReportInput, TimelineParams,
};
use rayon::prelude::*;

/// x264 preset of the overlay video.
pub const OVERLAY_PRESET: &str = "veryfast";

/// File extensions read as videos; anything else is read as a keypoint track.
pub const VIDEO_EXTENSIONS: [&str; 10] = [
    "mp4", "mov", "avi", "webm", "mkv", "m4v", "mpg", "mpeg", "wmv", "flv",
];

/// Arguments of `mp run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// A video (mp4, mov, avi, webm, mkv, …) or a keypoint track (npz, json, csv, npy, bvh, OpenPose folder).
    pub input: PathBuf,
    /// Output folder (created if needed).
    #[arg(long, short)]
    pub out: PathBuf,
    /// Pose model for videos: full, lite (BlazePose) or movenet.
    #[arg(long, default_value = "full")]
    pub model: String,
    /// Only the first N frames.
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Keep all of the pose model's joints (BlazePose: 33) instead of the COCO-17 body joints.
    #[arg(long)]
    pub all_joints: bool,
    /// Largest side of the video frame in pixels, for track input (scale = frame / 512); default: from the motion's extent.
    #[arg(long)]
    pub frame_size: Option<f64>,
    /// ONNX Runtime threads.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Do not write the overlay video.
    #[arg(long)]
    pub no_video: bool,
    /// No progress bars and no summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Where the keypoints come from (built once per run, so its size does not matter).
#[allow(clippy::large_enum_variant)]
pub enum Source {
    /// A video, run through a pose model.
    Video {
        /// The file.
        path: PathBuf,
        /// The pose model.
        model: ModelChoice,
        /// Only the first N frames.
        max_frames: Option<usize>,
        /// Keep the model's own skeleton instead of COCO-17.
        all_joints: bool,
        /// ONNX Runtime threads.
        threads: usize,
    },
    /// A track already in memory.
    Track {
        /// The keypoints.
        track: Track,
        /// Title of the report.
        title: String,
        /// Where the track came from (subtitle of the report).
        description: String,
        /// Frame size (width, height) in pixels, when known.
        frame_size: Option<(usize, usize)>,
        /// Largest frame side used as the scale, when known.
        frame_px: Option<f64>,
    },
}

/// Options of [`run_pipeline`].
#[derive(Debug, Clone, Copy)]
pub struct RunOptions {
    /// Progress bars and summary off.
    pub quiet: bool,
    /// Write `overlay.mp4` for video input.
    pub overlay_video: bool,
}

/// Time spent in one stage.
#[derive(Debug, Clone)]
pub struct StageTime {
    /// Stage name.
    pub name: &'static str,
    /// Wall time.
    pub time: Duration,
    /// Frames processed by the stage (for frames per second).
    pub frames: usize,
    /// What the stage covers and what it runs alongside.
    pub note: &'static str,
}

/// What [`run_pipeline`] produced.
pub struct RunSummary {
    /// The analysis.
    pub analysis: Analysis,
    /// The report page.
    pub report: PathBuf,
    /// Time per stage.
    pub stages: Vec<StageTime>,
    /// Wall time of the whole run.
    pub total: Duration,
    /// Duration of the input motion in seconds.
    pub motion_s: f64,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
}

static HANDLER: Once = Once::new();

/// Installs the Ctrl-C handler: the run stops at its next check and removes
/// its staging folder; if it has not finished within 3 s the handler removes
/// every staging folder itself and exits with status 130.
pub fn install_interrupt_handler() {
    HANDLER.call_once(|| {
        let res = ctrlc::set_handler(|| {
            if interrupted() {
                // A second Ctrl-C: stop now.
                let _guard = emergency_cleanup();
                std::process::exit(130);
            }
            request_interrupt();
            std::thread::spawn(|| {
                std::thread::sleep(Duration::from_secs(3));
                let _guard = emergency_cleanup();
                eprintln!("\ninterrupted");
                std::process::exit(130);
            });
        });
        if let Err(e) = res {
            eprintln!("warning: cannot install the Ctrl-C handler: {e}");
        }
    });
}

fn bar(len: Option<usize>, msg: &str, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = match len {
        Some(n) => ProgressBar::new(n as u64),
        None => ProgressBar::new_spinner(),
    };
    let template = if len.is_some() {
        "{spinner:.green} {msg:<12} [{bar:36.cyan/blue}] {pos}/{len} ({per_sec}, eta {eta})"
    } else {
        "{spinner:.green} {msg:<12} {elapsed}"
    };
    if let Ok(style) = ProgressStyle::with_template(template) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(msg.to_string());
    if len.is_none() {
        pb.enable_steady_tick(Duration::from_millis(120));
    }
    pb
}

/// Whether a path names a video by its extension.
pub fn is_video(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .is_some_and(|e| VIDEO_EXTENSIONS.contains(&e.as_str()))
}

fn pose_err(e: mp_pose::PoseError) -> anyhow::Error {
    anyhow::anyhow!("{e}")
}

/// `mp run`.
pub fn run_cmd(a: &RunArgs) -> Result<()> {
    if !a.input.exists() {
        bail!("input {} does not exist", a.input.display());
    }
    let source = if is_video(&a.input) {
        Source::Video {
            path: a.input.clone(),
            model: ModelChoice::parse(&a.model).map_err(pose_err)?,
            max_frames: a.max_frames,
            all_joints: a.all_joints,
            threads: a.threads,
        }
    } else {
        let mut track = mp_geom::io::read_track(&a.input).with_context(|| {
            format!(
                "reading {} as a keypoint track (videos need one of the extensions {})",
                a.input.display(),
                VIDEO_EXTENSIONS.join(", ")
            )
        })?;
        if let Some(n) = a.max_frames {
            if n < track.n_frames() {
                track = track.slice_frames(0, n.max(1))?;
            }
        }
        let name = a
            .input
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        Source::Track {
            description: format!(
                "keypoint track {} · {} frames × {} joints ({}, {}D, {}) at {} fps",
                name,
                track.n_frames(),
                track.n_joints(),
                track.skeleton().name,
                track.dims(),
                track.units().as_str(),
                track.fps()
            ),
            title: name,
            track,
            frame_size: None,
            frame_px: a.frame_size,
        }
    };
    let opts = RunOptions {
        quiet: a.quiet,
        overlay_video: !a.no_video,
    };
    let summary = run_or_exit(source, &a.out, &opts)?;
    if !a.quiet {
        print_summary(&summary, &a.out);
    }
    Ok(())
}

/// Runs the pipeline; on Ctrl-C removes the staging folder and exits with status 130.
pub fn run_or_exit(source: Source, out: &Path, opts: &RunOptions) -> Result<RunSummary> {
    install_interrupt_handler();
    let res = run_pipeline(source, out, opts);
    if interrupted() {
        // The output folder's staging area is gone (dropped inside run_pipeline).
        if out.is_dir() {
            eprintln!("\ninterrupted: {} holds only complete files", out.display());
        } else {
            eprintln!("\ninterrupted before anything was written");
        }
        std::process::exit(130);
    }
    res
}

/// Prints the outputs, the loops and the stage timings.
pub fn print_summary(s: &RunSummary, out: &Path) {
    let an = &s.analysis;
    println!(
        "{} frames × {} joints → {} segments ({} primitives), {} loop{}",
        an.concrete.n_frames(),
        an.concrete.n_joints(),
        an.concrete.n_segments(),
        an.concrete.n_segments() * an.concrete.n_joints(),
        an.intervals.len(),
        if an.intervals.len() == 1 { "" } else { "s" }
    );
    for (i, iv) in an.intervals.iter().enumerate() {
        println!(
            "  loop {}: frames {:>4}..{:<4} ({:.2}–{:.2} s)  {} repetitions of {} primitives",
            i + 1,
            iv.start_frame,
            iv.end_frame,
            iv.start_frame as f64 / an.concrete.fps,
            iv.end_frame as f64 / an.concrete.fps,
            iv.count,
            iv.body_size
        );
    }
    println!();
    println!("{}", stage_table(s));
    println!("Report: {}", s.report.display());
    println!(
        "All files in {}/: {}",
        out.display(),
        s.files
            .iter()
            .filter(|f| !f.starts_with("plots/"))
            .cloned()
            .collect::<Vec<_>>()
            .join(", ")
    );
}

/// The stage-timing table.
pub fn stage_table(s: &RunSummary) -> String {
    let mut t = String::from("stage        time (s)   frames/s\n");
    for st in &s.stages {
        let secs = st.time.as_secs_f64();
        let fps = if secs > 0.0 && st.frames > 0 {
            format!("{:9.1}", st.frames as f64 / secs)
        } else {
            format!("{:>9}", "–")
        };
        t.push_str(&format!(
            "{:<12} {:>8.2}  {}   {}\n",
            st.name, secs, fps, st.note
        ));
    }
    let total = s.total.as_secs_f64();
    t.push_str(&format!(
        "{:<12} {:>8.2}  {:9.1}   ({:.1} s of motion: {:.2}× real time)\n",
        "total",
        total,
        s.analysis.concrete.n_frames() as f64 / total.max(1e-9),
        s.motion_s,
        s.motion_s / total.max(1e-9)
    ));
    t
}

/// Full-size frames kept in memory during the pose pass for the overlay
/// video, up to this many bytes; longer videos are decoded a second time.
pub const KEEP_FRAMES_BUDGET_BYTES: usize = 512 << 20;

/// Frames buffered between the decoding thread and the pose model.
const DECODE_AHEAD_FRAMES: usize = 8;

/// Quality of the report's frame copies on FFmpeg's `-q:v` scale (2 best,
/// 31 worst). 4 gives about the PSNR of libjpeg quality 72 at full chroma
/// resolution (≈ 40 dB on the golf swing) in files about 25 % smaller.
pub const REPORT_JPEG_QSCALE: u32 = 4;

/// What the decoding thread hands back when the pose pass is over.
struct Decoded {
    /// Full-size RGB frames for the overlay video, when they fit the budget.
    kept: Option<Vec<Vec<u8>>>,
    /// Time spent decoding (waiting on FFmpeg's pipe).
    decode: Duration,
}

/// Decodes frames on its own thread and sends them to the pose model through
/// a bounded channel, keeping full-size copies on the way when asked. Stops
/// at Ctrl-C, after `limit` frames, at the end of the video, or when the
/// receiving side is gone.
fn decode_feed(
    reader: VideoReader,
    limit: Option<usize>,
    keep_full: bool,
    tx: SyncSender<mp_pose::Result<Frame>>,
) -> Decoded {
    let mut kept = keep_full.then(Vec::new);
    let mut decode = Duration::ZERO;
    let mut frames = reader.take(limit.unwrap_or(usize::MAX));
    loop {
        if interrupted() {
            break;
        }
        let t0 = Instant::now();
        let Some(f) = frames.next() else { break };
        decode += t0.elapsed();
        if let (Ok(frame), Some(k)) = (&f, kept.as_mut()) {
            k.push(frame.rgb.clone());
        }
        let failed = f.is_err();
        if tx.send(f).is_err() || failed {
            break;
        }
    }
    Decoded { kept, decode }
}

/// What the JPEG thread hands back.
struct JpegCopies {
    store: FrameStore,
    result: Result<()>,
    time: Duration,
}

/// Starts a second FFmpeg process that writes the frames the store keeps as
/// reduced JPEGs (its `mjpeg` encoder, much faster than encoding them here),
/// and a thread that reads them into the store.
fn start_jpeg_copies(
    info: &VideoInfo,
    limit: Option<usize>,
    mut store: FrameStore,
) -> Result<std::thread::JoinHandle<JpegCopies>> {
    let mut filters = Vec::new();
    if store.step > 1 {
        filters.push(format!("select=not(mod(n\\,{}))", store.step));
    }
    if store.size != store.source_size {
        filters.push(format!(
            "scale={}:{}:flags=area",
            store.size.0, store.size.1
        ));
    }
    let mut cmd = std::process::Command::new("ffmpeg");
    cmd.args(["-v", "error", "-nostdin", "-i"])
        .arg(&info.path)
        .args(["-map", "0:v:0", "-fps_mode", "passthrough"]);
    if !filters.is_empty() {
        cmd.arg("-vf").arg(filters.join(","));
    }
    if let Some(n) = limit {
        cmd.arg("-frames:v")
            .arg(n.div_ceil(store.step).max(1).to_string());
    }
    cmd.args(["-c:v", "mjpeg", "-q:v"])
        .arg(REPORT_JPEG_QSCALE.to_string())
        .args(["-f", "image2pipe", "-"])
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    let mut child = cmd
        .spawn()
        .with_context(|| format!("starting ffmpeg for the frames of {}", info.path.display()))?;
    let what = format!("frames of {}", info.path.display());
    let handle = std::thread::Builder::new()
        .name("jpeg".into())
        .spawn(move || {
            let t0 = Instant::now();
            let stderr = child.stderr.take().map(|mut e| {
                std::thread::spawn(move || {
                    let mut s = String::new();
                    let _ = std::io::Read::read_to_string(&mut e, &mut s);
                    s
                })
            });
            let mut result = Ok(());
            if let Some(out) = child.stdout.take() {
                let mut r = std::io::BufReader::with_capacity(1 << 16, out);
                for k in 0.. {
                    if interrupted() {
                        break;
                    }
                    let index = k * store.step;
                    if limit.is_some_and(|n| index >= n) {
                        break;
                    }
                    match mp_report::frames::read_jpeg(&mut r, &what, k) {
                        Ok(Some(jpg)) => {
                            if let Err(e) = store.push_jpeg(index, jpg) {
                                result = Err(anyhow::Error::new(e));
                                break;
                            }
                        }
                        Ok(None) => break,
                        Err(e) => {
                            result = Err(anyhow::Error::new(e));
                            break;
                        }
                    }
                }
            }
            // Stop FFmpeg if it still runs (frame limit, error, Ctrl-C), then collect its status.
            let _ = child.kill();
            let status = child.wait();
            let msg = stderr
                .and_then(|h| h.join().ok())
                .unwrap_or_default()
                .trim()
                .to_string();
            if result.is_ok() && store.frames.is_empty() && !interrupted() {
                result = Err(anyhow::anyhow!(
                    "ffmpeg wrote no JPEG frames for {} ({}){}",
                    what,
                    status.map(|s| s.to_string()).unwrap_or_default(),
                    if msg.is_empty() {
                        String::new()
                    } else {
                        format!(": {msg}")
                    }
                ));
            }
            JpegCopies {
                store,
                result,
                time: t0.elapsed(),
            }
        })
        .context("starting the JPEG thread")?;
    Ok(handle)
}

/// The frames of the overlay video.
struct OverlayFrames {
    /// The video (size, frame rate, path).
    info: VideoInfo,
    /// Full-size RGB frames kept during the pose pass; `None`: decode the video again.
    kept: Option<Vec<Vec<u8>>>,
}

struct Keypoints {
    track: Track,
    frames: Option<FrameStore>,
    overlay_frames: Option<OverlayFrames>,
    title: String,
    description: String,
    frame_size: Option<(usize, usize)>,
    frame_px: Option<f64>,
    extra_cards: Vec<Card>,
}

fn keypoints_from_video(
    path: &Path,
    model: ModelChoice,
    max_frames: Option<usize>,
    all_joints: bool,
    threads: usize,
    opts: &RunOptions,
    stages: &mut Vec<StageTime>,
) -> Result<Keypoints> {
    let reader = VideoReader::open(path)
        .map_err(pose_err)
        .with_context(|| format!("opening video {}", path.display()))?;
    let info = reader.info().clone();
    let expected = match (info.frame_count, max_frames) {
        (Some(n), Some(m)) => Some(n.min(m)),
        (n, None) => n,
        (None, m) => m,
    };
    let store = FrameStore::new(
        info.width,
        info.height,
        expected,
        &FrameStoreParams::default(),
    )?;
    // Full-size frames are kept for the overlay when their count is known and they fit.
    let frame_bytes = info.width * info.height * 3;
    let keep_full = opts.overlay_video
        && expected.is_some_and(|n| n.saturating_mul(frame_bytes) <= KEEP_FRAMES_BUDGET_BYTES);
    // Decoding runs on its own thread, ahead of the pose model; the reduced
    // copies for the report come from a second FFmpeg process.
    let t0 = Instant::now();
    let jpegs = start_jpeg_copies(&info, max_frames, store)?;
    let (tx, rx) = sync_channel(DECODE_AHEAD_FRAMES);
    let decoder = std::thread::Builder::new()
        .name("decode".into())
        .spawn(move || decode_feed(reader, max_frames, keep_full, tx))
        .context("starting the decoding thread")?;
    let source = FrameSource {
        width: info.width,
        height: info.height,
        fps: info.fps,
        frame_count: info.frame_count,
        frames: Box::new(rx.into_iter()),
    };
    let estimator = open_estimator(
        model,
        SessionParams {
            intra_threads: threads.max(1),
            ..Default::default()
        },
    )
    .map_err(pose_err)
    .context("loading the pose model");
    let pb = bar(expected, "pose", opts.quiet);
    let ex = estimator.and_then(|mut est| {
        let ex = extract(
            source,
            est.as_mut(),
            &ExtractOptions {
                max_frames,
                ..Default::default()
            },
            |done, _| pb.set_position(done as u64),
        )
        .map_err(pose_err)
        .with_context(|| format!("extracting keypoints from {}", path.display()))?;
        Ok((ex, est.name().to_string()))
    });
    pb.finish_and_clear();
    // The receiver is gone once `extract` returns, so the decoder stops too.
    let decoded = decoder
        .join()
        .map_err(|_| anyhow::anyhow!("the decoding thread panicked"))?;
    let wall = t0.elapsed();
    let copies = jpegs
        .join()
        .map_err(|_| anyhow::anyhow!("the JPEG thread panicked"))?;
    let (ex, model_name) = ex?;
    check_interrupt()?;
    copies
        .result
        .context("keeping reduced frames for the report")?;
    let n = ex.track.n_frames();
    stages.push(StageTime {
        name: "decode",
        time: decoded.decode,
        frames: n,
        note: "FFmpeg rgb24 pipe, own thread alongside pose",
    });
    stages.push(StageTime {
        name: "jpeg",
        time: copies.time,
        frames: copies.store.frames.len(),
        note: "reduced JPEG copies (FFmpeg mjpeg), own thread alongside pose",
    });
    stages.push(StageTime {
        name: "pose",
        time: wall,
        frames: n,
        note: "model loading + inference (waits on decoding included)",
    });
    let found = ex.found_fraction();
    if found == 0.0 {
        bail!(
            "no person was found in any of the {n} frames of {}",
            path.display()
        );
    }
    let mut track = ex.track;
    if !all_joints && track.skeleton().name != "coco17" && track.skeleton().maps_to_coco17() {
        track = track
            .to_coco17()
            .context("mapping the keypoints to COCO-17")?;
    }
    let overlay_frames = opts.overlay_video.then(|| OverlayFrames {
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
        extra_cards: vec![Card::new(
            "pose",
            format!("{:.0}%", 100.0 * found),
            format!("of frames with a person · {model_name}"),
        )],
        track,
        frames: Some(copies.store),
        overlay_frames,
        frame_size: Some((info.width, info.height)),
        frame_px: Some(info.width.max(info.height) as f64),
    })
}

/// Concrete and abstract programs of a track, timed separately.
pub fn analyse_timed(
    track: &Track,
    frame_px: Option<f64>,
    quiet: bool,
    stages: &mut Vec<StageTime>,
) -> Result<Analysis> {
    // The abstract analysis' defaults (adaptive λ), with the frame size as the scale when known.
    let defaults = AbstractParams::default();
    let synth = SynthParams {
        scale: match frame_px {
            Some(frame_px) => Scale::FrameSize { frame_px },
            None => Scale::Auto,
        },
        unobserved_joints: UnobservedJoints::Ignore,
        ..defaults.synth
    };
    let pb = bar(None, "concrete", quiet);
    let t0 = Instant::now();
    let syn = synthesize_detailed(track, &synth).context("fitting the concrete program")?;
    stages.push(StageTime {
        name: "concrete",
        time: t0.elapsed(),
        frames: track.n_frames(),
        note: "segmentation and primitive fits",
    });
    pb.finish_and_clear();
    check_interrupt()?;
    let pb = bar(None, "abstract", quiet);
    let t1 = Instant::now();
    let loops = LoopParams {
        unit_scale: syn.unit_scale,
        ..defaults.loops
    };
    let (program, found, prims) = mp_abstract::pipeline::from_concrete(&syn.program, &loops)
        .context("finding loops (abstract program)")?;
    let intervals = mp_abstract::repetition::intervals(&prims, &found, 0);
    stages.push(StageTime {
        name: "abstract",
        time: t1.elapsed(),
        frames: track.n_frames(),
        note: "abstract program and loops",
    });
    pb.finish_and_clear();
    check_interrupt()?;
    Ok(Analysis {
        concrete: syn.program,
        prims,
        program,
        loops: found,
        intervals,
        unit_scale: syn.unit_scale,
    })
}

/// Writes the track, the programs and the loops: `track.npz`, `program.txt`,
/// `program.json`, `abstract.txt`, `abstract.json`, `loops.json`.
pub fn write_analysis(out: &OutputDir, track: &Track, an: &Analysis) -> Result<Vec<String>> {
    let mut files = Vec::new();
    let mut put = |rel: &str, bytes: &[u8]| -> Result<()> {
        out.write(rel, bytes)
            .with_context(|| format!("writing {}", out.path(rel).display()))?;
        files.push(rel.to_string());
        Ok(())
    };
    put(
        "track.npz",
        &mp_geom::io::native::track_to_npz_bytes(track)?,
    )?;
    put("program.txt", an.concrete.to_dsl().as_bytes())?;
    put("program.json", an.concrete.to_json()?.as_bytes())?;
    put(
        "abstract.txt",
        mp_abstract::dsl::print(&an.program).as_bytes(),
    )?;
    put(
        "abstract.json",
        serde_json::to_string_pretty(&an.program)?.as_bytes(),
    )?;
    let loops = serde_json::json!({
        "fps": track.fps(),
        "frames": track.n_frames(),
        "intervals": an.intervals,
        "counts": an.intervals.iter().map(|i| i.count).collect::<Vec<_>>(),
        "total_repetitions": an.intervals.iter().map(|i| i.count).sum::<usize>(),
    });
    put(
        "loops.json",
        serde_json::to_string_pretty(&loops)?.as_bytes(),
    )?;
    Ok(files)
}

fn file_stem_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn loop_caption(an: &Analysis, f: usize) -> Option<String> {
    an.intervals
        .iter()
        .find(|iv| f >= iv.start_frame && f < iv.end_frame)
        .map(|iv| {
            let it = iv
                .boundaries
                .windows(2)
                .position(|w| f >= w[0] && f < w[1])
                .unwrap_or(0);
            format!("rep {}/{}", it + 1, iv.count)
        })
}

/// The whole pipeline into `out_dir`.
///
/// Video input: a decoding thread feeds the pose model. After the programs,
/// the overlay video (its own thread, plus the FFmpeg encoder) is made
/// alongside the plots, the contact sheet and the report page; the report is
/// written last.
pub fn run_pipeline(source: Source, out_dir: &Path, opts: &RunOptions) -> Result<RunSummary> {
    let start = Instant::now();
    let mut stages: Vec<StageTime> = Vec::new();

    // 1. Keypoints.
    let kp = match source {
        Source::Video {
            path,
            model,
            max_frames,
            all_joints,
            threads,
        } => keypoints_from_video(
            &path,
            model,
            max_frames,
            all_joints,
            threads,
            opts,
            &mut stages,
        )?,
        Source::Track {
            track,
            title,
            description,
            frame_size,
            frame_px,
        } => Keypoints {
            track,
            frames: None,
            overlay_frames: None,
            title,
            description,
            frame_size,
            frame_px,
            extra_cards: Vec::new(),
        },
    };
    let Keypoints {
        track,
        frames,
        overlay_frames,
        title,
        description,
        frame_size,
        frame_px,
        extra_cards,
    } = kp;
    if track.n_frames() < 2 {
        bail!(
            "the motion has {} frame(s); at least 2 are needed",
            track.n_frames()
        );
    }

    // 2–3. Programs and loops; the output folder is created once there is something to write.
    let an = analyse_timed(&track, frame_px, opts.quiet, &mut stages)?;
    let out = OutputDir::create(out_dir)
        .with_context(|| format!("creating the output folder {}", out_dir.display()))?;
    let mut files = write_analysis(&out, &track, &an)?;
    let executed = an.concrete.execute().context("executing the program")?;

    // 4–5. Overlay video on its own thread; pictures, then the report page, here.
    let multi = if opts.quiet {
        MultiProgress::with_draw_target(ProgressDrawTarget::hidden())
    } else {
        MultiProgress::new()
    };
    let n = track.n_frames();
    let overlay_rel = overlay_frames.as_ref().map(|_| "overlay.mp4".to_string());
    let (pictures, overlay, html) = std::thread::scope(|s| {
        let overlay = overlay_frames.map(|src| {
            let pb = multi.add(bar(Some(n), "overlay", opts.quiet));
            let (out, track, executed) = (&out, &track, &executed);
            s.spawn(move || {
                let t0 = Instant::now();
                let r = write_overlay(out, src, track, executed, &pb);
                pb.finish_and_clear();
                r.map(|()| t0.elapsed())
            })
        });
        let t_pic = Instant::now();
        let pictures = write_pictures(
            &out,
            &track,
            &executed,
            &an,
            frames.as_ref(),
            frame_size,
            &title,
            &multi,
            opts.quiet,
        )
        .map(|f| (f, t_pic.elapsed()));
        let html = pictures.as_ref().ok().map(|(pic_files, _)| {
            let t_rep = Instant::now();
            let pb = multi.add(bar(None, "report", opts.quiet));
            let mut linked = vec![
                "program.txt".to_string(),
                "program.json".into(),
                "abstract.txt".into(),
                "abstract.json".into(),
                "loops.json".into(),
                "track.npz".into(),
                "timeline.svg".into(),
                "contact_sheet.png".into(),
            ];
            linked.extend(overlay_rel.iter().cloned());
            linked.extend(
                pic_files
                    .iter()
                    .filter(|f| f.starts_with("plots/") && f.ends_with(".svg"))
                    .cloned(),
            );
            let html = report_page(
                &track,
                &executed,
                &an,
                frames.as_ref(),
                &title,
                &description,
                &extra_cards,
                &linked,
            );
            pb.finish_and_clear();
            html.map(|h| (h, t_rep.elapsed()))
        });
        let overlay = overlay.map(|h| {
            h.join()
                .map_err(|_| anyhow::anyhow!("the overlay thread panicked"))
                .and_then(|r| r)
        });
        (pictures, overlay, html)
    });
    let (pic_files, pic_time) = pictures?;
    files.extend(pic_files);
    stages.push(StageTime {
        name: "pictures",
        time: pic_time,
        frames: n,
        note: "plots (SVG + PNG), timeline, contact sheet",
    });
    if let Some(ov) = overlay {
        let t = ov?;
        files.push("overlay.mp4".into());
        stages.push(StageTime {
            name: "overlay",
            time: t,
            frames: n,
            note: "own thread, alongside pictures + report; draw + H.264",
        });
    }
    let (html, t_html) = html.context("the report page was not made")??;
    // The report is written last: when it exists, everything it links to does too.
    check_interrupt()?;
    let t_write = Instant::now();
    let report = out.write("report.html", html.as_bytes())?;
    files.push("report.html".into());
    stages.push(StageTime {
        name: "report",
        time: t_html + t_write.elapsed(),
        frames: n,
        note: "HTML page with the frames embedded",
    });
    let motion_s = n as f64 / track.fps();
    drop(out);
    Ok(RunSummary {
        analysis: an,
        report,
        stages,
        total: start.elapsed(),
        motion_s,
        files,
    })
}

/// Plots, timeline and contact sheet; returns the files written.
#[allow(clippy::too_many_arguments)]
fn write_pictures(
    out: &OutputDir,
    track: &Track,
    executed: &Track,
    an: &Analysis,
    frames: Option<&FrameStore>,
    frame_size: Option<(usize, usize)>,
    title: &str,
    multi: &MultiProgress,
    quiet: bool,
) -> Result<Vec<String>> {
    let mut files = Vec::new();
    let j = an.concrete.n_joints();
    let pb = multi.add(bar(Some(j + 2), "pictures", quiet));
    let plot_params = PlotParams::default();
    // Plots are drawn in parallel and written in joint order.
    let rendered: Vec<Result<(String, String, Vec<u8>)>> = an
        .concrete
        .joints
        .par_iter()
        .enumerate()
        .map(|(ji, name)| {
            check_interrupt()?;
            let svg = joint_trajectory_svg(track, &an.concrete, &an.intervals, ji, &plot_params)?;
            let png = svg_to_png(name, &svg, 1.0)?;
            pb.inc(1);
            Ok((
                format!("plots/{:02}_{}", ji, file_stem_safe(name)),
                svg,
                png,
            ))
        })
        .collect();
    for r in rendered {
        let (stem, svg, png) = r?;
        out.write(&format!("{stem}.svg"), svg.as_bytes())?;
        out.write(&format!("{stem}.png"), &png)?;
        files.push(format!("{stem}.svg"));
        files.push(format!("{stem}.png"));
    }
    let (tl_svg, _) = timeline_svg(&an.concrete, &an.intervals, &TimelineParams::default())?;
    out.write("timeline.svg", tl_svg.as_bytes())?;
    out.write("timeline.png", &svg_to_png("timeline", &tl_svg, 1.0)?)?;
    files.push("timeline.svg".into());
    files.push("timeline.png".into());
    pb.inc(1);
    // Contact sheet: 12 evenly spaced frames, drawn in parallel.
    let n_frames = track.n_frames();
    let n_tiles = 12.min(n_frames);
    let picks: Vec<usize> = (0..n_tiles)
        .map(|i| ((i as f64 + 0.5) * n_frames as f64 / n_tiles as f64) as usize)
        .map(|f| f.min(n_frames - 1))
        .collect();
    let kp_style = SkeletonStyle::default();
    let prog_style = SkeletonStyle::program();
    let tiles: Vec<Tile> = picks
        .par_iter()
        .map(|&f| -> Result<Tile> {
            let caption = match loop_caption(an, f) {
                Some(l) => format!("frame {f} · {:.2} s · {l}", f as f64 / track.fps()),
                None => format!("frame {f} · {:.2} s", f as f64 / track.fps()),
            };
            let pixmap = match (frames, frame_size) {
                (Some(store), Some((w, h))) => {
                    let tile_w = 240u32;
                    let tile_h = ((h as f64 / w as f64) * tile_w as f64).round().max(1.0) as u32;
                    let pos = store.nearest(f).context("no stored frame")?;
                    let rgb = store.rgb(pos)?;
                    let small = rgb_to_pixmap(&rgb, store.size.0, store.size.1)?;
                    let mut tile = blank_canvas(tile_w, tile_h)?;
                    blit_scaled(&mut tile, &small);
                    let view = View::frame(tile_w as f64 / w as f64);
                    draw_skeleton(&mut tile, executed, f, &view, &prog_style.scaled(0.8));
                    draw_skeleton(&mut tile, track, f, &view, &kp_style.scaled(0.8));
                    tile
                }
                _ => {
                    let (tw, th) = (240u32, 240u32);
                    let mut tile = blank_canvas(tw, th)?;
                    let view = View::fit(&[track, executed], tw as f64, th as f64, 16.0);
                    draw_skeleton(&mut tile, executed, f, &view, &prog_style.scaled(0.8));
                    draw_skeleton(&mut tile, track, f, &view, &kp_style.scaled(0.8));
                    tile
                }
            };
            Ok(Tile { pixmap, caption })
        })
        .collect::<Result<_>>()?;
    check_interrupt()?;
    let sheet = contact_sheet(
        &tiles,
        4,
        &format!("{title} — keypoints and program (pink)"),
    )?;
    out.write(
        "contact_sheet.png",
        &pixmap_to_png("contact sheet", &sheet)?,
    )?;
    files.push("contact_sheet.png".into());
    pb.inc(1);
    pb.finish_and_clear();
    Ok(files)
}

/// The report page (not yet written).
#[allow(clippy::too_many_arguments)]
fn report_page(
    track: &Track,
    executed: &Track,
    an: &Analysis,
    frames: Option<&FrameStore>,
    title: &str,
    description: &str,
    extra_cards: &[Card],
    linked: &[String],
) -> Result<String> {
    let mut cards = standard_cards(track, &an.concrete, executed, &an.intervals);
    cards.extend(extra_cards.iter().cloned());
    let abstract_text = print_with(&an.program, &PrintOptions::summary());
    let (tl_page, _) = timeline_svg(
        &an.concrete,
        &an.intervals,
        &TimelineParams {
            title: false,
            ..TimelineParams::default()
        },
    )?;
    Ok(report_html(&ReportInput {
        title,
        subtitle: description,
        track,
        program: &an.concrete,
        executed,
        abstract_text: &abstract_text,
        intervals: &an.intervals,
        frames,
        timeline_svg: &tl_page,
        cards: &cards,
        files: linked,
    })?)
}

/// Encodes every analysed frame with the keypoints and the executed program
/// drawn on it into `overlay.mp4` (x264 `veryfast`: about twice as fast as
/// the default preset, and smaller files on this kind of footage).
fn write_overlay(
    out: &OutputDir,
    src: OverlayFrames,
    track: &Track,
    executed: &Track,
    pb: &ProgressBar,
) -> Result<()> {
    let n = track.n_frames();
    let (width, height, fps) = (src.info.width, src.info.height, src.info.fps);
    let staged = out.staging_file("overlay.mp4");
    let mut writer = VideoWriter::create_with_preset(&staged, width, height, fps, OVERLAY_PRESET)
        .map_err(pose_err)?;
    let s = (width.max(height) as f32 / 512.0).max(0.6);
    let kp_style = SkeletonStyle::default().scaled(s);
    let prog_style = SkeletonStyle::program().scaled(s);
    let view = View::frame(1.0);
    let mut draw = |index: usize, rgb: &[u8]| -> Result<()> {
        check_interrupt()?;
        let mut pm = rgb_to_pixmap(rgb, width, height)?;
        draw_skeleton(&mut pm, executed, index, &view, &prog_style);
        draw_skeleton(&mut pm, track, index, &view, &kp_style);
        writer.write(&pixmap_to_rgb(&pm)).map_err(pose_err)?;
        pb.inc(1);
        Ok(())
    };
    match src.kept {
        Some(frames) => {
            for (index, rgb) in frames.iter().take(n).enumerate() {
                draw(index, rgb)?;
            }
        }
        None => {
            let reader = VideoReader::from_info(src.info).map_err(pose_err)?;
            for frame in reader.take(n) {
                let frame = frame.map_err(pose_err)?;
                draw(frame.index, &frame.rgb)?;
            }
        }
    }
    check_interrupt()?;
    writer
        .finish()
        .map_err(pose_err)
        .context("encoding overlay.mp4")?;
    out.commit(&staged, "overlay.mp4")?;
    Ok(())
}
