//! The concrete program: one shared segmentation × one primitive per joint per segment.

use std::path::Path;

use mp_geom::{binary, write_atomic};
use mp_geom::{Primitive, PrimitiveKind, Skeleton, Units};
use serde::{Deserialize, Serialize};

use crate::error::{ConcreteError, Result};
use crate::smooth::Continuity;

/// One segment of a program: a duration shared by every joint and, for each
/// joint (in the program's joint order), the primitive it traces.
///
/// Time inside a segment is `t = 0, 1, …, duration_frames − 1` (frames since
/// the segment's first frame; fractional values are allowed when executing).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// Number of frames the segment lasts (≥ 1).
    pub duration_frames: usize,
    /// One primitive per joint, in the order of [`Program::joints`].
    pub primitives: Vec<Primitive>,
}

/// A concrete motion program (paper §3.1, Table 1): a sequence of segments
/// whose boundaries are shared by all joints (paper eq. 1, "multiple
/// keypoints"), each holding one primitive per joint.
///
/// The first segment starts at frame 0 of the program; segment `i` starts at
/// the sum of the durations before it (see [`Program::boundaries`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Program {
    /// Frame rate of the program's time axis (frames per second).
    pub fps: f64,
    /// Units of positions (pixels, metres).
    pub units: Units,
    /// Dimensions per joint D (2 or 3 for images / mocap; any D ≥ 1 is allowed).
    pub dims: usize,
    /// Skeleton identifier (e.g. `penn13`, `coco17`, `generic`).
    pub skeleton: String,
    /// Joint names, in storage order (unique).
    pub joints: Vec<String>,
    /// Whether consecutive segments share their boundary pose
    /// ([`Continuity::C0`]: segment `i` at `t = duration` equals segment
    /// `i + 1` at `t = 0`, as synthesis with [`crate::SynthParams::continuity`]
    /// writes it) or were fitted independently. A statement about how the
    /// program was made, not checked by [`Program::validate`]
    /// ([`Program::max_boundary_gap`] measures it). Absent in files written
    /// before the field existed: [`Continuity::None`].
    #[serde(default)]
    pub continuity: Continuity,
    /// The segments, in time order.
    pub segments: Vec<Segment>,
}

impl Program {
    /// Number of joints J.
    pub fn n_joints(&self) -> usize {
        self.joints.len()
    }

    /// Number of segments (= primitives per joint).
    pub fn n_segments(&self) -> usize {
        self.segments.len()
    }

    /// Total number of frames (sum of durations).
    pub fn n_frames(&self) -> usize {
        self.segments.iter().map(|s| s.duration_frames).sum()
    }

    /// Segment boundaries in frames: `[0, b1, …, T]` (length `n_segments + 1`).
    pub fn boundaries(&self) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.segments.len() + 1);
        let mut acc = 0;
        out.push(0);
        for s in &self.segments {
            acc += s.duration_frames;
            out.push(acc);
        }
        out
    }

    /// The primitives of one joint, with their durations.
    pub fn joint_statements(&self, joint: usize) -> Vec<(&Primitive, usize)> {
        self.segments
            .iter()
            .filter_map(|s| s.primitives.get(joint).map(|p| (p, s.duration_frames)))
            .collect()
    }

    /// Index of a joint by name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j == name)
    }

    /// Number of free parameters of the program: the parameters of every
    /// primitive ([`Primitive::n_params`]) plus one duration per segment
    /// (durations are shared by all joints, so they are counted once), less
    /// what continuity determines ([`Program::n_shared_params`]).
    pub fn n_params(&self) -> usize {
        self.n_numbers() - self.n_shared_params()
    }

    /// Numbers written for the program: the parameters of every primitive
    /// ([`Primitive::n_params`]) plus one duration per segment, whether or
    /// not continuity determines some of them.
    pub fn n_numbers(&self) -> usize {
        self.segments
            .iter()
            .map(|s| 1 + s.primitives.iter().map(Primitive::n_params).sum::<usize>())
            .sum()
    }

    /// Parameters that continuity determines: in a [`Continuity::C0`]
    /// program, a primitive that starts where the joint's previous primitive
    /// ends (within 1e-6 relative) has its start pose given, `D` numbers
    /// (every kind can start anywhere: the held point, the line's start, the
    /// circle's centre, the cubic's constant term follow from it). 0 for a
    /// program with independent segments, or one that does not validate
    /// ([`Program::validate`]: nothing is evaluated then).
    pub fn n_shared_params(&self) -> usize {
        if self.continuity != Continuity::C0 || self.validate().is_err() {
            return 0;
        }
        let d = self.dims;
        let (mut end, mut start) = (vec![0.0; d], vec![0.0; d]);
        let mut shared = 0;
        for pair in self.segments.windows(2) {
            let (prev, next) = (&pair[0], &pair[1]);
            for (a, b) in prev.primitives.iter().zip(&next.primitives) {
                a.eval_into(prev.duration_frames as f64, &mut end);
                b.eval_into(0.0, &mut start);
                let same = end
                    .iter()
                    .zip(&start)
                    .all(|(x, y)| (x - y).abs() <= 1e-6 * (1.0 + x.abs().max(y.abs())));
                if same {
                    shared += d;
                }
            }
        }
        shared
    }

    /// Number of primitives of each kind, over all joints and segments.
    pub fn kind_counts(&self) -> Vec<(PrimitiveKind, usize)> {
        PrimitiveKind::ALL
            .iter()
            .map(|&k| {
                let n = self
                    .segments
                    .iter()
                    .flat_map(|s| s.primitives.iter())
                    .filter(|p| p.kind() == k)
                    .count();
                (k, n)
            })
            .collect()
    }

    /// The skeleton to attach to executed tracks: the built-in skeleton of
    /// that name when its joints match, else a custom one with these joint names.
    pub fn skeleton(&self) -> Skeleton {
        match Skeleton::by_name(&self.skeleton) {
            Ok(s) if s.joints == self.joints => s,
            _ => Skeleton::custom(&self.skeleton, self.joints.clone(), Vec::new(), None),
        }
    }

    /// Checks that the parts agree: fps finite and > 0, D ≥ 1, at least one
    /// joint and one segment, unique non-empty joint names, durations ≥ 1,
    /// one primitive per joint in every segment, every primitive of dimension
    /// D with finite parameters, lines whose velocity has D values, circles
    /// with radius ≥ 0 (and D ≥ 2) and, when given, two plane axes of length D.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(ConcreteError::Program(m));
        if !(self.fps.is_finite() && self.fps > 0.0) {
            return bad(format!("fps must be finite and > 0, got {}", self.fps));
        }
        if self.dims == 0 {
            return bad("dims must be ≥ 1".into());
        }
        if self.joints.is_empty() {
            return bad("no joints".into());
        }
        for (i, j) in self.joints.iter().enumerate() {
            if j.is_empty() {
                return bad(format!("joint {i} has an empty name"));
            }
            if self.joints[..i].contains(j) {
                return bad(format!("joint name `{j}` appears twice"));
            }
        }
        if self.segments.is_empty() {
            return bad("no segments".into());
        }
        for (si, s) in self.segments.iter().enumerate() {
            if s.duration_frames == 0 {
                return bad(format!("segment {si} has duration 0"));
            }
            if s.primitives.len() != self.joints.len() {
                return bad(format!(
                    "segment {si} has {} primitives for {} joints",
                    s.primitives.len(),
                    self.joints.len()
                ));
            }
            for (ji, p) in s.primitives.iter().enumerate() {
                let name = &self.joints[ji];
                if p.dims() != self.dims {
                    return bad(format!(
                        "segment {si}, joint `{name}`: primitive has {} dimensions, program has {}",
                        p.dims(),
                        self.dims
                    ));
                }
                if !p.is_finite() {
                    return bad(format!(
                        "segment {si}, joint `{name}`: non-finite parameter"
                    ));
                }
                if let Primitive::Line { start, velocity } = p {
                    if velocity.len() != start.len() {
                        return bad(format!(
                            "segment {si}, joint `{name}`: line velocity has {} values, start {}",
                            velocity.len(),
                            start.len()
                        ));
                    }
                }
                if let Primitive::Circle { radius, axes, .. } = p {
                    if *radius < 0.0 {
                        return bad(format!(
                            "segment {si}, joint `{name}`: negative radius {radius}"
                        ));
                    }
                    if self.dims < 2 {
                        return bad(format!(
                            "segment {si}, joint `{name}`: a circle needs ≥ 2 dimensions"
                        ));
                    }
                    if !(axes.is_empty()
                        || (axes.len() == 2 && axes.iter().all(|a| a.len() == self.dims)))
                    {
                        return bad(format!(
                            "segment {si}, joint `{name}`: circle axes must be empty or two vectors of length {}",
                            self.dims
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// Serialises to pretty JSON.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self)
            .map_err(|source| ConcreteError::Json { path: None, source })
    }

    /// Parses JSON and validates the program.
    pub fn from_json(text: &str) -> Result<Self> {
        let p: Program = serde_json::from_str(text)
            .map_err(|source| ConcreteError::Json { path: None, source })?;
        p.validate()?;
        Ok(p)
    }

    /// The lossless DSL text (see `docs/DSL.md`): every number in its
    /// shortest round-trip form, so `Program::from_dsl(&p.to_dsl()) == p`
    /// for every valid program.
    pub fn to_dsl(&self) -> String {
        crate::dsl::print(self)
    }

    /// Human-friendly DSL text with `decimals` digits after the point (the
    /// paper uses 2; [`NumberFormat::pretty_decimals`](crate::NumberFormat::pretty_decimals)
    /// suits the units). Not lossless.
    pub fn to_dsl_pretty(&self, decimals: usize) -> String {
        crate::dsl::print_pretty(self, decimals)
    }

    /// Parses DSL text (see `docs/DSL.md`) and validates the program.
    pub fn from_dsl(text: &str) -> Result<Self> {
        crate::dsl::parse(text)
    }

    /// Encodes the program in the compact binary form (`.mpb`): the framing
    /// of [`mp_geom::binary`] with magic `mp-program` and version 2, then
    /// the record `fps: f64`, `units` (variant 0 = px, 1 = m, 2 = unitless),
    /// `dims`, `skeleton`, `joints`, `segments` (each `duration_frames`, then
    /// per joint a primitive: variant 0 stationary `{point}`, 1 line `{start,
    /// velocity}`, 2 circle `{center, radius, angle_start, angle_vel,
    /// angle_acc, axes}`, 3 spline `{coeffs}`), then `continuity` (variant 0 =
    /// none, 1 = C0; version 1 files end before it and read as none). Numbers
    /// are exact `f64`s, so [`Program::from_bincode`] gives back an equal
    /// program. The program is validated first.
    pub fn to_bincode(&self) -> Result<Vec<u8>> {
        self.validate()?;
        Ok(binary::encode(
            BINARY_MAGIC,
            BINARY_VERSION,
            &ProgramBin::from(self),
        )?)
    }

    /// Decodes a program written by [`Program::to_bincode`] and validates it
    /// as [`Program::from_json`] does. Corrupt or truncated bytes are a
    /// [`ConcreteError::Geom`] format error, an inconsistent program a
    /// [`ConcreteError::Program`]; neither panics.
    pub fn from_bincode(bytes: &[u8]) -> Result<Self> {
        Self::from_bincode_at(bytes, Path::new("bincode program"))
    }

    fn from_bincode_at(bytes: &[u8], source: &Path) -> Result<Self> {
        let version = bytes
            .strip_prefix(BINARY_MAGIC)
            .and_then(|rest| rest.first_chunk::<4>())
            .map(|v| u32::from_le_bytes(*v));
        let rec: ProgramBin = if version == Some(1) {
            binary::decode::<ProgramBinV1>(BINARY_MAGIC, 1, bytes, source)?.into()
        } else {
            binary::decode(BINARY_MAGIC, BINARY_VERSION, bytes, source)?
        };
        let p = Program::try_from(rec)?;
        p.validate()?;
        Ok(p)
    }

    /// Reads a program from a file: JSON when the extension is `.json`, the
    /// binary form when it is `.mpb`, DSL text otherwise.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let io_err = |source| ConcreteError::Io {
            path: path.into(),
            source,
        };
        let res = match Format::of(path) {
            Format::Binary => {
                let bytes = std::fs::read(path).map_err(io_err)?;
                Self::from_bincode_at(&bytes, path)
            }
            Format::Json => Self::from_json(&std::fs::read_to_string(path).map_err(io_err)?),
            Format::Dsl => Self::from_dsl(&std::fs::read_to_string(path).map_err(io_err)?),
        };
        res.map_err(|e| match e {
            ConcreteError::Parse { err, .. } => ConcreteError::Parse {
                path: Some(path.into()),
                err,
            },
            ConcreteError::Json { source, .. } => ConcreteError::Json {
                path: Some(path.into()),
                source,
            },
            ConcreteError::Program(m) => ConcreteError::Program(format!("{}: {m}", path.display())),
            other => other,
        })
    }

    /// Writes a program to a file: JSON when the extension is `.json`, the
    /// binary form when it is `.mpb`, lossless DSL text otherwise. Atomic
    /// (a temporary file in the same folder renamed into place).
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.validate()?;
        let bytes = match Format::of(path) {
            Format::Binary => self.to_bincode()?,
            Format::Json => self.to_json()?.into_bytes(),
            Format::Dsl => self.to_dsl().into_bytes(),
        };
        Ok(write_atomic(path, &bytes)?)
    }
}

/// Magic bytes that open the binary program format.
pub const BINARY_MAGIC: &[u8] = b"mp-program";
/// Version of the binary program format (2: with `continuity`; version 1 is still read).
pub const BINARY_VERSION: u32 = 2;

/// File formats of [`Program::read`] / [`Program::write`], by extension.
enum Format {
    Json,
    Binary,
    Dsl,
}

impl Format {
    fn of(path: &Path) -> Self {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("json") => Format::Json,
            Some("mpb") => Format::Binary,
            _ => Format::Dsl,
        }
    }
}

/// The binary record of a program. [`Primitive`] is internally tagged in
/// JSON (`"type": "line"`), which bincode cannot decode, so the binary form
/// mirrors it with an externally tagged enum (variant index, then fields).
#[derive(Serialize, Deserialize)]
struct ProgramBin {
    fps: f64,
    units: Units,
    dims: u64,
    skeleton: String,
    joints: Vec<String>,
    segments: Vec<SegmentBin>,
    continuity: Continuity,
}

/// The version-1 record: no `continuity` (read as [`Continuity::None`]).
#[derive(Serialize, Deserialize)]
struct ProgramBinV1 {
    fps: f64,
    units: Units,
    dims: u64,
    skeleton: String,
    joints: Vec<String>,
    segments: Vec<SegmentBin>,
}

impl From<ProgramBinV1> for ProgramBin {
    fn from(r: ProgramBinV1) -> Self {
        ProgramBin {
            fps: r.fps,
            units: r.units,
            dims: r.dims,
            skeleton: r.skeleton,
            joints: r.joints,
            segments: r.segments,
            continuity: Continuity::None,
        }
    }
}

#[derive(Serialize, Deserialize)]
struct SegmentBin {
    duration_frames: u64,
    primitives: Vec<PrimitiveBin>,
}

#[derive(Serialize, Deserialize)]
enum PrimitiveBin {
    Stationary {
        point: Vec<f64>,
    },
    Line {
        start: Vec<f64>,
        velocity: Vec<f64>,
    },
    Circle {
        center: Vec<f64>,
        radius: f64,
        angle_start: f64,
        angle_vel: f64,
        angle_acc: f64,
        axes: Vec<Vec<f64>>,
    },
    Spline {
        coeffs: Vec<[f64; 4]>,
    },
}

impl From<&Primitive> for PrimitiveBin {
    fn from(p: &Primitive) -> Self {
        match p.clone() {
            Primitive::Stationary { point } => PrimitiveBin::Stationary { point },
            Primitive::Line { start, velocity } => PrimitiveBin::Line { start, velocity },
            Primitive::Circle {
                center,
                radius,
                angle_start,
                angle_vel,
                angle_acc,
                axes,
            } => PrimitiveBin::Circle {
                center,
                radius,
                angle_start,
                angle_vel,
                angle_acc,
                axes,
            },
            Primitive::Spline { coeffs } => PrimitiveBin::Spline { coeffs },
        }
    }
}

impl From<PrimitiveBin> for Primitive {
    fn from(p: PrimitiveBin) -> Self {
        match p {
            PrimitiveBin::Stationary { point } => Primitive::Stationary { point },
            PrimitiveBin::Line { start, velocity } => Primitive::Line { start, velocity },
            PrimitiveBin::Circle {
                center,
                radius,
                angle_start,
                angle_vel,
                angle_acc,
                axes,
            } => Primitive::Circle {
                center,
                radius,
                angle_start,
                angle_vel,
                angle_acc,
                axes,
            },
            PrimitiveBin::Spline { coeffs } => Primitive::Spline { coeffs },
        }
    }
}

impl From<&Program> for ProgramBin {
    fn from(p: &Program) -> Self {
        ProgramBin {
            fps: p.fps,
            units: p.units,
            dims: p.dims as u64,
            skeleton: p.skeleton.clone(),
            joints: p.joints.clone(),
            segments: p
                .segments
                .iter()
                .map(|s| SegmentBin {
                    duration_frames: s.duration_frames as u64,
                    primitives: s.primitives.iter().map(PrimitiveBin::from).collect(),
                })
                .collect(),
            continuity: p.continuity,
        }
    }
}

impl TryFrom<ProgramBin> for Program {
    type Error = ConcreteError;
    fn try_from(r: ProgramBin) -> Result<Self> {
        let size = |v: u64, what: &str| {
            usize::try_from(v).map_err(|_| {
                ConcreteError::Program(format!("{what} {v} does not fit this machine"))
            })
        };
        Ok(Program {
            fps: r.fps,
            units: r.units,
            dims: size(r.dims, "dims")?,
            skeleton: r.skeleton,
            joints: r.joints,
            continuity: r.continuity,
            segments: r
                .segments
                .into_iter()
                .enumerate()
                .map(|(i, s)| {
                    Ok(Segment {
                        duration_frames: size(
                            s.duration_frames,
                            &format!("segment {i}: duration"),
                        )?,
                        primitives: s.primitives.into_iter().map(Primitive::from).collect(),
                    })
                })
                .collect::<Result<_>>()?,
        })
    }
}
