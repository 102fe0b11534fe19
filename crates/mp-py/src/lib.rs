//! # motion_programs — the Python package of `mp`
//!
//! A thin layer over the libraries: every function calls the same library
//! function as the `mp` command that does the same job, with the same
//! defaults (`mp_pipeline::Params::default()`), releases the GIL while Rust
//! works, and raises the library's errors as Python exceptions (one type
//! per error family, all deriving from `MpError`). Build it with
//! `maturin build` (see `crates/mp-py/pyproject.toml`).

mod batch;
mod errors;
mod live;
mod people;
mod programs;
mod run;
mod track;

use std::path::PathBuf;

use mp_geom::CancelToken;
use mp_pipeline::{Input, Params, Silent};
use pyo3::prelude::*;

use people::PyPeople;
use programs::{PyAbstract, PyCounts, PyProgram};
use track::PyTrack;

/// The pipeline's parameters with the options a Python call gave.
#[allow(clippy::too_many_arguments)]
pub(crate) fn params_with(
    model: Option<&str>,
    threads: Option<usize>,
    max_frames: Option<usize>,
    all_joints: bool,
    lambda_: Option<f64>,
    max_segment_frames: Option<usize>,
) -> PyResult<Params> {
    params_from(
        None,
        model,
        threads,
        max_frames,
        all_joints,
        lambda_,
        max_segment_frames,
    )
}

/// The parameters of a dict (`params=`, the JSON form of
/// `mp_pipeline::Params`: a partial dict changes only what it names), or
/// the defaults; the keyword arguments given on top.
pub(crate) fn base_params(params: Option<&Bound<'_, PyAny>>) -> PyResult<Params> {
    let Some(d) = params else {
        return Ok(Params::default());
    };
    let json = d.py().import("json")?;
    let text: String = json
        .call_method1("dumps", (d,))
        .map_err(|e| errors::ParamError::new_err(format!("params: not JSON-like: {e}")))?
        .extract()?;
    Params::from_json(&text).map_err(errors::pipeline)
}

/// [`params_with`] on top of [`base_params`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn params_from(
    base: Option<&Bound<'_, PyAny>>,
    model: Option<&str>,
    threads: Option<usize>,
    max_frames: Option<usize>,
    all_joints: bool,
    lambda_: Option<f64>,
    max_segment_frames: Option<usize>,
) -> PyResult<Params> {
    let mut p = base_params(base)?;
    if let Some(m) = model {
        p.pose.model = mp_pose_model(m)?;
    }
    if let Some(t) = threads {
        p.pose.threads = t;
    }
    if max_frames.is_some() {
        p.pose.max_frames = max_frames;
    }
    if all_joints {
        p.pose.all_joints = true;
    }
    if let Some(l) = lambda_ {
        p.analysis.synth.lambda = mp_concrete::Lambda::fixed(l);
    }
    if let Some(w) = max_segment_frames {
        p.analysis.synth.max_segment_frames = w;
    }
    p.validate().map_err(errors::pipeline)?;
    Ok(p)
}

/// Sets `params.pose.rate` from a Python `pose_fps`: a number of poses a
/// second, `"auto"` or `"all"` (None: the library's default).
pub(crate) fn pose_rate_arg(
    params: &mut Params,
    pose_fps: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let Some(v) = pose_fps else {
        return Ok(());
    };
    let rate = if let Ok(text) = v.extract::<String>() {
        mp_pipeline::PoseRate::parse(&text)
    } else if let Ok(n) = v.extract::<f64>() {
        let r = mp_pipeline::PoseRate::Fps(n);
        r.validate().map(|_| r)
    } else {
        return Err(errors::ParamError::new_err(
            "pose_fps: expected a number of poses a second, \"auto\" or \"all\"",
        ));
    };
    params.pose.rate = rate.map_err(errors::pipeline)?;
    Ok(())
}

/// Sets `params.pose.device` from a Python `device` (`"auto"`, `"cpu"`,
/// `"cuda"`, `"cuda:N"`; None: the library's default).
pub(crate) fn device_arg(params: &mut Params, device: Option<&str>) -> PyResult<()> {
    if let Some(d) = device {
        params.pose.device =
            mp_pose::Device::parse(d).map_err(|e| errors::ParamError::new_err(e.to_string()))?;
    }
    Ok(())
}

fn mp_pose_model(name: &str) -> PyResult<mp_pose::ModelChoice> {
    mp_pose::ModelChoice::parse(name).map_err(|e| errors::ParamError::new_err(e.to_string()))
}

/// Reads a keypoint track: the project's `.npz`/`.json`/`.mpt`, CSV, `.npy`,
/// BVH, C3D, Parquet, pose-format `.pose`, OpenPose folders. `fps`: the frame
/// rate, over what the file states; by default the file's (a CSV or Parquet
/// `time` column, the project's formats, BVH, C3D, `.pose`),
/// and 30 with a `UserWarning` for a file that states none.
#[pyfunction]
#[pyo3(signature = (path, fps = None))]
fn read_track(py: Python<'_>, path: PathBuf, fps: Option<f64>) -> PyResult<PyTrack> {
    Ok(PyTrack::new(track::read_track_file(py, &path, fps)?.track))
}

/// Every setting of a run as a dict (what `mp params` prints): change
/// any part of it and pass it as `params=` to `run` or `Analyser`.
#[pyfunction]
fn default_params(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let text = Params::default().to_json().map_err(errors::pipeline)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Keypoints of a video or a still image, as `mp extract` makes them (the
/// same library call, `mp_pipeline::extract`; COCO-17 joints unless
/// `all_joints`): BlazePose `full` (default), `lite`, or `movenet`.
/// `recover_s` (BlazePose): after the tracked person is lost, the seconds
/// during which the region of the last pose is tried again (default 0,
/// MediaPipe's tracking). Every person in view of a video is tracked (at
/// most `max_people` at once) unless `single_person` (MediaPipe's
/// single-person pipeline); the `Track` returned is the main person's over
/// the whole video, or with `people=True` every tracked person, as `People`.
/// `world=True`: BlazePose's world landmarks instead (metres, hip-centred,
/// 3D, all 33; as `mp extract --world`), the input of `refine`. `pose_fps`:
/// how often the pose model runs, a number of poses a second, `"auto"` (12 a
/// second) or `"all"` (default); the frames between are filled from the
/// motion (as `mp extract --pose-fps`). `device`: where the pose model runs,
/// `"auto"` (default: the GPU where ONNX Runtime's CUDA build and a GPU are
/// there), `"cpu"`, `"cuda"` or `"cuda:N"`. `smooth=True`: One-Euro
/// smoothing of the keypoints (MediaPipe's `smooth_landmarks`, `mp extract
/// --smooth`).
#[pyfunction]
#[pyo3(signature = (video, model="full", max_frames=None, threads=None, all_joints=false, recover_s=None, people=false, max_people=None, single_person=false, world=false, pose_fps=None, device=None, smooth=false))]
#[allow(clippy::too_many_arguments)]
fn extract<'py>(
    py: Python<'py>,
    video: PathBuf,
    model: &str,
    max_frames: Option<usize>,
    threads: Option<usize>,
    all_joints: bool,
    recover_s: Option<f64>,
    people: bool,
    max_people: Option<usize>,
    single_person: bool,
    world: bool,
    pose_fps: Option<&Bound<'py, PyAny>>,
    device: Option<&str>,
    smooth: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let mut params = params_with(Some(model), threads, max_frames, all_joints, None, None)?;
    pose_rate_arg(&mut params, pose_fps)?;
    device_arg(&mut params, device)?;
    if let Some(r) = recover_s {
        params.pose.recover_s = r;
    }
    people::apply(&mut params, None, max_people, single_person)?;
    if world && people {
        return Err(errors::ParamError::new_err(
            "world=True follows one person (MediaPipe's world landmarks); people=True needs \
             image coordinates",
        ));
    }
    if people && (single_person || params.pose.model.landmark_model().is_none()) {
        return Err(errors::ParamError::new_err(
            "people=True needs the people tracker: a BlazePose model (full, lite or heavy) \
             without single_person",
        ));
    }
    let what = if world {
        mp_pipeline::ExtractParams::world(smooth)
    } else {
        mp_pipeline::ExtractParams::pixels(smooth)
    };
    let ex = py
        .detach(|| mp_pipeline::extract(&video, &params, what, &Silent, &CancelToken::new()))
        .map_err(errors::pipeline)?;
    if people {
        let p = match ex.poses {
            mp_pipeline::ExtractedPoses::People(p) => p,
            mp_pipeline::ExtractedPoses::One(t) => {
                mp_geom::People::from_track(t).map_err(errors::geom)?
            }
            _ => return Err(errors::PoseError::new_err("no keypoints were extracted")),
        };
        return Ok(Bound::new(py, PyPeople::new(p))?.into_any());
    }
    let track = ex.main_track().map_err(errors::pipeline)?;
    Ok(Bound::new(py, PyTrack::new(track))?.into_any())
}

/// The concrete program of a track (as `mp fit`): `frame_size` is the
/// largest side of the video frame in pixels (default: the motion's own
/// extent sets the scale), `lambda_` a fixed segment penalty at the 512-px
/// reference (default: the local spread held for one second), `max_segment_frames` the longest segment,
/// `continuity` `"c0"` (consecutive segments share their boundary pose) or
/// `"none"` (segments fitted independently; default: the library's, C0),
/// `budget` a parameter budget instead of `lambda_`: the most accurate program
/// with at most this share of the track's numbers (T·J·D), e.g. 0.1;
/// `kinds` the primitive kinds segments may use (default: stationary, line,
/// circle; `"spline"` adds cubics), `quadratic_angle` circles with an
/// angular acceleration, `refit_norm` what the C0 refit minimises
/// (`"squared"` residuals or their `"euclidean"` lengths, the default),
/// `lambda_spread` λ from the local spread held for this many seconds
/// (default 1; as `mp fit --lambda-spread`).
#[pyfunction]
#[pyo3(signature = (track, frame_size=None, lambda_=None, max_segment_frames=None, continuity=None, budget=None, kinds=None, quadratic_angle=false, refit_norm=None, lambda_spread=None))]
#[allow(clippy::too_many_arguments)]
fn fit(
    py: Python<'_>,
    track: &Bound<'_, PyAny>,
    frame_size: Option<f64>,
    lambda_: Option<f64>,
    max_segment_frames: Option<usize>,
    continuity: Option<&str>,
    budget: Option<f64>,
    kinds: Option<Vec<String>>,
    quadratic_angle: bool,
    refit_norm: Option<&str>,
    lambda_spread: Option<f64>,
) -> PyResult<PyProgram> {
    let parse = |what: &str, e: String| errors::ParamError::new_err(format!("{what}: {e}"));
    let options = mp_pipeline::FitOptions {
        lambda: lambda_,
        budget,
        lambda_spread,
        max_segment_frames,
        continuity: continuity
            .map(|c| c.parse::<mp_concrete::Continuity>())
            .transpose()
            .map_err(|e| parse("continuity", e))?,
        refit_norm: refit_norm
            .map(|n| n.parse::<mp_concrete::RefitNorm>())
            .transpose()
            .map_err(|e| parse("refit_norm", e))?,
        kinds: kinds
            .map(|k| {
                k.iter()
                    .map(|s| s.parse::<mp_geom::PrimitiveKind>())
                    .collect::<Result<Vec<_>, _>>()
            })
            .transpose()
            .map_err(|e| parse("kinds", e))?,
        quadratic_angle,
        strict_joints: false,
    };
    let params = options.params().map_err(errors::pipeline)?;
    let (t, frame) = track::track_arg_framed(track, "fit")?;
    let t = &t;
    // A track file that states its video frame (`mp run`'s and `mp
    // extract`'s npz) is fitted at that scale, as `mp fit` does.
    let frame_size = frame_size.or(frame.map(|(w, h)| w.max(h) as f64));
    let syn = py
        .detach(|| mp_pipeline::concrete_program(t, frame_size, &params))
        .map_err(errors::pipeline)?;
    Ok(PyProgram { inner: syn.program })
}

/// The abstract program of a track (as `mp abstract`).
#[pyfunction(name = "abstract")]
#[pyo3(signature = (track, frame_size=None))]
fn abstract_program(
    py: Python<'_>,
    track: &PyTrack,
    frame_size: Option<f64>,
) -> PyResult<PyAbstract> {
    let params = Params::default();
    let t = &track.inner;
    let an = py
        .detach(|| mp_pipeline::analyse_track(t, frame_size, &params))
        .map_err(errors::pipeline)?;
    Ok(PyAbstract { inner: an })
}

/// Repetition counts (as `mp loops` and `mp run`): of a `Track` (from its
/// keypoints), or of a video or track file given by its path (a video is
/// decoded and run through the pose model, and its frames are read too).
/// For a video, every person in view is tracked (at most `max_people` at
/// once; `single_person`: MediaPipe's single-person pipeline) and `person`
/// chooses whose counts are the top-level ones: `"all"` (default: the main
/// person's, and everyone seen long enough gets their own in
/// `Counts.people`), `"main"` or a person's id.
#[pyfunction]
#[pyo3(signature = (source, thumbnails=None, person=None, max_people=None, single_person=false))]
fn count(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    thumbnails: Option<&PyTrack>,
    person: Option<&Bound<'_, PyAny>>,
    max_people: Option<usize>,
    single_person: bool,
) -> PyResult<PyCounts> {
    let mut params = Params::default();
    people::apply(&mut params, person, max_people, single_person)?;
    if let Ok(t) = source.cast::<PyTrack>() {
        let t = &t.get().inner;
        let th = thumbnails.map(|x| &x.inner);
        let c = py
            .detach(|| mp_pipeline::count(t, th, &params))
            .map_err(errors::pipeline)?;
        return Ok(PyCounts::of_counts(c));
    }
    let Ok(path) = source.extract::<PathBuf>() else {
        // An array (or anything else a track is made from).
        let t = track::track_arg(source, "count")?;
        let th = thumbnails.map(|x| &x.inner);
        let c = py
            .detach(|| mp_pipeline::count(&t, th, &params))
            .map_err(errors::pipeline)?;
        return Ok(PyCounts::of_counts(c));
    };
    let out = py
        .detach(|| {
            let input = Input::open(&path, None)?;
            mp_pipeline::analyse_input(input, &params, &Silent, &CancelToken::new())
        })
        .map_err(errors::pipeline)?;
    Ok(PyCounts::of_outcome(&out))
}

/// The future of a track (as `mp predict`): `horizon` frames after its
/// first `observe` frames (default: all of them). `method`: `loop`
/// (unrolling the last loop; default), `constant`, `nn`, `ar`, `ar-pose`.
/// Returns the predicted frames as a `Track` and a line saying which path
/// was taken (or None).
#[pyfunction]
#[pyo3(signature = (track, horizon, method="loop", observe=None, models=None, train=None))]
fn predict(
    py: Python<'_>,
    track: &Bound<'_, PyAny>,
    horizon: usize,
    method: &str,
    observe: Option<usize>,
    models: Option<PathBuf>,
    train: Option<PathBuf>,
) -> PyResult<(PyTrack, Option<String>)> {
    let m: mp_forecast::ForecastMethod = method
        .parse()
        .map_err(|e: mp_forecast::ForecastError| errors::ParamError::new_err(e.to_string()))?;
    let opts = mp_forecast::PredictOptions {
        models,
        train,
        ..mp_forecast::PredictOptions::with_method(m)
    };
    let t = &track::track_arg(track, "predict")?;
    let observe = observe.unwrap_or(t.n_frames());
    let p = py
        .detach(|| mp_forecast::forecast(t, observe, horizon, &opts))
        .map_err(errors::forecast)?;
    let why = p.explanation();
    Ok((PyTrack::new(p.track), why))
}

/// Learned refinement of a 3D track (as `mp refine`): MSR Action3D's 20
/// joints, or BlazePose world landmarks (`extract(video, world=True)`),
/// mapped onto the networks' joints and back. `action` (1–20) skips action recognition.
#[pyfunction]
#[pyo3(signature = (track, action=None, models=None, concepts=None))]
fn refine(
    py: Python<'_>,
    track: &Bound<'_, PyAny>,
    action: Option<u32>,
    models: Option<PathBuf>,
    concepts: Option<PathBuf>,
) -> PyResult<PyTrack> {
    let opts = mp_refine::RefineOptions {
        models,
        concepts,
        action,
        ..mp_refine::RefineOptions::default()
    };
    let t = &track::track_arg(track, "refine")?;
    let r = py
        .detach(|| mp_refine::refine_default(t, &opts))
        .map_err(errors::refine)?;
    Ok(PyTrack::new(r.track))
}

/// The Python module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_class::<PyTrack>()?;
    m.add_class::<PyPeople>()?;
    m.add_class::<people::PyPerson>()?;
    m.add_class::<PyProgram>()?;
    m.add_class::<PyAbstract>()?;
    m.add_class::<PyCounts>()?;
    m.add_class::<run::PySummary>()?;
    m.add_class::<run::PyAnalyser>()?;
    m.add_class::<live::PyLive>()?;
    m.add_function(wrap_pyfunction!(read_track, m)?)?;
    m.add_function(wrap_pyfunction!(people::read_people, m)?)?;
    m.add_function(wrap_pyfunction!(extract, m)?)?;
    m.add_function(wrap_pyfunction!(default_params, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(abstract_program, m)?)?;
    m.add_function(wrap_pyfunction!(count, m)?)?;
    m.add_function(wrap_pyfunction!(predict, m)?)?;
    m.add_function(wrap_pyfunction!(refine, m)?)?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch, m)?)?;
    m.add_function(wrap_pyfunction!(live::live, m)?)?;
    m.add_function(wrap_pyfunction!(run::grammar_symbols, m)?)?;
    m.add_function(wrap_pyfunction!(run::grammar_learn, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
