//! `People` and `Person`: several tracked people in one video, each with a
//! steady id (1, 2, …) and a track over their own frames; and the keyword
//! arguments that choose whom a video's analysis follows.

use mp_geom::{People, Person, PersonId};
use mp_pipeline::{Params, PersonChoice};
use pyo3::exceptions::PyKeyError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyIterator, PyList};

use crate::errors;
use crate::track::PyTrack;

/// One tracked person: `id`, `first_frame` and `last_frame` (video frames,
/// inclusive), `frames_found`, `box` (the mean box `(x0, y0, x1, y1)` of the
/// joints found, pixels; None if never found) and `track` (the person's
/// keypoints over their own frames, `first_frame ..= last_frame`;
/// confidence 0 where they were not found).
#[pyclass(name = "Person", module = "motion_programs", frozen)]
pub struct PyPerson {
    inner: Person,
}

/// What a person pickles through: id, first frame, track bytes.
type PersonState<'py> = (PersonId, usize, Bound<'py, PyBytes>);

#[pymethods]
impl PyPerson {
    /// The person's id (1, 2, … in order of appearance).
    #[getter]
    fn id(&self) -> PersonId {
        self.inner.id
    }

    /// Video frame of the track's first frame.
    #[getter]
    fn first_frame(&self) -> usize {
        self.inner.first_frame
    }

    /// Video frame of the track's last frame (inclusive).
    #[getter]
    fn last_frame(&self) -> usize {
        self.inner.last_frame()
    }

    /// Frames of the person's span where they were found.
    #[getter]
    fn frames_found(&self) -> usize {
        self.inner.frames_found()
    }

    /// The mean box `(x0, y0, x1, y1)` of the joints found, or None.
    #[getter]
    #[pyo3(name = "box")]
    fn mean_box(&self) -> Option<(f64, f64, f64, f64)> {
        self.inner.mean_box().map(|[a, b, c, d]| (a, b, c, d))
    }

    /// The box `(x0, y0, x1, y1)` at video frame `frame`, or None where the
    /// person was not found (or the frame lies outside their span).
    fn box_at(&self, frame: usize) -> Option<(f64, f64, f64, f64)> {
        self.inner.box_at(frame).map(|[a, b, c, d]| (a, b, c, d))
    }

    /// The keypoints over the person's own frames (a copy).
    #[getter]
    fn track(&self) -> PyTrack {
        PyTrack::new(self.inner.track.clone())
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }

    /// A person from its pickled state (id, first frame, track bytes).
    #[staticmethod]
    fn _from_state(id: PersonId, first_frame: usize, track: &[u8]) -> PyResult<Self> {
        Ok(PyPerson {
            inner: Person {
                id,
                first_frame,
                track: mp_geom::track_from_bincode(track).map_err(errors::geom)?,
            },
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, PersonState<'py>)> {
        let py = slf.py();
        let p = &slf.get().inner;
        let track = mp_geom::track_to_bincode(&p.track).map_err(errors::geom)?;
        let from_state = py.get_type::<PyPerson>().getattr("_from_state")?;
        Ok((from_state, (p.id, p.first_frame, PyBytes::new(py, &track))))
    }

    fn __repr__(&self) -> String {
        let p = &self.inner;
        format!(
            "Person(id={}, frames {}–{}, found on {} frames)",
            p.id,
            p.first_frame,
            p.last_frame(),
            p.frames_found()
        )
    }
}

/// The people tracked in one video: `len(people)` people, iterated as
/// `Person`s in id order; `people[id]` (KeyError when there is no such
/// person) or `people.get(id)`; `ids`, `main` (the main person's id: the
/// one seen longest and largest; None when nobody was found), `n_frames`
/// and `fps` of the video; `track(id)` and `main_track()` give a person's
/// track over the whole video. People pickle (through a compact binary form)
/// and are written with `save` (`.npz`, `.json`, `.mpt`).
#[pyclass(name = "People", module = "motion_programs", frozen)]
pub struct PyPeople {
    pub(crate) inner: People,
}

impl PyPeople {
    pub(crate) fn new(inner: People) -> Self {
        PyPeople { inner }
    }

    fn person(&self, id: i64) -> Option<&Person> {
        PersonId::try_from(id)
            .ok()
            .and_then(|id| self.inner.get(id))
    }
}

fn no_person(id: i64, people: &People) -> PyErr {
    let ids: Vec<String> = people.people().iter().map(|p| p.id.to_string()).collect();
    PyKeyError::new_err(if ids.is_empty() {
        format!("there is no person {id}: nobody was tracked")
    } else {
        format!("there is no person {id}; the people are {}", ids.join(", "))
    })
}

#[pymethods]
impl PyPeople {
    /// The people's ids, in increasing order.
    #[getter]
    fn ids(&self) -> Vec<PersonId> {
        self.inner.people().iter().map(|p| p.id).collect()
    }

    /// The main person's id (seen longest and largest), or None when
    /// nobody was tracked.
    #[getter]
    fn main(&self) -> Option<PersonId> {
        self.inner.main_person().map(|p| p.id)
    }

    /// Frames of the video.
    #[getter]
    fn n_frames(&self) -> usize {
        self.inner.n_frames()
    }

    /// Frames per second of the video (and of every track).
    #[getter]
    fn fps(&self) -> f64 {
        self.inner.fps()
    }

    /// Person `id`, or `default` when there is none.
    #[pyo3(signature = (id, default=None))]
    fn get<'py>(
        &self,
        py: Python<'py>,
        id: i64,
        default: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        match self.person(id) {
            Some(p) => Ok(Bound::new(py, PyPerson { inner: p.clone() })?.into_any()),
            None => Ok(default.unwrap_or_else(|| py.None().into_bound(py))),
        }
    }

    /// Person `id`'s track over the whole video (`n_frames` frames):
    /// confidence 0 outside their span. KeyError when there is no such person.
    fn track(&self, py: Python<'_>, id: i64) -> PyResult<PyTrack> {
        let Some(p) = self.person(id) else {
            return Err(no_person(id, &self.inner));
        };
        let (people, pid) = (&self.inner, p.id);
        let t = py.detach(|| people.full_track(pid)).map_err(errors::geom)?;
        Ok(PyTrack::new(t))
    }

    /// The main person's track over the whole video; TrackError when nobody
    /// was tracked.
    fn main_track(&self, py: Python<'_>) -> PyResult<PyTrack> {
        let people = &self.inner;
        let t = py.detach(|| people.main_track()).map_err(errors::geom)?;
        Ok(PyTrack::new(t))
    }

    /// Writes the people; the format follows the extension (`.npz` with a
    /// person axis, `.json`, `.mpt`, `.parquet` with a `person` column,
    /// `.pose`), through a temporary file and a rename.
    fn save(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        let p = &self.inner;
        py.detach(|| mp_geom::write_people(&path, p))
            .map_err(errors::geom)
    }

    /// The people in their compact binary form (the one they pickle through).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let b = mp_geom::people_to_bincode(&self.inner).map_err(errors::geom)?;
        Ok(PyBytes::new(py, &b))
    }

    /// People from [`People.to_bytes`]'s output.
    #[staticmethod]
    fn from_bytes(data: &[u8]) -> PyResult<Self> {
        Ok(PyPeople::new(
            mp_geom::people_from_bincode(data).map_err(errors::geom)?,
        ))
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let py = slf.py();
        let from_bytes = py.get_type::<PyPeople>().getattr("from_bytes")?;
        Ok((from_bytes, (slf.get().to_bytes(py)?,)))
    }

    fn __getitem__(&self, id: i64) -> PyResult<PyPerson> {
        match self.person(id) {
            Some(p) => Ok(PyPerson { inner: p.clone() }),
            None => Err(no_person(id, &self.inner)),
        }
    }

    fn __contains__(&self, id: &Bound<'_, PyAny>) -> bool {
        !id.is_instance_of::<PyBool>()
            && id.extract::<i64>().is_ok_and(|i| self.person(i).is_some())
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyIterator>> {
        let people = self
            .inner
            .people()
            .iter()
            .map(|p| PyPerson { inner: p.clone() });
        PyList::new(py, people)?.into_any().try_iter()
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }

    fn __repr__(&self) -> String {
        let p = &self.inner;
        format!(
            "People({} {}, ids {:?}, main {}, {} frames, {} fps)",
            p.len(),
            if p.len() == 1 { "person" } else { "people" },
            self.ids(),
            p.main_person()
                .map_or_else(|| "None".to_string(), |m| m.id.to_string()),
            p.n_frames(),
            p.fps()
        )
    }
}

/// Reads the people of a video: a people file (`.npz` with a person axis,
/// `.json`, `.mpt`, a Parquet table with a `person` column, a `.pose` file
/// with several people), or any track file as one person (id 1) over the
/// whole track.
#[pyfunction]
pub fn read_people(py: Python<'_>, path: std::path::PathBuf) -> PyResult<PyPeople> {
    let p = py
        .detach(|| mp_geom::read_people(&path))
        .map_err(errors::geom)?;
    Ok(PyPeople::new(p))
}

/// Whose motion is analysed: `"all"`, `"main"` or a person's id.
fn person_choice(person: &Bound<'_, PyAny>) -> PyResult<PersonChoice> {
    let bad = || {
        errors::ParamError::new_err(format!(
            "person must be \"all\", \"main\" or a person's id (1, 2, …), got {}",
            person
                .repr()
                .map_or_else(|_| "?".to_string(), |r| r.to_string())
        ))
    };
    if person.is_instance_of::<PyBool>() {
        return Err(bad());
    }
    if let Ok(s) = person.extract::<String>() {
        return PersonChoice::parse(&s).map_err(errors::pipeline);
    }
    match person.extract::<i64>() {
        Ok(i) => match PersonId::try_from(i) {
            Ok(id) if id > 0 => Ok(PersonChoice::Id(id)),
            _ => Err(bad()),
        },
        Err(_) => Err(bad()),
    }
}

/// Sets the several-people options of a Python call on `params`: `person`
/// (`"all"`, `"main"` or an id; default all), `max_people` (the most people
/// tracked at once) and `single_person` (MediaPipe's single-person pipeline
/// instead of the tracker), as `mp run --person --max-people --single-person`.
pub(crate) fn apply(
    params: &mut Params,
    person: Option<&Bound<'_, PyAny>>,
    max_people: Option<usize>,
    single_person: bool,
) -> PyResult<()> {
    if let Some(p) = person {
        params.person.choice = person_choice(p)?;
    }
    if let Some(m) = max_people {
        params.pose.tracker.max_people = m;
    }
    if single_person {
        params.pose.people = false;
    }
    params.validate().map_err(errors::pipeline)
}
