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
//! use mp_geom::CancelToken;
//! use mp_pipeline::{batch, batch_items, BatchParams, Silent};
//! let items = batch_items("videos/")?;
//! let params = BatchParams { jobs: 2, ..BatchParams::default() };
//! let summary = batch(&items, "out/".as_ref(), &params, &Silent, &CancelToken::new())?;
//! println!("{} ok, {} failed", summary.ok(), summary.failed());
//! # Ok::<(), mp_pipeline::BatchError>(())
//! ```

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use mp_geom::CancelToken;
use mp_pose::{BlazePoseParams, Device, SharedLandmarks, SharedStats};
use serde::{Deserialize, Serialize};

use crate::error::PipelineError;
use crate::input::Input;
use crate::params::Params;
use crate::progress::{Observer, Silent, Stage, StageTime};

mod items;
mod manifest;

pub use items::{batch_items, output_names};
pub use manifest::{ItemReport, ItemStatus};

use items::work_estimate;
use manifest::Manifest;

/// Extensions of the keypoint track files that [`batch_items`] lists from a
/// folder (besides the videos of [`crate::Input::VIDEO_EXTENSIONS`]).
pub const TRACK_EXTENSIONS: [&str; 9] = mp_geom::TRACK_EXTENSIONS;

/// The file whose presence marks an item's output folder as complete
/// (together with an `ok` manifest line).
pub const RESULT_FILE: &str = "loops.json";

/// Most items at once.
pub(crate) const MAX_JOBS: usize = 1024;

/// Everything that stops a whole batch (an item's own failure does not: it
/// is recorded in its [`ItemReport`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
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
        crate::Input::VIDEO_EXTENSIONS.join(", "),
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
    /// Frame rate of track inputs, over what a file states, as in
    /// [`Input::open_with`]. Default `None`: each file's own (30 fps where
    /// it states none).
    pub fps: Option<f64>,
    /// The parameters of every item's [`run`](crate::run). Default [`Params::default()`].
    pub params: Params,
    /// Whether the jobs share one landmark model, whose runs take the crops
    /// of every job's current frame together. Default [`SharedModel::Auto`].
    pub shared_model: SharedModel,
}

/// Whether a batch's jobs share one landmark model
/// ([`BatchParams::shared_model`]; `mp batch --shared-model`).
///
/// One model run on the crops of several videos keeps a GPU busy where one
/// run per crop and job would not; on a CPU the model's arithmetic, not the
/// number of runs, is the cost, and the jobs' own models run side by side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum SharedModel {
    /// Shared when several jobs run the several-people pipeline on a GPU
    /// (`--device cuda`, or `auto` where a GPU takes the model). Default.
    #[default]
    Auto,
    /// Shared whenever several jobs run the several-people pipeline.
    Always,
    /// Each job opens its own.
    Never,
}

impl SharedModel {
    /// Parses `auto`, `always` or `never`.
    pub fn parse(text: &str) -> Result<Self> {
        match text.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(SharedModel::Auto),
            "always" => Ok(SharedModel::Always),
            "never" => Ok(SharedModel::Never),
            other => Err(BatchError::param(
                "shared_model",
                format!("must be auto, always or never, got {other:?}"),
            )),
        }
    }
}

impl Default for BatchParams {
    fn default() -> Self {
        BatchParams {
            jobs: 1,
            threads: None,
            frame_px: None,
            fps: None,
            params: Params::default(),
            shared_model: SharedModel::Auto,
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
        for (name, v) in [("frame_px", self.frame_px), ("fps", self.fps)] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return Err(BatchError::param(
                        name,
                        format!("must be finite and > 0, got {v}"),
                    ));
                }
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
    /// What the landmark model the jobs shared did, when they shared one
    /// ([`BatchParams::shared_model`]).
    pub shared_model: Option<SharedStats>,
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

/// The error message followed by its causes (each once).
pub(crate) fn error_chain(e: &dyn std::error::Error) -> String {
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

/// Runs one item: [`Input::open`], then [`run`](crate::run) into `output`, with the
/// worker's pose model (`slot`, kept loaded between its items).
#[allow(clippy::too_many_arguments)]
fn run_item(
    index: usize,
    input: &Path,
    output: &Path,
    params: &Params,
    (frame_px, fps): (Option<f64>, Option<f64>),
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
        let opened = Input::open_with(input, frame_px, fps)?;
        crate::run_with(opened, output, params, &item_observer, cancel, slot)
    }));
    if result.is_err() {
        // A model that panicked mid-video is not reused.
        slot.reset();
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

/// The landmark model the jobs share ([`BatchParams::shared_model`]), with
/// the pose settings of `run_params` and the threads of every job.
fn open_shared(
    params: &BatchParams,
    run_params: &Params,
    jobs: usize,
) -> Result<Option<SharedLandmarks>> {
    let pose = &run_params.pose;
    let Some(model) = pose.model.landmark_model() else {
        return Ok(None);
    };
    if !pose.people || jobs < 2 {
        return Ok(None);
    }
    let mut session = pose.session();
    session.intra_threads = pose.threads * jobs;
    let open = |session| {
        SharedLandmarks::open(&BlazePoseParams {
            model,
            session,
            ..Default::default()
        })
    };
    let err = |e| BatchError::from(PipelineError::from(e));
    match (params.shared_model, session.device) {
        (SharedModel::Never, _) => Ok(None),
        (SharedModel::Always, _) | (SharedModel::Auto, Device::Cuda(_)) => {
            Ok(Some(open(session).map_err(err)?))
        }
        // On the GPU where one takes the model; else a model per job.
        (SharedModel::Auto, Device::Auto) => {
            session.device = Device::Cuda(0);
            Ok(open(session).ok())
        }
        (SharedModel::Auto, _) => Ok(None),
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
    let manifest_path = out_dir.join(ItemReport::MANIFEST);
    let earlier = ItemReport::read_manifest(&manifest_path)?;
    let outputs: Vec<PathBuf> = output_names(items)
        .into_iter()
        .map(|n| out_dir.join(n))
        .collect();

    let (reports, mut pending) = manifest::resume(items, &outputs, &earlier);
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
    if jobs > 1 && run_params.pose.pieces == 0 {
        // The jobs already share the cores out: each video in one piece.
        run_params.pose.pieces = 1;
    }
    let shared = open_shared(params, &run_params, jobs)?;

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
                let mut slot = crate::ModelSlot::with_shared(shared.clone());
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
                        (params.frame_px, params.fps),
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
        shared_model: shared.as_ref().map(SharedLandmarks::stats),
        cancelled: cancel.is_cancelled(),
        manifest: manifest_path,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
