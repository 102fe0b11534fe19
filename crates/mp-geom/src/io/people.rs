//! The project's formats for several tracked people ([`People`]), which read
//! back identically.
//!
//! **npz** (compressed; readable with `numpy.load`): the single-track
//! arrays of [`super::native`] (`positions`, `confidence`, `fps`, `units`,
//! `skeleton_name`, `joints`, `bones`, `coco17`, `root`,
//! `mp_track_version`) hold the **main person's** track
//! ([`People::main_person`]) over the whole video, so every single-track
//! reader ([`super::read_track`], or `numpy.load(f)["positions"]`) gets the
//! performer. The people themselves are in:
//!
//! | array | dtype / shape | meaning |
//! |---|---|---|
//! | `people_n_frames` | `<i8 ()` | video length T in frames |
//! | `people_ids` | `<i8 (P,)` | person ids, ascending |
//! | `people_first_frame` | `<i8 (P,)` | video frame of each track's first frame |
//! | `people_frames` | `<i8 (P,)` | length F of each person's span (≥ 1) |
//! | `people_positions` | `<f8 (ΣF, J, D)` | each person's positions over their own span, one person after the other in `people_ids` order |
//! | `people_confidence` | `<f8 (ΣF, J)` | each person's confidence, laid out as `people_positions` |
//! | `fps` | `<f8 ()` | frames per second (always written) |
//! | `mp_people_version` | `<i8 ()` | format version (2) |
//!
//! Person `i`'s rows are `Σ_{k<i} F_k .. Σ_{k≤i} F_k` of `people_positions`
//! / `people_confidence` (in numpy, `numpy.split(a, numpy.cumsum(frames)[:-1])`),
//! and are the video's frames `first_frame .. first_frame + F_i`; the units and
//! skeleton come from the single-track arrays. Each person's poses are held
//! once, so the file grows with the frames where people are, not with people
//! × video length (an hour with hundreds of passers-by). Version 1 files, whose
//! `people_positions` / `people_confidence` were `(P, T, J, D)` / `(P, T, J)`
//! over the whole video (0 outside each span), are still read.
//!
//! **Nobody in the video** (zero people): there is no main person and no
//! skeleton, so the single-track arrays other than `fps` are left out;
//! `people_ids`, `people_first_frame` and `people_frames` have shape `(0,)`,
//! `people_positions` shape `(0, 0, 0)` and `people_confidence` shape
//! `(0, 0)`. Such a file reads back as an empty [`People`];
//! [`super::read_track`] refuses it ("no person in this file").
//!
//! **JSON**: `{"format": "mp-people", "version": 1, "n_frames", "fps",
//! "people": [{"id", "first_frame", "track": {…}}]}` where each `track` is
//! the `mp-track` JSON object of [`super::native`] over that person's span.
//! Floats are written with the shortest representation that reads back to
//! the same `f64`.
//!
//! **Binary** (`.mpt`, compact, exact): the framing of [`super::binary`]
//! with magic `mp-people` and version 1, then the record `n_frames: u64`,
//! `fps: f64`, `people` (a length, then per person `id: u32`,
//! `first_frame: u64` and the track record of the binary track form:
//! `fps`, `units`, `skeleton`, `shape`, `positions`, `confidence`). See
//! [`people_to_bincode`] / [`people_from_bincode`].
//!
//! [`super::read_track`] reads a people JSON or `.mpt` file as the main
//! person's track over the whole video, like the npz.

use std::path::Path;

use ndarray::{arr0, s, Array1, Array2, Array3, Ix1, Ix2, Ix3, Ix4};
use serde::{Deserialize, Serialize};

use super::binary;
use super::native::{self, TrackBin};
use super::npz::{Npz, NpzOut};
use super::write_atomic;
use crate::error::{GeomError, Result};
use crate::people::{People, Person, PersonId};
use crate::track::Track;

/// Value of the `format` field of the JSON people format.
pub(crate) const JSON_FORMAT: &str = "mp-people";
/// Version written in the JSON format.
pub(crate) const FORMAT_VERSION: i64 = 1;
/// Version written in the npz format (`mp_people_version`): 2, each
/// person's frames once; 1, every person over the whole video.
pub(crate) const NPZ_FORMAT_VERSION: i64 = 2;
/// The npz array whose presence marks a people file.
pub(crate) const NPZ_VERSION_KEY: &str = "mp_people_version";
/// Magic bytes that open the binary people format.
pub const BINARY_MAGIC: &[u8] = b"mp-people";
/// Version of the binary people format.
pub const BINARY_VERSION: u32 = 1;

/// The error of a single-track reader given a file with nobody in it.
pub(crate) fn no_person(path: &Path) -> GeomError {
    GeomError::format(
        path,
        "no person in this file (a people file of a video with nobody in it)",
    )
}

/// The main person's track over the whole video, for single-track readers;
/// a file with nobody in it is an error naming `path`.
pub(crate) fn main_track_of(people: &People, path: &Path) -> Result<Track> {
    if people.is_empty() {
        return Err(no_person(path));
    }
    people
        .main_track()
        .map_err(|e| GeomError::format(path, e.to_string()))
}

/// Prefixes a format error's reason with the person it concerns.
fn in_person(id: impl std::fmt::Display) -> impl Fn(GeomError) -> GeomError {
    move |e| match e {
        GeomError::Format { path, reason } => GeomError::Format {
            path,
            reason: format!("person {id}: {reason}"),
        },
        other => other,
    }
}

/// Validation errors of [`People::new`] as format errors naming `path`.
fn build(n_frames: usize, fps: f64, people: Vec<Person>, path: &Path) -> Result<People> {
    People::new(n_frames, fps, people).map_err(|e| GeomError::format(path, e.to_string()))
}

// ---------------------------------------------------------------- npz

/// Encodes people as compressed npz bytes (see the module docs for the
/// arrays and for a video with nobody in it).
pub fn people_to_npz_bytes(people: &People) -> Result<Vec<u8>> {
    people_to_npz_bytes_framed(people, None)
}

/// [`people_to_npz_bytes`] with the video frame size (`frame_size`, as
/// [`native::track_to_npz_bytes_framed`]).
pub fn people_to_npz_bytes_framed(
    people: &People,
    frame_size: Option<(usize, usize)>,
) -> Result<Vec<u8>> {
    let t = people.n_frames();
    let list = people.people();
    let (j, d) = list
        .first()
        .map_or((0, 0), |p| (p.track.n_joints(), p.track.dims()));
    let mut out = NpzOut::new(true);
    match people.main_person() {
        // The single-track arrays hold the main person over the whole video.
        Some(main) => native::add_track_arrays(&mut out, &people.full_track(main.id)?)?,
        None => out.add("fps", &arr0(people.fps()))?,
    }
    let ids: Array1<i64> = list.iter().map(|p| i64::from(p.id)).collect();
    let first: Array1<i64> = list.iter().map(|p| p.first_frame as i64).collect();
    let frames: Array1<i64> = list.iter().map(|p| p.track.n_frames() as i64).collect();
    let total: usize = list.iter().map(|p| p.track.n_frames()).sum();
    let mut pos = Array3::<f64>::zeros((total, j, d));
    let mut conf = Array2::<f64>::zeros((total, j));
    let mut at = 0;
    for person in list {
        let rows = at..at + person.track.n_frames();
        pos.slice_mut(s![rows.clone(), .., ..])
            .assign(&person.track.positions());
        conf.slice_mut(s![rows.clone(), ..])
            .assign(&person.track.confidence());
        at = rows.end;
    }
    out.add("people_n_frames", &arr0(t as i64))?;
    out.add("people_ids", &ids)?;
    out.add("people_first_frame", &first)?;
    out.add("people_frames", &frames)?;
    out.add("people_positions", &pos)?;
    out.add("people_confidence", &conf)?;
    out.add(NPZ_VERSION_KEY, &arr0(NPZ_FORMAT_VERSION))?;
    native::add_frame_size(&mut out, frame_size)?;
    out.finish()
}

/// Whether an opened npz is a people file (has `mp_people_version`).
pub fn is_people_npz(z: &Npz) -> bool {
    z.contains(NPZ_VERSION_KEY)
}

/// The single integer of a scalar (or one-element) integer array.
fn scalar_i64(z: &Npz, name: &str) -> Result<i64> {
    let a = z.array(name)?;
    if a.len() != 1 {
        return Err(GeomError::format(
            z.path(),
            format!("`{name}` should be a scalar, has shape {:?}", a.shape),
        ));
    }
    a.to_i64()?
        .iter()
        .next()
        .copied()
        .ok_or_else(|| GeomError::format(z.path(), format!("`{name}` holds no value")))
}

/// A one-dimensional integer array of `n` elements.
fn ints(z: &Npz, name: &str, n: Option<usize>) -> Result<Array1<i64>> {
    let a = z.array(name)?;
    a.expect_shape(name, &[n])?;
    a.to_i64()?
        .into_dimensionality::<Ix1>()
        .map_err(|e| GeomError::format(z.path(), format!("{name}: {e}")))
}

/// Decodes people from an opened npz in the people format (see the module
/// docs). Inconsistent arrays (shapes, spans past the video, duplicate ids)
/// are [`GeomError::Format`] errors naming the file.
pub fn people_from_npz(z: &Npz) -> Result<People> {
    let path = z.path().to_path_buf();
    let bad = |reason: String| GeomError::format(&path, reason);
    let version = scalar_i64(z, NPZ_VERSION_KEY)?;
    if !(1..=NPZ_FORMAT_VERSION).contains(&version) {
        return Err(bad(format!(
            "people format version {version} is not supported (this build reads 1 to \
             {NPZ_FORMAT_VERSION})"
        )));
    }
    let t = scalar_i64(z, "people_n_frames")?;
    let t = usize::try_from(t).ok().filter(|&t| t >= 1).ok_or_else(|| {
        bad(format!(
            "`people_n_frames` is {t}, a video has at least 1 frame"
        ))
    })?;
    let fps = z.scalar_f64("fps")?;
    let ids = ints(z, "people_ids", None)?;
    let p = ids.len();
    let first = ints(z, "people_first_frame", Some(p))?;
    let frames = ints(z, "people_frames", Some(p))?;
    if p == 0 {
        return build(t, fps, Vec::new(), &path);
    }
    // Units, skeleton and dimensions come from the main person's track.
    let main = native::track_from_npz(z)?;
    let (j, d) = (main.n_joints(), main.dims());
    if main.n_frames() != t {
        return Err(bad(format!(
            "`positions` has {} frames, `people_n_frames` says {t}",
            main.n_frames()
        )));
    }
    let mut spans = Vec::with_capacity(p);
    for i in 0..p {
        let id = PersonId::try_from(ids[i])
            .map_err(|_| bad(format!("person id {} is outside 0..=4294967295", ids[i])))?;
        let span = usize::try_from(first[i])
            .ok()
            .zip(usize::try_from(frames[i]).ok().filter(|&n| n >= 1))
            .and_then(|(a, n)| Some((a, a.checked_add(n)?)))
            .filter(|&(_, b)| b <= t)
            .ok_or_else(|| {
                bad(format!(
                    "person {id}: first frame {} and {} frames do not lie within the video's \
                     {t} frames",
                    first[i], frames[i]
                ))
            })?;
        spans.push((id, span));
    }
    let person = |id: PersonId,
                  span: (usize, usize),
                  pos: ndarray::ArrayView3<f64>,
                  conf: ndarray::ArrayView2<f64>|
     -> Result<Person> {
        let track = Track::new(
            pos.to_owned(),
            Some(conf.to_owned()),
            fps,
            main.units(),
            main.skeleton().clone(),
        )
        .map_err(|e| bad(format!("person {id}: {e}")))?;
        Ok(Person {
            id,
            first_frame: span.0,
            track,
        })
    };
    let mut people = Vec::with_capacity(p);
    if version == 1 {
        // Every person over the whole video: their span of their row.
        let pos = z
            .array_f64_shaped("people_positions", &[Some(p), Some(t), Some(j), Some(d)])?
            .into_dimensionality::<Ix4>()
            .map_err(|e| bad(format!("people_positions: {e}")))?;
        let conf = z
            .array_f64_shaped("people_confidence", &[Some(p), Some(t), Some(j)])?
            .into_dimensionality::<Ix3>()
            .map_err(|e| bad(format!("people_confidence: {e}")))?;
        for (i, (id, (a, b))) in spans.into_iter().enumerate() {
            people.push(person(
                id,
                (a, b),
                pos.slice(s![i, a..b, .., ..]),
                conf.slice(s![i, a..b, ..]),
            )?);
        }
    } else {
        // Each person's frames once, one person after the other.
        let total: usize = spans.iter().map(|(_, (a, b))| b - a).sum();
        let pos = z
            .array_f64_shaped("people_positions", &[Some(total), Some(j), Some(d)])?
            .into_dimensionality::<Ix3>()
            .map_err(|e| bad(format!("people_positions: {e}")))?;
        let conf = z
            .array_f64_shaped("people_confidence", &[Some(total), Some(j)])?
            .into_dimensionality::<Ix2>()
            .map_err(|e| bad(format!("people_confidence: {e}")))?;
        let mut at = 0;
        for (id, (a, b)) in spans {
            let rows = at..at + (b - a);
            people.push(person(
                id,
                (a, b),
                pos.slice(s![rows.clone(), .., ..]),
                conf.slice(s![rows.clone(), ..]),
            )?);
            at = rows.end;
        }
    }
    build(t, fps, people, &path)
}

// ---------------------------------------------------------------- JSON

#[derive(Serialize, Deserialize)]
struct PeopleDoc {
    format: String,
    version: i64,
    n_frames: usize,
    fps: f64,
    people: Vec<PersonDoc>,
}

#[derive(Serialize, Deserialize)]
struct PersonDoc {
    id: PersonId,
    first_frame: usize,
    track: serde_json::Value,
}

/// Encodes people as JSON text.
pub fn people_to_json_string(people: &People) -> Result<String> {
    let doc = PeopleDoc {
        format: JSON_FORMAT.into(),
        version: FORMAT_VERSION,
        n_frames: people.n_frames(),
        fps: people.fps(),
        people: people
            .people()
            .iter()
            .map(|p| {
                Ok(PersonDoc {
                    id: p.id,
                    first_frame: p.first_frame,
                    track: native::track_to_json_value(&p.track)?,
                })
            })
            .collect::<Result<_>>()?,
    };
    serde_json::to_string(&doc).map_err(|e| GeomError::format("json", e.to_string()))
}

/// Writes people as JSON (atomic).
pub(crate) fn write_people_json(path: impl AsRef<Path>, people: &People) -> Result<()> {
    write_atomic(path, people_to_json_string(people)?.as_bytes())
}

/// Whether a parsed JSON document is a people file (`"format": "mp-people"`).
pub fn is_people_json(value: &serde_json::Value) -> bool {
    value.get("format").and_then(|f| f.as_str()) == Some(JSON_FORMAT)
}

/// Decodes a parsed JSON document in the people format; `path` names the
/// source in errors.
pub(crate) fn people_from_json_value(value: serde_json::Value, path: &Path) -> Result<People> {
    let doc: PeopleDoc = serde_json::from_value(value)
        .map_err(|e| GeomError::format(path, format!("not an mp people file: {e}")))?;
    if doc.format != JSON_FORMAT {
        return Err(GeomError::format(
            path,
            format!("`format` is `{}`, expected `{JSON_FORMAT}`", doc.format),
        ));
    }
    if !(1..=FORMAT_VERSION).contains(&doc.version) {
        return Err(GeomError::format(
            path,
            format!(
                "people format version {} is not supported (this build reads 1 to \
                 {FORMAT_VERSION})",
                doc.version
            ),
        ));
    }
    let people = doc
        .people
        .into_iter()
        .map(|p| {
            let track = native::track_from_json_value(p.track, path).map_err(in_person(p.id))?;
            Ok(Person {
                id: p.id,
                first_frame: p.first_frame,
                track,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    build(doc.n_frames, doc.fps, people, path)
}

/// Parses JSON text in the people format; `path` names the source in errors.
pub fn people_from_json_str(text: &str, path: &Path) -> Result<People> {
    let value: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| GeomError::format(path, format!("invalid JSON: {e}")))?;
    people_from_json_value(value, path)
}

// ---------------------------------------------------------------- binary

#[derive(Serialize, Deserialize)]
struct PeopleBin {
    n_frames: u64,
    fps: f64,
    people: Vec<PersonBin>,
}

#[derive(Serialize, Deserialize)]
struct PersonBin {
    id: PersonId,
    first_frame: u64,
    track: TrackBin,
}

/// Encodes people in the compact binary form (`.mpt` with magic
/// `mp-people`): exact `f64`s; [`people_from_bincode`] gives back equal
/// people.
pub fn people_to_bincode(people: &People) -> Result<Vec<u8>> {
    let rec = PeopleBin {
        n_frames: people.n_frames() as u64,
        fps: people.fps(),
        people: people
            .people()
            .iter()
            .map(|p| PersonBin {
                id: p.id,
                first_frame: p.first_frame as u64,
                track: TrackBin::of(&p.track),
            })
            .collect(),
    };
    binary::encode(BINARY_MAGIC, BINARY_VERSION, &rec)
}

/// Decodes people written by [`people_to_bincode`]. Corrupt or truncated
/// bytes, invalid tracks and people that break the invariants of
/// [`People::new`] are errors ([`GeomError::Format`]), never panics.
pub fn people_from_bincode(bytes: &[u8]) -> Result<People> {
    people_from_bincode_at(bytes, Path::new("bincode people"))
}

/// [`people_from_bincode`] naming `path` in errors.
pub(crate) fn people_from_bincode_at(bytes: &[u8], path: &Path) -> Result<People> {
    let rec: PeopleBin = binary::decode(BINARY_MAGIC, BINARY_VERSION, bytes, path)?;
    let bad = |reason: String| GeomError::format(path, reason);
    let n_frames = usize::try_from(rec.n_frames)
        .map_err(|_| bad(format!("{} frames do not fit this machine", rec.n_frames)))?;
    let people = rec
        .people
        .into_iter()
        .map(|p| {
            let first_frame = usize::try_from(p.first_frame).map_err(|_| {
                bad(format!(
                    "person {}: first frame {} does not fit this machine",
                    p.id, p.first_frame
                ))
            })?;
            let track = native::track_from_record(p.track, path).map_err(in_person(p.id))?;
            Ok(Person {
                id: p.id,
                first_frame,
                track,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    build(n_frames, rec.fps, people, path)
}

/// Whether bytes open with the binary people magic (`mp-people`).
pub fn is_people_bincode(bytes: &[u8]) -> bool {
    bytes.starts_with(BINARY_MAGIC)
}

/// Writes people in the binary form (atomic).
pub(crate) fn write_people_bincode(path: impl AsRef<Path>, people: &People) -> Result<()> {
    write_atomic(path, &people_to_bincode(people)?)
}
