//! Programs and counts: `Program` (concrete), `AbstractProgram`, `Counts`,
//! `Summary` of a run.

use mp_abstract::{Analysis, Counts};
use mp_concrete::{ExecParams, Program};
use mp_geom::PersonId;
use mp_pipeline::Outcome;
use numpy::{PyArray3, ToPyArray};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

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

#[pymethods]
impl PyAbstract {
    /// The abstract program in its text form.
    #[getter]
    fn text(&self) -> String {
        mp_abstract::dsl::print(&self.inner.program)
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

    /// The loops as frame intervals: dicts with `start_frame`, `end_frame`,
    /// `iterations`, `body_size`, `boundaries`.
    #[getter]
    fn loops<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for iv in &self.inner.intervals {
            let d = PyDict::new(py);
            d.set_item("start_frame", iv.start_frame)?;
            d.set_item("end_frame", iv.end_frame)?;
            d.set_item("iterations", iv.iterations)?;
            d.set_item("body_size", iv.body_size)?;
            d.set_item("boundaries", iv.boundaries.clone())?;
            list.append(d)?;
        }
        Ok(list)
    }

    fn __repr__(&self) -> String {
        format!(
            "AbstractProgram({} statements, {} loops)",
            self.inner.program.stmts.len(),
            self.inner.loops.len()
        )
    }
}

/// Repetition counts: `total`, `intervals` (dicts with `start_frame`,
/// `end_frame`, `period_frames`, `count`, `cycles`, `boundaries`,
/// `confidence`), the `signal` (`keypoints` or `frames`) and `method`
/// (`period`, `intervals`, `none`) that decided, and a `confidence`; for a
/// video with several people tracked, `person` (whose counts these are) and
/// `people` (every tracked person's entry of `loops.json`).
#[pyclass(name = "Counts", module = "motion_programs", frozen)]
pub struct PyCounts {
    pub(crate) inner: Counts,
    /// The entries of `loops.json`'s `people` list.
    people: Vec<serde_json::Value>,
    /// The person the counts follow.
    person: Option<PersonId>,
}

/// The keys of a person's entry that only analysed people have; the others
/// get them as None, so every entry has the same keys.
const ANALYSED_KEYS: [&str; 7] = [
    "total_repetitions",
    "counts",
    "intervals",
    "signal",
    "method",
    "confidence",
    "periodicity",
];

/// Every tracked person's entry, as `loops.json`'s `people` list (the same
/// function writes it), each with every key.
pub(crate) fn people_entries(outcome: &Outcome) -> Vec<serde_json::Value> {
    let mut v = mp_pipeline::output::loops_json(outcome);
    let list = match v.get_mut("people").map(serde_json::Value::take) {
        Some(serde_json::Value::Array(list)) => list,
        _ => Vec::new(),
    };
    list.into_iter()
        .map(|mut e| {
            if let Some(obj) = e.as_object_mut() {
                for k in ANALYSED_KEYS {
                    obj.entry(k).or_insert(serde_json::Value::Null);
                }
            }
            e
        })
        .collect()
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
        PyCounts {
            inner: outcome.counts.clone(),
            people: people_entries(outcome),
            person: outcome.keypoints.person,
        }
    }
}

#[pymethods]
impl PyCounts {
    /// The counts with their people, as JSON (what they pickle through).
    fn _state(&self) -> PyResult<String> {
        let v = serde_json::json!({
            "counts": self.inner,
            "people": self.people,
            "person": self.person,
        });
        serde_json::to_string(&v).map_err(|e| errors::MpError::new_err(e.to_string()))
    }

    /// Counts from the output of `Counts.to_json` (or of their pickled state).
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let bad = |e: serde_json::Error| {
            errors::ParamError::new_err(format!("not the JSON of Counts: {e}"))
        };
        let mut v: serde_json::Value = serde_json::from_str(text).map_err(bad)?;
        if v.get("counts").is_none() {
            v = serde_json::json!({ "counts": v });
        }
        let mut take = |k: &str| v.get_mut(k).map(serde_json::Value::take);
        let counts: Counts =
            serde_json::from_value(take("counts").unwrap_or_default()).map_err(bad)?;
        let people = match take("people") {
            Some(p) => serde_json::from_value(p).map_err(bad)?,
            None => Vec::new(),
        };
        let person = match take("person") {
            Some(p) => serde_json::from_value(p).map_err(bad)?,
            None => None,
        };
        Ok(PyCounts {
            inner: counts,
            people,
            person,
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let py = slf.py();
        let from_json = py.get_type::<PyCounts>().getattr("from_json")?;
        Ok((from_json, (slf.get()._state()?,)))
    }

    /// Every tracked person of a video (empty for a track and the
    /// single-person pipeline): dicts with `id`, `main`, `first_frame`,
    /// `last_frame`, `frames_found`, `box` (mean box `[x0, y0, x1, y1]`,
    /// px), `analysed`, and `total_repetitions`, `counts`, `intervals`,
    /// `signal`, `method`, `confidence` (None for people not analysed: seen
    /// too briefly); frames are the video's. The entries of `loops.json`.
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

    /// The counted intervals.
    #[getter]
    fn intervals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for iv in &self.inner.intervals {
            let d = PyDict::new(py);
            d.set_item("start_frame", iv.start_frame)?;
            d.set_item("end_frame", iv.end_frame)?;
            d.set_item("period_frames", iv.period_frames)?;
            d.set_item("cycles", iv.cycles)?;
            d.set_item("count", iv.count)?;
            d.set_item("boundaries", iv.boundaries.clone())?;
            d.set_item("confidence", iv.confidence)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The counts as JSON (the `counted` part of `loops.json`).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.inner)
            .map_err(|e| errors::MpError::new_err(e.to_string()))
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
