//! `mp run`: a video or a keypoint track in, programs, loops, pictures and a
//! report out.
//!
//! Steps: keypoints (FFmpeg decoding + pose model, or a track file) →
//! concrete program → abstract program and loops → pictures (trajectory
//! plots, timeline, contact sheet, overlay video) → `report.html`. Every
//! file goes through the output folder's staging area
//! ([`mp_report::OutputDir`]), so Ctrl-C leaves only complete files.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, Once};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use mp_abstract::dsl::{print_with, PrintOptions};
use mp_abstract::{AbstractParams, Analysis, LoopParams};
use mp_concrete::{synthesize_detailed, Scale, SynthParams, UnobservedJoints};
use mp_geom::Track;
use mp_pose::extract::{extract, open_estimator, ExtractOptions, ModelChoice};
use mp_pose::video::{Frame, FrameSource, VideoReader, VideoWriter};
use mp_pose::SessionParams;
use mp_report::draw::{
    blank_canvas, blit_scaled, contact_sheet, draw_skeleton, SkeletonStyle, Tile, View,
};
use mp_report::outdir::{check_interrupt, emergency_cleanup, interrupted, request_interrupt};
use mp_report::raster::{pixmap_to_rgb, rgb_to_pixmap, svg_to_png};
use mp_report::{
    joint_trajectory_svg, report_html, standard_cards, timeline_svg, Card, FrameStore,
    FrameStoreParams, OutputDir, PlotParams, ReportError, ReportInput, TimelineParams,
};
use rayon::prelude::*;

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
        t.push_str(&format!("{:<12} {:>8.2}  {}\n", st.name, secs, fps));
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

/// An iterator over frames that keeps reduced copies for the report, times
/// decoding and stops at Ctrl-C.
struct Tap {
    inner: Box<dyn Iterator<Item = mp_pose::Result<Frame>> + Send>,
    store: Arc<Mutex<FrameStore>>,
    decode_ns: Arc<AtomicU64>,
    store_ns: Arc<AtomicU64>,
    store_err: Arc<Mutex<Option<ReportError>>>,
}

impl Iterator for Tap {
    type Item = mp_pose::Result<Frame>;
    fn next(&mut self) -> Option<Self::Item> {
        if interrupted() {
            return None;
        }
        let t0 = Instant::now();
        let f = self.inner.next();
        self.decode_ns
            .fetch_add(t0.elapsed().as_nanos() as u64, Ordering::Relaxed);
        if let Some(Ok(frame)) = &f {
            let t1 = Instant::now();
            if let Ok(mut st) = self.store.lock() {
                if let Err(e) = st.push(frame.index, &frame.rgb) {
                    if let Ok(mut slot) = self.store_err.lock() {
                        slot.get_or_insert(e);
                    }
                }
            }
            self.store_ns
                .fetch_add(t1.elapsed().as_nanos() as u64, Ordering::Relaxed);
        }
        f
    }
}

struct Keypoints {
    track: Track,
    frames: Option<FrameStore>,
    video: Option<PathBuf>,
    title: String,
    description: String,
    frame_size: Option<(usize, usize)>,
    frame_px: Option<f64>,
    extra_cards: Vec<Card>,
    /// Time spent keeping reduced frames for the report (counted in the report stage).
    keep_frames: Duration,
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
    let store = Arc::new(Mutex::new(FrameStore::new(
        info.width,
        info.height,
        expected,
        &FrameStoreParams::default(),
    )?));
    let decode_ns = Arc::new(AtomicU64::new(0));
    let store_ns = Arc::new(AtomicU64::new(0));
    let store_err = Arc::new(Mutex::new(None));
    let source = FrameSource {
        width: info.width,
        height: info.height,
        fps: info.fps,
        frame_count: info.frame_count,
        frames: Box::new(Tap {
            inner: Box::new(reader),
            store: store.clone(),
            decode_ns: decode_ns.clone(),
            store_ns: store_ns.clone(),
            store_err: store_err.clone(),
        }),
    };
    let mut est = open_estimator(
        model,
        SessionParams {
            intra_threads: threads.max(1),
            ..Default::default()
        },
    )
    .map_err(pose_err)
    .context("loading the pose model")?;
    let pb = bar(expected, "pose", opts.quiet);
    let t0 = Instant::now();
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
    pb.finish_and_clear();
    check_interrupt()?;
    let wall = t0.elapsed();
    let dec = Duration::from_nanos(decode_ns.load(Ordering::Relaxed));
    let sto = Duration::from_nanos(store_ns.load(Ordering::Relaxed));
    let n = ex.track.n_frames();
    stages.push(StageTime {
        name: "decode",
        time: dec + sto,
        frames: n,
    });
    stages.push(StageTime {
        name: "pose",
        time: wall.saturating_sub(dec + sto),
        frames: n,
    });
    if let Some(e) = store_err.lock().ok().and_then(|mut s| s.take()) {
        return Err(e).context("keeping frames for the report");
    }
    let found = ex.found_fraction();
    if found == 0.0 {
        bail!(
            "no person was found in any of the {n} frames of {}",
            path.display()
        );
    }
    let model_name = est.name().to_string();
    let mut track = ex.track;
    if !all_joints && track.skeleton().name != "coco17" && track.skeleton().maps_to_coco17() {
        track = track
            .to_coco17()
            .context("mapping the keypoints to COCO-17")?;
    }
    let frames = Arc::try_unwrap(store)
        .ok()
        .and_then(|m| m.into_inner().ok())
        .context("collecting the stored frames")?;
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
        frames: Some(frames),
        video: Some(path.to_path_buf()),
        keep_frames: sto,
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
            video: None,
            title,
            description,
            frame_size,
            frame_px,
            extra_cards: Vec::new(),
            keep_frames: Duration::ZERO,
        },
    };
    let track = kp.track;
    if track.n_frames() < 2 {
        bail!(
            "the motion has {} frame(s); at least 2 are needed",
            track.n_frames()
        );
    }

    // 2–3. Programs and loops; the output folder is created once there is something to write.
    let an = analyse_timed(&track, kp.frame_px, opts.quiet, &mut stages)?;
    let out = OutputDir::create(out_dir)
        .with_context(|| format!("creating the output folder {}", out_dir.display()))?;
    let mut files = write_analysis(&out, &track, &an)?;

    // 4. Pictures.
    let t_pic = Instant::now();
    let executed = an.concrete.execute().context("executing the program")?;
    let j = an.concrete.n_joints();
    let pb = bar(Some(j + 2), "pictures", opts.quiet);
    let plot_params = PlotParams::default();
    // Plots are drawn in parallel and written in joint order.
    let rendered: Vec<Result<(String, String, Vec<u8>)>> = an
        .concrete
        .joints
        .par_iter()
        .enumerate()
        .map(|(ji, name)| {
            check_interrupt()?;
            let svg = joint_trajectory_svg(&track, &an.concrete, &an.intervals, ji, &plot_params)?;
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
    // Contact sheet: 12 evenly spaced frames.
    let n_tiles = 12.min(track.n_frames());
    let picks: Vec<usize> = (0..n_tiles)
        .map(|i| ((i as f64 + 0.5) * track.n_frames() as f64 / n_tiles as f64) as usize)
        .map(|f| f.min(track.n_frames() - 1))
        .collect();
    let mut tiles = Vec::with_capacity(n_tiles);
    let kp_style = SkeletonStyle::default();
    let prog_style = SkeletonStyle::program();
    for &f in &picks {
        let caption = match loop_caption(&an, f) {
            Some(l) => format!("frame {f} · {:.2} s · {l}", f as f64 / track.fps()),
            None => format!("frame {f} · {:.2} s", f as f64 / track.fps()),
        };
        let pixmap = match (&kp.frames, kp.frame_size) {
            (Some(store), Some((w, h))) => {
                let tile_w = 240u32;
                let tile_h = ((h as f64 / w as f64) * tile_w as f64).round().max(1.0) as u32;
                let pos = store.nearest(f).context("no stored frame")?;
                let rgb = store.rgb(pos)?;
                let small = rgb_to_pixmap(&rgb, store.size.0, store.size.1)?;
                let mut tile = blank_canvas(tile_w, tile_h)?;
                blit_scaled(&mut tile, &small);
                let view = View::frame(tile_w as f64 / w as f64);
                draw_skeleton(&mut tile, &executed, f, &view, &prog_style.scaled(0.8));
                draw_skeleton(&mut tile, &track, f, &view, &kp_style.scaled(0.8));
                tile
            }
            _ => {
                let (tw, th) = (240u32, 240u32);
                let mut tile = blank_canvas(tw, th)?;
                let view = View::fit(&[&track, &executed], tw as f64, th as f64, 16.0);
                draw_skeleton(&mut tile, &executed, f, &view, &prog_style.scaled(0.8));
                draw_skeleton(&mut tile, &track, f, &view, &kp_style.scaled(0.8));
                tile
            }
        };
        tiles.push(Tile { pixmap, caption });
    }
    let sheet = contact_sheet(
        &tiles,
        4,
        &format!("{} — keypoints and program (pink)", kp.title),
    )?;
    let sheet_png = sheet
        .encode_png()
        .map_err(|e| anyhow::anyhow!("encoding the contact sheet: {e}"))?;
    out.write("contact_sheet.png", &sheet_png)?;
    files.push("contact_sheet.png".into());
    pb.inc(1);
    pb.finish_and_clear();
    // Overlay video.
    if let (Some(video), true) = (&kp.video, opts.overlay_video) {
        write_overlay(&out, video, &track, &executed, opts.quiet)?;
        files.push("overlay.mp4".into());
    }
    stages.push(StageTime {
        name: "pictures",
        time: t_pic.elapsed(),
        frames: track.n_frames(),
    });

    // 5. Report.
    check_interrupt()?;
    let t_rep = Instant::now();
    let pb = bar(None, "report", opts.quiet);
    let mut cards = standard_cards(&track, &an.concrete, &executed, &an.intervals);
    cards.extend(kp.extra_cards.iter().cloned());
    let abstract_text = print_with(&an.program, &PrintOptions::summary());
    let (tl_page, _) = timeline_svg(
        &an.concrete,
        &an.intervals,
        &TimelineParams {
            title: false,
            ..TimelineParams::default()
        },
    )?;
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
    if files.iter().any(|f| f == "overlay.mp4") {
        linked.push("overlay.mp4".into());
    }
    linked.extend(
        files
            .iter()
            .filter(|f| f.starts_with("plots/") && f.ends_with(".svg"))
            .cloned(),
    );
    let html = report_html(&ReportInput {
        title: &kp.title,
        subtitle: &kp.description,
        track: &track,
        program: &an.concrete,
        executed: &executed,
        abstract_text: &abstract_text,
        intervals: &an.intervals,
        frames: kp.frames.as_ref(),
        timeline_svg: &tl_page,
        cards: &cards,
        files: &linked,
    })?;
    let report = out.write("report.html", html.as_bytes())?;
    files.push("report.html".into());
    pb.finish_and_clear();
    stages.push(StageTime {
        name: "report",
        time: t_rep.elapsed() + kp.keep_frames,
        frames: track.n_frames(),
    });
    let motion_s = track.n_frames() as f64 / track.fps();
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

/// Decodes the video again and encodes every analysed frame with the
/// keypoints and the executed program drawn on it.
fn write_overlay(
    out: &OutputDir,
    video: &Path,
    track: &Track,
    executed: &Track,
    quiet: bool,
) -> Result<()> {
    let reader = VideoReader::open(video).map_err(pose_err)?;
    let info = reader.info().clone();
    let staged = out.staging_file("overlay.mp4");
    let mut writer =
        VideoWriter::create(&staged, info.width, info.height, info.fps).map_err(pose_err)?;
    let n = track.n_frames();
    let pb = bar(Some(n), "overlay", quiet);
    let s = (info.width.max(info.height) as f32 / 512.0).max(0.6);
    let kp_style = SkeletonStyle::default().scaled(s);
    let prog_style = SkeletonStyle::program().scaled(s);
    let view = View::frame(1.0);
    for frame in reader.take(n) {
        check_interrupt()?;
        let frame = frame.map_err(pose_err)?;
        let mut pm = rgb_to_pixmap(&frame.rgb, frame.width, frame.height)?;
        draw_skeleton(&mut pm, executed, frame.index, &view, &prog_style);
        draw_skeleton(&mut pm, track, frame.index, &view, &kp_style);
        writer.write(&pixmap_to_rgb(&pm)).map_err(pose_err)?;
        pb.inc(1);
    }
    check_interrupt()?;
    writer
        .finish()
        .map_err(pose_err)
        .context("encoding overlay.mp4")?;
    out.commit(&staged, "overlay.mp4")?;
    pb.finish_and_clear();
    Ok(())
}
