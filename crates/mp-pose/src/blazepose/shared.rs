//! One landmark model shared by the estimators of several threads
//! ([`SharedLandmarks`]): each estimator crops its own frames and sends the
//! crops; a thread of its own runs the model on the crops that arrived
//! together, in one run where the model's batch is open, and sends each
//! estimator its results. What a GPU needs to be kept busy by several
//! videos at once: one session, large batches.

use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::thread;
use std::time::{Duration, Instant};

use super::landmarks::{LandmarkModel, LandmarkModelKind, LandmarkOutput, LANDMARK_INPUT};
use super::BlazePoseParams;
use crate::error::{PoseError, Result};

/// Values of one crop in a run's input (`256 × 256 × 3`).
const CROP_VALUES: usize = LANDMARK_INPUT * LANDMARK_INPUT * 3;

/// Crops sent by one estimator and where their results go.
struct Request {
    input: Vec<f32>,
    count: usize,
    reply: Sender<Result<Vec<LandmarkOutput>>>,
}

/// Counters of a shared model.
#[derive(Debug, Default)]
struct Counters {
    requests: AtomicU64,
    crops: AtomicU64,
    runs: AtomicU64,
}

/// What a shared model has done so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SharedStats {
    /// Requests received (one per estimator call).
    pub requests: u64,
    /// Crops run.
    pub crops: u64,
    /// Runs of the model (one per batch where the batch is open).
    pub runs: u64,
}

/// The thread that runs the model, as the estimators see it.
struct Shared {
    name: String,
    kind: LandmarkModelKind,
    refine: super::RefineParams,
    batch_open: bool,
    counters: Counters,
}

/// A landmark model on a thread of its own, which the estimators of other
/// threads use instead of opening one each ([`BlazePoseParams::shared`]):
/// the crops that arrive within [`SharedLandmarks::start`]'s `wait` of
/// each other (up to `max_crops`) go through the model in one run. The
/// thread ends when the last handle and the last estimator using it are
/// dropped.
#[derive(Clone)]
pub struct SharedLandmarks {
    tx: Sender<Request>,
    shared: Arc<Shared>,
}

impl SharedLandmarks {
    /// Largest batch by default: 32 crops.
    pub const DEFAULT_MAX_CROPS: usize = 32;
    /// Wait for more crops by default: 2 ms.
    pub const DEFAULT_WAIT: Duration = Duration::from_millis(2);

    /// Opens the landmark model of `params` (its model, refinement and
    /// session: the device and threads of the shared run) and starts its thread.
    pub fn open(params: &BlazePoseParams) -> Result<Self> {
        params.validate()?;
        let model = params.own_landmark_model()?;
        Self::start(model, Self::DEFAULT_MAX_CROPS, Self::DEFAULT_WAIT)
    }

    /// Starts the thread that runs `model`: after a request arrives it waits
    /// up to `wait` for more, until `max_crops` crops are waiting, and runs
    /// them together (one run each where the model's batch is closed).
    pub fn start(model: LandmarkModel, max_crops: usize, wait: Duration) -> Result<Self> {
        if max_crops == 0 {
            return Err(PoseError::param("max_crops", "must be at least 1"));
        }
        let shared = Arc::new(Shared {
            name: model.name().to_string(),
            kind: model.kind(),
            refine: model.refine_params(),
            batch_open: model.batch_open(),
            counters: Counters::default(),
        });
        let (tx, rx) = mpsc::channel();
        let worker = Arc::clone(&shared);
        thread::Builder::new()
            .name("mp-landmarks".into())
            .spawn(move || serve(model, rx, &worker, max_crops, wait))
            .map_err(|e| PoseError::model(&shared.name, format!("starting its thread: {e}")))?;
        Ok(SharedLandmarks { tx, shared })
    }

    /// Which landmark model runs.
    pub fn kind(&self) -> LandmarkModelKind {
        self.shared.kind
    }

    /// What the model has done so far.
    pub fn stats(&self) -> SharedStats {
        let c = &self.shared.counters;
        SharedStats {
            requests: c.requests.load(Ordering::Relaxed),
            crops: c.crops.load(Ordering::Relaxed),
            runs: c.runs.load(Ordering::Relaxed),
        }
    }

    /// A landmark model whose runs go to this one (for a thread of its own:
    /// its `run` and `run_many` wait for the shared run their crops join).
    pub fn model(&self) -> LandmarkModel {
        LandmarkModel::client(
            self.clone(),
            self.shared.name.clone(),
            self.shared.kind,
            self.shared.refine,
            // The estimator sends every crop of a frame at once.
            true,
        )
    }

    /// [`SharedLandmarks::model`] for an estimator that asks for `kind` (an
    /// error names both when they differ).
    pub(crate) fn model_for(&self, kind: LandmarkModelKind) -> Result<LandmarkModel> {
        if kind != self.shared.kind {
            return Err(PoseError::param(
                "shared",
                format!(
                    "the shared landmark model is {}, the estimator asks for {}",
                    self.shared.kind.as_str(),
                    kind.as_str()
                ),
            ));
        }
        Ok(self.model())
    }
}

impl fmt::Debug for SharedLandmarks {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SharedLandmarks")
            .field("model", &self.shared.name)
            .field("stats", &self.stats())
            .finish()
    }
}

/// Two handles are equal when they share one model.
impl PartialEq for SharedLandmarks {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.shared, &other.shared)
    }
}

impl SharedLandmarks {
    /// Sends `count` crops laid end to end and waits for their results.
    pub(crate) fn run(&self, input: &[f32], count: usize) -> Result<Vec<LandmarkOutput>> {
        if input.len() != count * CROP_VALUES {
            return Err(PoseError::Contract {
                model: self.shared.name.clone(),
                reason: format!(
                    "{} input values for {count} crops of {CROP_VALUES}",
                    input.len()
                ),
            });
        }
        let stopped = || PoseError::model(&self.shared.name, "the shared model's thread stopped");
        let (reply, answer) = mpsc::channel();
        self.tx
            .send(Request {
                input: input.to_vec(),
                count,
                reply,
            })
            .map_err(|_| stopped())?;
        answer.recv().map_err(|_| stopped())?
    }
}

/// The model's thread: batches of requests until every sender is gone.
fn serve(
    mut model: LandmarkModel,
    rx: Receiver<Request>,
    shared: &Shared,
    max_crops: usize,
    wait: Duration,
) {
    let mut input = Vec::new();
    while let Ok(first) = rx.recv() {
        let mut crops = first.count;
        let mut batch = vec![first];
        let deadline = Instant::now() + wait;
        while crops < max_crops {
            match rx.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
                Ok(r) => {
                    crops += r.count;
                    batch.push(r);
                }
                Err(RecvTimeoutError::Timeout | RecvTimeoutError::Disconnected) => break,
            }
        }
        let c = &shared.counters;
        c.requests.fetch_add(batch.len() as u64, Ordering::Relaxed);
        c.crops.fetch_add(crops as u64, Ordering::Relaxed);
        if shared.batch_open {
            input.clear();
            for r in &batch {
                input.extend_from_slice(&r.input);
            }
            c.runs.fetch_add(1, Ordering::Relaxed);
            match model.run_batch(&input, crops) {
                Ok(mut outs) => {
                    for r in batch {
                        let rest = outs.split_off(r.count.min(outs.len()));
                        // A client that stopped waiting is no concern of the others.
                        let _ = r.reply.send(Ok(std::mem::replace(&mut outs, rest)));
                    }
                }
                Err(e) => {
                    let reason = e.to_string();
                    for r in batch {
                        let _ = r.reply.send(Err(PoseError::model(&shared.name, &reason)));
                    }
                }
            }
        } else {
            for r in batch {
                let mut outs = Vec::with_capacity(r.count);
                let mut result = Ok(());
                for crop in r.input.chunks_exact(CROP_VALUES) {
                    c.runs.fetch_add(1, Ordering::Relaxed);
                    match model.run_batch(crop, 1) {
                        Ok(o) => outs.extend(o),
                        Err(e) => {
                            result = Err(e);
                            break;
                        }
                    }
                }
                let _ = r.reply.send(result.map(|()| outs));
            }
        }
    }
}
