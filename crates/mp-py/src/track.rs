//! `Track`: keypoints as numpy arrays (`positions` T × J × D, `confidence`
//! T × J), with the frame rate, units and joint names.

use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array2, Array3};
use numpy::{AllowTypeChange, PyArray2, PyArray3, PyArrayLikeDyn, ToPyArray};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::errors;

/// Keypoints of one performer over time.
///
/// `positions` is a `T × J × D` float64 array (pixels or metres), `confidence`
/// a `T × J` array in [0, 1] (0: the joint is missing in that frame), `fps` the
/// frame rate, `joint_names` the J names, `skeleton` the skeleton's name
/// (`coco17`, `blazepose33`, `penn13`, `msr20`, `generic`, …) and `units`
/// `px`, `m` or `unitless`. Tracks pickle (through a compact binary form).
#[pyclass(name = "Track", module = "motion_programs", frozen)]
pub struct PyTrack {
    pub(crate) inner: Track,
}

impl PyTrack {
    pub(crate) fn new(inner: Track) -> Self {
        PyTrack { inner }
    }
}

fn skeleton_for(
    name: Option<&str>,
    joint_names: Option<Vec<String>>,
    j: usize,
) -> PyResult<Skeleton> {
    let sk = match name {
        Some(n) if n != "generic" => Skeleton::by_name(n).map_err(errors::geom)?,
        _ => Skeleton::generic(j),
    };
    match joint_names {
        Some(names) => {
            if names.len() != j {
                return Err(errors::TrackError::new_err(format!(
                    "joint_names has {} names, positions have {j} joints",
                    names.len()
                )));
            }
            if sk.name == "generic" {
                Ok(Skeleton {
                    joints: names,
                    ..sk
                })
            } else if sk.joints != names {
                Err(errors::TrackError::new_err(format!(
                    "joint_names differ from the joints of skeleton `{}`",
                    sk.name
                )))
            } else {
                Ok(sk)
            }
        }
        None => Ok(sk),
    }
}

#[pymethods]
impl PyTrack {
    /// Builds a track from numpy arrays or nested lists of any numeric type
    /// and memory layout (copied as float64): `positions` T × J × D
    /// (D = 2 or 3; any D for `units="unitless"`), `confidence` T × J
    /// (default: all 1; NaN positions become missing joints), `fps`,
    /// `skeleton` (a built-in name, default `generic`), `joint_names`,
    /// `units` (`px`, `m` or `unitless`).
    #[staticmethod]
    #[pyo3(signature = (positions, fps, confidence=None, skeleton=None, joint_names=None, units="px"))]
    fn from_numpy(
        positions: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        fps: f64,
        confidence: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        skeleton: Option<&str>,
        joint_names: Option<Vec<String>>,
        units: &str,
    ) -> PyResult<Self> {
        let p = positions.as_array();
        if p.ndim() != 3 {
            return Err(errors::TrackError::new_err(format!(
                "positions must be a T × J × D array, got {} dimensions {:?}",
                p.ndim(),
                p.shape()
            )));
        }
        let (t, j) = (p.shape()[0], p.shape()[1]);
        // Any memory layout (a transposed or sliced array) is copied into
        // the standard one.
        let pos: Array3<f64> = p
            .into_dimensionality::<ndarray::Ix3>()
            .map_err(|e| errors::TrackError::new_err(e.to_string()))?
            .as_standard_layout()
            .into_owned();
        let conf: Option<Array2<f64>> = match confidence {
            Some(c) => {
                let c = c.as_array();
                if c.shape() != [t, j] {
                    return Err(errors::TrackError::new_err(format!(
                        "confidence must be a T × J = {t} × {j} array, got {:?}",
                        c.shape()
                    )));
                }
                Some(
                    c.into_dimensionality::<ndarray::Ix2>()
                        .map_err(|e| errors::TrackError::new_err(e.to_string()))?
                        .as_standard_layout()
                        .into_owned(),
                )
            }
            None => None,
        };
        let units = if units == "unitless" {
            Units::Unitless
        } else {
            Units::parse(units).map_err(errors::geom)?
        };
        let sk = skeleton_for(skeleton, joint_names, j)?;
        Ok(PyTrack::new(
            Track::new(pos, conf, fps, units, sk).map_err(errors::geom)?,
        ))
    }

    /// Joint positions, a `T × J × D` float64 array: a read-only copy (a
    /// track does not change; `Track.from_numpy(positions.copy(), …)` makes
    /// a new one from edited positions).
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        read_only(self.inner.positions().to_pyarray(py))
    }

    /// Per-joint confidence, a `T × J` float64 array in [0, 1] (a read-only
    /// copy, as `positions`).
    #[getter]
    fn confidence<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        read_only(self.inner.confidence().to_pyarray(py))
    }

    /// Frames per second.
    #[getter]
    fn fps(&self) -> f64 {
        self.inner.fps()
    }

    /// Joint names, in storage order.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.inner.skeleton().joints.clone()
    }

    /// The skeleton's name.
    #[getter]
    fn skeleton(&self) -> String {
        self.inner.skeleton().name.clone()
    }

    /// `px`, `m` or `unitless`.
    #[getter]
    fn units(&self) -> &'static str {
        match self.inner.units() {
            Units::Unitless => "unitless",
            u => u.as_str(),
        }
    }

    /// Number of frames T.
    #[getter]
    fn n_frames(&self) -> usize {
        self.inner.n_frames()
    }

    /// Number of joints J.
    #[getter]
    fn n_joints(&self) -> usize {
        self.inner.n_joints()
    }

    /// Dimensions per joint D.
    #[getter]
    fn dims(&self) -> usize {
        self.inner.dims()
    }

    /// Frames `start..end` as a new track.
    fn slice(&self, start: usize, end: usize) -> PyResult<Self> {
        Ok(PyTrack::new(
            self.inner.slice_frames(start, end).map_err(errors::geom)?,
        ))
    }

    /// Writes the track; the format follows the extension (`.npz`, `.json`,
    /// `.csv`, `.mpt`, `.parquet`, `.pose`; `.bvh` and `.c3d` for 3D tracks
    /// in metres), through a temporary file and a rename.
    fn save(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        let t = &self.inner;
        py.detach(|| mp_geom::write_track(&path, t))
            .map_err(errors::geom)
    }

    /// The track in its compact binary form (the one it pickles through).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let b = mp_geom::track_to_bincode(&self.inner).map_err(errors::geom)?;
        Ok(PyBytes::new(py, &b))
    }

    /// A track from [`Track.to_bytes`]'s output.
    #[staticmethod]
    fn from_bytes(data: &[u8]) -> PyResult<Self> {
        Ok(PyTrack::new(
            mp_geom::track_from_bincode(data).map_err(errors::geom)?,
        ))
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let py = slf.py();
        let from_bytes = py.get_type::<PyTrack>().getattr("from_bytes")?;
        Ok((from_bytes, (slf.get().to_bytes(py)?,)))
    }

    fn __len__(&self) -> usize {
        self.inner.n_frames()
    }

    fn __repr__(&self) -> String {
        let t = &self.inner;
        format!(
            "Track({} frames × {} joints × {}D, {}, {}, {} fps)",
            t.n_frames(),
            t.n_joints(),
            t.dims(),
            t.skeleton().name,
            t.units().as_str(),
            t.fps()
        )
    }
}

/// The array with numpy's write flag cleared, so that an edit raises
/// instead of changing a copy nobody reads.
fn read_only<T>(a: Bound<'_, T>) -> PyResult<Bound<'_, T>> {
    a.as_any().call_method1("setflags", (false,))?;
    Ok(a)
}

/// Issues a Python `UserWarning`.
pub(crate) fn warn(py: Python<'_>, msg: &str) -> PyResult<()> {
    let msg = std::ffi::CString::new(msg)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    PyErr::warn(
        py,
        &py.get_type::<pyo3::exceptions::PyUserWarning>(),
        &msg,
        1,
    )
}

/// Reads a track file at `fps` (over what it states), warning when 30 fps
/// is assumed; with the frame size the file states.
pub(crate) fn read_track_file(
    py: Python<'_>,
    path: &std::path::Path,
    fps: Option<f64>,
) -> PyResult<mp_geom::TrackRead> {
    let opts = mp_geom::ReadOptions {
        fps,
        ..Default::default()
    };
    let read = py
        .detach(|| mp_geom::read_track_rated(path, &opts))
        .map_err(errors::geom)?;
    if read.rate == mp_geom::RateSource::Assumed {
        warn(
            py,
            &format!(
                "{} states no frame rate: {} fps assumed (pass fps=)",
                path.display(),
                mp_geom::DEFAULT_FPS
            ),
        )?;
    }
    Ok(read)
}

/// What the functions that take a track accept: a `Track`, the path of a
/// track file, or a T × J × D array (30 fps assumed, with a warning). A
/// video's path gets advice (`extract` first).
pub(crate) fn track_arg(obj: &Bound<'_, PyAny>, func: &str) -> PyResult<Track> {
    track_arg_framed(obj, func).map(|(t, _)| t)
}

/// [`track_arg`] with the video frame (width, height) a track file states.
pub(crate) fn track_arg_framed(
    obj: &Bound<'_, PyAny>,
    func: &str,
) -> PyResult<(Track, Option<(usize, usize)>)> {
    let py = obj.py();
    if let Ok(t) = obj.cast::<PyTrack>() {
        return Ok((t.get().inner.clone(), None));
    }
    if let Ok(path) = obj.extract::<std::path::PathBuf>() {
        if mp_pipeline::Input::is_video(&path) {
            return Err(errors::ParamError::new_err(format!(
                "{func}() takes a track; {} is a video: extract(video) reads its keypoints",
                path.display()
            )));
        }
        let read = read_track_file(py, &path, None)?;
        return Ok((read.track, read.frame_size));
    }
    if let Ok(a) = obj.extract::<PyArrayLikeDyn<'_, f64, AllowTypeChange>>() {
        warn(
            py,
            &format!(
                "{func}(): an array states no frame rate: {} fps assumed (Track.from_numpy(a, fps) \
                 gives one)",
                mp_geom::DEFAULT_FPS
            ),
        )?;
        let t = PyTrack::from_numpy(a, mp_geom::DEFAULT_FPS, None, None, None, "px")?;
        return Ok((t.inner, None));
    }
    Err(errors::ParamError::new_err(format!(
        "{func}() takes a Track, the path of a track file or a T × J × D array, got {}",
        obj.get_type().name()?
    )))
}
