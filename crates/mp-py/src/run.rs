//! `run` (the whole pipeline into an output folder, as `mp run`) and the
//! grammar's symbol search.

use std::path::PathBuf;
use std::sync::Mutex;

use mp_abstract::{Analysis, Counts};
use mp_geom::CancelToken;
use mp_geom::{People, PersonId, Track};
use mp_grammar::find_symbols;
use mp_grammar::Motion;
use mp_grammar::{PoseDistanceParams, SymbolParams};
use mp_pipeline::{Analyser, Input, Outcome, Params, RunSummary, Silent};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use serde::{Deserialize, Serialize};

use crate::errors;
use crate::people::PyPeople;
use crate::programs::{analysis_from_json, analysis_to_json, PyAbstract, PyCounts, PyProgram};
use crate::track::PyTrack;

/// What `run` produced: `counts`, `track`, `program` and `abstract_program`
/// (None when no person was found in any frame), `report` (path or None),
/// `files` (relative to the output folder), `stages` (name, seconds,
/// frames), `seconds` (wall time); for a video with several people tracked,
/// `person` (whose results these are), `people` (every tracked person's
/// entry of `loops.json`), `tracked` (their keypoints, `People`) and
/// `program_of(id)` / `abstract_program_of(id)`. Pickles (`to_bytes` /
/// `Summary.from_bytes`).
#[pyclass(name = "Summary", module = "motion_programs", frozen)]
pub struct PySummary {
    track: Track,
    tracked: Option<People>,
    person: Option<PersonId>,
    analysis: Option<Analysis>,
    counts: Counts,
    /// `loops.json`'s `people` entries.
    people: Vec<serde_json::Value>,
    /// Every analysed person's programs.
    analyses: Vec<(PersonId, Analysis)>,
    found_fraction: f64,
    /// (stage name, seconds, frames).
    stages: Vec<(String, f64, usize)>,
    seconds: f64,
    report: Option<PathBuf>,
    files: Vec<String>,
    out_dir: Option<PathBuf>,
}

/// What a summary pickles through: the track and people as their own
/// binary forms, the analyses and people entries as JSON text, the rest as
/// they are.
#[derive(Serialize, Deserialize)]
struct SummaryState {
    track: Vec<u8>,
    tracked: Option<Vec<u8>>,
    person: Option<PersonId>,
    /// JSON (see `programs::analysis_to_json`).
    analysis: Option<String>,
    counts: Counts,
    people: String,
    analyses: Vec<(PersonId, String)>,
    found_fraction: f64,
    stages: Vec<(String, f64, usize)>,
    seconds: f64,
    report: Option<PathBuf>,
    files: Vec<String>,
    out_dir: Option<PathBuf>,
}

/// Magic and version of a pickled summary.
const SUMMARY_MAGIC: &[u8] = b"mp-summary";
const SUMMARY_VERSION: u32 = 1;

impl PySummary {
    /// The summary of an analysis written to `out_dir` (or nothing written).
    fn of_outcome(
        outcome: Outcome,
        report: Option<PathBuf>,
        files: Vec<String>,
        out_dir: Option<PathBuf>,
    ) -> Self {
        let people = crate::programs::people_entries(&outcome);
        let stages = outcome
            .stages
            .iter()
            .map(|s| (s.stage.name().to_string(), s.time.as_secs_f64(), s.frames))
            .collect();
        let analyses = outcome
            .people
            .iter()
            .filter_map(|p| p.analysis.clone().map(|a| (p.id, a)))
            .collect();
        let seconds = outcome.total.as_secs_f64();
        let kp = outcome.keypoints;
        PySummary {
            track: kp.track,
            tracked: kp.people,
            person: kp.person,
            analysis: outcome.analysis,
            counts: outcome.counts,
            people,
            analyses,
            found_fraction: kp.found_fraction,
            stages,
            seconds,
            report,
            files,
            out_dir,
        }
    }

    fn of_run(s: RunSummary, out_dir: PathBuf) -> Self {
        Self::of_outcome(s.outcome, s.report, s.files, Some(out_dir))
    }

    fn person_analysis(&self, id: PersonId) -> Option<&Analysis> {
        self.analyses.iter().find(|(p, _)| *p == id).map(|(_, a)| a)
    }
}

#[pymethods]
impl PySummary {
    /// The summary as bytes (what it pickles through).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let state = SummaryState {
            track: mp_geom::track_to_bincode(&self.track).map_err(errors::geom)?,
            tracked: self
                .tracked
                .as_ref()
                .map(mp_geom::people_to_bincode)
                .transpose()
                .map_err(errors::geom)?,
            person: self.person,
            analysis: self.analysis.as_ref().map(analysis_to_json).transpose()?,
            counts: self.counts.clone(),
            people: serde_json::to_string(&self.people)
                .map_err(|e| errors::MpError::new_err(e.to_string()))?,
            analyses: self
                .analyses
                .iter()
                .map(|(id, a)| Ok((*id, analysis_to_json(a)?)))
                .collect::<PyResult<_>>()?,
            found_fraction: self.found_fraction,
            stages: self.stages.clone(),
            seconds: self.seconds,
            report: self.report.clone(),
            files: self.files.clone(),
            out_dir: self.out_dir.clone(),
        };
        let b = mp_geom::binary::encode(SUMMARY_MAGIC, SUMMARY_VERSION, &state)
            .map_err(errors::geom)?;
        Ok(PyBytes::new(py, &b))
    }

    /// A summary from `Summary.to_bytes`'s output.
    #[staticmethod]
    fn from_bytes(data: &[u8]) -> PyResult<Self> {
        let s: SummaryState = mp_geom::binary::decode(
            SUMMARY_MAGIC,
            SUMMARY_VERSION,
            data,
            std::path::Path::new("summary bytes"),
        )
        .map_err(errors::geom)?;
        let people = serde_json::from_str(&s.people)
            .map_err(|e| errors::ParamError::new_err(format!("summary bytes: people: {e}")))?;
        Ok(PySummary {
            track: mp_geom::track_from_bincode(&s.track).map_err(errors::geom)?,
            tracked: s
                .tracked
                .as_deref()
                .map(mp_geom::people_from_bincode)
                .transpose()
                .map_err(errors::geom)?,
            person: s.person,
            analysis: s.analysis.as_deref().map(analysis_from_json).transpose()?,
            counts: s.counts,
            people,
            analyses: s
                .analyses
                .iter()
                .map(|(id, a)| Ok((*id, analysis_from_json(a)?)))
                .collect::<PyResult<_>>()?,
            found_fraction: s.found_fraction,
            stages: s.stages,
            seconds: s.seconds,
            report: s.report,
            files: s.files,
            out_dir: s.out_dir,
        })
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let py = slf.py();
        let from_bytes = py.get_type::<PySummary>().getattr("from_bytes")?;
        Ok((from_bytes, (slf.get().to_bytes(py)?,)))
    }

    /// Repetition counts (what `loops.json` holds).
    #[getter]
    fn counts(&self) -> PyCounts {
        PyCounts::new(self.counts.clone(), self.people.clone(), self.person)
    }

    /// Every tracked person (empty for a track and the single-person
    /// pipeline): the dicts of `Counts.people`, `loops.json`'s `people` list.
    #[getter]
    fn people<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::programs::to_python(py, &serde_json::Value::Array(self.people.clone()))
    }

    /// The id of the person the top-level results follow, or None (a track,
    /// the single-person pipeline, nobody found).
    #[getter]
    fn person(&self) -> Option<PersonId> {
        self.person
    }

    /// Every tracked person's keypoints (`People`), or None (a track, the
    /// single-person pipeline).
    #[getter]
    fn tracked(&self) -> Option<PyPeople> {
        self.tracked.clone().map(PyPeople::new)
    }

    /// The concrete program of person `id` (over their own frames, from
    /// their `first_frame`; the main person's over the whole video), or
    /// None when they were not analysed.
    fn program_of(&self, id: PersonId) -> Option<PyProgram> {
        self.person_analysis(id).map(|a| PyProgram {
            inner: a.concrete.clone(),
        })
    }

    /// The abstract program of person `id` (see `program_of`), or None.
    fn abstract_program_of(&self, id: PersonId) -> Option<PyAbstract> {
        self.person_analysis(id)
            .map(|a| PyAbstract { inner: a.clone() })
    }

    /// The keypoints.
    #[getter]
    fn track(&self) -> PyTrack {
        PyTrack::new(self.track.clone())
    }

    /// The concrete program, or None.
    #[getter]
    fn program(&self) -> Option<PyProgram> {
        self.analysis.as_ref().map(|a| PyProgram {
            inner: a.concrete.clone(),
        })
    }

    /// The abstract program, or None.
    #[getter]
    fn abstract_program(&self) -> Option<PyAbstract> {
        self.analysis
            .as_ref()
            .map(|a| PyAbstract { inner: a.clone() })
    }

    /// The report page, or None.
    #[getter]
    fn report(&self) -> Option<PathBuf> {
        self.report.clone()
    }

    /// The output folder (None for an analysis that wrote nothing).
    #[getter]
    fn out_dir(&self) -> Option<PathBuf> {
        self.out_dir.clone()
    }

    /// Frames analysed.
    #[getter]
    fn frames(&self) -> usize {
        self.track.n_frames()
    }

    /// Files written, relative to the output folder.
    #[getter]
    fn files(&self) -> Vec<String> {
        self.files.clone()
    }

    /// Fraction of frames with a person.
    #[getter]
    fn person_found(&self) -> f64 {
        self.found_fraction
    }

    /// Time per stage: a list of (name, seconds, frames).
    #[getter]
    fn stages(&self) -> Vec<(String, f64, usize)> {
        self.stages.clone()
    }

    /// Wall time of the run, seconds.
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    fn __repr__(&self) -> String {
        format!(
            "Summary({} repetitions, {} files in {}, {:.2} s)",
            self.counts.total,
            self.files.len(),
            self.out_dir
                .as_ref()
                .map(|d| d.display().to_string())
                .unwrap_or_else(|| "no folder".into()),
            self.seconds
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
/// `pose_fps`: how often the pose model runs (a number of poses a second,
/// `"auto"` or `"all"`, the default), as `mp run --pose-fps`; `device`
/// where the pose model runs (`"auto"`, `"cpu"`, `"cuda"`, `"cuda:N"`), as
/// `mp run --device`. `params`: every other setting, as the dict of
/// `default_params()` (`mp params`), partial or whole; the keywords given
/// apply on top of it.
#[pyfunction]
#[pyo3(signature = (source, out_dir, model=None, threads=None, max_frames=None, all_joints=false, frame_size=None, overlay_video=None, report=None, person=None, max_people=None, single_person=false, pose_fps=None, device=None, params=None))]
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
    overlay_video: Option<bool>,
    report: Option<bool>,
    person: Option<&Bound<'_, PyAny>>,
    max_people: Option<usize>,
    single_person: bool,
    pose_fps: Option<&Bound<'_, PyAny>>,
    device: Option<&str>,
    params: Option<&Bound<'_, PyAny>>,
) -> PyResult<PySummary> {
    let params = run_params(
        params,
        (model, threads, max_frames, all_joints),
        (overlay_video, report),
        (person, max_people, single_person),
        pose_fps,
        device,
    )?;
    let input = input_of(source, frame_size)?;
    let dir = out_dir.clone();
    let s = py
        .detach(|| mp_pipeline::run(input, &dir, &params, &Silent, &CancelToken::new()))
        .map_err(errors::pipeline)?;
    Ok(PySummary::of_run(s, out_dir))
}

/// The parameters of `run`, `Analyser` and `batch`: `params` (the dict of
/// `default_params()`, partial or whole) with the keywords given on top —
/// the pose model `(model, threads, max_frames, all_joints)`, the outputs
/// `(overlay_video, report)`, the people `(person, max_people,
/// single_person)`, `pose_fps` and `device`.
pub(crate) fn run_params(
    params: Option<&Bound<'_, PyAny>>,
    (model, threads, max_frames, all_joints): (Option<&str>, Option<usize>, Option<usize>, bool),
    (overlay_video, report): (Option<bool>, Option<bool>),
    (person, max_people, single_person): (Option<&Bound<'_, PyAny>>, Option<usize>, bool),
    pose_fps: Option<&Bound<'_, PyAny>>,
    device: Option<&str>,
) -> PyResult<Params> {
    let mut params =
        crate::params_from(params, model, threads, max_frames, all_joints, None, None)?;
    crate::pose_rate_arg(&mut params, pose_fps)?;
    crate::device_arg(&mut params, device)?;
    output_args(&mut params, overlay_video, report);
    crate::people::apply(&mut params, person, max_people, single_person)?;
    Ok(params)
}

/// `overlay_video=` and `report=` where given.
fn output_args(params: &mut Params, overlay_video: Option<bool>, report: Option<bool>) {
    if let Some(v) = overlay_video {
        params.output.overlay_video = v;
    }
    if let Some(r) = report {
        params.output.report = r;
    }
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
/// input at a time (calls from several threads wait for each other). Its
/// options are `run`'s.
#[pyclass(name = "Analyser", module = "motion_programs", frozen)]
pub struct PyAnalyser {
    inner: Mutex<Analyser>,
}

#[pymethods]
impl PyAnalyser {
    #[new]
    #[pyo3(signature = (model=None, threads=None, max_frames=None, all_joints=false, overlay_video=None, report=None, person=None, max_people=None, single_person=false, pose_fps=None, device=None, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        model: Option<&str>,
        threads: Option<usize>,
        max_frames: Option<usize>,
        all_joints: bool,
        overlay_video: Option<bool>,
        report: Option<bool>,
        person: Option<&Bound<'_, PyAny>>,
        max_people: Option<usize>,
        single_person: bool,
        pose_fps: Option<&Bound<'_, PyAny>>,
        device: Option<&str>,
        params: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let params = run_params(
            params,
            (model, threads, max_frames, all_joints),
            (overlay_video, report),
            (person, max_people, single_person),
            pose_fps,
            device,
        )?;
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
        Ok(PySummary::of_outcome(outcome, None, Vec::new(), None))
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
        Ok(PySummary::of_run(s, out_dir))
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
    let sf: mp_grammar::SymbolsFile = serde_json::from_str(&text)
        .map_err(|e| errors::GrammarError::new_err(format!("not a symbols dict: {e}")))?;
    let mut p = mp_grammar::PartitionParams::default();
    if let Some(s) = seed {
        p.seed = s;
    }
    let g = py
        .detach(|| mp_grammar::learn_grammar(&sf, &p))
        .map_err(errors::grammar)?;
    let out = serde_json::to_string(&g).map_err(|e| errors::MpError::new_err(e.to_string()))?;
    json.getattr("loads")?.call1((out,))
}
