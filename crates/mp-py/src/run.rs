//! `run` (the whole pipeline into an output folder, as `mp run`) and the
//! grammar's symbol search.

use std::path::PathBuf;
use std::sync::Mutex;

use mp_grammar::data::Motion;
use mp_grammar::model::find_symbols;
use mp_grammar::{PoseDistanceParams, SymbolParams};
use mp_pipeline::{Analyser, CancelToken, Input, RunSummary, Silent};
use pyo3::prelude::*;
use pyo3::types::PyList;

use crate::errors;
use crate::people::PyPeople;
use crate::programs::{PyAbstract, PyCounts, PyProgram};
use crate::track::PyTrack;

/// What `run` produced: `counts`, `track`, `program` and `abstract_program`
/// (None when no person was found in any frame), `report` (path or None),
/// `files` (relative to the output folder), `stages` (name, seconds,
/// frames), `seconds` (wall time); for a video with several people tracked,
/// `person` (whose results these are), `people` (every tracked person's
/// entry of `loops.json`), `tracked` (their keypoints, `People`) and
/// `program_of(id)` / `abstract_program_of(id)`.
#[pyclass(name = "Summary", module = "motion_programs", frozen)]
pub struct PySummary {
    inner: RunSummary,
    out_dir: Option<PathBuf>,
}

impl PySummary {
    fn person_analysis(&self, id: mp_geom::PersonId) -> Option<&mp_pipeline::Analysis> {
        self.inner
            .outcome
            .people
            .iter()
            .find(|p| p.id == id)
            .and_then(|p| p.analysis.as_ref())
    }
}

#[pymethods]
impl PySummary {
    /// Repetition counts (what `loops.json` holds).
    #[getter]
    fn counts(&self) -> PyCounts {
        PyCounts::of_outcome(&self.inner.outcome)
    }

    /// Every tracked person (empty for a track and the single-person
    /// pipeline): the dicts of `Counts.people`, `loops.json`'s `people` list.
    #[getter]
    fn people<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let list = crate::programs::people_entries(&self.inner.outcome);
        crate::programs::to_python(py, &serde_json::Value::Array(list))
    }

    /// The id of the person the top-level results follow, or None (a track,
    /// the single-person pipeline, nobody found).
    #[getter]
    fn person(&self) -> Option<mp_geom::PersonId> {
        self.inner.outcome.keypoints.person
    }

    /// Every tracked person's keypoints (`People`), or None (a track, the
    /// single-person pipeline).
    #[getter]
    fn tracked(&self) -> Option<PyPeople> {
        self.inner
            .outcome
            .keypoints
            .people
            .clone()
            .map(PyPeople::new)
    }

    /// The concrete program of person `id` (over their own frames, from
    /// their `first_frame`; the main person's over the whole video), or
    /// None when they were not analysed.
    fn program_of(&self, id: mp_geom::PersonId) -> Option<PyProgram> {
        self.person_analysis(id).map(|a| PyProgram {
            inner: a.concrete.clone(),
        })
    }

    /// The abstract program of person `id` (see `program_of`), or None.
    fn abstract_program_of(&self, id: mp_geom::PersonId) -> Option<PyAbstract> {
        self.person_analysis(id)
            .map(|a| PyAbstract { inner: a.clone() })
    }

    /// The keypoints.
    #[getter]
    fn track(&self) -> PyTrack {
        PyTrack::new(self.inner.outcome.keypoints.track.clone())
    }

    /// The concrete program, or None.
    #[getter]
    fn program(&self) -> Option<PyProgram> {
        self.inner.outcome.analysis.as_ref().map(|a| PyProgram {
            inner: a.concrete.clone(),
        })
    }

    /// The abstract program, or None.
    #[getter]
    fn abstract_program(&self) -> Option<PyAbstract> {
        self.inner
            .outcome
            .analysis
            .as_ref()
            .map(|a| PyAbstract { inner: a.clone() })
    }

    /// The report page, or None.
    #[getter]
    fn report(&self) -> Option<PathBuf> {
        self.inner.report.clone()
    }

    /// The output folder (None for an analysis that wrote nothing).
    #[getter]
    fn out_dir(&self) -> Option<PathBuf> {
        self.out_dir.clone()
    }

    /// Frames analysed.
    #[getter]
    fn frames(&self) -> usize {
        self.inner.outcome.keypoints.track.n_frames()
    }

    /// Files written, relative to the output folder.
    #[getter]
    fn files(&self) -> Vec<String> {
        self.inner.files.clone()
    }

    /// Fraction of frames with a person.
    #[getter]
    fn person_found(&self) -> f64 {
        self.inner.outcome.keypoints.found_fraction
    }

    /// Time per stage: a list of (name, seconds, frames).
    #[getter]
    fn stages<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let l = PyList::empty(py);
        for s in &self.inner.outcome.stages {
            l.append((s.stage.name(), s.time.as_secs_f64(), s.frames))?;
        }
        Ok(l)
    }

    /// Wall time of the run, seconds.
    #[getter]
    fn seconds(&self) -> f64 {
        self.inner.outcome.total.as_secs_f64()
    }

    fn __repr__(&self) -> String {
        format!(
            "Summary({} repetitions, {} files in {}, {:.2} s)",
            self.inner.outcome.counts.total,
            self.inner.files.len(),
            self.out_dir
                .as_ref()
                .map(|d| d.display().to_string())
                .unwrap_or_else(|| "no folder".into()),
            self.inner.outcome.total.as_secs_f64()
        )
    }
}

/// The whole pipeline into `out_dir` (as `mp run`): keypoints (for a video),
/// programs, counts, pictures, `overlay.mp4` (video only, unless
/// `overlay_video=False`) and the report, `report.html` with its folder
/// `report/` (unless `report=False`).
/// `source` is a video or track file path, or a `Track`. For a video, every
/// person in view is tracked (at most `max_people`; `single_person`:
/// MediaPipe's single-person pipeline) and `person` (`"all"`, the default,
/// `"main"` or an id) chooses whom to analyse, as `mp run --person`.
#[pyfunction]
#[pyo3(signature = (source, out_dir, model=None, threads=None, max_frames=None, all_joints=false, frame_size=None, overlay_video=true, report=true, person=None, max_people=None, single_person=false))]
#[allow(clippy::too_many_arguments)]
pub fn run(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    out_dir: PathBuf,
    model: Option<&str>,
    threads: Option<usize>,
    max_frames: Option<usize>,
    all_joints: bool,
    frame_size: Option<f64>,
    overlay_video: bool,
    report: bool,
    person: Option<&Bound<'_, PyAny>>,
    max_people: Option<usize>,
    single_person: bool,
) -> PyResult<PySummary> {
    let mut params = crate::params_with(model, threads, max_frames, all_joints, None, None)?;
    params.output.overlay_video = overlay_video;
    params.output.report = report;
    crate::people::apply(&mut params, person, max_people, single_person)?;
    let input = input_of(source, frame_size)?;
    let dir = out_dir.clone();
    let s = py
        .detach(|| mp_pipeline::run(input, &dir, &params, &Silent, &CancelToken::new()))
        .map_err(errors::pipeline)?;
    Ok(PySummary {
        inner: s,
        out_dir: Some(out_dir),
    })
}

/// The input a Python call names: a `Track`, or the path of a video or track file.
fn input_of(source: &Bound<'_, PyAny>, frame_size: Option<f64>) -> PyResult<Input> {
    if let Ok(t) = source.cast::<PyTrack>() {
        return Ok(Input::from_track(
            t.get().inner.clone(),
            "track",
            frame_size,
        ));
    }
    let path: PathBuf = source.extract().map_err(|_| {
        errors::ParamError::new_err("expected a Track or the path of a video or track file")
    })?;
    Input::open(&path, frame_size).map_err(errors::pipeline)
}

/// Analyses many inputs with one set of parameters and the pose model kept
/// loaded between videos — one per worker of a batch job (a Ray actor, a
/// process of a pool). Its methods release the GIL; one analyser runs one
/// input at a time (calls from several threads wait for each other).
#[pyclass(name = "Analyser", module = "motion_programs", frozen)]
pub struct PyAnalyser {
    inner: Mutex<Analyser>,
}

#[pymethods]
impl PyAnalyser {
    #[new]
    #[pyo3(signature = (model=None, threads=None, max_frames=None, all_joints=false, overlay_video=true, report=true, person=None, max_people=None, single_person=false))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        model: Option<&str>,
        threads: Option<usize>,
        max_frames: Option<usize>,
        all_joints: bool,
        overlay_video: bool,
        report: bool,
        person: Option<&Bound<'_, PyAny>>,
        max_people: Option<usize>,
        single_person: bool,
    ) -> PyResult<Self> {
        let mut params = crate::params_with(model, threads, max_frames, all_joints, None, None)?;
        params.output.overlay_video = overlay_video;
        params.output.report = report;
        crate::people::apply(&mut params, person, max_people, single_person)?;
        Ok(PyAnalyser {
            inner: Mutex::new(Analyser::new(params).map_err(errors::pipeline)?),
        })
    }

    /// Keypoints, programs and counts of `source` (a video or track path, or
    /// a `Track`) without writing anything; `Summary.out_dir` is None.
    #[pyo3(signature = (source, frame_size=None))]
    fn analyse(
        &self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        frame_size: Option<f64>,
    ) -> PyResult<PySummary> {
        let input = input_of(source, frame_size)?;
        let outcome = py
            .detach(|| {
                let mut a = self.inner.lock().unwrap_or_else(|e| e.into_inner());
                a.analyse(input, &Silent, &CancelToken::new())
            })
            .map_err(errors::pipeline)?;
        Ok(PySummary {
            inner: RunSummary {
                outcome,
                report: None,
                files: Vec::new(),
            },
            out_dir: None,
        })
    }

    /// As `run()`, with this analyser's parameters and loaded model.
    #[pyo3(signature = (source, out_dir, frame_size=None))]
    fn run(
        &self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        out_dir: PathBuf,
        frame_size: Option<f64>,
    ) -> PyResult<PySummary> {
        let input = input_of(source, frame_size)?;
        let dir = out_dir.clone();
        let s = py
            .detach(|| {
                let mut a = self.inner.lock().unwrap_or_else(|e| e.into_inner());
                a.run(input, &dir, &Silent, &CancelToken::new())
            })
            .map_err(errors::pipeline)?;
        Ok(PySummary {
            inner: s,
            out_dir: Some(out_dir),
        })
    }
}

/// Terminal symbols of a motion (as `mp grammar symbols`): the track is
/// cut into segments clustered into `k` symbols (PAM + genetic search +
/// annealing). Returns a dict: `text` (the symbol string), `k`, `segments`
/// (start/end frame and symbol), `quality` and the parameters used.
#[pyfunction]
#[pyo3(signature = (track, k=None, seed=None))]
pub fn grammar_symbols<'py>(
    py: Python<'py>,
    track: &Bound<'py, PyAny>,
    k: Option<usize>,
    seed: Option<u64>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut p = SymbolParams::default();
    if let Some(k) = k {
        p.k = k;
    }
    if let Some(s) = seed {
        p.seed = s;
    }
    let motion = Motion {
        track: crate::track::track_arg(track, "grammar_symbols")?,
        bvh: None,
        paths: Vec::new(),
        frame_step: 1,
    };
    let s = py
        .detach(|| find_symbols(&motion, &PoseDistanceParams::default(), &p))
        .map_err(errors::grammar)?;
    let json = serde_json::to_string(&s).map_err(|e| errors::MpError::new_err(e.to_string()))?;
    let loads = py.import("json")?.getattr("loads")?;
    let d = loads.call1((json,))?;
    Ok(d)
}

/// A context-free grammar of a motion's symbols (as `mp grammar learn`):
/// the symbol string (a dict from `grammar_symbols`) is cut into sentences
/// by MDL, and Alignment-Based Learning induces the grammar. Returns the
/// grammar model as a dict (`grammar` with its rules, `sentences`,
/// `description_length`, …).
#[pyfunction]
#[pyo3(signature = (symbols, seed=None))]
pub fn grammar_learn<'py>(
    py: Python<'py>,
    symbols: &Bound<'py, PyAny>,
    seed: Option<u64>,
) -> PyResult<Bound<'py, PyAny>> {
    let json = py.import("json")?;
    let text: String = json.getattr("dumps")?.call1((symbols,))?.extract()?;
    let sf: mp_grammar::model::SymbolsFile = serde_json::from_str(&text)
        .map_err(|e| errors::GrammarError::new_err(format!("not a symbols dict: {e}")))?;
    let mut p = mp_grammar::sentences::PartitionParams::default();
    if let Some(s) = seed {
        p.seed = s;
    }
    let g = py
        .detach(|| mp_grammar::model::learn_grammar(&sf, &p))
        .map_err(errors::grammar)?;
    let out = serde_json::to_string(&g).map_err(|e| errors::MpError::new_err(e.to_string()))?;
    json.getattr("loads")?.call1((out,))
}
