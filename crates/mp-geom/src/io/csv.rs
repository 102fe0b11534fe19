//! CSV tracks, in two layouts. Lines starting with `#` and blank lines are
//! skipped; fields are separated by commas (no quoting).
//!
//! **Long**: one row per (frame, joint), header
//! `frame,joint,x,y[,z][,confidence]`. `joint` is either an index or a joint
//! name; `confidence` may also be called `conf`, `score` or `visibility`.
//! Frames run from 0 to the largest frame index; (frame, joint) pairs without
//! a row are missing (confidence 0).
//!
//! ```text
//! frame,joint,x,y,confidence
//! 0,nose,101.5,48.0,0.98
//! 0,left_eye,104.0,45.5,0.95
//! ```
//!
//! **Wide**: one row per frame, header `[frame,]j0_x,j0_y[,j0_z][,j0_conf],j1_x,…`
//! where the prefix before `_x` is the joint name (`_c`, `_conf`,
//! `_confidence`, `_score`, `_visibility` are confidence columns). An empty
//! cell or `nan` is a missing value.
//!
//! ```text
//! frame,nose_x,nose_y,nose_conf,left_eye_x,left_eye_y,left_eye_conf
//! 0,101.5,48.0,0.98,104.0,45.5,0.95
//! ```
//!
//! A `time` column (seconds; also `t`) states the frame rate: the frames
//! over the time from the first to the last (times must increase with the
//! frame). Without one the rate is [`ReadOptions::fps`], else
//! [`super::DEFAULT_FPS`]. The writer adds `time` after `frame`.
//!
//! The skeleton is the one in [`ReadOptions::skeleton`], else chosen from the
//! joint names (`super::skeleton_from_names`).

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use ndarray::{Array2, Array3};

use super::{skeleton_from_names, write_atomic, ReadOptions};
use crate::error::{GeomError, Result};
use crate::track::Track;

/// The most frame × joint cells a long-form CSV may imply by its largest
/// frame and joint indices when it has fewer than one row per 100 cells:
/// 10 million (240 MB of positions in 3D). A file with more rows may imply
/// up to 100 cells per row.
pub const MAX_SPARSE_CELLS: usize = 10_000_000;

/// Which CSV layout to write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum CsvLayout {
    /// `frame,joint,x,y[,z],confidence`, one row per frame and joint (joint by name).
    Long,
    /// `frame,<joint>_x,<joint>_y[,<joint>_z],<joint>_conf,…`, one row per frame.
    Wide,
}

fn is_conf(name: &str) -> bool {
    matches!(name, "confidence" | "conf" | "score" | "visibility" | "c")
}

fn parse_cell(cell: &str, path: &Path, line: usize, col: &str) -> Result<f64> {
    let c = cell.trim();
    if c.is_empty() || c.eq_ignore_ascii_case("nan") {
        return Ok(f64::NAN);
    }
    c.parse::<f64>().map_err(|_| {
        GeomError::format(
            path,
            format!("line {line}, column `{col}`: `{c}` is not a number"),
        )
    })
}

/// Reads a CSV track (long or wide, detected from the header).
pub fn read_csv(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<Track> {
    read_csv_rated(path, opts).map(|(t, _)| t)
}

/// [`read_csv`], and whether the file states its frame rate (a `time`
/// column).
pub(crate) fn read_csv_rated(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<(Track, bool)> {
    let path = path.as_ref();
    opts.validate()?;
    let text = std::fs::read_to_string(path).map_err(|e| GeomError::io(path, e))?;
    csv_rated(&text, path, opts)
}

/// Parses CSV text (long or wide, detected from the header) as
/// [`read_csv`] does; `path` names the source in errors.
pub fn track_from_csv_str(text: &str, path: &Path, opts: &ReadOptions) -> Result<Track> {
    csv_rated(text, path, opts).map(|(t, _)| t)
}

fn is_time(name: &str) -> bool {
    matches!(name, "time" | "t")
}

/// The frame rate stated by `(frame, seconds)` pairs: the frames over the
/// time from the first frame to the last. The times of one frame must
/// agree and increase with the frame.
pub(crate) fn rate_from_times(path: &Path, times: &[(usize, f64)]) -> Result<Option<f64>> {
    let mut by_frame: Vec<(usize, f64)> = times.to_vec();
    by_frame.sort_by_key(|&(f, _)| f);
    by_frame.dedup_by(|b, a| a.0 == b.0 && a.1 == b.1);
    for w in by_frame.windows(2) {
        let ((f0, t0), (f1, t1)) = (w[0], w[1]);
        if !(t0.is_finite() && t1.is_finite()) || f1 == f0 || t1 <= t0 {
            return Err(GeomError::format(
                path,
                format!(
                    "the `time` column must increase with the frame and be the same within a \
                     frame: frame {f0} at {t0} s, frame {f1} at {t1} s"
                ),
            ));
        }
    }
    let (Some(&(fa, ta)), Some(&(fb, tb))) = (by_frame.first(), by_frame.last()) else {
        return Ok(None);
    };
    if fb == fa {
        return Ok(None);
    }
    let fps = (fb - fa) as f64 / (tb - ta);
    // Times written with a few decimals: a rate within 0.01 % of a whole
    // number is that number.
    let r = fps.round();
    Ok(Some(if (fps - r).abs() <= 1e-4 * r { r } else { fps }))
}

fn csv_rated(text: &str, path: &Path, opts: &ReadOptions) -> Result<(Track, bool)> {
    opts.validate()?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (_, header) = lines
        .next()
        .ok_or_else(|| GeomError::format(path, "empty CSV file"))?;
    let cols: Vec<String> = header
        .split(',')
        .map(|c| c.trim().to_ascii_lowercase())
        .collect();
    let rows: Vec<(usize, Vec<&str>)> = lines.map(|(n, l)| (n, l.split(',').collect())).collect();
    for (n, r) in &rows {
        if r.len() != cols.len() {
            return Err(GeomError::format(
                path,
                format!("line {n} has {} fields, header has {}", r.len(), cols.len()),
            ));
        }
    }
    let track = if cols.iter().any(|c| c == "joint") {
        read_long(path, &cols, &rows, opts)?
    } else {
        // Keep the header's original case for joint names.
        let raw: Vec<String> = header.split(',').map(|c| c.trim().to_string()).collect();
        read_wide(path, &raw, &rows, opts)?
    };
    // The rate a `time` column states: per row, its frame (the `frame`
    // column, else the row's place) and its time.
    let Some(tc) = cols.iter().position(|c| is_time(c)) else {
        return Ok((track, false));
    };
    let fc = cols.iter().position(|c| c == "frame");
    let mut times = Vec::with_capacity(rows.len());
    for (i, (n, r)) in rows.iter().enumerate() {
        let f = match fc {
            Some(fc) => r[fc].trim().parse::<usize>().map_err(|_| {
                GeomError::format(path, format!("line {n}: frame `{}` is not an index", r[fc]))
            })?,
            None => i,
        };
        times.push((f, parse_cell(r[tc], path, *n, &cols[tc])?));
    }
    match rate_from_times(path, &times)? {
        Some(fps) => Ok((track.with_fps(fps)?, true)),
        None => Ok((track, false)),
    }
}

fn read_long(
    path: &Path,
    cols: &[String],
    rows: &[(usize, Vec<&str>)],
    opts: &ReadOptions,
) -> Result<Track> {
    let find = |n: &str| cols.iter().position(|c| c == n);
    let need = |n: &str| {
        find(n).ok_or_else(|| GeomError::format(path, format!("long CSV needs a `{n}` column")))
    };
    let (fc, jc, xc, yc) = (need("frame")?, need("joint")?, need("x")?, need("y")?);
    let zc = find("z");
    let cc = cols.iter().position(|c| is_conf(c));
    let d = if zc.is_some() { 3 } else { 2 };
    // Joint ids: all integers → indices; otherwise names.
    let numeric = rows
        .iter()
        .all(|(_, r)| r[jc].trim().parse::<usize>().is_ok());
    let mut names: Vec<String> = match &opts.skeleton {
        Some(s) => s.joints.clone(),
        None => Vec::new(),
    };
    let mut by_name: HashMap<String, usize> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.clone(), i))
        .collect();
    let mut entries = Vec::with_capacity(rows.len());
    let mut max_frame = 0usize;
    let mut max_joint = 0usize;
    for (n, r) in rows {
        let f: usize = r[fc].trim().parse().map_err(|_| {
            GeomError::format(path, format!("line {n}: frame `{}` is not an index", r[fc]))
        })?;
        let key = r[jc].trim();
        let j = if numeric {
            key.parse::<usize>().unwrap_or(0)
        } else if let Some(&j) = by_name.get(key) {
            j
        } else if opts.skeleton.is_some() {
            return Err(GeomError::format(
                path,
                format!("line {n}: joint `{key}` is not in the given skeleton"),
            ));
        } else {
            names.push(key.to_string());
            by_name.insert(key.to_string(), names.len() - 1);
            names.len() - 1
        };
        let mut p = [0.0; 3];
        p[0] = parse_cell(r[xc], path, *n, "x")?;
        p[1] = parse_cell(r[yc], path, *n, "y")?;
        if let Some(zc) = zc {
            p[2] = parse_cell(r[zc], path, *n, "z")?;
        }
        let c = match cc {
            Some(cc) => parse_cell(r[cc], path, *n, &cols[cc])?,
            None => 1.0,
        };
        max_frame = max_frame.max(f);
        max_joint = max_joint.max(j);
        entries.push((f, j, p, c));
    }
    if entries.is_empty() {
        return Err(GeomError::format(path, "CSV has a header but no rows"));
    }
    // Guard against absurd indices that would allocate huge, almost empty
    // arrays: the frames × joints they imply must stay within
    // `MAX_SPARSE_CELLS`, or within 100 cells per row of the file.
    let allowed = entries.len().saturating_mul(100).max(MAX_SPARSE_CELLS);
    let cells = (max_frame as u128 + 1) * (max_joint as u128 + 1);
    if cells > allowed as u128 {
        return Err(GeomError::format(
            path,
            format!(
                "frame index {max_frame} and joint index {max_joint} imply {cells} frame × joint \
                 cells for {} rows; at most {allowed} are allowed ({MAX_SPARSE_CELLS}, or 100 per \
                 row for longer files)",
                entries.len()
            ),
        ));
    }
    let t = max_frame + 1;
    let j = if numeric {
        match &opts.skeleton {
            Some(s) if max_joint < s.len() => s.len(),
            Some(s) => {
                return Err(GeomError::format(
                    path,
                    format!("joint index {max_joint} outside skeleton `{}`", s.name),
                ))
            }
            None => max_joint + 1,
        }
    } else {
        names.len()
    };
    let mut pos = Array3::<f64>::zeros((t, j, d));
    let mut conf = Array2::<f64>::zeros((t, j));
    for (f, ji, p, c) in entries {
        for k in 0..d {
            pos[[f, ji, k]] = p[k];
        }
        conf[[f, ji]] = c;
    }
    let skeleton = match &opts.skeleton {
        Some(s) => s.clone(),
        None if numeric => super::infer_skeleton(opts, j, path)?,
        None => skeleton_from_names(&names),
    };
    Track::new(pos, Some(conf), opts.rate(), opts.units_for(d), skeleton)
        .map_err(|e| GeomError::format(path, e.to_string()))
}

fn read_wide(
    path: &Path,
    cols: &[String],
    rows: &[(usize, Vec<&str>)],
    opts: &ReadOptions,
) -> Result<Track> {
    // Column role per header cell: (joint, axis 0/1/2 or 3 = confidence).
    let mut names: Vec<String> = Vec::new();
    let mut index: HashMap<&str, usize> = HashMap::new();
    let mut roles: Vec<Option<(usize, usize)>> = Vec::with_capacity(cols.len());
    let mut has_z = false;
    for c in cols {
        let lc = c.to_ascii_lowercase();
        if lc == "frame" || is_time(&lc) {
            roles.push(None);
            continue;
        }
        let (joint, suffix) = c.rsplit_once('_').ok_or_else(|| {
            GeomError::format(
                path,
                format!("wide CSV column `{c}` is not `<joint>_x/_y/_z/_conf`"),
            )
        })?;
        let axis = match suffix.to_ascii_lowercase().as_str() {
            "x" => 0,
            "y" => 1,
            "z" => {
                has_z = true;
                2
            }
            s if is_conf(s) => 3,
            _ => {
                return Err(GeomError::format(
                    path,
                    format!("wide CSV column `{c}`: unknown suffix `_{suffix}`"),
                ))
            }
        };
        let ji = *index.entry(joint).or_insert_with(|| {
            names.push(joint.to_string());
            names.len() - 1
        });
        roles.push(Some((ji, axis)));
    }
    if names.is_empty() {
        return Err(GeomError::format(path, "wide CSV has no joint columns"));
    }
    let d = if has_z { 3 } else { 2 };
    // Which (joint, axis) columns exist, in one pass over the header.
    let mut present = vec![[false; 4]; names.len()];
    for &(ji, axis) in roles.iter().flatten() {
        present[ji][axis] = true;
    }
    for (ji, name) in names.iter().enumerate() {
        for (axis, axis_name) in ["x", "y", "z"].iter().enumerate().take(d) {
            if !present[ji][axis] {
                return Err(GeomError::format(
                    path,
                    format!("joint `{name}` lacks its `_{axis_name}` column"),
                ));
            }
        }
    }
    if rows.is_empty() {
        return Err(GeomError::format(path, "CSV has a header but no rows"));
    }
    let (t, j) = (rows.len(), names.len());
    let mut pos = Array3::<f64>::zeros((t, j, d));
    let mut conf = Array2::<f64>::ones((t, j));
    for (fi, (n, r)) in rows.iter().enumerate() {
        for (ci, role) in roles.iter().enumerate() {
            if let Some((ji, axis)) = *role {
                let v = parse_cell(r[ci], path, *n, &cols[ci])?;
                if axis == 3 {
                    conf[[fi, ji]] = v;
                } else {
                    pos[[fi, ji, axis]] = v;
                }
            }
        }
    }
    let skeleton = match &opts.skeleton {
        Some(s) if s.len() == j => s.clone(),
        Some(s) => {
            return Err(GeomError::format(
                path,
                format!("CSV has {j} joints, skeleton `{}` has {}", s.name, s.len()),
            ))
        }
        None => skeleton_from_names(&names),
    };
    Track::new(pos, Some(conf), opts.rate(), opts.units_for(d), skeleton)
        .map_err(|e| GeomError::format(path, e.to_string()))
}

/// Encodes a track as CSV text in the given layout.
pub fn track_to_csv_string(track: &Track, layout: CsvLayout) -> Result<String> {
    let sk = track.skeleton();
    if let Some(bad) = sk
        .joints
        .iter()
        .find(|n| n.contains(',') || n.contains('\n'))
    {
        return Err(GeomError::param(
            "skeleton",
            format!("joint name `{bad}` cannot be written to CSV"),
        ));
    }
    let (t, j, d) = track.positions().dim();
    let pos = track.positions();
    let conf = track.confidence();
    let axes = ["x", "y", "z"];
    // Seconds to the nanosecond: the rate read back is within 1e-6 of the
    // track's over any two frames up to 1 kHz.
    let fps = track.fps();
    let time = |f: usize| format!("{:.9}", f as f64 / fps);
    let mut s = String::new();
    match layout {
        CsvLayout::Long => {
            s.push_str("frame,time,joint,x,y");
            if d == 3 {
                s.push_str(",z");
            }
            s.push_str(",confidence\n");
            for f in 0..t {
                for ji in 0..j {
                    let _ = write!(s, "{f},{},{}", time(f), sk.joints[ji]);
                    for k in 0..d {
                        let _ = write!(s, ",{}", pos[[f, ji, k]]);
                    }
                    let _ = writeln!(s, ",{}", conf[[f, ji]]);
                }
            }
        }
        CsvLayout::Wide => {
            if d > 3 {
                return Err(GeomError::param(
                    "track",
                    format!("wide CSV holds at most 3 dimensions, track has {d}"),
                ));
            }
            s.push_str("frame,time");
            for name in &sk.joints {
                for a in axes.iter().take(d) {
                    let _ = write!(s, ",{name}_{a}");
                }
                let _ = write!(s, ",{name}_conf");
            }
            s.push('\n');
            for f in 0..t {
                let _ = write!(s, "{f},{}", time(f));
                for ji in 0..j {
                    for k in 0..d {
                        let _ = write!(s, ",{}", pos[[f, ji, k]]);
                    }
                    let _ = write!(s, ",{}", conf[[f, ji]]);
                }
                s.push('\n');
            }
        }
    }
    Ok(s)
}

/// Writes a track as CSV (atomic), with a `time` column that states the
/// frame rate. Units and bones are not stored: read back with the same
/// [`ReadOptions`].
pub fn write_csv(path: impl AsRef<Path>, track: &Track, layout: CsvLayout) -> Result<()> {
    let s = track_to_csv_string(track, layout)?;
    write_atomic(path, s.as_bytes())
}
