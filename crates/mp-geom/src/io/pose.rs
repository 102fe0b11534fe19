//! The `.pose` files of the `pose-format` Python package (sign-language
//! work: MediaPipe Holistic, OpenPose, AlphaPose output), read and written
//! here from the package's definition (versions 0.1 and 0.2 read, 0.2
//! written; all numbers little-endian).
//!
//! ```text
//! header  f32 version | u16 width, height, depth | u16 components
//!         per component: str name | str format ("XYC", "XYZC") |
//!                        u16 points, limbs, colours |
//!                        points × str | limbs × (u16, u16) | colours × (u16, u16, u16)
//! body    f32 fps | u32 frames | u16 people        (0.1: u16 fps, u16 frames, u16 people)
//!         f32 data[frames][people][points][dims] | f32 confidence[frames][people][points]
//! str     u16 byte length, UTF-8 bytes
//! ```
//!
//! `points` counts every component's points (concatenated in component
//! order); `dims` is the longest point format less its `C`.
//!
//! **Reading**: one component becomes the track — the body: the first
//! component called `POSE_LANDMARKS` (MediaPipe), `pose_keypoints_2d`
//! (OpenPose) or `BODY…` (AlphaPose), else the first component. Face and
//! hand components are left out: their hundreds of points are not the body
//! motion programs describe, and MediaPipe's world landmarks are in another
//! unit than the image ones. Its points are the joints, with that
//! component's own number of dimensions: MediaPipe's 33 pose landmarks read
//! as BlazePose-33 (names compared without case), OpenPose's 25 as BODY_25,
//! other names as they are with the component's limbs as bones
//! ([`ReadOptions::skeleton`] overrides). Confidence is the file's (0 =
//! missing). The header's width and height, when both are non-zero, are the
//! frame size ([`super::TrackRead::frame_size`]) and make the units pixels;
//! otherwise a 3D component is in metres and a 2D one in pixels
//! ([`ReadOptions::units`] overrides). Several people: each person slot is
//! a person (ids 1, 2, … in slot order) over the frames from their first to
//! their last with a confident point; as a single track the main person.
//!
//! **Writing**: one component with the track's joints — BlazePose-33 as
//! MediaPipe's `POSE_LANDMARKS` (upper-case landmark names, so the package's
//! Holistic helpers find them), BODY_25 as OpenPose's `pose_keypoints_2d`,
//! any other skeleton under its own name with its joint names; bones as
//! limbs; format `XYC` or `XYZC`; the frame size as width × height (0 × 0
//! when unknown); positions and confidence as 32-bit floats, a missing joint
//! as 0 with confidence 0 (how the package masks points). People are
//! written one slot per person in id order over the whole video; ids
//! themselves are not stored.

use std::path::Path;

use ndarray::{Array2, Array3};

use super::openpose::BODY25_JOINTS;
use super::{skeleton_from_names, write_atomic, Content, ReadOptions};
use crate::error::{GeomError, Result};
use crate::people::{People, Person};
use crate::skeleton::{Skeleton, BLAZEPOSE33_JOINTS};
use crate::track::{Track, Units};

/// The point names of OpenPose BODY_25 in the `pose-format` package.
const OPENPOSE_BODY25: [&str; 25] = [
    "Nose",
    "Neck",
    "RShoulder",
    "RElbow",
    "RWrist",
    "LShoulder",
    "LElbow",
    "LWrist",
    "MidHip",
    "RHip",
    "RKnee",
    "RAnkle",
    "LHip",
    "LKnee",
    "LAnkle",
    "REye",
    "LEye",
    "REar",
    "LEar",
    "LBigToe",
    "LSmallToe",
    "LHeel",
    "RBigToe",
    "RSmallToe",
    "RHeel",
];

/// One component of the header.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseComponent {
    /// Component name (`POSE_LANDMARKS`, `FACE_LANDMARKS`, …).
    pub name: String,
    /// Point format: one letter per dimension, then `C` (`XYC`, `XYZC`).
    pub format: String,
    /// Point names.
    pub points: Vec<String>,
    /// Limbs as pairs of point indices within the component.
    pub limbs: Vec<(u16, u16)>,
    /// Limb colours (RGB).
    pub colors: Vec<[u16; 3]>,
}

impl PoseComponent {
    /// Dimensions of its points (format length less the confidence letter).
    pub fn dims(&self) -> usize {
        self.format.chars().count().saturating_sub(1)
    }
}

/// A parsed `.pose` file.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseFile {
    /// Format version (0.1 or 0.2).
    pub version: f32,
    /// Frame width, height and depth (0 when unknown).
    pub dimensions: [u16; 3],
    /// The components, in file order.
    pub components: Vec<PoseComponent>,
    /// Frames per second.
    pub fps: f64,
    /// Frames, people, points (all components), dims.
    pub shape: [usize; 4],
    /// Positions, `frames × people × points × dims`, row-major.
    pub data: Vec<f32>,
    /// Confidence, `frames × people × points`, row-major.
    pub confidence: Vec<f32>,
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
    path: &'a Path,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.b.len());
        let Some(end) = end else {
            return Err(GeomError::format(
                self.path,
                format!(
                    "truncated: {what} needs {n} bytes at byte {}, the file has {}",
                    self.at,
                    self.b.len()
                ),
            ));
        };
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u16(&mut self, what: &str) -> Result<u16> {
        let s = self.take(2, what)?;
        Ok(u16::from_le_bytes([s[0], s[1]]))
    }
    fn u32(&mut self, what: &str) -> Result<u32> {
        let s = self.take(4, what)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn f32(&mut self, what: &str) -> Result<f32> {
        let s = self.take(4, what)?;
        Ok(f32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn str(&mut self, what: &str) -> Result<String> {
        let n = self.u16(what)? as usize;
        let s = self.take(n, what)?;
        String::from_utf8(s.to_vec())
            .map_err(|_| GeomError::format(self.path, format!("{what} is not UTF-8 text")))
    }
    fn floats(&mut self, n: usize, what: &str) -> Result<Vec<f32>> {
        let bytes = n
            .checked_mul(4)
            .ok_or_else(|| GeomError::format(self.path, format!("{what}: size overflows")))?;
        let s = self.take(bytes, what)?;
        Ok(s.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }
}

/// A 32-bit float as the decimal it was written from.
fn f64_of(v: f32) -> f64 {
    format!("{v}").parse().unwrap_or(v as f64)
}

impl PoseFile {
    /// Parses `.pose` bytes; `path` names the source in errors.
    pub fn parse(b: &[u8], path: &Path) -> Result<PoseFile> {
        let mut r = Reader { b, at: 0, path };
        let version = r.f32("the version")?;
        let v = (version * 1000.0).round() as i32;
        if v != 100 && v != 200 {
            return Err(GeomError::format(
                path,
                format!(
                    "not a pose-format file: version {version} (versions 0.1 and 0.2 are read)"
                ),
            ));
        }
        let dimensions = [
            r.u16("the width")?,
            r.u16("the height")?,
            r.u16("the depth")?,
        ];
        let n_comp = r.u16("the component count")? as usize;
        let mut components = Vec::with_capacity(n_comp.min(64));
        for c in 0..n_comp {
            let name = r.str(&format!("component {c}'s name"))?;
            let format = r.str(&format!("component `{name}`'s format"))?;
            let (np, nl, nc) = (
                r.u16("the point count")? as usize,
                r.u16("the limb count")? as usize,
                r.u16("the colour count")? as usize,
            );
            let mut points = Vec::with_capacity(np.min(4096));
            for i in 0..np {
                points.push(r.str(&format!("point {i} of `{name}`"))?);
            }
            let mut limbs = Vec::with_capacity(nl.min(4096));
            for _ in 0..nl {
                limbs.push((r.u16("a limb")?, r.u16("a limb")?));
            }
            let mut colors = Vec::with_capacity(nc.min(4096));
            for _ in 0..nc {
                colors.push([r.u16("a colour")?, r.u16("a colour")?, r.u16("a colour")?]);
            }
            components.push(PoseComponent {
                name,
                format,
                points,
                limbs,
                colors,
            });
        }
        let n_points: usize = components.iter().map(|c| c.points.len()).sum();
        let dims = components
            .iter()
            .map(PoseComponent::dims)
            .max()
            .unwrap_or(0);
        let (fps, frames, people) = if v == 100 {
            let fps = r.u16("the frame rate")? as f64;
            let _ = r.u16("the frame count")?;
            let people = r.u16("the people count")? as usize;
            // Version 0.1's frame count is a u16 that overflowed: the
            // frames are what the bytes left hold.
            let per_frame = people
                .checked_mul(n_points)
                .and_then(|x| x.checked_mul(dims + 1))
                .and_then(|x| x.checked_mul(4))
                .unwrap_or(0);
            let frames = (b.len() - r.at).checked_div(per_frame).unwrap_or(0);
            (fps, frames, people)
        } else {
            let fps = f64_of(r.f32("the frame rate")?);
            let frames = r.u32("the frame count")? as usize;
            (fps, frames, r.u16("the people count")? as usize)
        };
        let cells = frames
            .checked_mul(people)
            .and_then(|x| x.checked_mul(n_points))
            .ok_or_else(|| GeomError::format(path, "frame × people × point count overflows"))?;
        let values = cells
            .checked_mul(dims)
            .ok_or_else(|| GeomError::format(path, "the data size overflows"))?;
        let needed = values
            .checked_add(cells)
            .and_then(|x| x.checked_mul(4))
            .ok_or_else(|| GeomError::format(path, "the data size overflows"))?;
        let left = b.len() - r.at;
        if left < needed {
            return Err(GeomError::format(
                path,
                format!(
                    "truncated: {frames} frames of {people} people × {n_points} points × {dims} \
                     dimensions need {needed} bytes of data and confidence, the file has {left}"
                ),
            ));
        }
        if v == 200 && left > needed {
            return Err(GeomError::format(
                path,
                format!(
                    "{} bytes after the {frames} frames the header announces",
                    left - needed
                ),
            ));
        }
        let data = r.floats(values, "the positions")?;
        let confidence = r.floats(cells, "the confidence")?;
        Ok(PoseFile {
            version,
            dimensions,
            components,
            fps,
            shape: [frames, people, n_points, dims],
            data,
            confidence,
        })
    }

    /// The bytes of the file (version 0.2).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(64 + 4 * (self.data.len() + self.confidence.len()));
        let s = |out: &mut Vec<u8>, t: &str| {
            out.extend((t.len() as u16).to_le_bytes());
            out.extend(t.as_bytes());
        };
        out.extend(0.2f32.to_le_bytes());
        for d in self.dimensions {
            out.extend(d.to_le_bytes());
        }
        out.extend((self.components.len() as u16).to_le_bytes());
        for c in &self.components {
            s(&mut out, &c.name);
            s(&mut out, &c.format);
            for n in [c.points.len(), c.limbs.len(), c.colors.len()] {
                out.extend((n as u16).to_le_bytes());
            }
            for p in &c.points {
                s(&mut out, p);
            }
            for (a, b) in &c.limbs {
                out.extend(a.to_le_bytes());
                out.extend(b.to_le_bytes());
            }
            for rgb in &c.colors {
                for v in rgb {
                    out.extend(v.to_le_bytes());
                }
            }
        }
        out.extend((self.fps as f32).to_le_bytes());
        out.extend((self.shape[0] as u32).to_le_bytes());
        out.extend((self.shape[1] as u16).to_le_bytes());
        for v in self.data.iter().chain(&self.confidence) {
            out.extend(v.to_le_bytes());
        }
        out
    }

    /// Index of the body component (see the module docs).
    pub fn body_component(&self) -> Option<usize> {
        self.components
            .iter()
            .position(|c| {
                let n = c.name.to_ascii_uppercase();
                n == "POSE_LANDMARKS" || n == "POSE_KEYPOINTS_2D" || n.starts_with("BODY")
            })
            .or_else(|| (!self.components.is_empty()).then_some(0))
    }
}

/// The skeleton of a component: BlazePose-33, BODY_25, else its names and limbs.
fn component_skeleton(c: &PoseComponent) -> Skeleton {
    let lower: Vec<String> = c.points.iter().map(|p| p.to_ascii_lowercase()).collect();
    if lower == BLAZEPOSE33_JOINTS {
        return Skeleton::blazepose33();
    }
    if c.points == OPENPOSE_BODY25 {
        return super::openpose::body25_skeleton();
    }
    let sk = skeleton_from_names(&c.points);
    if sk.name != "custom" && sk.name != "generic" {
        return sk;
    }
    let n = c.points.len();
    let bones = c
        .limbs
        .iter()
        .map(|&(a, b)| (a as usize, b as usize))
        .filter(|&(a, b)| a < n && b < n)
        .collect();
    Skeleton::custom(&c.name, c.points.clone(), bones, None)
}

/// Reads a `.pose` file's body component (see the module docs), with the
/// frame size it states.
pub(crate) fn read_pose_any(
    path: &Path,
    opts: &ReadOptions,
) -> Result<(Content, Option<(usize, usize)>)> {
    opts.validate()?;
    let bytes = std::fs::read(path).map_err(|e| GeomError::io(path, e))?;
    let f = PoseFile::parse(&bytes, path)?;
    let ci = f
        .body_component()
        .ok_or_else(|| GeomError::format(path, "the file has no components"))?;
    let comp = &f.components[ci];
    let d = comp.dims();
    if d != 2 && d != 3 {
        return Err(GeomError::format(
            path,
            format!(
                "component `{}` has point format `{}`: 2 or 3 dimensions are read",
                comp.name, comp.format
            ),
        ));
    }
    let [frames, people, n_points, dims] = f.shape;
    if people == 0 {
        return Err(GeomError::format(path, "no person in this file"));
    }
    if !(f.fps.is_finite() && f.fps > 0.0) && opts.fps.is_none() {
        return Err(GeomError::format(
            path,
            format!("frame rate {} is not > 0 (give one)", f.fps),
        ));
    }
    let fps = if f.fps.is_finite() && f.fps > 0.0 {
        f.fps
    } else {
        opts.rate()
    };
    let offset: usize = f.components[..ci].iter().map(|c| c.points.len()).sum();
    let n_j = comp.points.len();
    let skeleton = match &opts.skeleton {
        Some(_) => super::infer_skeleton(opts, n_j, path)?,
        None => component_skeleton(comp),
    };
    let [w, h, _] = f.dimensions;
    let frame_size = (w > 0 && h > 0).then_some((w as usize, h as usize));
    let units = opts.units.unwrap_or(if d == 2 || frame_size.is_some() {
        Units::Pixels
    } else {
        Units::Metres
    });
    let slot = |p: usize, span: std::ops::Range<usize>| -> Result<Track> {
        let mut pos = Array3::<f64>::zeros((span.len(), n_j, d));
        let mut conf = Array2::<f64>::zeros((span.len(), n_j));
        for (t, fr) in span.enumerate() {
            for j in 0..n_j {
                let cell = (fr * people + p) * n_points + offset + j;
                for k in 0..d {
                    pos[[t, j, k]] = f.data[cell * dims + k] as f64;
                }
                conf[[t, j]] = f.confidence[cell] as f64;
            }
        }
        Track::new(pos, Some(conf), fps, units, skeleton.clone())
            .map_err(|e| GeomError::format(path, e.to_string()))
    };
    if people == 1 {
        return Ok((Content::Track(Box::new(slot(0, 0..frames)?)), frame_size));
    }
    let mut list = Vec::new();
    for p in 0..people {
        let found: Vec<usize> = (0..frames)
            .filter(|&fr| {
                (0..n_j).any(|j| f.confidence[(fr * people + p) * n_points + offset + j] > 0.0)
            })
            .collect();
        let (Some(&first), Some(&last)) = (found.first(), found.last()) else {
            continue;
        };
        list.push(Person {
            id: p as u32 + 1,
            first_frame: first,
            track: slot(p, first..last + 1)?,
        });
    }
    let people = People::new(frames.max(1), fps, list)
        .map_err(|e| GeomError::format(path, e.to_string()))?;
    Ok((Content::People(people), frame_size))
}

/// The component that holds tracks of `skeleton` in `dims` dimensions.
fn component_of(skeleton: &Skeleton, dims: usize) -> Result<PoseComponent> {
    let n = skeleton.len();
    if n > u16::MAX as usize {
        return Err(GeomError::param(
            "track",
            format!("a .pose component holds at most 65535 points, the track has {n} joints"),
        ));
    }
    let (name, points): (String, Vec<String>) = if skeleton.joints == BLAZEPOSE33_JOINTS {
        (
            "POSE_LANDMARKS".into(),
            skeleton
                .joints
                .iter()
                .map(|j| j.to_ascii_uppercase())
                .collect(),
        )
    } else if skeleton.joints == BODY25_JOINTS {
        (
            "pose_keypoints_2d".into(),
            OPENPOSE_BODY25.iter().map(|s| s.to_string()).collect(),
        )
    } else {
        (skeleton.name.clone(), skeleton.joints.clone())
    };
    if let Some(long) = points
        .iter()
        .chain([&name])
        .find(|p| p.len() > u16::MAX as usize)
    {
        return Err(GeomError::param(
            "skeleton",
            format!("name `{long:.40}…` is longer than a .pose string (65535 bytes)"),
        ));
    }
    let limbs: Vec<(u16, u16)> = skeleton
        .bones
        .iter()
        .take(u16::MAX as usize)
        .map(|&(a, b)| (a as u16, b as u16))
        .collect();
    Ok(PoseComponent {
        name,
        format: if dims == 3 { "XYZC" } else { "XYC" }.into(),
        points,
        limbs,
        colors: vec![[255, 0, 0]],
    })
}

fn header_dims(frame_size: Option<(usize, usize)>) -> [u16; 3] {
    match frame_size {
        Some((w, h)) => [w.min(65535) as u16, h.min(65535) as u16, 0],
        None => [0, 0, 0],
    }
}

/// The `.pose` file of tracks sharing skeleton, rate and dimensions, one
/// person slot each, over `n_frames` frames from `first` frames.
fn pose_of(
    tracks: &[(&Track, usize)],
    n_frames: usize,
    fps: f64,
    frame_size: Option<(usize, usize)>,
) -> Result<PoseFile> {
    let Some((t0, _)) = tracks.first() else {
        return Err(GeomError::param(
            "people",
            "nobody to write: a .pose file needs a person to take its points from",
        ));
    };
    let d = t0.dims();
    if d != 2 && d != 3 {
        return Err(GeomError::param(
            "track",
            format!("a .pose file holds 2D or 3D points; this track has {d} dimensions"),
        ));
    }
    if tracks.len() > u16::MAX as usize || n_frames > u32::MAX as usize {
        return Err(GeomError::param(
            "track",
            "a .pose file holds at most 65535 people and 2³² − 1 frames",
        ));
    }
    let comp = component_of(t0.skeleton(), d)?;
    let (np, nj) = (tracks.len(), t0.n_joints());
    let mut data = vec![0f32; n_frames * np * nj * d];
    let mut confidence = vec![0f32; n_frames * np * nj];
    for (p, (tr, first)) in tracks.iter().enumerate() {
        for t in 0..tr.n_frames() {
            let fr = first + t;
            for j in 0..nj {
                let cell = (fr * np + p) * nj + j;
                let c = tr.confidence()[[t, j]];
                if c > 0.0 {
                    for k in 0..d {
                        data[cell * d + k] = tr.positions()[[t, j, k]] as f32;
                    }
                    confidence[cell] = c as f32;
                }
            }
        }
    }
    Ok(PoseFile {
        version: 0.2,
        dimensions: header_dims(frame_size),
        components: vec![comp],
        fps,
        shape: [n_frames, np, nj, d],
        data,
        confidence,
    })
}

/// The `.pose` bytes of a track (see the module docs).
pub(crate) fn track_to_pose_bytes(
    track: &Track,
    frame_size: Option<(usize, usize)>,
) -> Result<Vec<u8>> {
    Ok(pose_of(&[(track, 0)], track.n_frames(), track.fps(), frame_size)?.to_bytes())
}

/// The `.pose` bytes of people: one slot per person, in id order.
pub(crate) fn people_to_pose_bytes(
    people: &People,
    frame_size: Option<(usize, usize)>,
) -> Result<Vec<u8>> {
    let tracks: Vec<(&Track, usize)> = people
        .people()
        .iter()
        .map(|p| (&p.track, p.first_frame))
        .collect();
    Ok(pose_of(&tracks, people.n_frames(), people.fps(), frame_size)?.to_bytes())
}

/// Writes a track as a `.pose` file (atomic).
pub(crate) fn write_pose(
    path: impl AsRef<Path>,
    track: &Track,
    frame_size: Option<(usize, usize)>,
) -> Result<()> {
    write_atomic(path, &track_to_pose_bytes(track, frame_size)?)
}

/// Writes people as a `.pose` file (atomic).
pub(crate) fn write_people_pose(
    path: impl AsRef<Path>,
    people: &People,
    frame_size: Option<(usize, usize)>,
) -> Result<()> {
    write_atomic(path, &people_to_pose_bytes(people, frame_size)?)
}
