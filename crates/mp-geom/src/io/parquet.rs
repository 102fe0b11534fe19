//! Parquet tables of tracks and people, through the `parquet` crate's
//! column reader and writer (no Arrow).
//!
//! **Layout**: a long ("tidy") table, one row per frame × joint (× person):
//!
//! | column | type | meaning |
//! |---|---|---|
//! | `person` | int64 | person id (people files only) |
//! | `frame` | int64 | frame index (of the video, for people) |
//! | `time` | double | seconds, `frame / fps` |
//! | `joint` | string | joint name |
//! | `x`, `y` (, `z`) | double, nullable | position; null where the joint is missing |
//! | `confidence` | double | 0 (missing) … 1 |
//!
//! Written with Snappy compression. The file's key-value metadata keeps what
//! the table cannot: `mp.format` (`mp-track` or `mp-people`), `mp.version`
//! (1), `mp.fps`, `mp.units`, `mp.skeleton` (the skeleton as JSON: name,
//! joints, bones, COCO-17 mapping, root), `mp.n_frames` and, when known,
//! `mp.frame_size` (`W×H` pixels), so that a file written here reads back
//! with the same rate, units, skeleton and frame size, and the same
//! positions and confidence wherever a joint was found (a missing joint's
//! position, which means nothing, reads back as 0).
//!
//! **Other tables** (pandas `df.to_parquet`, polars, Spark, …) read as long
//! CSV does: columns matched by lower-case name, `frame` and `joint` (names,
//! or integer indices) and `x`, `y` required, `z` and a confidence column
//! (`confidence`, `conf`, `score`, `visibility`) optional, a `person`
//! column makes people; (frame, joint) pairs without a row and null or NaN
//! coordinates are missing; integer or floating columns of any width; rows
//! in any order (joints in order of appearance, or in a built-in skeleton's
//! order when their names are that skeleton's).
//! Without metadata the rate comes from a `time` column (as CSV), else
//! [`ReadOptions::fps`] / [`super::DEFAULT_FPS`]; the skeleton is
//! [`ReadOptions::skeleton`] or chosen from the joint names; the units are
//! [`ReadOptions::units`] or pixels (2D) / metres (3D).

use std::collections::HashMap;
use std::fs::File;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::Arc;

use ndarray::{Array2, Array3};
use parquet::basic::Compression;
use parquet::column::reader::ColumnReader;
use parquet::data_type::{ByteArray, ByteArrayType, DoubleType, Int64Type};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::parser::parse_message_type;

use super::csv::MAX_SPARSE_CELLS;
use super::{skeleton_from_names, write_atomic, Content, ReadOptions};
use crate::error::{GeomError, Result};
use crate::people::{People, Person};
use crate::skeleton::Skeleton;
use crate::track::{Track, Units};

/// `mp.format` of a single track.
const TRACK_FORMAT: &str = "mp-track";
/// `mp.format` of people.
const PEOPLE_FORMAT: &str = "mp-people";

/// A Parquet file read: its content, whether it states its frame rate and
/// the frame size it states.
pub(crate) struct ParquetRead {
    pub content: Content,
    pub rate_stated: bool,
    pub frame_size: Option<(usize, usize)>,
}

/// One row of a table: person, frame, joint, position, confidence.
type Row = (Option<usize>, usize, usize, [f64; 3], f64);

/// One column's values, null as `None`.
enum Column {
    Int(Vec<Option<i64>>),
    Float(Vec<Option<f64>>),
    Text(Vec<Option<String>>),
}

impl Column {
    fn len(&self) -> usize {
        match self {
            Column::Int(v) => v.len(),
            Column::Float(v) => v.len(),
            Column::Text(v) => v.len(),
        }
    }
    /// Row `i` as a number (NaN for null or text).
    fn number(&self, i: usize) -> f64 {
        match self {
            Column::Int(v) => v[i].map_or(f64::NAN, |x| x as f64),
            Column::Float(v) => v[i].unwrap_or(f64::NAN),
            Column::Text(_) => f64::NAN,
        }
    }
}

/// Reads every value of a column reader (levels expanded to nulls).
macro_rules! read_all {
    ($reader:expr, $max_def:expr, $map:expr) => {{
        let mut values = Vec::new();
        let mut defs = Vec::new();
        loop {
            let (records, _, _) = if $max_def > 0 {
                $reader.read_records(8192, Some(&mut defs), None, &mut values)?
            } else {
                $reader.read_records(8192, None, None, &mut values)?
            };
            if records == 0 {
                break;
            }
        }
        let mut out = Vec::with_capacity(defs.len().max(values.len()));
        if $max_def > 0 {
            let mut it = values.into_iter();
            for d in defs {
                out.push(if d == $max_def {
                    it.next().map($map)
                } else {
                    None
                });
            }
        } else {
            out.extend(values.into_iter().map(|v| Some($map(v))));
        }
        out
    }};
}

/// The columns called `wanted` (lower case) and the key-value metadata.
fn read_columns(
    path: &Path,
    wanted: &[&str],
) -> Result<(HashMap<String, Column>, HashMap<String, String>)> {
    let fail = |e: parquet::errors::ParquetError| {
        GeomError::format(path, format!("not a readable Parquet file: {e}"))
    };
    let file = File::open(path).map_err(|e| GeomError::io(path, e))?;
    let reader = SerializedFileReader::new(file).map_err(fail)?;
    let meta = reader.metadata();
    let kv: HashMap<String, String> = meta
        .file_metadata()
        .key_value_metadata()
        .map(|l| {
            l.iter()
                .filter_map(|k| Some((k.key.clone(), k.value.clone()?)))
                .collect()
        })
        .unwrap_or_default();
    let schema = meta.file_metadata().schema_descr();
    let mut picks: Vec<(usize, String)> = Vec::new();
    for (i, c) in schema.columns().iter().enumerate() {
        let name = c.name().to_ascii_lowercase();
        if c.path().parts().len() == 1 && wanted.contains(&name.as_str()) {
            if c.max_rep_level() > 0 {
                return Err(GeomError::format(
                    path,
                    format!(
                        "column `{}` is a list; a track table has one value per cell",
                        c.name()
                    ),
                ));
            }
            if picks.iter().any(|(_, n)| *n == name) {
                return Err(GeomError::format(
                    path,
                    format!("two columns called `{name}`"),
                ));
            }
            picks.push((i, name));
        }
    }
    let mut cols: HashMap<String, Column> = HashMap::new();
    for g in 0..meta.num_row_groups() {
        let rg = reader.get_row_group(g).map_err(fail)?;
        for (i, name) in &picks {
            let max_def = schema.column(*i).max_def_level();
            let col = read_column(rg.get_column_reader(*i).map_err(fail)?, max_def)
                .map_err(fail)?
                .ok_or_else(|| {
                    GeomError::format(
                        path,
                        format!(
                            "column `{name}` has type {}: a number or a string is needed",
                            schema.column(*i).physical_type()
                        ),
                    )
                })?;
            match (cols.get_mut(name), col) {
                (None, c) => {
                    cols.insert(name.clone(), c);
                }
                (Some(Column::Int(a)), Column::Int(b)) => a.extend(b),
                (Some(Column::Float(a)), Column::Float(b)) => a.extend(b),
                (Some(Column::Text(a)), Column::Text(b)) => a.extend(b),
                _ => {
                    return Err(GeomError::format(
                        path,
                        format!("column `{name}` changes type between row groups"),
                    ))
                }
            }
        }
    }
    Ok((cols, kv))
}

fn read_column(r: ColumnReader, max_def: i16) -> parquet::errors::Result<Option<Column>> {
    Ok(Some(match r {
        ColumnReader::Int32ColumnReader(mut r) => {
            Column::Int(read_all!(r, max_def, |v: i32| v as i64))
        }
        ColumnReader::Int64ColumnReader(mut r) => Column::Int(read_all!(r, max_def, |v: i64| v)),
        ColumnReader::FloatColumnReader(mut r) => {
            Column::Float(read_all!(r, max_def, |v: f32| v as f64))
        }
        ColumnReader::DoubleColumnReader(mut r) => Column::Float(read_all!(r, max_def, |v: f64| v)),
        ColumnReader::ByteArrayColumnReader(mut r) => {
            Column::Text(read_all!(r, max_def, |v: ByteArray| {
                String::from_utf8_lossy(v.data()).into_owned()
            }))
        }
        _ => return Ok(None),
    }))
}

/// What the `mp.*` metadata states.
#[derive(Default)]
struct Meta {
    fps: Option<f64>,
    units: Option<Units>,
    skeleton: Option<Skeleton>,
    n_frames: Option<usize>,
    frame_size: Option<(usize, usize)>,
}

fn parse_meta(kv: &HashMap<String, String>, path: &Path) -> Result<Meta> {
    let bad =
        |k: &str, v: &str| GeomError::format(path, format!("metadata `{k}` = `{v}` is invalid"));
    let mut m = Meta::default();
    if let Some(v) = kv.get("mp.fps") {
        let fps: f64 = v.parse().map_err(|_| bad("mp.fps", v))?;
        if !(fps.is_finite() && fps > 0.0) {
            return Err(bad("mp.fps", v));
        }
        m.fps = Some(fps);
    }
    if let Some(v) = kv.get("mp.units") {
        m.units = Some(Units::parse(v).map_err(|_| bad("mp.units", v))?);
    }
    if let Some(v) = kv.get("mp.skeleton") {
        let s: Skeleton = serde_json::from_str(v).map_err(|_| bad("mp.skeleton", v))?;
        let n = s.len();
        if s.bones.iter().any(|&(a, b)| a >= n || b >= n)
            || s.root.is_some_and(|r| r >= n)
            || s.coco17.iter().flatten().any(|&c| c >= n)
        {
            return Err(bad("mp.skeleton", "(joint index out of range)"));
        }
        m.skeleton = Some(s);
    }
    if let Some(v) = kv.get("mp.n_frames") {
        m.n_frames = Some(v.parse().map_err(|_| bad("mp.n_frames", v))?);
    }
    if let Some(v) = kv.get("mp.frame_size") {
        let (w, h) = v.split_once('x').ok_or_else(|| bad("mp.frame_size", v))?;
        let w: usize = w.trim().parse().map_err(|_| bad("mp.frame_size", v))?;
        let h: usize = h.trim().parse().map_err(|_| bad("mp.frame_size", v))?;
        m.frame_size = Some((w, h));
    }
    Ok(m)
}

const WANTED: [&str; 12] = [
    "person",
    "frame",
    "time",
    "t",
    "joint",
    "x",
    "y",
    "z",
    "confidence",
    "conf",
    "score",
    "visibility",
];

/// Reads a Parquet table (see the module docs).
pub(crate) fn read_parquet_any(path: &Path, opts: &ReadOptions) -> Result<ParquetRead> {
    opts.validate()?;
    let read = catch_unwind(AssertUnwindSafe(|| read_columns(path, &WANTED)));
    let (cols, kv) = read.map_err(|_| {
        GeomError::format(
            path,
            "not a readable Parquet file: the reader failed on its structure",
        )
    })??;
    let meta = parse_meta(&kv, path)?;
    let need = |n: &str| {
        cols.get(n).ok_or_else(|| {
            GeomError::format(
                path,
                format!(
                    "a track table needs a `{n}` column (has: {})",
                    sorted_keys(&cols)
                ),
            )
        })
    };
    let (frame, joint, x, y) = (need("frame")?, need("joint")?, need("x")?, need("y")?);
    let z = cols.get("z");
    let conf = ["confidence", "conf", "score", "visibility"]
        .iter()
        .find_map(|n| cols.get(*n));
    let person = cols.get("person");
    let time = cols.get("time").or_else(|| cols.get("t"));
    let n = frame.len();
    for (name, c) in &cols {
        if c.len() != n {
            return Err(GeomError::format(
                path,
                format!("column `{name}` has {} values, `frame` has {n}", c.len()),
            ));
        }
    }
    if n == 0 {
        return Err(GeomError::format(path, "the table has no rows"));
    }
    let d = if z.is_some() { 3 } else { 2 };
    let index = |c: &Column, i: usize, what: &str| -> Result<usize> {
        let v = c.number(i);
        if v.is_finite() && v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64 {
            Ok(v as usize)
        } else {
            Err(GeomError::format(
                path,
                format!("row {i}: {what} `{v}` is not an index"),
            ))
        }
    };
    // Joints: names (text) or indices.
    let skeleton_given = opts.skeleton.clone().or_else(|| meta.skeleton.clone());
    let mut names: Vec<String> = skeleton_given
        .as_ref()
        .map(|s| s.joints.clone())
        .unwrap_or_default();
    let mut by_name: HashMap<String, usize> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.clone(), i))
        .collect();
    let mut rows: Vec<Row> = Vec::with_capacity(n);
    let (mut max_frame, mut max_joint) = (0usize, 0usize);
    for i in 0..n {
        let f = index(frame, i, "frame")?;
        let j = match joint {
            Column::Text(v) => {
                let key = v[i].as_deref().ok_or_else(|| {
                    GeomError::format(path, format!("row {i}: the joint is null"))
                })?;
                match by_name.get(key) {
                    Some(&j) => j,
                    None if skeleton_given.is_some() => {
                        return Err(GeomError::format(
                            path,
                            format!("row {i}: joint `{key}` is not in the skeleton"),
                        ))
                    }
                    None => {
                        names.push(key.to_string());
                        by_name.insert(key.to_string(), names.len() - 1);
                        names.len() - 1
                    }
                }
            }
            c => index(c, i, "joint")?,
        };
        let p = match person {
            Some(c) => Some(index(c, i, "person")?),
            None => None,
        };
        let mut xyz = [x.number(i), y.number(i), 0.0];
        if let Some(z) = z {
            xyz[2] = z.number(i);
        }
        let c = conf.map_or(1.0, |c| c.number(i));
        max_frame = max_frame.max(f);
        max_joint = max_joint.max(j);
        rows.push((p, f, j, xyz, c));
    }
    let n_joints = match (&joint, &skeleton_given) {
        (Column::Text(_), _) => names.len(),
        (_, Some(s)) if max_joint < s.len() => s.len(),
        (_, Some(s)) => {
            return Err(GeomError::format(
                path,
                format!("joint index {max_joint} outside skeleton `{}`", s.name),
            ))
        }
        (_, None) => max_joint + 1,
    };
    let n_frames = meta.n_frames.unwrap_or(0).max(max_frame + 1);
    let allowed = n.saturating_mul(100).max(MAX_SPARSE_CELLS);
    if (n_frames as u128) * (n_joints as u128) > allowed as u128 {
        return Err(GeomError::format(
            path,
            format!(
                "frame index {max_frame} and {n_joints} joints imply more frame × joint cells \
                 than {n} rows allow ({allowed})"
            ),
        ));
    }
    let skeleton = match skeleton_given {
        Some(s) => s,
        None if matches!(joint, Column::Text(_)) => {
            // Rows in any order: the names of a built-in skeleton take its order.
            let mut sorted: Vec<&String> = names.iter().collect();
            sorted.sort();
            let builtin = super::builtin_skeletons().into_iter().find(|sk| {
                let mut theirs: Vec<&String> = sk.joints.iter().collect();
                theirs.sort();
                theirs == sorted
            });
            match builtin {
                Some(sk) => {
                    let to: Vec<usize> = names
                        .iter()
                        .map(|n| sk.joint_index(n).unwrap_or(0))
                        .collect();
                    for r in &mut rows {
                        r.2 = to[r.2];
                    }
                    sk
                }
                None => skeleton_from_names(&names),
            }
        }
        None => super::infer_skeleton(opts, n_joints, path)?,
    };
    let units = opts.units.or(meta.units).unwrap_or(opts.units_for(d));
    let (fps, rate_stated) = match meta.fps {
        Some(fps) => (fps, true),
        None => match time {
            Some(tc) => {
                let times: Vec<(usize, f64)> = rows
                    .iter()
                    .enumerate()
                    .map(|(i, r)| (r.1, tc.number(i)))
                    .collect();
                match super::csv::rate_from_times(path, &times)? {
                    Some(fps) => (fps, true),
                    None => (opts.rate(), false),
                }
            }
            None => (opts.rate(), false),
        },
    };
    let build = |span: std::ops::Range<usize>, rows: &[&Row]| {
        let mut pos = Array3::<f64>::from_elem((span.len(), n_joints, d), f64::NAN);
        let mut cf = Array2::<f64>::zeros((span.len(), n_joints));
        for &&(_, f, j, p, c) in rows {
            for k in 0..d {
                pos[[f - span.start, j, k]] = p[k];
            }
            cf[[f - span.start, j]] = c;
        }
        Track::new(pos, Some(cf), fps, units, skeleton.clone())
            .map_err(|e| GeomError::format(path, e.to_string()))
    };
    let content = if person.is_some()
        || kv.get("mp.format").map(String::as_str) == Some(PEOPLE_FORMAT)
    {
        let mut ids: Vec<usize> = rows.iter().filter_map(|r| r.0).collect();
        ids.sort_unstable();
        ids.dedup();
        let mut list = Vec::with_capacity(ids.len());
        for id in ids {
            let mine: Vec<_> = rows.iter().filter(|r| r.0 == Some(id)).collect();
            let first = mine.iter().map(|r| r.1).min().unwrap_or(0);
            let last = mine.iter().map(|r| r.1).max().unwrap_or(0);
            let id = u32::try_from(id)
                .map_err(|_| GeomError::format(path, format!("person id {id} is too large")))?;
            list.push(Person {
                id,
                first_frame: first,
                track: build(first..last + 1, &mine)?,
            });
        }
        Content::People(
            People::new(n_frames, fps, list).map_err(|e| GeomError::format(path, e.to_string()))?,
        )
    } else {
        let all: Vec<_> = rows.iter().collect();
        Content::Track(Box::new(build(0..n_frames, &all)?))
    };
    Ok(ParquetRead {
        content,
        rate_stated,
        frame_size: meta.frame_size,
    })
}

fn sorted_keys(cols: &HashMap<String, Column>) -> String {
    let mut k: Vec<&str> = cols.keys().map(String::as_str).collect();
    k.sort_unstable();
    if k.is_empty() {
        "none of frame, joint, x, y".into()
    } else {
        k.join(", ")
    }
}

/// The columns to write: (person, frame, joint index) per row.
struct Rows {
    person: Vec<i64>,
    frame: Vec<i64>,
    time: Vec<f64>,
    joint: Vec<ByteArray>,
    axes: [Vec<f64>; 3],
    /// Definition level per row: 1 where the position is written, 0 for null.
    defined: Vec<i16>,
    confidence: Vec<f64>,
}

impl Rows {
    fn new() -> Rows {
        Rows {
            person: Vec::new(),
            frame: Vec::new(),
            time: Vec::new(),
            joint: Vec::new(),
            axes: [Vec::new(), Vec::new(), Vec::new()],
            defined: Vec::new(),
            confidence: Vec::new(),
        }
    }

    fn push_track(&mut self, track: &Track, person: Option<u32>, first_frame: usize) {
        let (t_n, _, d) = track.positions().dim();
        let fps = track.fps();
        let names: Vec<ByteArray> = track
            .skeleton()
            .joints
            .iter()
            .map(|n| ByteArray::from(n.as_str()))
            .collect();
        for t in 0..t_n {
            let f = first_frame + t;
            for (j, name) in names.iter().enumerate() {
                if let Some(p) = person {
                    self.person.push(p as i64);
                }
                self.frame.push(f as i64);
                self.time.push(f as f64 / fps);
                self.joint.push(name.clone());
                let c = track.confidence()[[t, j]];
                if c > 0.0 {
                    for k in 0..d {
                        self.axes[k].push(track.positions()[[t, j, k]]);
                    }
                    self.defined.push(1);
                } else {
                    self.defined.push(0);
                }
                self.confidence.push(c);
            }
        }
    }
}

fn parquet_err(e: parquet::errors::ParquetError) -> GeomError {
    GeomError::param("track", format!("the Parquet writer failed: {e}"))
}

/// Writes the table of `rows` with the `mp.*` metadata of `track_like`.
fn table_bytes(rows: &Rows, d: usize, meta: Vec<KeyValue>, people: bool) -> Result<Vec<u8>> {
    if d != 2 && d != 3 {
        return Err(GeomError::param(
            "track",
            format!("a Parquet track table holds 2D or 3D positions, not {d} dimensions"),
        ));
    }
    let mut schema = String::from("message track {\n");
    if people {
        schema.push_str("  REQUIRED INT64 person;\n");
    }
    schema.push_str(
        "  REQUIRED INT64 frame;\n  REQUIRED DOUBLE time;\n  REQUIRED BYTE_ARRAY joint (STRING);\n",
    );
    for a in ["x", "y", "z"].iter().take(d) {
        schema.push_str(&format!("  OPTIONAL DOUBLE {a};\n"));
    }
    schema.push_str("  REQUIRED DOUBLE confidence;\n}\n");
    let schema = Arc::new(parse_message_type(&schema).map_err(parquet_err)?);
    let props = Arc::new(
        WriterProperties::builder()
            .set_compression(Compression::SNAPPY)
            .set_key_value_metadata(Some(meta))
            .set_created_by(format!("mp {}", env!("CARGO_PKG_VERSION")))
            .build(),
    );
    let mut w = SerializedFileWriter::new(Vec::new(), schema, props).map_err(parquet_err)?;
    let mut rg = w.next_row_group().map_err(parquet_err)?;
    let mut k = 0usize;
    while let Some(mut col) = rg.next_column().map_err(parquet_err)? {
        // Columns in schema order: [person], frame, time, joint, axes…, confidence.
        let c = if people { k } else { k + 1 };
        match c {
            0 => {
                col.typed::<Int64Type>()
                    .write_batch(&rows.person, None, None)
                    .map_err(parquet_err)?;
            }
            1 => {
                col.typed::<Int64Type>()
                    .write_batch(&rows.frame, None, None)
                    .map_err(parquet_err)?;
            }
            2 => {
                col.typed::<DoubleType>()
                    .write_batch(&rows.time, None, None)
                    .map_err(parquet_err)?;
            }
            3 => {
                col.typed::<ByteArrayType>()
                    .write_batch(&rows.joint, None, None)
                    .map_err(parquet_err)?;
            }
            c if c < 4 + d => {
                col.typed::<DoubleType>()
                    .write_batch(&rows.axes[c - 4], Some(&rows.defined), None)
                    .map_err(parquet_err)?;
            }
            _ => {
                col.typed::<DoubleType>()
                    .write_batch(&rows.confidence, None, None)
                    .map_err(parquet_err)?;
            }
        }
        col.close().map_err(parquet_err)?;
        k += 1;
    }
    rg.close().map_err(parquet_err)?;
    w.into_inner().map_err(parquet_err)
}

fn meta_of(
    format: &str,
    fps: f64,
    units: Units,
    skeleton: &Skeleton,
    n_frames: usize,
    frame_size: Option<(usize, usize)>,
) -> Result<Vec<KeyValue>> {
    let sk =
        serde_json::to_string(skeleton).map_err(|e| GeomError::param("skeleton", e.to_string()))?;
    let mut kv = vec![
        KeyValue::new("mp.format".into(), format.to_string()),
        KeyValue::new("mp.version".into(), "1".to_string()),
        KeyValue::new("mp.fps".into(), format!("{fps}")),
        KeyValue::new("mp.units".into(), units.as_str().to_string()),
        KeyValue::new("mp.skeleton".into(), sk),
        KeyValue::new("mp.n_frames".into(), n_frames.to_string()),
    ];
    if let Some((w, h)) = frame_size {
        kv.push(KeyValue::new("mp.frame_size".into(), format!("{w}x{h}")));
    }
    Ok(kv)
}

/// The Parquet bytes of a track (see the module docs).
pub(crate) fn track_to_parquet_bytes(
    track: &Track,
    frame_size: Option<(usize, usize)>,
) -> Result<Vec<u8>> {
    let mut rows = Rows::new();
    rows.push_track(track, None, 0);
    let meta = meta_of(
        TRACK_FORMAT,
        track.fps(),
        track.units(),
        track.skeleton(),
        track.n_frames(),
        frame_size,
    )?;
    table_bytes(&rows, track.dims(), meta, false)
}

/// The Parquet bytes of people: rows of each person over their span, with
/// a `person` column.
pub(crate) fn people_to_parquet_bytes(
    people: &People,
    frame_size: Option<(usize, usize)>,
) -> Result<Vec<u8>> {
    let Some(first) = people.people().first() else {
        return Err(GeomError::param(
            "people",
            "nobody to write: a Parquet people table needs a person to take its skeleton from",
        ));
    };
    let t = &first.track;
    let mut rows = Rows::new();
    for p in people.people() {
        rows.push_track(&p.track, Some(p.id), p.first_frame);
    }
    let meta = meta_of(
        PEOPLE_FORMAT,
        people.fps(),
        t.units(),
        t.skeleton(),
        people.n_frames(),
        frame_size,
    )?;
    table_bytes(&rows, t.dims(), meta, true)
}

/// Writes a track as a Parquet table (atomic).
pub fn write_parquet(
    path: impl AsRef<Path>,
    track: &Track,
    frame_size: Option<(usize, usize)>,
) -> Result<()> {
    write_atomic(path, &track_to_parquet_bytes(track, frame_size)?)
}

/// Writes people as a Parquet table (atomic).
pub(crate) fn write_people_parquet(
    path: impl AsRef<Path>,
    people: &People,
    frame_size: Option<(usize, usize)>,
) -> Result<()> {
    write_atomic(path, &people_to_parquet_bytes(people, frame_size)?)
}
