//! The project's own track formats, which read back identically.
//!
//! **npz** (compressed; readable with `numpy.load`):
//!
//! | array | dtype / shape | meaning |
//! |---|---|---|
//! | `positions` | `<f8 (T, J, D)` | joint positions |
//! | `confidence` | `<f8 (T, J)` | per-joint confidence in [0, 1] |
//! | `fps` | `<f8 ()` | frames per second |
//! | `units` | `<U ()` | `px`, `m` or `1` |
//! | `skeleton_name` | `<U ()` | skeleton identifier |
//! | `joints` | `<U (J,)` | joint names |
//! | `bones` | `<i8 (B, 2)` | bones as joint index pairs |
//! | `coco17` | `<i8 (17,)` or `(0,)` | COCO-17 mapping, −1 = none |
//! | `root` | `<i8 ()` | root joint, −1 = none |
//! | `mp_track_version` | `<i8 ()` | format version (1) |
//! | `frame_size` | `<i8 (2,)` | optional: width and height of the video frame the pixels are in |
//!
//! **JSON**: `{"format": "mp-track", "version": 1, "fps", "units", "skeleton":
//! {name, joints, bones, coco17, root}, "positions": [[[x, y(, z)] per joint]
//! per frame], "confidence": [[c per joint] per frame]}`. Floats are written
//! with the shortest representation that reads back to the same `f64`.
//!
//! **Binary** (`.mpt`, compact, exact): the framing of [`super::binary`]
//! with magic `mp-track` and version 1, then the record `fps: f64`,
//! `units` (variant 0 = px, 1 = m, 2 = unitless), `skeleton {name, joints,
//! bones, coco17, root}`, `shape: [T, J, D]`, `positions` (`T·J·D` f64,
//! row-major) and `confidence` (`T·J` f64, row-major). See
//! [`track_to_bincode`] / [`track_from_bincode`].
//!
//! Several tracked people have their own formats in [`super::people`],
//! whose npz holds the main person in the arrays above.

use std::path::Path;

use ndarray::{arr0, Array1, Array2, Array3, Ix2, Ix3};
use serde::{Deserialize, Serialize};

use super::binary;
use super::npz::{Npz, NpzOut};
use super::{infer_skeleton, write_atomic, ReadOptions};
use crate::error::{GeomError, Result};
use crate::skeleton::Skeleton;
use crate::track::{Track, Units};

/// Value of the `format` field of the JSON track format.
pub(crate) const JSON_FORMAT: &str = "mp-track";
/// Version written in both formats.
pub(crate) const FORMAT_VERSION: i64 = 1;
/// Magic bytes that open the binary track format.
pub const BINARY_MAGIC: &[u8] = b"mp-track";
/// Version of the binary track format.
pub const BINARY_VERSION: u32 = 1;

/// Encodes a track as compressed npz bytes.
pub fn track_to_npz_bytes(track: &Track) -> Result<Vec<u8>> {
    track_to_npz_bytes_framed(track, None)
}

/// [`track_to_npz_bytes`] with the width and height of the video frame the
/// track's pixels are in (`frame_size`), which [`super::read_track_rated`]
/// gives back: the scale a program of the track is fitted at.
pub fn track_to_npz_bytes_framed(
    track: &Track,
    frame_size: Option<(usize, usize)>,
) -> Result<Vec<u8>> {
    let mut out = NpzOut::new(true);
    add_track_arrays(&mut out, track)?;
    add_frame_size(&mut out, frame_size)?;
    out.finish()
}

/// Adds the optional `frame_size` array.
pub(crate) fn add_frame_size(out: &mut NpzOut, frame_size: Option<(usize, usize)>) -> Result<()> {
    if let Some((w, h)) = frame_size {
        out.add("frame_size", &Array1::from(vec![w as i64, h as i64]))?;
    }
    Ok(())
}

/// The video frame size (width, height) an opened npz track or people file
/// states (`frame_size`), if any.
pub(crate) fn frame_size_of(z: &Npz) -> Result<Option<(usize, usize)>> {
    let path = z.path();
    if !z.contains("frame_size") {
        return Ok(None);
    }
    let a = z.array("frame_size")?.to_f64()?;
    let v: Vec<f64> = a.iter().copied().collect();
    match v.as_slice() {
        [w, h] if *w >= 1.0 && *h >= 1.0 && w.is_finite() && h.is_finite() => {
            Ok(Some((*w as usize, *h as usize)))
        }
        _ => Err(GeomError::format(
            path,
            format!("frame_size must be two positive sizes (width, height), got {v:?}"),
        )),
    }
}

/// Adds the arrays of the npz track format to an archive being built.
pub(crate) fn add_track_arrays(out: &mut NpzOut, track: &Track) -> Result<()> {
    let sk = track.skeleton();
    out.add("positions", &track.positions())?;
    out.add("confidence", &track.confidence())?;
    out.add("fps", &arr0(track.fps()))?;
    out.add_strings("units", &[track.units().as_str().to_string()], &[])?;
    out.add_strings("skeleton_name", std::slice::from_ref(&sk.name), &[])?;
    out.add_strings("joints", &sk.joints, &[sk.joints.len()])?;
    let mut bones = Array2::<i64>::zeros((sk.bones.len(), 2));
    for (i, &(a, b)) in sk.bones.iter().enumerate() {
        bones[[i, 0]] = a as i64;
        bones[[i, 1]] = b as i64;
    }
    out.add("bones", &bones)?;
    let coco: Array1<i64> = sk
        .coco17
        .iter()
        .map(|c| c.map_or(-1, |v| v as i64))
        .collect();
    out.add("coco17", &coco)?;
    out.add("root", &arr0(sk.root.map_or(-1, |r| r as i64)))?;
    out.add("mp_track_version", &arr0(FORMAT_VERSION))?;
    Ok(())
}

fn index(v: i64, n: usize, what: &str, path: &Path) -> Result<usize> {
    usize::try_from(v)
        .ok()
        .filter(|&i| i < n)
        .ok_or_else(|| GeomError::format(path, format!("{what}: joint index {v} outside 0..{n}")))
}

/// Decodes a track from an opened npz in the project's format. Files with
/// only `positions` (and optionally `confidence`, `fps`) are accepted too:
/// the skeleton is then inferred from the joint count.
pub fn track_from_npz(z: &Npz) -> Result<Track> {
    let path = z.path().to_path_buf();
    let pos = z
        .array_f64_shaped("positions", &[None, None, None])?
        .into_dimensionality::<Ix3>()
        .map_err(|e| GeomError::format(&path, format!("positions: {e}")))?;
    let (t, j, d) = pos.dim();
    let conf = if z.contains("confidence") {
        Some(
            z.array_f64_shaped("confidence", &[Some(t), Some(j)])?
                .into_dimensionality::<Ix2>()
                .map_err(|e| GeomError::format(&path, format!("confidence: {e}")))?,
        )
    } else {
        None
    };
    let fps = if z.contains("fps") {
        z.scalar_f64("fps")?
    } else {
        super::DEFAULT_FPS
    };
    let units = if z.contains("units") {
        Units::parse(&z.scalar_string("units")?)?
    } else {
        ReadOptions::default().units_for(d)
    };
    let skeleton = if z.contains("joints") {
        let joints = z.strings("joints")?;
        if joints.len() != j {
            return Err(GeomError::format(
                &path,
                format!("`joints` names {} joints, positions have {j}", joints.len()),
            ));
        }
        let name = if z.contains("skeleton_name") {
            z.scalar_string("skeleton_name")?
        } else {
            "custom".to_string()
        };
        let mut bones = Vec::new();
        if z.contains("bones") {
            let b = z.array("bones")?;
            if !b.is_empty() {
                b.expect_shape("bones", &[None, Some(2)])?;
            }
            let b = b.to_i64()?;
            let flat: Vec<i64> = b.iter().copied().collect();
            for pair in flat.chunks_exact(2) {
                bones.push((
                    index(pair[0], j, "bones", &path)?,
                    index(pair[1], j, "bones", &path)?,
                ));
            }
        }
        let coco17 = if z.contains("coco17") {
            z.array_i64("coco17")?
                .iter()
                .map(|&v| {
                    if v < 0 {
                        Ok(None)
                    } else {
                        index(v, j, "coco17", &path).map(Some)
                    }
                })
                .collect::<Result<Vec<_>>>()?
        } else {
            Vec::new()
        };
        if !(coco17.is_empty() || coco17.len() == 17) {
            return Err(GeomError::format(
                &path,
                format!("`coco17` has {} entries, expected 17 or 0", coco17.len()),
            ));
        }
        let root = if z.contains("root") {
            let r = z.scalar_f64("root")? as i64;
            if r < 0 {
                None
            } else {
                Some(index(r, j, "root", &path)?)
            }
        } else {
            None
        };
        Skeleton {
            name,
            joints,
            bones,
            coco17,
            root,
        }
    } else {
        check_has_values(t, j, d, &path)?;
        infer_skeleton(&ReadOptions::default(), j, &path)?
    };
    Track::new(pos, conf, fps, units, skeleton)
}

/// Reads a track from an npz file in the project's format.
pub fn read_track_npz(path: impl AsRef<Path>) -> Result<Track> {
    track_from_npz(&Npz::open(path)?)
}

#[derive(Serialize, Deserialize)]
struct TrackDoc {
    format: String,
    version: i64,
    fps: f64,
    units: Units,
    skeleton: Skeleton,
    positions: Vec<Vec<Vec<f64>>>,
    confidence: Vec<Vec<f64>>,
}

/// Encodes a track as JSON text.
pub fn track_to_json_string(track: &Track) -> Result<String> {
    serde_json::to_string(&track_doc(track)).map_err(|e| GeomError::format("json", e.to_string()))
}

/// Encodes a track as a JSON value (the object [`track_to_json_string`]
/// writes), for documents that embed tracks.
pub(crate) fn track_to_json_value(track: &Track) -> Result<serde_json::Value> {
    serde_json::to_value(track_doc(track)).map_err(|e| GeomError::format("json", e.to_string()))
}

fn track_doc(track: &Track) -> TrackDoc {
    let pos = track.positions();
    let conf = track.confidence();
    TrackDoc {
        format: JSON_FORMAT.into(),
        version: FORMAT_VERSION,
        fps: track.fps(),
        units: track.units(),
        skeleton: track.skeleton().clone(),
        positions: pos
            .outer_iter()
            .map(|f| f.outer_iter().map(|p| p.to_vec()).collect())
            .collect(),
        confidence: conf.outer_iter().map(|c| c.to_vec()).collect(),
    }
}

/// Writes a track as JSON (atomic).
pub(crate) fn write_track_json(path: impl AsRef<Path>, track: &Track) -> Result<()> {
    let text = track_to_json_string(track)?;
    write_atomic(path, text.as_bytes())
}

/// Decodes a parsed JSON document in the project's format.
pub(crate) fn track_from_json_value(value: serde_json::Value, path: &Path) -> Result<Track> {
    let doc: TrackDoc = serde_json::from_value(value)
        .map_err(|e| GeomError::format(path, format!("not an mp track: {e}")))?;
    if doc.format != JSON_FORMAT {
        return Err(GeomError::format(
            path,
            format!("`format` is `{}`, expected `{JSON_FORMAT}`", doc.format),
        ));
    }
    if doc.version > FORMAT_VERSION {
        return Err(GeomError::format(
            path,
            format!(
                "track format version {} is newer than {FORMAT_VERSION}",
                doc.version
            ),
        ));
    }
    let t = doc.positions.len();
    let j = doc
        .positions
        .first()
        .map_or(doc.skeleton.len(), |f| f.len());
    let d = doc
        .positions
        .first()
        .and_then(|f| f.first())
        .map_or(2, |p| p.len());
    let mut pos = Array3::<f64>::zeros((t, j, d));
    for (ti, frame) in doc.positions.iter().enumerate() {
        if frame.len() != j {
            return Err(GeomError::format(
                path,
                format!("frame {ti} has {} joints, frame 0 has {j}", frame.len()),
            ));
        }
        for (ji, p) in frame.iter().enumerate() {
            if p.len() != d {
                return Err(GeomError::format(
                    path,
                    format!("frame {ti}, joint {ji}: {} values, expected {d}", p.len()),
                ));
            }
            for (k, &v) in p.iter().enumerate() {
                pos[[ti, ji, k]] = v;
            }
        }
    }
    if doc.confidence.len() != t {
        return Err(GeomError::format(
            path,
            format!(
                "confidence has {} frames, positions {t}",
                doc.confidence.len()
            ),
        ));
    }
    let mut conf = Array2::<f64>::zeros((t, j));
    for (ti, row) in doc.confidence.iter().enumerate() {
        if row.len() != j {
            return Err(GeomError::format(
                path,
                format!(
                    "confidence frame {ti} has {} joints, expected {j}",
                    row.len()
                ),
            ));
        }
        for (ji, &c) in row.iter().enumerate() {
            conf[[ti, ji]] = c;
        }
    }
    check_skeleton_indices(&doc.skeleton, j, path)?;
    Track::new(pos, Some(conf), doc.fps, doc.units, doc.skeleton)
        .map_err(|e| GeomError::format(path, e.to_string()))
}

/// Reads a track from a JSON file in the project's format.
pub fn read_track_json(path: impl AsRef<Path>) -> Result<Track> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| GeomError::io(path, e))?;
    track_from_json_str(&text, path)
}

/// Parses JSON text in the project's format; `path` names the source in errors.
pub fn track_from_json_str(text: &str, path: &Path) -> Result<Track> {
    let value: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| GeomError::format(path, format!("invalid JSON: {e}")))?;
    track_from_json_value(value, path)
}

/// The binary track record (after the framing), also embedded in the
/// binary people form.
#[derive(Serialize, Deserialize)]
pub(crate) struct TrackBin {
    fps: f64,
    units: Units,
    skeleton: Skeleton,
    shape: [u64; 3],
    positions: Vec<f64>,
    confidence: Vec<f64>,
}

impl TrackBin {
    /// The record of a track.
    pub(crate) fn of(track: &Track) -> Self {
        let (t, j, d) = track.positions().dim();
        TrackBin {
            fps: track.fps(),
            units: track.units(),
            skeleton: track.skeleton().clone(),
            shape: [t as u64, j as u64, d as u64],
            positions: track.positions().iter().copied().collect(),
            confidence: track.confidence().iter().copied().collect(),
        }
    }
}

/// Encodes a track in the compact binary form (`.mpt`): exact `f64`s,
/// skeleton included; [`track_from_bincode`] gives back an equal track.
pub fn track_to_bincode(track: &Track) -> Result<Vec<u8>> {
    binary::encode(BINARY_MAGIC, BINARY_VERSION, &TrackBin::of(track))
}

/// Decodes a track written by [`track_to_bincode`]. Corrupt or truncated
/// bytes, shapes that disagree with the data, a non-finite or non-positive
/// frame rate and skeleton indices outside the joints are errors
/// ([`GeomError::Format`]), never panics.
pub fn track_from_bincode(bytes: &[u8]) -> Result<Track> {
    track_from_bincode_at(bytes, Path::new("bincode track"))
}

/// [`track_from_bincode`] naming `path` in errors.
pub(crate) fn track_from_bincode_at(bytes: &[u8], path: &Path) -> Result<Track> {
    let rec: TrackBin = binary::decode(BINARY_MAGIC, BINARY_VERSION, bytes, path)?;
    track_from_record(rec, path)
}

/// Validates a decoded [`TrackBin`] and builds its track; `path` names the
/// source in errors.
pub(crate) fn track_from_record(rec: TrackBin, path: &Path) -> Result<Track> {
    let bad = |reason: String| GeomError::format(path, reason);
    let [t, j, d] = rec.shape;
    let dim = |v: u64, what: &str| {
        usize::try_from(v).map_err(|_| bad(format!("{what} count {v} does not fit this machine")))
    };
    let (t, j, d) = (dim(t, "frame")?, dim(j, "joint")?, dim(d, "dimension")?);
    let n_pos = t
        .checked_mul(j)
        .and_then(|v| v.checked_mul(d))
        .ok_or_else(|| bad(format!("shape ({t}, {j}, {d}) overflows")))?;
    if rec.positions.len() != n_pos {
        return Err(bad(format!(
            "positions hold {} values, shape ({t}, {j}, {d}) needs {n_pos}",
            rec.positions.len()
        )));
    }
    if rec.confidence.len() != t * j {
        return Err(bad(format!(
            "confidence holds {} values, shape ({t}, {j}) needs {}",
            rec.confidence.len(),
            t * j
        )));
    }
    check_skeleton_indices(&rec.skeleton, j, path)?;
    let pos = Array3::from_shape_vec((t, j, d), rec.positions)
        .map_err(|e| bad(format!("positions: {e}")))?;
    let conf = Array2::from_shape_vec((t, j), rec.confidence)
        .map_err(|e| bad(format!("confidence: {e}")))?;
    Track::new(pos, Some(conf), rec.fps, rec.units, rec.skeleton).map_err(|e| bad(e.to_string()))
}

/// Writes a track in the binary form (atomic).
pub(crate) fn write_track_bincode(path: impl AsRef<Path>, track: &Track) -> Result<()> {
    write_atomic(path, &track_to_bincode(track)?)
}

/// Refuses positions without values before a skeleton of `j` joints is
/// inferred: with no frame (or no dimension) the joint count is not backed
/// by any data and may be anything.
fn check_has_values(t: usize, j: usize, d: usize, path: &Path) -> Result<()> {
    if t == 0 || j == 0 || d == 0 {
        return Err(GeomError::format(
            path,
            format!("positions of shape ({t}, {j}, {d}) hold no values"),
        ));
    }
    Ok(())
}

/// Checks that a skeleton's bones, COCO-17 mapping and root refer to joints in `0..j`.
fn check_skeleton_indices(sk: &Skeleton, j: usize, path: &Path) -> Result<()> {
    if sk.bones.iter().any(|&(a, b)| a >= j || b >= j)
        || sk.coco17.iter().flatten().any(|&c| c >= j)
        || sk.root.is_some_and(|r| r >= j)
    {
        return Err(GeomError::format(
            path,
            format!("skeleton `{}` refers to a joint outside 0..{j}", sk.name),
        ));
    }
    if !(sk.coco17.is_empty() || sk.coco17.len() == 17) {
        return Err(GeomError::format(
            path,
            format!(
                "skeleton `{}`: COCO-17 mapping has {} entries, expected 17 or 0",
                sk.name,
                sk.coco17.len()
            ),
        ));
    }
    Ok(())
}

/// Reads a `(T, J, D)` `.npy` array as a track (D = 2 or 3; a `(T, J, D+1)`
/// array is not guessed: pass positions only). Frame rate, units and
/// skeleton come from `opts`.
pub fn read_track_npy(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<Track> {
    let path = path.as_ref();
    opts.validate()?;
    let bytes = std::fs::read(path).map_err(|e| GeomError::io(path, e))?;
    track_from_npy_bytes(&bytes, path, opts)
}

/// Decodes `.npy` bytes as [`read_track_npy`] does; `path` names the
/// source in errors.
pub fn track_from_npy_bytes(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Track> {
    opts.validate()?;
    let a = super::npz::NpyArray::from_bytes(bytes, &path.display().to_string())?;
    a.expect_shape("array", &[None, None, None])?;
    let pos = a
        .to_f64()?
        .into_dimensionality::<Ix3>()
        .map_err(|e| GeomError::format(path, e.to_string()))?;
    let (t, j, d) = pos.dim();
    check_has_values(t, j, d, path)?;
    let skeleton = infer_skeleton(opts, j, path)?;
    Track::new(pos, None, opts.rate(), opts.units_for(d), skeleton)
        .map_err(|e| GeomError::format(path, e.to_string()))
}

/// Writes a track's positions as a `(T, J, D)` float64 `.npy` (atomic).
/// Confidence, frame rate and skeleton are not stored: use npz for those.
pub fn write_track_npy(path: impl AsRef<Path>, track: &Track) -> Result<()> {
    use ndarray_npy::WriteNpyExt;
    let path = path.as_ref();
    let mut buf = Vec::new();
    track
        .positions()
        .write_npy(&mut buf)
        .map_err(|e| GeomError::format(path, e.to_string()))?;
    write_atomic(path, &buf)
}
