//! The concrete program: one shared segmentation × one primitive per joint per segment.

use std::path::Path;

use mp_geom::{Primitive, PrimitiveKind, Skeleton, Units};
use serde::{Deserialize, Serialize};

use crate::error::{ConcreteError, Result};

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
    /// (durations are shared by all joints, so they are counted once).
    pub fn n_params(&self) -> usize {
        self.segments
            .iter()
            .map(|s| 1 + s.primitives.iter().map(Primitive::n_params).sum::<usize>())
            .sum()
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
    /// D with finite parameters, circles with radius ≥ 0 (and D ≥ 2) and, when
    /// given, two plane axes of length D.
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

    /// The lossless DSL text (see `docs/DSL.md`).
    pub fn to_dsl(&self) -> String {
        crate::dsl::print(self)
    }

    /// Parses DSL text (see `docs/DSL.md`) and validates the program.
    pub fn from_dsl(text: &str) -> Result<Self> {
        crate::dsl::parse(text)
    }

    /// Reads a program from a file: JSON when the extension is `.json`, DSL text otherwise.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| ConcreteError::Io {
            path: path.into(),
            source,
        })?;
        let res = if is_json(path) {
            Self::from_json(&text)
        } else {
            Self::from_dsl(&text)
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

    /// Writes a program to a file: JSON when the extension is `.json`, lossless DSL text otherwise.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.validate()?;
        let text = if is_json(path) {
            self.to_json()?
        } else {
            self.to_dsl()
        };
        std::fs::write(path, text).map_err(|source| ConcreteError::Io {
            path: path.into(),
            source,
        })
    }
}

fn is_json(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}
