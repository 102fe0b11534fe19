//! `live()`: the live analysis of `mp live` as a Python iterator of events.
//!
//! The run (`mp_live::watch`) goes on a thread of its own and sends each event,
//! as JSON (the lines of `mp live --json`), over a bounded channel; the
//! iterator waits for the next one with the GIL released and turns it into a
//! dict. Closing the iterator (or dropping it) cancels the run and joins its
//! thread, which ends the FFmpeg decoder.

use std::path::PathBuf;
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError};
use std::sync::Mutex;
use std::thread::JoinHandle;
use std::time::Duration;

use mp_geom::CancelToken;
use mp_live::{Event, LiveError, LiveParams, LiveSource, Summary};
use pyo3::prelude::*;

use crate::errors;

/// Events waiting for the Python side at most (the run waits beyond).
const QUEUE: usize = 256;
/// How often a wait for the next event looks for Ctrl-C.
const POLL: Duration = Duration::from_millis(100);

type Outcome = std::result::Result<Summary, LiveError>;

/// The channel and the thread of a run.
struct Running {
    rx: Option<Receiver<String>>,
    thread: Option<JoinHandle<Outcome>>,
    /// The summary came: the next call ends the iteration.
    finished: bool,
}

/// A live run's events, as dicts: `for event in motion_programs.live(...)`.
#[pyclass(name = "Live", module = "motion_programs", frozen)]
pub struct PyLive {
    name: String,
    cancel: CancelToken,
    state: Mutex<Running>,
}

/// What one wait for the next event gives.
enum Next {
    Line(String),
    Waiting,
    Over,
}

impl PyLive {
    fn lock(&self) -> std::sync::MutexGuard<'_, Running> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Cancels the run, stops listening and joins its thread (call without
    /// the GIL); returns how the run ended, when that was not taken yet.
    fn stop(&self) -> Option<Outcome> {
        self.cancel.cancel();
        let h = {
            let mut st = self.lock();
            st.rx = None;
            st.finished = true;
            st.thread.take()
        }?;
        Some(h.join().unwrap_or_else(|_| {
            Err(LiveError::Source(
                "the live analysis thread panicked".into(),
            ))
        }))
    }

    /// Waits at most [`POLL`] for the next event (call without the GIL).
    fn wait(&self) -> Next {
        let st = self.lock();
        if st.finished {
            return Next::Over;
        }
        let Some(rx) = st.rx.as_ref() else {
            return Next::Over;
        };
        match rx.recv_timeout(POLL) {
            Ok(line) => Next::Line(line),
            Err(RecvTimeoutError::Timeout) => Next::Waiting,
            // The thread ended without a summary: only a panic does that.
            Err(RecvTimeoutError::Disconnected) => Next::Over,
        }
    }

    /// Ends the iteration: `None`, or the run's error.
    fn end(&self, py: Python<'_>) -> PyResult<Option<Py<PyAny>>> {
        match py.detach(|| self.stop()) {
            Some(Err(e)) => Err(to_py(py, &self.name, e)),
            _ => Ok(None),
        }
    }
}

/// The exception of a run's error, with the source's name.
fn to_py(py: Python<'_>, name: &str, e: LiveError) -> PyErr {
    let msg = format!("live analysis of {name}: {e}");
    match e {
        LiveError::Param { .. } => errors::ParamError::new_err(msg),
        LiveError::Geom(_) => errors::TrackError::new_err(msg),
        // The family of the pipeline's error, with this message.
        LiveError::Pipeline(p) => PyErr::from_type(errors::pipeline(p).get_type(py), msg),
        LiveError::Source(_) | LiveError::Stalled(_) | LiveError::Pose(_) => {
            errors::PoseError::new_err(msg)
        }
        // An error kind added later: the base class.
        _ => errors::MpError::new_err(msg),
    }
}

#[pymethods]
impl PyLive {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    /// The next event as a dict; after the summary, the run's error (when it
    /// stopped on one) is raised, else the iteration ends.
    fn __next__(&self, py: Python<'_>) -> PyResult<Option<Py<PyAny>>> {
        let line = loop {
            match py.detach(|| self.wait()) {
                Next::Line(l) => break l,
                Next::Over => return self.end(py),
                Next::Waiting => {
                    if let Err(e) = py.check_signals() {
                        py.detach(|| self.stop());
                        return Err(e);
                    }
                }
            }
        };
        if line.starts_with("{\"type\":\"summary\"") {
            self.lock().finished = true;
        }
        let json = py.import("json")?;
        Ok(Some(json.call_method1("loads", (line,))?.unbind()))
    }

    /// Stops the run (if still going) and waits for its thread and decoder
    /// to end; the iteration ends. Also done when the iterator is dropped.
    fn close(&self, py: Python<'_>) {
        py.detach(|| self.stop());
    }

    fn __enter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, pyo3::types::PyTuple>) {
        self.close(py);
    }

    fn __repr__(&self) -> String {
        format!("Live({})", self.name)
    }
}

impl Drop for PyLive {
    fn drop(&mut self) {
        // Without the GIL's release: dropping runs where Python holds it, and
        // the run's thread never needs it.
        self.stop();
    }
}

/// Live analysis of a video file, or of a stream on standard input (`"-"`),
/// as `mp live SOURCE --json`: an iterator of its events as dicts, the same
/// keys and values as the lines `mp live --json` prints. Options (defaults
/// of `mp live`): `realtime` reads a file at its own speed, `duration` stops
/// after that many seconds of stream time, `window` is the seconds of each
/// person's recent motion counted, `stall_timeout` how long the stream may
/// go without a frame, `out` a folder into which the files `mp run` writes
/// are written when the stream ends (as `mp live --out`; the summary's
/// `out` then names it), `pose_fps` how often the pose model runs (as
/// `extract`'s; the summary's `posed` counts its frames). When the run stops on an error, the `error` and
/// `summary` events come, then the error is raised (`PoseError` for the
/// source, decoding or the pose model; `ParamError` for an option).
#[pyfunction]
#[pyo3(signature = (source, realtime=false, duration=None, window=None, stall_timeout=None, out=None, pose_fps=None))]
#[allow(clippy::too_many_arguments)]
pub fn live(
    py: Python<'_>,
    source: PathBuf,
    realtime: bool,
    duration: Option<f64>,
    window: Option<f64>,
    stall_timeout: Option<f64>,
    out: Option<PathBuf>,
    pose_fps: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyLive> {
    let d = LiveParams::default();
    let mut params = LiveParams {
        realtime,
        duration_s: duration,
        window_s: window.unwrap_or(d.window_s),
        stall_timeout_s: stall_timeout.unwrap_or(d.stall_timeout_s),
        out,
        ..d
    };
    crate::pose_rate_arg(&mut params.analysis, pose_fps)?;
    let source = match source.to_str() {
        Some("-") => LiveSource::Stdin,
        _ => LiveSource::File(source),
    };
    let name = source.name();
    params.validate().map_err(|e| to_py(py, &name, e))?;
    let cancel = CancelToken::new();
    let (tx, rx) = sync_channel::<String>(QUEUE);
    let token = cancel.clone();
    let thread = std::thread::Builder::new()
        .name("live".into())
        .spawn(move || {
            let mut send = |e: &Event| {
                if let Ok(line) = serde_json::to_string(e) {
                    // A closed channel: the iterator is gone and the run is
                    // being cancelled.
                    let _ = tx.send(line);
                }
            };
            mp_live::watch(&source, &params, &token, &mut send)
        })
        .map_err(|e| errors::MpError::new_err(format!("cannot start the live analysis: {e}")))?;
    Ok(PyLive {
        name,
        cancel,
        state: Mutex::new(Running {
            rx: Some(rx),
            thread: Some(thread),
            finished: false,
        }),
    })
}
