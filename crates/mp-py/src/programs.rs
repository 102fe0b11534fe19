//! Programs and counts: `Program` (concrete), `AbstractProgram`, `Counts`,
//! `Summary` of a run.

use mp_abstract::{Analysis, Counts, ProgramLoopJson, RepetitionsJson};
use mp_concrete::{ExecParams, Program};
use mp_geom::PersonId;
use mp_pipeline::Outcome;
use numpy::{PyArray3, ToPyArray};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

use crate::errors;
use crate::track::PyTrack;

/// A concrete program: per joint, a sequence of primitives (circle, line,
/// stationary, cubic spline) over shared segments, executable at any frame
/// rate.
#[pyclass(name = "Program", module = "motion_programs", frozen)]
pub struct PyProgram {
    pub(crate) inner: Program,
}

#[pymethods]
impl PyProgram {
    /// The program in the paper's notation (lossless; `Program.parse` reads it back).
    #[getter]
    fn text(&self) -> String {
        self.inner.to_dsl()
    }

    /// The program as JSON.
    fn to_json(&self) -> PyResult<String> {
        self.inner.to_json().map_err(errors::concrete)
    }

    /// A program from its notation or JSON text.
    #[staticmethod]
    fn parse(text: &str) -> PyResult<Self> {
        let p = if text.trim_start().starts_with('{') {
            Program::from_json(text)
        } else {
            Program::from_dsl(text)
        }
        .map_err(errors::concrete)?;
        Ok(PyProgram { inner: p })
    }

    /// Reads a program (`.json`, `.mpb` or the notation).
    #[staticmethod]
    fn read(path: std::path::PathBuf) -> PyResult<Self> {
        Ok(PyProgram {
            inner: Program::read(&path).map_err(errors::concrete)?,
        })
    }

    /// Writes the program (`.json`, `.mpb`, anything else: the notation), atomically.
    fn save(&self, path: std::path::PathBuf) -> PyResult<()> {
        self.inner.write(&path).map_err(errors::concrete)
    }

    /// Pickles through the JSON form (exact numbers).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let py = slf.py();
        let parse = py.get_type::<PyProgram>().getattr("parse")?;
        Ok((parse, (slf.get().to_json()?,)))
    }

    /// Positions of the executed program, `T' × J × D`, at `fps` frames per
    /// second (default: the program's own rate).
    #[pyo3(signature = (fps=None))]
    fn execute<'py>(
        &self,
        py: Python<'py>,
        fps: Option<f64>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let t = self.execute_track(py, fps)?;
        Ok(t.inner.positions().to_pyarray(py))
    }

    /// The executed program as a `Track` (see `execute`).
    #[pyo3(signature = (fps=None))]
    fn execute_track(&self, py: Python<'_>, fps: Option<f64>) -> PyResult<PyTrack> {
        let p = &self.inner;
        let params = ExecParams {
            fps_out: fps,
            ..ExecParams::default()
        };
        let t = py
            .detach(|| p.execute_with(&params))
            .map_err(errors::concrete)?;
        Ok(PyTrack::new(t))
    }

    /// The segments: one dict per segment with `start_frame`, `frames` and
    /// the primitive `kinds` of every joint.
    #[getter]
    fn segments<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        let mut start = 0usize;
        for s in &self.inner.segments {
            let d = PyDict::new(py);
            d.set_item("start_frame", start)?;
            d.set_item("frames", s.duration_frames)?;
            let kinds: Vec<&str> = s.primitives.iter().map(|p| p.kind().as_str()).collect();
            d.set_item("kinds", kinds)?;
            list.append(d)?;
            start += s.duration_frames;
        }
        Ok(list)
    }

    /// Frames per second.
    #[getter]
    fn fps(&self) -> f64 {
        self.inner.fps
    }

    /// Joint names.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.inner.joints.clone()
    }

    /// Number of segments.
    #[getter]
    fn n_segments(&self) -> usize {
        self.inner.n_segments()
    }

    /// Number of frames.
    #[getter]
    fn n_frames(&self) -> usize {
        self.inner.n_frames()
    }

    /// Number of free parameters: every primitive's parameters plus one
    /// duration per segment, less the start poses that continuity gives in a
    /// C0 program.
    #[getter]
    fn n_params(&self) -> usize {
        self.inner.n_params()
    }

    /// Number of numbers written: every primitive's parameters plus one
    /// duration per segment, continuity or not.
    #[getter]
    fn n_numbers(&self) -> usize {
        self.inner.n_numbers()
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }

    fn __repr__(&self) -> String {
        format!(
            "Program({} frames, {} joints, {} segments, {} fps)",
            self.inner.n_frames(),
            self.inner.n_joints(),
            self.inner.n_segments(),
            self.inner.fps
        )
    }
}

/// An abstract program: `for` loops of probabilistic primitives, with the
/// concrete program it was made from.
#[pyclass(name = "AbstractProgram", module = "motion_programs", frozen)]
pub struct PyAbstract {
    pub(crate) inner: Analysis,
}

/// An analysis as JSON text (its primitives are internally tagged, which
/// only a self-describing format reads back; JSON keeps every number exact).
pub(crate) fn analysis_to_json(a: &Analysis) -> PyResult<String> {
    serde_json::to_string(a).map_err(|e| errors::MpError::new_err(e.to_string()))
}

/// An analysis from [`analysis_to_json`]'s text.
pub(crate) fn analysis_from_json(text: &str) -> PyResult<Analysis> {
    serde_json::from_str(text).map_err(|e| {
        errors::ParamError::new_err(format!("not the bytes of an abstract program: {e}"))
    })
}

#[pymethods]
impl PyAbstract {
    /// The abstract program with the analysis it came from, as bytes (what
    /// it pickles through).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        Ok(PyBytes::new(py, analysis_to_json(&self.inner)?.as_bytes()))
    }

    /// An abstract program from `AbstractProgram.to_bytes`'s output.
    #[staticmethod]
    fn from_bytes(data: &[u8]) -> PyResult<Self> {
        let text = std::str::from_utf8(data).map_err(|e| {
            errors::ParamError::new_err(format!("not the bytes of an abstract program: {e}"))
        })?;
        Ok(PyAbstract {
            inner: analysis_from_json(text)?,
        })
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let py = slf.py();
        let from_bytes = py.get_type::<PyAbstract>().getattr("from_bytes")?;
        Ok((from_bytes, (slf.get().to_bytes(py)?,)))
    }

    /// The abstract program in its text form.
    #[getter]
    fn text(&self) -> String {
        self.inner.program.to_dsl()
    }

    /// The abstract program as JSON.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.inner.program)
            .map_err(|e| errors::MpError::new_err(e.to_string()))
    }

    /// The concrete program it was made from.
    #[getter]
    fn concrete(&self) -> PyProgram {
        PyProgram {
            inner: self.inner.concrete.clone(),
        }
    }

    /// The program loops (its `for` statements) as frame ranges: dicts
    /// with `first_frame`, `last_frame` (inclusive), `iterations`,
    /// `body_primitives`, `score` and `iteration_frames` (`[first, last]`
    /// of each iteration) — the entries of `loops.json`'s `program_loops`.
    #[getter]
    fn program_loops<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let loops: Vec<ProgramLoopJson> = self
            .inner
            .intervals
            .iter()
            .map(ProgramLoopJson::new)
            .collect();
        to_python(py, &json_value(&loops)?)
    }

    fn __repr__(&self) -> String {
        format!(
            "AbstractProgram({} statements, {} loops)",
            self.inner.program.stmts.len(),
            self.inner.loops.len()
        )
    }
}

/// Repetition counts: `total`, `intervals` (dicts as in `loops.json`'s
/// `repetitions.intervals`: `first_frame`, `last_frame` (inclusive),
/// `count`, `period_frames`, `period_s`, `cycles`, `periodicity`,
/// `repetitions` (`[first, last]` of each) and `signal`, what the interval
/// was counted from), the `signal` (`keypoints` or `frames`) and `method`
/// (`period`, `intervals`, `none`) that decided, and
/// a `confidence`; for a video with several people tracked, `person` (whose
/// counts these are) and `people` (every tracked person's entry of
/// `loops.json`). `to_json()` gives the `loops.json` document (without
/// program loops), `Counts.from_json` reads it back, or reads a
/// `loops.json` that `mp run` wrote.
#[pyclass(name = "Counts", module = "motion_programs", frozen)]
pub struct PyCounts {
    pub(crate) inner: Counts,
    /// The entries of `loops.json`'s `people` list.
    people: Vec<serde_json::Value>,
    /// The person the counts follow.
    person: Option<PersonId>,
}

/// Every tracked person's entry, as `loops.json`'s `people` list (the same
/// function writes it; `repetitions` is None for people not analysed).
pub(crate) fn people_entries(outcome: &Outcome) -> Vec<serde_json::Value> {
    let mut v = outcome.loops_json();
    match v.get_mut("people").map(serde_json::Value::take) {
        Some(serde_json::Value::Array(list)) => list,
        _ => Vec::new(),
    }
}

/// A value as JSON, errors as `MpError`.
fn json_value<T: serde::Serialize>(x: &T) -> PyResult<serde_json::Value> {
    serde_json::to_value(x).map_err(|e| errors::MpError::new_err(e.to_string()))
}

/// JSON values as Python objects (dicts, lists, numbers, None).
pub(crate) fn to_python<'py>(
    py: Python<'py>,
    value: &serde_json::Value,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| errors::MpError::new_err(e.to_string()))?;
    py.import("json")?.getattr("loads")?.call1((text,))
}

impl PyCounts {
    /// Counts of a track (no people).
    pub(crate) fn of_counts(inner: Counts) -> Self {
        PyCounts {
            inner,
            people: Vec::new(),
            person: None,
        }
    }

    /// The top-level counts of an analysis, with every tracked person's entry.
    pub(crate) fn of_outcome(outcome: &Outcome) -> Self {
        Self::new(
            outcome.counts.clone(),
            people_entries(outcome),
            outcome.keypoints.person,
        )
    }

    /// Counts with `loops.json`'s people entries and whose counts they are.
    pub(crate) fn new(
        inner: Counts,
        people: Vec<serde_json::Value>,
        person: Option<PersonId>,
    ) -> Self {
        PyCounts {
            inner,
            people,
            person,
        }
    }
}

#[pymethods]
impl PyCounts {
    /// The counts as the `loops.json` document (`schema`, `version`, `fps`,
    /// `frames`, `person`, `repetitions`, `people`; no program loops).
    fn to_json(&self) -> PyResult<String> {
        let v = serde_json::json!({
            "schema": RepetitionsJson::LOOPS_SCHEMA,
            "version": RepetitionsJson::LOOPS_VERSION,
            "fps": self.inner.fps,
            "frames": self.inner.frames,
            "person": self.person,
            "repetitions": RepetitionsJson::new(&self.inner),
            "people": self.people,
        });
        serde_json::to_string_pretty(&v).map_err(|e| errors::MpError::new_err(e.to_string()))
    }

    /// Counts from the output of `Counts.to_json`, or from a `loops.json`
    /// that `mp run` or `mp loops --json` wrote.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let bad = |e: String| {
            errors::ParamError::new_err(format!("not the JSON of repetition counts: {e}"))
        };
        let v: serde_json::Value = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
        match v.get("version").and_then(serde_json::Value::as_u64) {
            Some(x) if x == u64::from(RepetitionsJson::LOOPS_VERSION) => {}
            Some(x) => {
                return Err(bad(format!(
                    "version {x}, this version of mp reads version {}",
                    RepetitionsJson::LOOPS_VERSION
                )))
            }
            None => return Err(bad("no `version` key".into())),
        }
        let field = |k: &str| v.get(k).cloned().unwrap_or(serde_json::Value::Null);
        let fps: f64 =
            serde_json::from_value(field("fps")).map_err(|e| bad(format!("fps: {e}")))?;
        let frames: usize =
            serde_json::from_value(field("frames")).map_err(|e| bad(format!("frames: {e}")))?;
        let reps: RepetitionsJson = serde_json::from_value(field("repetitions"))
            .map_err(|e| bad(format!("repetitions: {e}")))?;
        let inner = reps
            .to_counts(frames, fps)
            .map_err(|e| bad(e.to_string()))?;
        let people = match v.get("people") {
            Some(serde_json::Value::Array(p)) => p.clone(),
            _ => Vec::new(),
        };
        let person =
            serde_json::from_value(field("person")).map_err(|e| bad(format!("person: {e}")))?;
        Ok(PyCounts {
            inner,
            people,
            person,
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let py = slf.py();
        let from_json = py.get_type::<PyCounts>().getattr("from_json")?;
        Ok((from_json, (slf.get().to_json()?,)))
    }

    /// Every tracked person of a video (empty for a track and the
    /// single-person pipeline): dicts with `id`, `main`, `first_frame`,
    /// `last_frame`, `frames_found`, `box` (mean box `[x0, y0, x1, y1]`,
    /// px), `analysed`, and `repetitions` (as `Counts.to_json()`'s
    /// `repetitions`: `total`, `intervals`, `signal`, `method`,
    /// `confidence`, …; None for people not analysed: seen too briefly);
    /// frames are the video's. The entries of `loops.json`.
    #[getter]
    fn people<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &serde_json::Value::Array(self.people.clone()))
    }

    /// The id of the person these counts follow (the main person unless
    /// another was asked for); None for a track and the single-person
    /// pipeline.
    #[getter]
    fn person(&self) -> Option<PersonId> {
        self.person
    }

    /// Total repetitions.
    #[getter]
    fn total(&self) -> usize {
        self.inner.total
    }

    /// `keypoints` or `frames`.
    #[getter]
    fn signal(&self) -> &'static str {
        self.inner.signal.as_str()
    }

    /// `period`, `intervals` or `none`.
    #[getter]
    fn method(&self) -> &'static str {
        self.inner.method.as_str()
    }

    /// How likely it is that the motion repeats and that `total` is within
    /// one of the true count (0..1), calibrated on synthetic repetitions of
    /// real motion.
    #[getter]
    fn confidence(&self) -> f64 {
        self.inner.confidence
    }

    /// How periodic the deciding signal is: the autocorrelation of its
    /// motion at the period (0..1).
    #[getter]
    fn periodicity(&self) -> f64 {
        self.inner.periodicity
    }

    /// Frames of the recording.
    #[getter]
    fn frames(&self) -> usize {
        self.inner.frames
    }

    /// Frame rate.
    #[getter]
    fn fps(&self) -> f64 {
        self.inner.fps
    }

    /// The counted intervals: dicts with `first_frame`, `last_frame`
    /// (inclusive), `count`, `period_frames`, `period_s`, `cycles`,
    /// `periodicity`, `repetitions` (`[first, last]` of each) and `signal`
    /// (what the interval was counted from), as in `loops.json`.
    #[getter]
    fn intervals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(
            py,
            &json_value(&RepetitionsJson::new(&self.inner).intervals)?,
        )
    }

    fn __repr__(&self) -> String {
        let people = if self.people.is_empty() {
            String::new()
        } else {
            format!(", people={}", self.people.len())
        };
        format!(
            "Counts(total={}, signal='{}', method='{}', confidence={:.2}, intervals={}{people})",
            self.inner.total,
            self.inner.signal.as_str(),
            self.inner.method.as_str(),
            self.inner.confidence,
            self.inner.intervals.len()
        )
    }
}
