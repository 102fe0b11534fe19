//! `mp batch`: a folder (or a list) of videos and track files through the
//! pipeline, several at once — argument parsing, progress and printing around
//! `mp_pipeline::batch`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Duration;

use anyhow::{bail, Result};
use clap::Args;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use mp_pipeline::{BatchObserver, BatchSummary, ItemReport, ItemStatus};
use mp_pipeline::{BatchParams, SharedModel, Stage};

use crate::progress::ctrl_c_token;

/// Arguments of `mp batch`.
#[derive(Args, Debug)]
pub struct BatchArgs {
    /// A folder of videos and track files (npz, json, csv, npy, bvh, mpt, c3d, parquet, pose; hidden files and subfolders are not read), or a text file listing inputs, one per line (`#` comments; relative paths relative to the list).
    pub input: PathBuf,
    /// Output folder: one folder per input (named after the file) and `manifest.jsonl`.
    #[arg(long, short)]
    pub out: PathBuf,
    /// Inputs processed at once.
    #[arg(long, short, default_value_t = BatchParams::default().jobs)]
    pub jobs: usize,
    /// ONNX Runtime threads of each input's pose model; default: the cores divided by the jobs (at least 1).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Whether the jobs share one landmark model that runs the crops of every job's frame together: auto (on a GPU), always or never.
    #[arg(long, default_value = "auto", value_parser = SharedModel::parse)]
    pub shared_model: SharedModel,
    #[command(flatten)]
    pub pose: crate::cmd_run::PoseModelOpts,
    /// Largest side of the video frame in pixels, for track inputs (scale = frame / 512); default: from each motion's extent.
    #[arg(long)]
    pub frame_size: Option<f64>,
    #[command(flatten)]
    pub rate: crate::track_arg::RateOpt,
    #[command(flatten)]
    pub people: crate::cmd_run::PeopleOpts,
    /// Do not write the overlay videos.
    #[arg(long)]
    pub no_video: bool,
    /// Every setting of each run from a JSON file (`mp params` prints them); the options given here apply on top.
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// No progress bars and no summary (failures are still reported).
    #[arg(long, short)]
    pub quiet: bool,
}

impl BatchArgs {
    /// The library parameters these arguments ask for.
    pub fn params(&self) -> Result<BatchParams> {
        let mut p = BatchParams {
            jobs: self.jobs,
            threads: self.threads,
            frame_px: self.frame_size,
            fps: self.rate.fps,
            shared_model: self.shared_model,
            ..BatchParams::default()
        };
        p.params = crate::cmd_run::params_file(self.params.as_deref())?;
        let only_given = self.params.is_some();
        self.pose.apply(&mut p.params, only_given)?;
        if !only_given || crate::given("no_video") {
            p.params.output.overlay_video = !self.no_video;
        }
        self.people.apply(&mut p.params, only_given)?;
        p.validate()?;
        Ok(p)
    }
}

/// `mp batch`.
pub fn batch_cmd(a: &BatchArgs) -> Result<()> {
    crate::track_arg::check_out_dir(&a.out)?;
    let params = a.params()?;
    let items = mp_pipeline::batch_items(&a.input)?;
    let cancel = ctrl_c_token();
    let bars = BatchBars::new(items.len(), a.quiet);
    let res = mp_pipeline::batch(&items, &a.out, &params, &bars, &cancel);
    bars.finish();
    let summary = res?;
    if summary.cancelled {
        eprintln!(
            "\ninterrupted: {} of {} items finished; run the same command again to go on ({} lists them)",
            summary.items.len() - summary.cancelled_items(),
            summary.items.len(),
            summary.manifest.display()
        );
        std::process::exit(130);
    }
    if !a.quiet {
        print_summary(&summary);
    }
    let failed: Vec<&ItemReport> = summary
        .items
        .iter()
        .filter(|i| i.status == ItemStatus::Failed)
        .collect();
    if !failed.is_empty() {
        for f in &failed {
            eprintln!(
                "failed: {}: {}",
                f.input.display(),
                f.error.as_deref().unwrap_or("unknown error")
            );
        }
        bail!(
            "{} of {} items failed (see {})",
            failed.len(),
            summary.items.len(),
            summary.manifest.display()
        );
    }
    Ok(())
}

/// One line per item in input order, then the totals.
fn print_summary(s: &BatchSummary) {
    println!(
        "{:<8} {:>6} {:>8} {:>6}  input → output",
        "status", "frames", "time (s)", "reps"
    );
    for i in &s.items {
        println!("{}", item_line(i));
    }
    println!();
    println!(
        "{} items: {} ok, {} failed, {} skipped (complete from an earlier run)",
        s.items.len(),
        s.ok(),
        s.failed(),
        s.skipped()
    );
    let wall = s.wall.as_secs_f64();
    println!(
        "{} frames run in {:.1} s wall: {:.1} frames/s ({} job{} × {} ONNX thread{})",
        s.frames(),
        wall,
        s.throughput(),
        s.jobs,
        if s.jobs == 1 { "" } else { "s" },
        s.threads_per_item,
        if s.threads_per_item == 1 { "" } else { "s" }
    );
    if let Some(m) = s.shared_model {
        println!(
            "shared landmark model: {} crops in {} runs ({:.1} crops/s)",
            m.crops,
            m.runs,
            m.crops as f64 / wall.max(1e-9)
        );
    }
    println!("Manifest: {}", s.manifest.display());
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_else(|| "–".into())
}

/// `status frames seconds reps input → output`.
fn item_line(i: &ItemReport) -> String {
    format!(
        "{:<8} {:>6} {:>8} {:>6}  {} → {}",
        i.status.as_str(),
        opt(i.frames),
        opt(i.seconds.map(|s| format!("{s:.2}"))),
        opt(i.total_repetitions),
        i.input.display(),
        i.output.display()
    )
}

/// Two bars: items done, and frames through the pose model (or read from
/// track files) with their rate.
struct BatchBars {
    multi: MultiProgress,
    items: ProgressBar,
    frames: ProgressBar,
    /// Per running item: frames already counted on the frames bar, and its name.
    running: Mutex<HashMap<usize, (u64, String)>>,
    quiet: bool,
}

impl BatchBars {
    fn new(n: usize, quiet: bool) -> Self {
        let multi = if quiet {
            MultiProgress::with_draw_target(ProgressDrawTarget::hidden())
        } else {
            MultiProgress::new()
        };
        let items = multi.add(ProgressBar::new(n as u64));
        if let Ok(style) = ProgressStyle::with_template(
            "{spinner:.green} items  [{bar:30.cyan/blue}] {pos}/{len} {elapsed_precise} {wide_msg}",
        ) {
            items.set_style(style.progress_chars("=> "));
        }
        let frames = multi.add(ProgressBar::no_length());
        if let Ok(style) = ProgressStyle::with_template("  frames {pos} ({per_sec})") {
            frames.set_style(style);
        }
        if !quiet {
            items.enable_steady_tick(Duration::from_millis(200));
        }
        BatchBars {
            multi,
            items,
            frames,
            running: Mutex::new(HashMap::new()),
            quiet,
        }
    }

    fn set_running_message(&self, running: &HashMap<usize, (u64, String)>) {
        let mut names: Vec<(&usize, &String)> = running.iter().map(|(i, (_, n))| (i, n)).collect();
        names.sort();
        let names: Vec<&str> = names.into_iter().map(|(_, n)| n.as_str()).collect();
        self.items.set_message(names.join(", "));
    }

    fn finish(&self) {
        self.items.finish_and_clear();
        self.frames.finish_and_clear();
    }
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| p.display().to_string())
}

impl BatchObserver for BatchBars {
    fn item_started(&self, index: usize, input: &Path) {
        if let Ok(mut r) = self.running.lock() {
            r.insert(index, (0, file_name(input)));
            self.set_running_message(&r);
        }
    }

    fn stage_progress(&self, index: usize, stage: Stage, done: usize) {
        if stage != Stage::Pose {
            return;
        }
        if let Ok(mut r) = self.running.lock() {
            if let Some((counted, _)) = r.get_mut(&index) {
                let done = done as u64;
                if done > *counted {
                    self.frames.inc(done - *counted);
                    *counted = done;
                }
            }
        }
    }

    fn item_finished(&self, index: usize, report: &ItemReport) {
        if report.status == ItemStatus::Skipped || report.status == ItemStatus::Cancelled {
            self.items.inc(1);
            return;
        }
        if let Ok(mut r) = self.running.lock() {
            let counted = r.remove(&index).map(|(c, _)| c).unwrap_or(0);
            let frames = report.frames.unwrap_or(0) as u64;
            if frames > counted {
                self.frames.inc(frames - counted);
            }
            self.set_running_message(&r);
        }
        self.items.inc(1);
        if !self.quiet {
            let _ = self.multi.println(item_line(report));
        }
    }
}
