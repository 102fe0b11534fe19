//! `batch`: many inputs into their own folders, as `mp batch`.

use std::path::PathBuf;

use mp_geom::CancelToken;
use mp_pipeline::{batch_items, BatchParams, BatchSummary, SharedModel, Silent};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors;
use crate::programs::to_python;

/// Runs every input into its own folder under `out_dir`, as `mp batch`:
/// `inputs` is a folder (its videos and track files), a text file listing
/// inputs one per line, or a list of paths. `jobs` inputs run at once, each
/// pose model with `threads` ONNX Runtime threads (default: the cores
/// divided by the jobs); `shared_model` (`"auto"`, `"always"`, `"never"`)
/// whether the jobs share one landmark model (on a GPU, by default). The
/// other options are `run`'s; `frame_size` and `fps` apply to track files.
/// `out_dir/manifest.jsonl` gets a line per finished input, and an input
/// complete from an earlier batch is skipped, so a batch that stopped runs
/// on where it left off.
///
/// Returns a dict: `ok`, `failed`, `skipped`, `wall_s`, `jobs`,
/// `threads_per_item`, `shared_model` (crops and runs, or `None`),
/// `manifest`, and `items`, one dict per input in input order (the
/// manifest's lines: `input`, `output`, `status`, `error`, `frames`,
/// `seconds`, `total_repetitions`, …). A failed input does not stop the
/// others; it says `failed` with its error.
#[pyfunction]
#[pyo3(signature = (inputs, out_dir, jobs=1, threads=None, shared_model="auto", model=None, max_frames=None, all_joints=false, frame_size=None, fps=None, overlay_video=None, report=None, person=None, max_people=None, single_person=false, pose_fps=None, device=None, params=None))]
#[allow(clippy::too_many_arguments)]
pub fn batch<'py>(
    py: Python<'py>,
    inputs: &Bound<'py, PyAny>,
    out_dir: PathBuf,
    jobs: usize,
    threads: Option<usize>,
    shared_model: &str,
    model: Option<&str>,
    max_frames: Option<usize>,
    all_joints: bool,
    frame_size: Option<f64>,
    fps: Option<f64>,
    overlay_video: Option<bool>,
    report: Option<bool>,
    person: Option<&Bound<'py, PyAny>>,
    max_people: Option<usize>,
    single_person: bool,
    pose_fps: Option<&Bound<'py, PyAny>>,
    device: Option<&str>,
    params: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let run_params = crate::run::run_params(
        params,
        (model, None, max_frames, all_joints),
        (overlay_video, report),
        (person, max_people, single_person),
        pose_fps,
        device,
    )?;
    let items = items_of(inputs)?;
    let bp = BatchParams {
        jobs,
        threads,
        frame_px: frame_size,
        fps,
        params: run_params,
        shared_model: SharedModel::parse(shared_model).map_err(errors::batch)?,
    };
    let summary = py
        .detach(|| mp_pipeline::batch(&items, &out_dir, &bp, &Silent, &CancelToken::new()))
        .map_err(errors::batch)?;
    summary_dict(py, &summary)
}

/// The inputs a Python call names: a folder or list file, or a list of paths.
fn items_of(inputs: &Bound<'_, PyAny>) -> PyResult<Vec<PathBuf>> {
    if let Ok(list) = inputs.cast::<PyList>() {
        return list
            .iter()
            .map(|p| {
                p.extract::<PathBuf>()
                    .map_err(|_| errors::ParamError::new_err(format!("inputs: {p} is not a path")))
            })
            .collect();
    }
    let path: PathBuf = inputs.extract().map_err(|_| {
        errors::ParamError::new_err("inputs: expected a folder, a list file or a list of paths")
    })?;
    batch_items(&path).map_err(errors::batch)
}

/// What a batch did, as a dict.
fn summary_dict<'py>(py: Python<'py>, s: &BatchSummary) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    d.set_item("ok", s.ok())?;
    d.set_item("failed", s.failed())?;
    d.set_item("skipped", s.skipped())?;
    d.set_item("wall_s", s.wall.as_secs_f64())?;
    d.set_item("jobs", s.jobs)?;
    d.set_item("threads_per_item", s.threads_per_item)?;
    let shared = match s.shared_model {
        Some(m) => {
            let x = PyDict::new(py);
            x.set_item("requests", m.requests)?;
            x.set_item("crops", m.crops)?;
            x.set_item("runs", m.runs)?;
            x.into_any()
        }
        None => py.None().into_bound(py),
    };
    d.set_item("shared_model", shared)?;
    d.set_item("manifest", s.manifest.to_string_lossy())?;
    let items =
        serde_json::to_value(&s.items).map_err(|e| errors::MpError::new_err(e.to_string()))?;
    d.set_item("items", to_python(py, &items)?)?;
    Ok(d.into_any())
}
