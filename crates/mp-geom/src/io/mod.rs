//! Reading and writing tracks.
//!
//! * [`npz`]: `.npy`/`.npz` of any numeric, boolean or unicode dtype.
//! * [`datasets`]: the shared data sets (Penn Action, AIST++, MSR Action3D,
//!   CMU mocap features, MediaPipe reference keypoints).
//! * [`native`]: the project's own track formats (`.npz`, `.json` and the
//!   compact binary `.mpt`), which read back identically.
//! * [`people`]: the same three formats for several tracked people
//!   ([`People`]); their single-track view is the main person.
//! * [`binary`]: the binary framing (magic, version, bincode record) shared
//!   by `.mpt` tracks and `.mpb` programs.
//! * [`csv`]: long (`frame,joint,x,y[,z][,confidence]`) and wide
//!   (`j0_x,j0_y,…`) CSV tables.
//! * [`openpose`]: OpenPose per-frame JSON folders (BODY_25, COCO-18) and
//!   AlphaPose result files (COCO-17).
//! * [`bvh`]: BVH motion capture (hierarchy + channels, forward kinematics,
//!   slicing, concatenation, writing).
//! * [`bvh_export`]: BVH of a 3D joint-position track (a hierarchy from the
//!   skeleton's bones, per-frame joint rotations).
//! * [`c3d`]: C3D motion capture (the 3D points, through the `c3dio` crate).
//! * [`parquet`]: Parquet tables, one row per frame × joint (× person),
//!   through the `parquet` crate.
//! * [`pose`]: the `.pose` files of the `pose-format` Python package.
//! * [`read_track`] / [`write_track`]: one entry point that picks the format
//!   from the extension and the content; [`read_people`] / [`write_people`]
//!   the same for people (any single-track file reads as one person).
//!
//! | extension | read | written |
//! |---|---|---|
//! | `.npz`, `.json`, `.mpt` | the project's tracks and people; data sets (npz) | exactly |
//! | `.npy` | a `(T, J, D)` array | — |
//! | `.csv` | long or wide tables | wide, with `time` |
//! | `.bvh` | forward kinematics | 3D tracks in metres ([`bvh_export`]) |
//! | `.c3d` | 3D points, in metres | 3D tracks in metres (2D refused) |
//! | `.parquet` | long tables (any writer); people with a `person` column | exactly, rate/units/skeleton in the metadata |
//! | `.pose` | the body component; several people | one component, 32-bit floats |
//!
//! Every write goes to a temporary file in the destination folder that is
//! renamed into place, so a crash never leaves a half-written file.

mod atomic;
pub mod binary;
pub mod bvh;
pub mod bvh_export;
pub mod c3d;
pub mod csv;
pub mod datasets;
pub mod native;
pub mod npz;
pub mod openpose;
pub mod parquet;
pub mod people;
pub mod pose;

pub use atomic::{abandon_partial_writes, write_atomic, PartialFile};
pub use people::people_to_npz_bytes_framed;

use std::path::Path;

use crate::error::{GeomError, Result};
use crate::people::People;
use crate::skeleton::Skeleton;
use crate::track::{Track, Units};

/// What a reader cannot find in a file, supplied by the caller.
///
/// Formats that store these themselves (the project's npz/JSON, the data
/// sets, BVH) ignore the options they already know.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadOptions {
    /// Frame rate. `None`: the rate the file states (the project's npz, JSON
    /// and `.mpt`, people files, BVH's frame time, a CSV `time` column, the
    /// data sets), else [`DEFAULT_FPS`] ([`RateSource::Assumed`]). `Some`:
    /// this rate, whatever the file states ([`RateSource::Given`]).
    pub fps: Option<f64>,
    /// Units; `None` = pixels for D = 2, metres for D = 3.
    pub units: Option<Units>,
    /// Skeleton; `None` = inferred from the joint names or count
    /// (17 → COCO-17, 33 → BlazePose-33, otherwise generic).
    pub skeleton: Option<Skeleton>,
    /// BVH: factor applied to offsets and root translations (default 1).
    pub length_scale: f64,
}

/// The frame rate of a file that states none and was given none: 30 fps.
pub const DEFAULT_FPS: f64 = 30.0;

/// Where the frame rate of a track read from a file came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum RateSource {
    /// The file states it.
    File,
    /// [`ReadOptions::fps`].
    Given,
    /// Neither: [`DEFAULT_FPS`] (`.npy`, CSV without a `time` column,
    /// OpenPose and AlphaPose JSON).
    Assumed,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            fps: None,
            units: None,
            skeleton: None,
            length_scale: 1.0,
        }
    }
}

impl ReadOptions {
    /// Checks the options once.
    pub fn validate(&self) -> Result<()> {
        if let Some(fps) = self.fps {
            if !(fps.is_finite() && fps > 0.0) {
                return Err(GeomError::param(
                    "fps",
                    format!("must be finite and > 0, got {fps}"),
                ));
            }
        }
        if !(self.length_scale.is_finite() && self.length_scale > 0.0) {
            return Err(GeomError::param(
                "length_scale",
                format!("must be finite and > 0, got {}", self.length_scale),
            ));
        }
        Ok(())
    }

    /// The rate of a file that states none: [`ReadOptions::fps`], else
    /// [`DEFAULT_FPS`].
    pub(crate) fn rate(&self) -> f64 {
        self.fps.unwrap_or(DEFAULT_FPS)
    }

    pub(crate) fn units_for(&self, dims: usize) -> Units {
        self.units.unwrap_or(if dims == 3 {
            Units::Metres
        } else {
            Units::Pixels
        })
    }
}

/// Picks a skeleton for `n` joints: the caller's, else a built-in one by count.
pub(crate) fn infer_skeleton(opts: &ReadOptions, n: usize, path: &Path) -> Result<Skeleton> {
    match &opts.skeleton {
        Some(s) if s.len() == n => Ok(s.clone()),
        Some(s) => Err(GeomError::format(
            path,
            format!(
                "file has {n} joints but the given skeleton `{}` has {}",
                s.name,
                s.len()
            ),
        )),
        None => Ok(match n {
            17 => Skeleton::coco17(),
            33 => Skeleton::blazepose33(),
            _ => Skeleton::generic(n),
        }),
    }
}

/// Picks a skeleton from joint names: a built-in one when the names match it
/// exactly, else a custom skeleton with those names (generic when the names
/// are `j0`, `j1`, …).
pub fn skeleton_from_names(names: &[String]) -> Skeleton {
    for s in builtin_skeletons() {
        if s.joints == names {
            return s;
        }
    }
    let generic = Skeleton::generic(names.len());
    if generic.joints == names {
        return generic;
    }
    Skeleton::custom("custom", names.to_vec(), Vec::new(), None)
}

/// The skeletons readers recognise by their joint names.
pub(crate) fn builtin_skeletons() -> [Skeleton; 6] {
    [
        Skeleton::coco17(),
        Skeleton::blazepose33(),
        Skeleton::penn13(),
        Skeleton::msr20(),
        openpose::body25_skeleton(),
        openpose::coco18_skeleton(),
    ]
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

/// Reads a track with default [`ReadOptions`]. See `read_track_with`.
pub fn read_track(path: impl AsRef<Path>) -> Result<Track> {
    read_track_with(path, &ReadOptions::default())
}

/// Reads one track, choosing the format from the extension and content:
///
/// * a folder: OpenPose `*_keypoints.json` files;
/// * `.npz`: the project's format (has `positions`; a people file's
///   single-track arrays hold the main person), the MediaPipe reference
///   (`landmarks_px`) or the CMU features (`X` + `labels`); multi-clip data
///   sets (Penn Action, MSR, AIST++) are refused with a pointer to
///   [`datasets`];
/// * `.npy`: a `(T, J, D)` array;
/// * `.json`: the project's format, a people file (the main person's track
///   over the whole video), an AlphaPose result list, or a single OpenPose
///   frame;
/// * `.csv`: long or wide CSV;
/// * `.bvh`: BVH, forward kinematics to joint positions (a BVH that
///   [`bvh_export`] wrote from a built-in skeleton reads back as it);
/// * `.mpt`: the project's binary form ([`track_from_bincode`]), or a people
///   file (the main person's track over the whole video);
/// * `.c3d`: the 3D points of a C3D file ([`c3d`]);
/// * `.parquet`: a long table ([`parquet`]); with a `person` column, the
///   main person's track over the whole video;
/// * `.pose`: the body component of a pose-format file ([`pose`]); with
///   several people, the main person's track.
///
/// A people file with nobody in it is an error ("no person in this file").
pub fn read_track_with(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<Track> {
    read_track_rated(path, opts).map(|r| r.track)
}

/// A track read from a file, with what the file says around it.
#[derive(Debug, Clone)]
pub struct TrackRead {
    /// The track.
    pub track: Track,
    /// Where its frame rate came from (so that a caller can say when
    /// [`DEFAULT_FPS`] was assumed).
    pub rate: RateSource,
    /// The video frame (width, height) its pixels are in, when the file
    /// states it (the npz, Parquet and `.pose` files of [`write_track_framed`] /
    /// [`write_people_framed`], a `.pose` header's width and height).
    pub frame_size: Option<(usize, usize)>,
}

/// `read_track_with`, with where the rate came from and the frame size the
/// file states, in one read.
pub fn read_track_rated(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<TrackRead> {
    let path = path.as_ref();
    let (content, rate, stated) = read_rated(path, opts, false)?;
    let track = match content {
        Content::Track(t) => *t,
        Content::People(p) => people::main_track_of(&p, path)?,
    };
    Ok(TrackRead {
        track,
        rate,
        frame_size: stated.frame_size,
    })
}

/// [`read_any`] with [`ReadOptions::fps`] applied over what the file states.
fn read_rated(
    path: &Path,
    opts: &ReadOptions,
    people_npz: bool,
) -> Result<(Content, RateSource, Stated)> {
    let (content, stated) = read_any(path, opts, people_npz)?;
    let (content, rate) = rated(path, opts, content, stated.rate)?;
    Ok((content, rate, stated))
}

/// `content` at [`ReadOptions::fps`] when given, and where its rate came from.
fn rated(
    path: &Path,
    opts: &ReadOptions,
    content: Content,
    stated: bool,
) -> Result<(Content, RateSource)> {
    match (opts.fps, content) {
        (Some(fps), Content::Track(t)) => {
            let t = if t.fps() == fps { *t } else { t.with_fps(fps)? };
            Ok((Content::Track(Box::new(t)), RateSource::Given))
        }
        (Some(fps), Content::People(p)) => Ok((
            Content::People(
                p.with_fps(fps)
                    .map_err(|e| GeomError::format(path, e.to_string()))?,
            ),
            RateSource::Given,
        )),
        (None, c) => Ok((
            c,
            if stated {
                RateSource::File
            } else {
                RateSource::Assumed
            },
        )),
    }
}

/// What a file holds: one track, or people.
pub(crate) enum Content {
    Track(Box<Track>),
    People(People),
}

/// Reads a file as [`read_track_with`] describes, keeping people JSON and
/// `.mpt` files as people; a people npz too when `people_npz` is set (else
/// its single-track arrays are read). Also tells what the file states
/// besides ([`Stated`]).
fn read_any(path: &Path, opts: &ReadOptions, people_npz: bool) -> Result<(Content, Stated)> {
    opts.validate()?;
    if path.is_dir() {
        let t = openpose::read_openpose_dir(path, opts)?;
        return Ok((Content::Track(Box::new(t)), Stated::default()));
    }
    if !path.exists() {
        return Err(GeomError::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "no such file or folder"),
        ));
    }
    let people = |p: People, frame_size| {
        Ok((
            Content::People(p),
            Stated {
                rate: true,
                frame_size,
            },
        ))
    };
    let mut frame_size = None;
    let (track, stated) = match extension(path).as_str() {
        "npz" => {
            let z = npz::Npz::open(path)?;
            frame_size = native::frame_size_of(&z)?;
            if people::is_people_npz(&z) {
                if people_npz {
                    return people(people::people_from_npz(&z)?, frame_size);
                }
                // The single-track arrays hold the main person; a file of
                // nobody has none.
                if !z.contains("positions") {
                    return Err(people::no_person(path));
                }
                (native::track_from_npz(&z)?, true)
            } else if z.contains("positions") {
                (native::track_from_npz(&z)?, z.contains("fps"))
            } else if z.contains("landmarks_px") {
                (
                    datasets::MediaPipeReference::from_npz(&z, false)?.image,
                    true,
                )
            } else if z.contains("X") && z.contains("labels") {
                (datasets::CmuFeatures::from_npz(&z)?.track, true)
            } else if z.contains("keypoints2d") {
                return Err(GeomError::format(
                    path,
                    "AIST++ file with several camera views: use io::datasets::AistPlusPlus",
                ));
            } else if z.contains("offsets") {
                return Err(GeomError::format(
                    path,
                    "multi-clip data set: use io::datasets::PennAction or MsrAction3D",
                ));
            } else {
                return Err(GeomError::format(
                    path,
                    format!(
                        "npz holds no known track layout (arrays: {})",
                        z.names().join(", ")
                    ),
                ));
            }
        }
        "npy" => (native::read_track_npy(path, opts)?, false),
        "json" => {
            let text = std::fs::read_to_string(path).map_err(|e| GeomError::io(path, e))?;
            let value: serde_json::Value = serde_json::from_str(&text)
                .map_err(|e| GeomError::format(path, format!("invalid JSON: {e}")))?;
            if value.get("format").and_then(|f| f.as_str()) == Some(native::JSON_FORMAT) {
                (native::track_from_json_value(value, path)?, true)
            } else if people::is_people_json(&value) {
                return people(people::people_from_json_value(value, path)?, None);
            } else if value.is_array() {
                (openpose::alphapose_from_value(&value, path, opts)?, false)
            } else if value.get("people").is_some() {
                let frames = [(path.to_path_buf(), value)];
                (openpose::openpose_from_frames(&frames, opts)?, false)
            } else {
                return Err(GeomError::format(
                    path,
                    "JSON is neither an mp track, mp people, an AlphaPose result list nor an \
                     OpenPose frame",
                ));
            }
        }
        "csv" => csv::read_csv_rated(path, opts)?,
        "mpt" => {
            let bytes = std::fs::read(path).map_err(|e| GeomError::io(path, e))?;
            if people::is_people_bincode(&bytes) {
                return people(people::people_from_bincode_at(&bytes, path)?, None);
            }
            (native::track_from_bincode_at(&bytes, path)?, true)
        }
        "bvh" => {
            let b = bvh::Bvh::read(path)?;
            let t = b.to_track(&bvh::BvhTrackParams {
                length_scale: opts.length_scale,
                units: opts.units.unwrap_or(Units::Metres),
                include_end_sites: false,
            })?;
            (bvh_export::with_builtin_order(t)?, true)
        }
        "c3d" => c3d::read_c3d_rated(path, opts)?,
        "parquet" => {
            let r = parquet::read_parquet_any(path, opts)?;
            let stated = Stated {
                rate: r.rate_stated,
                frame_size: r.frame_size,
            };
            return Ok((r.content, stated));
        }
        "pose" => {
            let (content, frame_size) = pose::read_pose_any(path, opts)?;
            let stated = Stated {
                rate: true,
                frame_size,
            };
            return Ok((content, stated));
        }
        other => {
            return Err(GeomError::format(
                path,
                format!(
                    "unknown track file extension `{other}` ({} or a folder)",
                    TRACK_EXTENSIONS.join(", ")
                ),
            ))
        }
    };
    Ok((
        Content::Track(Box::new(track)),
        Stated {
            rate: stated,
            frame_size,
        },
    ))
}

/// What a file states besides its track or people.
#[derive(Debug, Default)]
struct Stated {
    /// Its frame rate (else [`ReadOptions::rate`] was used).
    rate: bool,
    /// The video frame its pixels are in.
    frame_size: Option<(usize, usize)>,
}

/// Reads people with default [`ReadOptions`]. See `read_people_with`.
pub fn read_people(path: impl AsRef<Path>) -> Result<People> {
    read_people_with(path, &ReadOptions::default())
}

/// Reads the people of a video: a people file ([`people`]: `.npz` with
/// `mp_people_version`, `.json` with `"format": "mp-people"`, `.mpt` with
/// magic `mp-people`; a Parquet table with a `person` column, a `.pose`
/// file with several people) as it is; any other file [`read_track_with`] reads
/// (a single-track npz, JSON, CSV, BVH, …) as one person with id 1
/// covering the whole track ([`People::from_track`]).
pub fn read_people_with(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<People> {
    let path = path.as_ref();
    match read_rated(path, opts, true)?.0 {
        Content::People(p) => Ok(p),
        Content::Track(t) => {
            People::from_track(*t).map_err(|e| GeomError::format(path, e.to_string()))
        }
    }
}

/// Writes people in the format chosen by extension: `.npz` (compressed),
/// `.json` or `.mpt` (binary), see [`people`]; `.parquet` (a `person`
/// column) or `.pose` (one person slot each; ids not kept). Atomic
/// (temporary file + rename).
pub fn write_people(path: impl AsRef<Path>, people: &People) -> Result<()> {
    write_people_framed(path, people, None)
}

/// [`write_people`] keeping the video frame size in an `.npz`, `.parquet`
/// or `.pose` (as [`write_track_framed`]).
pub fn write_people_framed(
    path: impl AsRef<Path>,
    people: &People,
    frame_size: Option<(usize, usize)>,
) -> Result<()> {
    let path = path.as_ref();
    let written = match extension(path).as_str() {
        "npz" => write_atomic(
            path,
            &people::people_to_npz_bytes_framed(people, frame_size)?,
        ),
        "json" => people::write_people_json(path, people),
        "mpt" => people::write_people_bincode(path, people),
        "parquet" => parquet::write_people_parquet(path, people, frame_size),
        "pose" => pose::write_people_pose(path, people, frame_size),
        other => Err(GeomError::format(
            path,
            format!("cannot write people as `{other}` (use .npz, .json, .mpt, .parquet or .pose)"),
        )),
    };
    written.map_err(|e| naming(path, e))
}

/// Writes a track in the format chosen by extension: `.npz` (compressed),
/// `.json`, `.csv` (wide), `.mpt` (binary), `.bvh` and `.c3d` (3D tracks in
/// metres; see `bvh_export` and `c3d`), `.parquet` or `.pose`. A track
/// a format cannot hold is an error naming the file. Atomic (temporary
/// file + rename).
pub fn write_track(path: impl AsRef<Path>, track: &Track) -> Result<()> {
    write_track_framed(path, track, None)
}

/// [`write_track`] keeping the width and height of the video frame the
/// track's pixels are in, in an `.npz`, a `.parquet` (metadata) or a `.pose`
/// (its header) ([`read_track_rated`] reads it back: the scale its programs
/// are fitted at); other formats leave it out.
pub fn write_track_framed(
    path: impl AsRef<Path>,
    track: &Track,
    frame_size: Option<(usize, usize)>,
) -> Result<()> {
    let path = path.as_ref();
    let written = match extension(path).as_str() {
        "npz" => native::track_to_npz_bytes_framed(track, frame_size)
            .and_then(|b| write_atomic(path, &b)),
        "json" => native::write_track_json(path, track),
        "csv" => csv::write_csv(path, track, csv::CsvLayout::Wide),
        "mpt" => native::write_track_bincode(path, track),
        "bvh" => bvh_export::track_to_bvh(track).and_then(|b| b.write_bvh(path)),
        "c3d" => c3d::write_c3d(path, track),
        "parquet" => parquet::write_parquet(path, track, frame_size),
        "pose" => pose::write_pose(path, track, frame_size),
        other => Err(GeomError::format(
            path,
            format!(
                "cannot write tracks as `{other}` (use .npz, .json, .csv, .mpt, .bvh, .c3d, \
                 .parquet or .pose)"
            ),
        )),
    };
    written.map_err(|e| naming(path, e))
}

/// A writer's refusal of what it was given, as an error naming the file.
fn naming(path: &Path, e: GeomError) -> GeomError {
    match e {
        GeomError::InvalidParam { reason, .. } => GeomError::format(path, reason),
        other => other,
    }
}

/// Whether [`write_people`] keeps several people in a file with this
/// extension (`.npz`, `.json`, `.mpt`, `.parquet`, `.pose`); the other
/// track formats hold one track.
pub fn holds_people(path: impl AsRef<Path>) -> bool {
    matches!(
        extension(path.as_ref()).as_str(),
        "npz" | "json" | "mpt" | "parquet" | "pose"
    )
}

/// Whether a track written with this extension must be 3D (`.bvh`, `.c3d`).
pub fn needs_3d(path: impl AsRef<Path>) -> bool {
    matches!(extension(path.as_ref()).as_str(), "bvh" | "c3d")
}

/// The extensions [`read_track`] reads (besides OpenPose folders).
pub const TRACK_EXTENSIONS: [&str; 9] = [
    "npz", "npy", "json", "csv", "bvh", "mpt", "c3d", "parquet", "pose",
];
