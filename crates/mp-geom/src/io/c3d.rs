//! C3D motion capture files: the 3D points of the `POINT` section as a
//! track (analog channels, force plates and events are not read), read
//! through the `c3dio` crate.
//!
//! **Reading**: one joint per point, named by `POINT:LABELS` (blank labels
//! become `j<index>`, a repeated label gets `_<index>` appended), the
//! skeleton chosen from the names as the other readers do
//! ([`super::skeleton_from_names`]) unless [`ReadOptions::skeleton`] is
//! given. A corrupt or truncated file is an error naming it: the layout
//! (header, block numbers, frame and point counts against the file's size)
//! is checked before the library parses it, and a failure inside the library
//! is caught. Positions are converted to metres from `POINT:UNITS` (`mm`, `cm`,
//! `m`, `in`, `ft`; blank means millimetres, the format's default), the frame
//! rate is `POINT:RATE` (the header's). A point whose residual is negative
//! (the format's mark of an invalid point) or whose coordinates are not
//! finite is missing (confidence 0); every other point has confidence 1.
//!
//! **Writing**: 3D tracks in metres only — a C3D file holds 3D points in a
//! length unit, so a 2D track (pixels) is refused rather than given a made-up
//! z. The file is written here from the format's definition (c3dio's writer
//! leaves out the length byte of group descriptions, which other readers
//! need): an Intel-order header, a parameter section with the `POINT` group
//! (`USED`, `SCALE` −1, `RATE` = the track's frame rate, `DATA_START`,
//! `FRAMES`, `UNITS` `mm`, `LABELS` = the joint names, non-ASCII characters
//! and whitespace becoming `_`, `DESCRIPTIONS`; `LONG_FRAMES` past 65535
//! frames) and the `ANALOG` group (no channels, rate 0), then 32-bit float
//! points in millimetres. A joint with confidence 0 is an invalid point (coordinates
//! 0, residual word −1); confidence values between 0 and 1 are not kept (C3D
//! has residuals, not confidence). At most 255 joints (one `POINT:LABELS`
//! dimension).

use std::panic::catch_unwind;
use std::path::Path;

use c3dio::C3d;
use ndarray::Array3;

use super::{skeleton_from_names, write_atomic, ReadOptions};
use crate::error::{GeomError, Result};
use crate::track::{Track, Units};

/// Metres per unit of a `POINT:UNITS` value.
fn metres_per_unit(units: &str) -> Option<f64> {
    Some(match units.trim().to_ascii_lowercase().as_str() {
        "" | "mm" => 1e-3,
        "cm" => 1e-2,
        "dm" => 1e-1,
        "m" => 1.0,
        "in" | "inch" | "inches" => 0.0254,
        "ft" | "feet" => 0.3048,
        _ => return None,
    })
}

/// The processor that wrote a C3D file: how its 16-bit words read.
#[derive(Clone, Copy)]
enum Words {
    Little,
    Big,
}

impl Words {
    fn u16(self, b: &[u8], at: usize) -> Option<u16> {
        let w = [*b.get(at)?, *b.get(at + 1)?];
        Some(match self {
            Words::Little => u16::from_le_bytes(w),
            Words::Big => u16::from_be_bytes(w),
        })
    }
}

/// Checks the layout of a C3D file before the library parses it, so that a
/// corrupt or truncated file gives a message naming what is wrong instead
/// of a failure (or a huge allocation) inside the parser.
fn check_layout(b: &[u8], path: &Path) -> Result<()> {
    let bad = |m: String| Err(GeomError::format(path, m));
    if b.len() < 1024 {
        return bad(format!(
            "{} bytes: too short for a C3D file (a 512-byte header and a parameter block)",
            b.len()
        ));
    }
    if b[1] != 0x50 {
        return bad(format!(
            "not a C3D file: the header's second byte is {:#04x}, a C3D file has 0x50",
            b[1]
        ));
    }
    if b[0] != 2 {
        return bad(format!(
            "parameters start in block {}: only files with the parameters in block 2 (as \
             every writer puts them) are read",
            b[0]
        ));
    }
    let words = match b[512 + 3] {
        0x54 | 0x55 => Words::Little,
        0x56 => Words::Big,
        p => {
            return bad(format!(
                "unknown processor type {p:#04x} in the parameter block"
            ))
        }
    };
    let word = |at: usize| words.u16(b, at).unwrap_or(0) as usize;
    let n_points = word(2);
    let analog_per_frame = word(4);
    let (first, last) = (word(6), word(8));
    let data_block = word(16);
    if n_points == 0 {
        return bad("the file holds no 3D points (header point count 0)".into());
    }
    if data_block < 3 || 512 * (data_block - 1) > b.len() {
        return bad(format!(
            "the header puts the data at block {data_block}, the file has {} blocks: truncated \
             or corrupt",
            b.len().div_ceil(512)
        ));
    }
    if last < first || last - first >= 65535 {
        return bad(format!(
            "the header's frame range {first}..{last} is not a range of frames"
        ));
    }
    // The header's frames must fit in the data (16 bytes a point and 4 an
    // analog sample in a float file, half in an integer one: the scale
    // factor's sign), which also bounds what the parser allocates.
    let sign_byte = match (words, b[512 + 3]) {
        (Words::Big, _) => 12,
        (_, 0x55) => 13,
        _ => 15,
    };
    let word_bytes = if b[sign_byte] & 0x80 != 0 { 4 } else { 2 };
    let frames = last - first + 1;
    let data = b.len() - 512 * (data_block - 1);
    if frames * (n_points * 4 + analog_per_frame) * word_bytes > data {
        return bad(format!(
            "the header announces {frames} frames of {n_points} points, the data holds {data} \
             bytes: truncated"
        ));
    }
    // The analog samples of a frame must be ANALOG:USED channels × samples
    // per channel (the parser allocates that many per frame before it checks).
    if analog_per_frame > 0 {
        let used = analog_used(b, words, 512 * (data_block - 1))
            .ok_or_else(|| GeomError::format(path, "corrupt parameter section"))?;
        let per_channel = word(18);
        if used * per_channel != analog_per_frame {
            return bad(format!(
                "{analog_per_frame} analog samples a frame, but {used} channels × {per_channel} \
                 samples: corrupt header or ANALOG:USED"
            ));
        }
    }
    Ok(())
}

/// `ANALOG:USED` found by walking the parameter section (bytes 512..end),
/// every entry checked against the section's bounds: `Some(0)` when absent,
/// `None` when an entry runs past the section.
fn analog_used(b: &[u8], words: Words, end: usize) -> Option<usize> {
    let sec = b.get(512..end)?;
    let mut i = 4;
    let mut analog_group = None;
    // (group id, value) of every parameter called USED.
    let mut used = Vec::new();
    for _ in 0..65536 {
        let (&len, &id) = (sec.get(i)?, sec.get(i + 1)?);
        let (len, id) = ((len as i8).unsigned_abs() as usize, id as i8);
        if len == 0 || id == 0 {
            break;
        }
        let name = sec.get(i + 2..i + 2 + len)?;
        let next_at = i + 2 + len;
        let next = words.u16(sec, next_at)? as usize;
        if id < 0 {
            if name.eq_ignore_ascii_case(b"ANALOG") {
                analog_group = Some(id.unsigned_abs());
            }
        } else if name.eq_ignore_ascii_case(b"USED") {
            let kind = *sec.get(next_at + 2)? as i8;
            let n_dims = *sec.get(next_at + 3)? as usize;
            let data = next_at + 4 + n_dims;
            let value = match kind {
                2 => words.u16(sec, data)? as usize,
                1 => *sec.get(data)? as usize,
                _ => 0,
            };
            used.push((id.unsigned_abs(), value));
        }
        if next == 0 {
            break;
        }
        i = next_at + next;
        if i + 1 >= sec.len() {
            break;
        }
    }
    let g = analog_group?;
    Some(used.iter().find(|(id, _)| *id == g).map_or(0, |(_, v)| *v))
}

/// A frame rate stored as a 32-bit float, as the decimal it was written
/// from (29.97, not 29.969999313354492).
fn rate_of(r: f32) -> f64 {
    format!("{r}").parse().unwrap_or(r as f64)
}

/// [`read_c3d`], and whether the file states its frame rate.
pub(crate) fn read_c3d_rated(path: &Path, opts: &ReadOptions) -> Result<(Track, bool)> {
    let bytes = std::fs::read(path).map_err(|e| GeomError::io(path, e))?;
    track_from_c3d_bytes_rated(&bytes, path, opts)
}

fn track_from_c3d_bytes_rated(
    bytes: &[u8],
    path: &Path,
    opts: &ReadOptions,
) -> Result<(Track, bool)> {
    opts.validate()?;
    check_layout(bytes, path)?;
    let parsed = catch_unwind(|| C3d::from_bytes(bytes).map_err(|e| format!("{e:?}")));
    let c3d =
        match parsed {
            Ok(Ok(c)) => c,
            Ok(Err(e)) => {
                return Err(GeomError::format(
                    path,
                    format!("not a readable C3D file: {e}"),
                ))
            }
            Err(_) => return Err(GeomError::format(
                path,
                "not a readable C3D file: the C3D parser failed on its structure (corrupt file)",
            )),
        };
    let pts = &c3d.points;
    let (t_n, j_n) = (pts.rows(), pts.cols());
    if t_n == 0 || j_n == 0 {
        return Err(GeomError::format(
            path,
            format!("the C3D file holds {t_n} frames of {j_n} 3D points: no track"),
        ));
    }
    let units: String = pts.units.iter().collect();
    let scale = metres_per_unit(&units).ok_or_else(|| {
        GeomError::format(
            path,
            format!(
                "POINT:UNITS `{}` is not a length unit this reader knows (mm, cm, m, in, ft)",
                units.trim()
            ),
        )
    })?;
    let mut names: Vec<String> = Vec::with_capacity(j_n);
    for j in 0..j_n {
        let l = pts.labels.get(j).map(|s| s.trim()).unwrap_or("");
        let name = if l.is_empty() {
            format!("j{j}")
        } else if names.iter().any(|n| n == l) {
            format!("{l}_{j}")
        } else {
            l.to_string()
        };
        names.push(name);
    }
    let mut pos = Array3::<f64>::from_elem((t_n, j_n, 3), f64::NAN);
    for t in 0..t_n {
        for j in 0..j_n {
            let Some(p) = pts.points.get(t, j) else {
                continue;
            };
            if p.residual >= 0.0 && p.point.iter().all(|v| v.is_finite()) {
                for k in 0..3 {
                    pos[[t, j, k]] = p.point[k] as f64 * scale;
                }
            }
        }
    }
    let file_rate = rate_of(pts.frame_rate);
    let stated = file_rate.is_finite() && file_rate > 0.0;
    let fps = if stated { file_rate } else { opts.rate() };
    let skeleton = match &opts.skeleton {
        Some(_) => super::infer_skeleton(opts, j_n, path)?,
        None => skeleton_from_names(&names),
    };
    let track = Track::new(pos, None, fps, Units::Metres, skeleton)
        .map_err(|e| GeomError::format(path, e.to_string()))?;
    Ok((track, stated))
}

/// A C3D label: ASCII, without whitespace.
fn label(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii() && !c.is_ascii_whitespace() && !c.is_ascii_control() {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// One entry of a C3D parameter section.
enum Entry<'a> {
    Group {
        id: u8,
        name: &'a str,
    },
    Param {
        group: u8,
        name: &'a str,
        /// Type (−1 char, 2 int16, 4 float), dimensions, data bytes.
        kind: i8,
        dims: Vec<u8>,
        data: Vec<u8>,
    },
}

/// A parameter's value: type (−1 char, 2 int16, 4 float), dimensions, data bytes.
type Value = (i8, Vec<u8>, Vec<u8>);

fn int16(v: u16) -> Value {
    (2, Vec::new(), v.to_le_bytes().to_vec())
}

fn float(v: f32) -> Value {
    (4, Vec::new(), v.to_le_bytes().to_vec())
}

/// A char parameter of `strings` padded to one length: dimensions
/// `[length, count]` (just `[length]` for one string).
fn chars(strings: &[String], one: bool) -> Value {
    let len = strings.iter().map(String::len).max().unwrap_or(0).max(1);
    let mut data = Vec::with_capacity(len * strings.len());
    for s in strings {
        data.extend(s.bytes());
        data.extend(std::iter::repeat_n(b' ', len - s.len()));
    }
    let dims = if one {
        vec![len as u8]
    } else {
        vec![len as u8, strings.len() as u8]
    };
    (-1, dims, data)
}

/// The parameter section (from its 4-byte header), padded to whole blocks.
fn parameter_section(entries: &[Entry<'_>]) -> Vec<u8> {
    let mut out = vec![0x01, 0x50, 0, 0x54];
    for (k, e) in entries.iter().enumerate() {
        let last = k + 1 == entries.len();
        match e {
            Entry::Group { id, name } => {
                out.push(name.len() as u8);
                out.push((-(*id as i8)) as u8);
                out.extend(name.bytes());
                // Offset to the next entry (from this word): itself, the
                // description's length byte, an empty description.
                out.extend(3u16.to_le_bytes());
                out.push(0);
            }
            Entry::Param {
                group,
                name,
                kind,
                dims,
                data,
            } => {
                out.push(name.len() as u8);
                out.push(*group);
                out.extend(name.bytes());
                let next = if last {
                    0
                } else {
                    (2 + 1 + 1 + dims.len() + data.len() + 1) as u16
                };
                out.extend(next.to_le_bytes());
                out.push(*kind as u8);
                out.push(dims.len() as u8);
                out.extend(dims);
                out.extend(data);
                out.push(0);
            }
        }
    }
    let blocks = out.len().div_ceil(512);
    out.resize(blocks * 512, 0);
    out[2] = blocks as u8;
    out
}

/// The C3D bytes of a 3D track in metres (see the module docs).
pub(crate) fn track_to_c3d_bytes(track: &Track) -> Result<Vec<u8>> {
    if track.dims() != 3 {
        return Err(GeomError::param(
            "track",
            format!(
                "a C3D file holds 3D points; this track has {} dimensions per joint (write a 2D \
                 track as .npz, .csv, .parquet or .pose)",
                track.dims()
            ),
        ));
    }
    if track.units() != Units::Metres {
        return Err(GeomError::param(
            "track",
            format!(
                "a C3D file holds positions in a length unit; this track is in `{}`",
                track.units().as_str()
            ),
        ));
    }
    let (t_n, j_n) = (track.n_frames(), track.n_joints());
    if t_n == 0 || j_n == 0 {
        return Err(GeomError::param(
            "track",
            format!(
                "a C3D file needs frames and points; this track has {t_n} frames of {j_n} joints"
            ),
        ));
    }
    if j_n > 255 {
        return Err(GeomError::param(
            "track",
            format!("a C3D file labels at most 255 points; this track has {j_n} joints"),
        ));
    }
    let labels: Vec<String> = track.skeleton().joints.iter().map(|n| label(n)).collect();
    if let Some(l) = labels.iter().find(|l| l.len() > 255) {
        return Err(GeomError::param(
            "track",
            format!("joint name `{l}` is longer than a C3D label (255 characters)"),
        ));
    }
    let fps = track.fps() as f32;
    let frames = t_n.min(65535) as u16;
    let mut params: Vec<(u8, &str, Value)> = vec![
        (1, "USED", int16(j_n as u16)),
        (1, "SCALE", float(-1.0)),
        (1, "RATE", float(fps)),
        (1, "DATA_START", int16(0)),
        (1, "FRAMES", int16(frames)),
        (1, "UNITS", chars(&["mm".to_string()], true)),
        (1, "LABELS", chars(&labels, false)),
        (1, "DESCRIPTIONS", chars(&labels, false)),
        (2, "USED", int16(0)),
        (2, "RATE", float(0.0)),
    ];
    if t_n > 65535 {
        params.push((1, "LONG_FRAMES", float(t_n as f32)));
    }
    let entries = |data_start: u16| -> Vec<Entry<'_>> {
        let mut e = vec![
            Entry::Group {
                id: 1,
                name: "POINT",
            },
            Entry::Group {
                id: 2,
                name: "ANALOG",
            },
        ];
        for (group, name, (kind, dims, data)) in &params {
            let data = if *name == "DATA_START" {
                data_start.to_le_bytes().to_vec()
            } else {
                data.clone()
            };
            e.push(Entry::Param {
                group: *group,
                name,
                kind: *kind,
                dims: dims.clone(),
                data,
            });
        }
        e
    };
    let blocks = parameter_section(&entries(0)).len() / 512;
    let data_start = 2 + blocks;
    if data_start > u16::MAX as usize {
        return Err(GeomError::param("track", "too many labels for a C3D file"));
    }
    let section = parameter_section(&entries(data_start as u16));
    let mut header = vec![0u8; 512];
    header[0] = 2;
    header[1] = 0x50;
    let mut word = |at: usize, v: u16| header[at..at + 2].copy_from_slice(&v.to_le_bytes());
    word(2, j_n as u16);
    word(4, 0);
    word(6, 1);
    word(8, frames);
    word(10, 0);
    word(16, data_start as u16);
    word(18, 0);
    header[12..16].copy_from_slice(&(-1.0f32).to_le_bytes());
    header[20..24].copy_from_slice(&fps.to_le_bytes());
    let mut out = header;
    out.extend(section);
    out.reserve(t_n * j_n * 16);
    for t in 0..t_n {
        for j in 0..j_n {
            let (p, residual) = if track.is_valid(t, j, 0.0) {
                let p = track.point(t, j);
                ([p[0] * 1e3, p[1] * 1e3, p[2] * 1e3], 0.0f32)
            } else {
                ([0.0; 3], -1.0f32)
            };
            for v in p {
                out.extend((v as f32).to_le_bytes());
            }
            out.extend(residual.to_le_bytes());
        }
    }
    let pad = out.len().div_ceil(512) * 512 - out.len();
    out.extend(std::iter::repeat_n(0u8, pad));
    Ok(out)
}

/// Writes a 3D track as a C3D file (atomic; see the module docs).
pub(crate) fn write_c3d(path: impl AsRef<Path>, track: &Track) -> Result<()> {
    write_atomic(path, &track_to_c3d_bytes(track)?)
}
