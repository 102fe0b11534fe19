//! Many inputs in one go: each video or track file through [`run`](crate::run) into its
//! own output folder, several at once, with a manifest that lets an
//! interrupted batch resume.
//!
//! * [`batch_items`] lists a folder's videos and track files, or reads a
//!   text file of paths.
//! * [`batch()`] runs every item into `OUT_DIR/<file stem>` (equal stems are
//!   told apart by their extension, then by a number) and appends one JSON
//!   line per finished item to `OUT_DIR/manifest.jsonl`, written to disk
//!   before the next line. What a folder holds is exactly what [`run`](crate::run)
//!   writes for that input.
//! * **Resume**: an item whose output folder holds `loops.json` and whose
//!   last manifest line says `ok` (or `skipped`) is not run again; its new
//!   line says `skipped` and carries the earlier counts. Delete an item's
//!   folder to run it again.
//! * **Failures** stay with their item: the manifest line says `failed`
//!   with the message and its causes, and the batch goes on.
//! * **Jobs share the machine**: [`BatchParams::jobs`] items run at once,
//!   and unless [`BatchParams::threads`] is set each item's pose model gets
//!   `max(1, cores / jobs)` ONNX Runtime threads. With one job items run in
//!   input order; with several, the longest videos start first (frames as
//!   the container states them), then the track files, so that the last
//!   item to finish is a short one.
//! * **Cancellation**: the [`CancelToken`] stops new items from starting
//!   and cancels the running ones ([`run`](crate::run) removes their staging folders);
//!   they get no manifest line and run again next time.
//!
//! The manifest describes the latest batch: at the start it is rewritten
//! with the lines of the items that are skipped, then each finished item
//! appends its line. With several jobs the order of the lines follows the
//! order in which items finish; [`BatchSummary::items`] is in input order.
//!
//! ```no_run
//! use mp_pipeline::batch::{batch, batch_items, BatchParams};
//! use mp_pipeline::{CancelToken, Silent};
//! let items = batch_items("videos/")?;
//! let params = BatchParams { jobs: 2, ..BatchParams::default() };
//! let summary = batch(&items, "out/".as_ref(), &params, &Silent, &CancelToken::new())?;
//! println!("{} ok, {} failed", summary.ok(), summary.failed());
//! # Ok::<(), mp_pipeline::batch::BatchError>(())
//! ```

use std::collections::{HashMap, HashSet};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use mp_geom::CancelToken;
use serde::{Deserialize, Serialize};

use crate::error::PipelineError;
use crate::input::{is_video, Input};
use crate::params::Params;
use crate::progress::{Observer, Silent, Stage, StageTime};

/// Extensions of the keypoint track files that [`batch_items`] lists from a
/// folder (besides the videos of [`crate::VIDEO_EXTENSIONS`]).
pub const TRACK_EXTENSIONS: [&str; 6] = ["npz", "json", "csv", "npy", "bvh", "mpt"];

/// File name of the manifest inside the output folder.
pub const MANIFEST: &str = "manifest.jsonl";

/// The file whose presence marks an item's output folder as complete
/// (together with an `ok` manifest line).
pub const RESULT_FILE: &str = "loops.json";

/// Most items at once.
pub const MAX_JOBS: usize = 1024;

/// Everything that stops a whole batch (an item's own failure does not: it
/// is recorded in its [`ItemReport`]).
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// A parameter is out of range.
    #[error("parameter `{name}`: {reason}")]
    Param {
        /// The parameter.
        name: &'static str,
        /// Why.
        reason: String,
    },
    /// The run parameters are invalid.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// A file or folder could not be read or written.
    #[error("cannot {action} {}", path.display())]
    Io {
        /// What was being done.
        action: &'static str,
        /// The file or folder.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A folder holds no videos or track files.
    #[error(
        "{} holds no videos ({}) or keypoint tracks ({}); hidden files and subfolders are not read",
        path.display(),
        crate::VIDEO_EXTENSIONS.join(", "),
        TRACK_EXTENSIONS.join(", ")
    )]
    NoItems {
        /// The folder.
        path: PathBuf,
    },
    /// A list of inputs names none.
    #[error("the list {} names no inputs (one path per line; `#` starts a comment line)", path.display())]
    EmptyList {
        /// The list file.
        path: PathBuf,
    },
    /// The batch input is neither a folder nor a file.
    #[error("{} does not exist (expected a folder of inputs or a text file listing them)", path.display())]
    Missing {
        /// The path given.
        path: PathBuf,
    },
}

impl BatchError {
    fn io(action: &'static str, path: &Path, source: std::io::Error) -> Self {
        BatchError::Io {
            action,
            path: path.to_path_buf(),
            source,
        }
    }

    fn param(name: &'static str, reason: impl Into<String>) -> Self {
        BatchError::Param {
            name,
            reason: reason.into(),
        }
    }
}

/// Result alias of [`batch()`] and [`batch_items`].
pub type Result<T> = std::result::Result<T, BatchError>;

/// The parameters of a batch.
#[derive(Debug, Clone, PartialEq)]
pub struct BatchParams {
    /// Items processed at once. Default 1.
    pub jobs: usize,
    /// ONNX Runtime threads of each item's pose model. Default `None`:
    /// `max(1, cores / jobs)` (cores from
    /// [`std::thread::available_parallelism`], jobs no more than the items
    /// to run), so that threads × jobs ≤ cores. Either way it replaces
    /// `params.pose.threads`.
    pub threads: Option<usize>,
    /// Largest side of the video frame in pixels for track inputs (the
    /// scale), as in [`Input::open`]. Default `None`: the motion's extent.
    pub frame_px: Option<f64>,
    /// The parameters of every item's [`run`](crate::run). Default [`Params::default()`].
    pub params: Params,
}

impl Default for BatchParams {
    fn default() -> Self {
        BatchParams {
            jobs: 1,
            threads: None,
            frame_px: None,
            params: Params::default(),
        }
    }
}

impl BatchParams {
    /// Checks every field (the run parameters included).
    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_JOBS).contains(&self.jobs) {
            return Err(BatchError::param(
                "jobs",
                format!("must be in 1..={MAX_JOBS}, got {}", self.jobs),
            ));
        }
        if self.threads == Some(0) {
            return Err(BatchError::param("threads", "must be at least 1"));
        }
        if let Some(px) = self.frame_px {
            if !(px.is_finite() && px > 0.0) {
                return Err(BatchError::param(
                    "frame_px",
                    format!("must be finite and > 0, got {px}"),
                ));
            }
        }
        self.params.validate()?;
        Ok(())
    }

    /// ONNX Runtime threads per item when `jobs` items run at once.
    pub fn threads_per_item(&self, jobs: usize) -> usize {
        self.threads.unwrap_or_else(|| {
            let cores = std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1);
            (cores / jobs.max(1)).max(1)
        })
    }
}

/// What became of an item.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ItemStatus {
    /// Run now, and complete.
    Ok,
    /// Failed; the report holds the message.
    Failed,
    /// Complete from an earlier batch, not run again.
    Skipped,
    /// Interrupted or not started because the batch was cancelled; never
    /// written to the manifest.
    Cancelled,
}

impl ItemStatus {
    /// Lower-case name, as in the manifest.
    pub fn as_str(self) -> &'static str {
        match self {
            ItemStatus::Ok => "ok",
            ItemStatus::Failed => "failed",
            ItemStatus::Skipped => "skipped",
            ItemStatus::Cancelled => "cancelled",
        }
    }
}

/// One item of a batch: a line of the manifest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ItemReport {
    /// The input file, as given.
    #[serde(serialize_with = "lossy_path")]
    pub input: PathBuf,
    /// Its output folder.
    #[serde(serialize_with = "lossy_path")]
    pub output: PathBuf,
    /// What became of it.
    pub status: ItemStatus,
    /// For a failed item, the error message followed by its causes.
    #[serde(default)]
    pub error: Option<String>,
    /// Frames of the motion.
    #[serde(default)]
    pub frames: Option<usize>,
    /// Frame rate of the motion.
    #[serde(default)]
    pub fps: Option<f64>,
    /// Wall time of the item in seconds (reading the input, the analysis and
    /// every output file); for a skipped item, that of the run it skips.
    #[serde(default)]
    pub seconds: Option<f64>,
    /// Repetitions counted in the whole motion.
    #[serde(default)]
    pub total_repetitions: Option<usize>,
    /// Repetitions per counted interval, in time order.
    #[serde(default)]
    pub counts: Vec<usize>,
    /// The signal that decided the count (`keypoints` or `frames`).
    #[serde(default)]
    pub signal: Option<String>,
    /// How the count was reached (`period`, `intervals` or `none`).
    #[serde(default)]
    pub method: Option<String>,
}

fn lossy_path<S: serde::Serializer>(p: &Path, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(&p.to_string_lossy())
}

impl ItemReport {
    fn empty(input: &Path, output: &Path, status: ItemStatus) -> Self {
        ItemReport {
            input: input.to_path_buf(),
            output: output.to_path_buf(),
            status,
            error: None,
            frames: None,
            fps: None,
            seconds: None,
            total_repetitions: None,
            counts: Vec::new(),
            signal: None,
            method: None,
        }
    }

    /// The report as one line of JSON (no newline).
    pub fn to_json_line(&self) -> String {
        // Serialising plain strings, numbers and enums cannot fail.
        serde_json::to_string(self).unwrap_or_else(|e| {
            serde_json::json!({ "input": self.input.to_string_lossy(), "error": e.to_string() })
                .to_string()
        })
    }
}

/// What a batch did.
#[derive(Debug, Clone)]
pub struct BatchSummary {
    /// Every item, in input order.
    pub items: Vec<ItemReport>,
    /// Wall time of the whole batch.
    pub wall: Duration,
    /// Items that ran at once.
    pub jobs: usize,
    /// ONNX Runtime threads of each item's pose model.
    pub threads_per_item: usize,
    /// Whether the batch was cancelled (some items then say `cancelled`).
    pub cancelled: bool,
    /// The manifest file.
    pub manifest: PathBuf,
}

impl BatchSummary {
    fn count(&self, status: ItemStatus) -> usize {
        self.items.iter().filter(|i| i.status == status).count()
    }

    /// Items run now and complete.
    pub fn ok(&self) -> usize {
        self.count(ItemStatus::Ok)
    }

    /// Items that failed.
    pub fn failed(&self) -> usize {
        self.count(ItemStatus::Failed)
    }

    /// Items complete from an earlier batch.
    pub fn skipped(&self) -> usize {
        self.count(ItemStatus::Skipped)
    }

    /// Items interrupted or not started.
    pub fn cancelled_items(&self) -> usize {
        self.count(ItemStatus::Cancelled)
    }

    /// Frames of the items run now (status `ok`).
    pub fn frames(&self) -> usize {
        self.items
            .iter()
            .filter(|i| i.status == ItemStatus::Ok)
            .filter_map(|i| i.frames)
            .sum()
    }

    /// Frames of the items run now per second of the batch's wall time.
    pub fn throughput(&self) -> f64 {
        self.frames() as f64 / self.wall.as_secs_f64().max(1e-9)
    }
}

/// Receives the progress of a batch. Every method has an empty default and
/// may be called from several threads at once; `index` is the item's
/// position in the input list.
pub trait BatchObserver: Sync {
    /// The batch starts: `items` in all, of which `to_run` will run (the
    /// others are skipped).
    fn batch_started(&self, _items: usize, _to_run: usize) {}
    /// An item starts.
    fn item_started(&self, _index: usize, _input: &Path) {}
    /// An item is finished (also called for skipped and cancelled items).
    fn item_finished(&self, _index: usize, _report: &ItemReport) {}
    /// A stage of an item's run starts; `total` is its number of steps when known.
    fn stage_started(&self, _index: usize, _stage: Stage, _total: Option<usize>) {}
    /// `done` steps of a stage of an item's run are finished.
    fn stage_progress(&self, _index: usize, _stage: Stage, _done: usize) {}
    /// A stage of an item's run is finished.
    fn stage_finished(&self, _index: usize, _time: &StageTime) {}
}

impl BatchObserver for Silent {}

/// Forwards one item's stage progress to the batch observer.
struct ItemObserver<'a> {
    index: usize,
    inner: &'a dyn BatchObserver,
}

impl Observer for ItemObserver<'_> {
    fn started(&self, stage: Stage, total: Option<usize>) {
        self.inner.stage_started(self.index, stage, total);
    }
    fn progress(&self, stage: Stage, done: usize) {
        self.inner.stage_progress(self.index, stage, done);
    }
    fn finished(&self, time: &StageTime) {
        self.inner.stage_finished(self.index, time);
    }
}

/// Whether [`batch_items`] lists a file of a folder: a video by its
/// extension ([`crate::VIDEO_EXTENSIONS`]) or a track file
/// ([`TRACK_EXTENSIONS`]), not hidden.
pub fn is_batch_input(path: &Path) -> bool {
    let hidden = path
        .file_name()
        .map(|n| n.to_string_lossy().starts_with('.'))
        .unwrap_or(true);
    !hidden && (is_video(path) || is_track_file(path))
}

fn is_track_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .is_some_and(|e| TRACK_EXTENSIONS.contains(&e.as_str()))
}

/// The inputs of a batch:
///
/// * a folder: its videos and track files ([`is_batch_input`]), sorted by
///   path; hidden files and subfolders (the output folder among them) are
///   not read;
/// * a video or track file: that one input;
/// * any other file: a text list of inputs, one path per line; blank lines
///   and lines starting with `#` are ignored, relative paths are relative to
///   the list's folder. Whether the listed files exist is checked per item
///   (a missing one fails alone).
pub fn batch_items(path: impl AsRef<Path>) -> Result<Vec<PathBuf>> {
    let path = path.as_ref();
    if path.is_dir() {
        let rd = std::fs::read_dir(path).map_err(|e| BatchError::io("read the folder", path, e))?;
        let mut items = Vec::new();
        for entry in rd {
            let entry = entry.map_err(|e| BatchError::io("read the folder", path, e))?;
            let p = entry.path();
            // Follows links: a linked file counts as a file.
            if p.is_file() && is_batch_input(&p) {
                items.push(p);
            }
        }
        items.sort();
        if items.is_empty() {
            return Err(BatchError::NoItems {
                path: path.to_path_buf(),
            });
        }
        return Ok(items);
    }
    if !path.is_file() {
        return Err(BatchError::Missing {
            path: path.to_path_buf(),
        });
    }
    if is_video(path) || is_track_file(path) {
        return Ok(vec![path.to_path_buf()]);
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| BatchError::io("read the list of inputs", path, e))?;
    let base = path.parent().unwrap_or(Path::new(""));
    let items: Vec<PathBuf> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| {
            let p = Path::new(l);
            if p.is_absolute() {
                p.to_path_buf()
            } else {
                base.join(p)
            }
        })
        .collect();
    if items.is_empty() {
        return Err(BatchError::EmptyList {
            path: path.to_path_buf(),
        });
    }
    Ok(items)
}

/// The output folder names of `items`, in order: the file stem, or
/// `<stem>-<extension>` where stems are equal (compared without case), then
/// a numeric suffix `-2`, `-3`, … where names are still equal. Depends only
/// on the list, so a batch run again maps every input to the same folder.
pub fn output_names(items: &[PathBuf]) -> Vec<String> {
    let stem = |p: &PathBuf| -> String {
        let s = p
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if s.is_empty() || s == "." || s == ".." {
            "item".to_string()
        } else {
            s
        }
    };
    let stems: Vec<String> = items.iter().map(stem).collect();
    let mut seen: HashMap<String, usize> = HashMap::new();
    for s in &stems {
        *seen.entry(s.to_lowercase()).or_default() += 1;
    }
    let mut used: HashSet<String> = HashSet::new();
    used.insert(MANIFEST.to_lowercase());
    let mut names = Vec::with_capacity(items.len());
    for (p, s) in items.iter().zip(&stems) {
        let mut name = s.clone();
        if seen[&s.to_lowercase()] > 1 {
            if let Some(ext) = p.extension() {
                name = format!("{s}-{}", ext.to_string_lossy());
            }
        }
        let mut candidate = name.clone();
        let mut k = 2;
        while used.contains(&candidate.to_lowercase()) {
            candidate = format!("{name}-{k}");
            k += 1;
        }
        used.insert(candidate.to_lowercase());
        names.push(candidate);
    }
    names
}

/// The error message followed by its causes (each once).
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut source = e.source();
    while let Some(c) = source {
        let m = c.to_string();
        if !s.contains(&m) {
            s.push_str(": ");
            s.push_str(&m);
        }
        source = c.source();
    }
    s
}

/// Reads a manifest; lines that do not parse (a line cut short by a crash)
/// are ignored. A missing manifest is empty.
pub fn read_manifest(path: &Path) -> Result<Vec<ItemReport>> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(BatchError::io("read the manifest", path, e)),
    };
    Ok(bytes
        .split(|&b| b == b'\n')
        .filter_map(|line| serde_json::from_slice::<ItemReport>(line).ok())
        .collect())
}

/// Same file when both can be resolved, else the same path.
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// The manifest, appended line by line, each on disk before the next.
struct Manifest {
    file: File,
    path: PathBuf,
}

impl Manifest {
    /// Replaces the manifest with `lines` (through a temporary file renamed
    /// into place) and opens it for appending.
    fn start(path: &Path, lines: &[ItemReport]) -> Result<Self> {
        let tmp = path.with_extension("jsonl.tmp");
        {
            let mut f = File::create(&tmp).map_err(|e| BatchError::io("write", &tmp, e))?;
            for l in lines {
                writeln!(f, "{}", l.to_json_line())
                    .map_err(|e| BatchError::io("write", &tmp, e))?;
            }
            f.sync_all().map_err(|e| BatchError::io("write", &tmp, e))?;
        }
        std::fs::rename(&tmp, path).map_err(|e| BatchError::io("write the manifest", path, e))?;
        if let Some(dir) = path.parent() {
            // Makes the rename durable where folders can be synced.
            if let Ok(d) = File::open(dir) {
                let _ = d.sync_all();
            }
        }
        let file = OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(|e| BatchError::io("open the manifest", path, e))?;
        Ok(Manifest {
            file,
            path: path.to_path_buf(),
        })
    }

    fn append(&mut self, report: &ItemReport) -> Result<()> {
        let mut line = report.to_json_line();
        line.push('\n');
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .and_then(|()| self.file.sync_data())
            .map_err(|e| BatchError::io("append to the manifest", &self.path, e))
    }
}

/// How long an item will take, for ordering: videos (frames, from the
/// container) before track files (bytes), which need no pose model.
fn work_estimate(path: &Path, max_frames: Option<usize>) -> (bool, u64) {
    if is_video(path) {
        let frames = mp_pose::video::probe(path)
            .ok()
            .and_then(|info| {
                info.frame_count
                    .or_else(|| info.duration_s.map(|d| (d * info.fps).round() as usize))
            })
            .unwrap_or(0);
        let frames = max_frames.map_or(frames, |m| frames.min(m));
        (true, frames as u64)
    } else {
        (false, std::fs::metadata(path).map(|m| m.len()).unwrap_or(0))
    }
}

/// Runs one item: [`Input::open`], then [`run`](crate::run) into `output`, with the
/// worker's pose model (`slot`, kept loaded between its items).
#[allow(clippy::too_many_arguments)]
fn run_item(
    index: usize,
    input: &Path,
    output: &Path,
    params: &Params,
    frame_px: Option<f64>,
    observer: &dyn BatchObserver,
    cancel: &CancelToken,
    slot: &mut crate::ModelSlot,
) -> ItemReport {
    let start = Instant::now();
    let item_observer = ItemObserver {
        index,
        inner: observer,
    };
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let opened = Input::open(input, frame_px)?;
        crate::run_with(opened, output, params, &item_observer, cancel, slot)
    }));
    if result.is_err() {
        // A model that panicked mid-video is not reused.
        *slot = crate::ModelSlot::default();
    }
    let seconds = start.elapsed().as_secs_f64();
    match result {
        Ok(Ok(summary)) => {
            let o = &summary.outcome;
            let c = &o.counts;
            ItemReport {
                error: None,
                frames: Some(o.keypoints.track.n_frames()),
                fps: Some(o.keypoints.track.fps()),
                seconds: Some(seconds),
                total_repetitions: Some(c.total),
                counts: c.intervals.iter().map(|i| i.count).collect(),
                signal: Some(c.signal.as_str().to_string()),
                method: Some(c.method.as_str().to_string()),
                ..ItemReport::empty(input, output, ItemStatus::Ok)
            }
        }
        Ok(Err(PipelineError::Cancelled)) => {
            ItemReport::empty(input, output, ItemStatus::Cancelled)
        }
        Ok(Err(e)) => ItemReport {
            error: Some(error_chain(&e)),
            seconds: Some(seconds),
            ..ItemReport::empty(input, output, ItemStatus::Failed)
        },
        Err(panic) => {
            let msg = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            ItemReport {
                error: Some(format!("internal error (panic): {msg}")),
                seconds: Some(seconds),
                ..ItemReport::empty(input, output, ItemStatus::Failed)
            }
        }
    }
}

/// Runs every item of `items` into its own folder under `out_dir` (see the
/// module docs): [`run`](crate::run) with `params.params`, `params.jobs` items at once,
/// one manifest line per finished item, items complete from an earlier
/// batch skipped.
///
/// Errors only when the batch as a whole cannot go on: invalid parameters,
/// an output folder or manifest that cannot be written. A cancelled batch
/// returns its summary with [`BatchSummary::cancelled`] set.
pub fn batch(
    items: &[PathBuf],
    out_dir: &Path,
    params: &BatchParams,
    observer: &dyn BatchObserver,
    cancel: &CancelToken,
) -> Result<BatchSummary> {
    params.validate()?;
    let start = Instant::now();
    std::fs::create_dir_all(out_dir)
        .map_err(|e| BatchError::io("create the output folder", out_dir, e))?;
    let manifest_path = out_dir.join(MANIFEST);
    let earlier = read_manifest(&manifest_path)?;
    let outputs: Vec<PathBuf> = output_names(items)
        .into_iter()
        .map(|n| out_dir.join(n))
        .collect();

    // Skipped items: complete folder and an ok line for the same input.
    let mut reports: Vec<Option<ItemReport>> = vec![None; items.len()];
    let mut pending = Vec::new();
    for (i, (input, output)) in items.iter().zip(&outputs).enumerate() {
        let name = output.file_name();
        let last = earlier
            .iter()
            .rev()
            .find(|l| l.output.file_name() == name && same_file(&l.input, input));
        let done = last.is_some_and(|l| {
            matches!(l.status, ItemStatus::Ok | ItemStatus::Skipped)
                && output.join(RESULT_FILE).is_file()
        });
        match (done, last) {
            (true, Some(l)) => {
                reports[i] = Some(ItemReport {
                    input: input.clone(),
                    output: output.clone(),
                    status: ItemStatus::Skipped,
                    error: None,
                    ..l.clone()
                })
            }
            _ => pending.push(i),
        }
    }
    let skipped: Vec<ItemReport> = reports.iter().flatten().cloned().collect();
    let manifest = Mutex::new(Manifest::start(&manifest_path, &skipped)?);

    let jobs = params.jobs.min(pending.len()).max(1);
    if jobs > 1 {
        // Longest items first, so that no job is left with a long item at
        // the end while the others idle (equal ones keep the input order).
        let max_frames = params.params.pose.max_frames;
        pending.sort_by_cached_key(|&i| std::cmp::Reverse(work_estimate(&items[i], max_frames)));
    }
    let threads = params.threads_per_item(jobs);
    let mut run_params = params.params.clone();
    run_params.pose.threads = threads;

    observer.batch_started(items.len(), pending.len());
    for (i, r) in reports.iter().enumerate() {
        if let Some(r) = r {
            observer.item_finished(i, r);
        }
    }

    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<ItemReport>>> = Mutex::new(reports);
    let fatal: Mutex<Option<BatchError>> = Mutex::new(None);
    let stopped = || cancel.is_cancelled() || fatal.lock().map(|f| f.is_some()).unwrap_or(true);
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                let mut slot = crate::ModelSlot::default();
                loop {
                    if stopped() {
                        break;
                    }
                    let k = next.fetch_add(1, Ordering::SeqCst);
                    let Some(&i) = pending.get(k) else {
                        break;
                    };
                    observer.item_started(i, &items[i]);
                    let report = run_item(
                        i,
                        &items[i],
                        &outputs[i],
                        &run_params,
                        params.frame_px,
                        observer,
                        cancel,
                        &mut slot,
                    );
                    if report.status != ItemStatus::Cancelled {
                        let written = match manifest.lock() {
                            Ok(mut m) => m.append(&report),
                            Err(_) => Err(BatchError::io(
                                "append to the manifest",
                                &manifest_path,
                                std::io::Error::other("a writer panicked"),
                            )),
                        };
                        if let Err(e) = written {
                            if let Ok(mut f) = fatal.lock() {
                                f.get_or_insert(e);
                            }
                        }
                    }
                    observer.item_finished(i, &report);
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(report);
                    }
                }
            });
        }
    });
    if let Some(e) = fatal.into_inner().unwrap_or_else(|e| e.into_inner()) {
        return Err(e);
    }
    let reports = results.into_inner().unwrap_or_else(|e| e.into_inner());
    let items: Vec<ItemReport> = reports
        .into_iter()
        .enumerate()
        .map(|(i, r)| {
            r.unwrap_or_else(|| {
                let r = ItemReport::empty(&items[i], &outputs[i], ItemStatus::Cancelled);
                observer.item_finished(i, &r);
                r
            })
        })
        .collect();
    Ok(BatchSummary {
        items,
        wall: start.elapsed(),
        jobs,
        threads_per_item: threads,
        cancelled: cancel.is_cancelled(),
        manifest: manifest_path,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_names_are_unique_and_deterministic() {
        let items: Vec<PathBuf> = ["a/x.npz", "b/x.json", "c/y.mp4", "d/x.npz", "e/x-npz.csv"]
            .iter()
            .map(PathBuf::from)
            .collect();
        let names = output_names(&items);
        assert_eq!(names, vec!["x-npz", "x-json", "y", "x-npz-2", "x-npz-3"]);
        assert_eq!(output_names(&items), names);
        let m = output_names(&[PathBuf::from("manifest.jsonl.csv")]);
        assert_eq!(m, vec!["manifest.jsonl-2"]);
    }

    #[test]
    fn params_are_validated() {
        let bad = BatchParams {
            jobs: 0,
            ..BatchParams::default()
        };
        assert!(matches!(
            bad.validate(),
            Err(BatchError::Param { name: "jobs", .. })
        ));
        let bad = BatchParams {
            threads: Some(0),
            ..BatchParams::default()
        };
        assert!(bad.validate().is_err());
        assert!(BatchParams::default().validate().is_ok());
        let p = BatchParams {
            threads: Some(3),
            ..BatchParams::default()
        };
        assert_eq!(p.threads_per_item(8), 3);
        assert!(BatchParams::default().threads_per_item(1_000_000) >= 1);
    }

    #[test]
    fn a_cut_line_in_the_manifest_is_ignored() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join(MANIFEST);
        let ok = ItemReport {
            frames: Some(10),
            total_repetitions: Some(3),
            counts: vec![3],
            ..ItemReport::empty(Path::new("in/a.npz"), Path::new("out/a"), ItemStatus::Ok)
        };
        let line = ok.to_json_line();
        std::fs::write(&path, format!("{line}\n{}", &line[..line.len() / 2])).unwrap();
        let read = read_manifest(&path).unwrap();
        assert_eq!(read, vec![ok]);
    }
}
