//! BVH motion capture: parse, write back, slice, concatenate, and forward
//! kinematics to world joint positions.
//!
//! Conventions (as in the BVH files of the CMU collection and most tools):
//! a joint's local transform is `T(offset + position channels) · R₁ · R₂ · R₃`
//! with the rotations in the order the `CHANNELS` line lists them (angles in
//! degrees, right-handed axes), so a point in the joint's frame maps to its
//! parent's frame by that product. The root's world position is its offset
//! plus its position channels. `End Site`s are kept (for writing back) and can
//! be included in the track as extra joints named `<joint>_end`.

use std::fmt::Write as _;
use std::path::Path;

use glam::{DAffine3, DMat3, DVec3};
use ndarray::{s, Array2, Array3, ArrayView2};

use super::write_atomic;
use crate::error::{GeomError, Result};
use crate::skeleton::Skeleton;
use crate::track::{Track, Units};

/// One BVH channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Channel {
    /// Translation along x.
    Xposition,
    /// Translation along y.
    Yposition,
    /// Translation along z.
    Zposition,
    /// Rotation about x, degrees.
    Xrotation,
    /// Rotation about y, degrees.
    Yrotation,
    /// Rotation about z, degrees.
    Zrotation,
}

impl Channel {
    fn parse(s: &str) -> Option<Self> {
        Some(match s.to_ascii_lowercase().as_str() {
            "xposition" => Channel::Xposition,
            "yposition" => Channel::Yposition,
            "zposition" => Channel::Zposition,
            "xrotation" => Channel::Xrotation,
            "yrotation" => Channel::Yrotation,
            "zrotation" => Channel::Zrotation,
            _ => return None,
        })
    }
    /// Name as written in BVH files.
    pub fn as_str(&self) -> &'static str {
        match self {
            Channel::Xposition => "Xposition",
            Channel::Yposition => "Yposition",
            Channel::Zposition => "Zposition",
            Channel::Xrotation => "Xrotation",
            Channel::Yrotation => "Yrotation",
            Channel::Zrotation => "Zrotation",
        }
    }
    /// Axis index 0/1/2.
    pub fn axis(&self) -> usize {
        match self {
            Channel::Xposition | Channel::Xrotation => 0,
            Channel::Yposition | Channel::Yrotation => 1,
            Channel::Zposition | Channel::Zrotation => 2,
        }
    }
    /// Whether this is a translation channel.
    pub fn is_position(&self) -> bool {
        matches!(
            self,
            Channel::Xposition | Channel::Yposition | Channel::Zposition
        )
    }
}

/// One joint of the hierarchy (file order = pre-order, parents first).
#[derive(Debug, Clone, PartialEq)]
pub struct BvhJoint {
    /// Joint name.
    pub name: String,
    /// Parent joint index (None for a root).
    pub parent: Option<usize>,
    /// Offset from the parent, in file units.
    pub offset: [f64; 3],
    /// Channels in file order.
    pub channels: Vec<Channel>,
    /// Index of this joint's first channel in a frame row.
    pub first_channel: usize,
    /// Offset of the joint's `End Site`, if it has one.
    pub end_site: Option<[f64; 3]>,
}

/// A parsed BVH file: hierarchy plus one row of channel values per frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    joints: Vec<BvhJoint>,
    frame_time_s: f64,
    motion: Array2<f64>,
}

/// How to turn a [`Bvh`] into a [`Track`].
#[derive(Debug, Clone, PartialEq)]
pub struct BvhTrackParams {
    /// Factor applied to offsets and translations (file units → track units).
    /// Default 1 (the CMU salsa files are already in metres).
    pub length_scale: f64,
    /// Units of the track after scaling. Default metres.
    pub units: Units,
    /// Add each `End Site` as a joint named `<joint>_end`. Default false.
    pub include_end_sites: bool,
}

impl Default for BvhTrackParams {
    fn default() -> Self {
        BvhTrackParams {
            length_scale: 1.0,
            units: Units::Metres,
            include_end_sites: false,
        }
    }
}

struct Tokens<'a> {
    toks: Vec<(&'a str, usize)>,
    pos: usize,
    path: &'a Path,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str, path: &'a Path) -> Self {
        let toks = text
            .lines()
            .enumerate()
            .flat_map(|(i, l)| l.split_whitespace().map(move |t| (t, i + 1)))
            .collect();
        Tokens { toks, pos: 0, path }
    }
    fn line(&self) -> usize {
        self.toks
            .get(self.pos)
            .or_else(|| self.toks.last())
            .map_or(0, |t| t.1)
    }
    fn err(&self, msg: impl std::fmt::Display) -> GeomError {
        GeomError::format(self.path, format!("line {}: {msg}", self.line()))
    }
    fn peek(&self) -> Option<&'a str> {
        self.toks.get(self.pos).map(|t| t.0)
    }
    fn next(&mut self, what: &str) -> Result<&'a str> {
        let t = self
            .toks
            .get(self.pos)
            .map(|t| t.0)
            .ok_or_else(|| self.err(format!("unexpected end of file, expected {what}")))?;
        self.pos += 1;
        Ok(t)
    }
    fn expect(&mut self, word: &str) -> Result<()> {
        let t = self.next(&format!("`{word}`"))?;
        if t.eq_ignore_ascii_case(word) {
            Ok(())
        } else {
            self.pos -= 1;
            Err(self.err(format!("expected `{word}`, found `{t}`")))
        }
    }
    fn number(&mut self, what: &str) -> Result<f64> {
        let t = self.next(what)?;
        match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => {
                self.pos -= 1;
                Err(self.err(format!("{what}: `{t}` is not a finite number")))
            }
        }
    }
    fn vec3(&mut self, what: &str) -> Result<[f64; 3]> {
        Ok([self.number(what)?, self.number(what)?, self.number(what)?])
    }
}

fn parse_joint(
    tk: &mut Tokens<'_>,
    parent: Option<usize>,
    joints: &mut Vec<BvhJoint>,
    n_channels: &mut usize,
    depth: usize,
) -> Result<()> {
    if depth > 256 {
        return Err(tk.err("hierarchy nested deeper than 256 joints"));
    }
    let mut name_parts = Vec::new();
    while let Some(t) = tk.peek() {
        if t == "{" {
            break;
        }
        name_parts.push(tk.next("joint name")?);
    }
    if name_parts.is_empty() {
        return Err(tk.err("joint without a name"));
    }
    let name = name_parts.join(" ");
    tk.expect("{")?;
    tk.expect("OFFSET")?;
    let offset = tk.vec3(&format!("OFFSET of `{name}`"))?;
    let mut channels = Vec::new();
    if tk
        .peek()
        .is_some_and(|t| t.eq_ignore_ascii_case("CHANNELS"))
    {
        tk.next("CHANNELS")?;
        let n = tk.number(&format!("channel count of `{name}`"))?;
        if !(0.0..=6.0).contains(&n) || n.fract() != 0.0 {
            return Err(tk.err(format!("`{name}`: channel count {n} is not 0–6")));
        }
        for _ in 0..n as usize {
            let c = tk.next("channel name")?;
            let ch = Channel::parse(c)
                .ok_or_else(|| tk.err(format!("`{name}`: unknown channel `{c}`")))?;
            channels.push(ch);
        }
    }
    let idx = joints.len();
    joints.push(BvhJoint {
        name,
        parent,
        offset,
        first_channel: *n_channels,
        channels,
        end_site: None,
    });
    *n_channels += joints[idx].channels.len();
    loop {
        let t = tk.next("`JOINT`, `End Site` or `}`")?;
        if t == "}" {
            return Ok(());
        } else if t.eq_ignore_ascii_case("JOINT") {
            parse_joint(tk, Some(idx), joints, n_channels, depth + 1)?;
        } else if t.eq_ignore_ascii_case("End") {
            tk.expect("Site")?;
            tk.expect("{")?;
            tk.expect("OFFSET")?;
            let o = tk.vec3("End Site OFFSET")?;
            tk.expect("}")?;
            if joints[idx].end_site.is_some() {
                return Err(tk.err(format!("`{}` has two End Sites", joints[idx].name)));
            }
            joints[idx].end_site = Some(o);
        } else {
            tk.pos -= 1;
            return Err(tk.err(format!("expected `JOINT`, `End Site` or `}}`, found `{t}`")));
        }
    }
}

/// Rotation by `deg` degrees about axis 0/1/2 (x/y/z), right-handed.
fn rot(axis: usize, deg: f64) -> DMat3 {
    let angle = deg.to_radians();
    match axis {
        0 => DMat3::from_rotation_x(angle),
        1 => DMat3::from_rotation_y(angle),
        _ => DMat3::from_rotation_z(angle),
    }
}

fn fmt_num(s: &mut String, v: f64) {
    // Shortest representation that reads back to the same f64.
    let _ = write!(s, "{v}");
}

/// Aliases of COCO-17 joints in common BVH naming schemes (lower case,
/// without `_`/spaces), tried in order after exact COCO names.
const BVH_COCO_ALIASES: [&[&str]; 17] = [
    &["nose", "head"],
    &["lefteye", "leye"],
    &["righteye", "reye"],
    &["leftear", "lear"],
    &["rightear", "rear"],
    &["lshldr", "leftarm", "lhumerus", "leftupperarm", "lshoulder"],
    &[
        "rshldr",
        "rightarm",
        "rhumerus",
        "rightupperarm",
        "rshoulder",
    ],
    &[
        "lforearm",
        "leftforearm",
        "lradius",
        "leftlowerarm",
        "lelbow",
    ],
    &[
        "rforearm",
        "rightforearm",
        "rradius",
        "rightlowerarm",
        "relbow",
    ],
    &["lhand", "lefthand", "lwrist", "leftwrist"],
    &["rhand", "righthand", "rwrist", "rightwrist"],
    &[
        "lthigh",
        "leftupleg",
        "lfemur",
        "leftupperleg",
        "lhip",
        "lefthip",
    ],
    &[
        "rthigh",
        "rightupleg",
        "rfemur",
        "rightupperleg",
        "rhip",
        "righthip",
    ],
    &[
        "lshin",
        "leftleg",
        "ltibia",
        "leftlowerleg",
        "lknee",
        "leftknee",
    ],
    &[
        "rshin",
        "rightleg",
        "rtibia",
        "rightlowerleg",
        "rknee",
        "rightknee",
    ],
    &["lfoot", "leftfoot", "lankle", "leftankle"],
    &["rfoot", "rightfoot", "rankle", "rightankle"],
];

/// COCO-17 mapping of BVH joint names: exact COCO names first, then common
/// BVH aliases (CMU `lShldr`/`lForeArm`/`lHand`/`lThigh`/`lShin`/`lFoot`,
/// `LeftArm`/`LeftForeArm`/`LeftUpLeg`/`LeftLeg`, Acclaim `lhumerus`…; the
/// head stands in for the nose). Empty when nothing matches.
pub(crate) fn bvh_coco17_mapping(joints: &[String]) -> Vec<Option<usize>> {
    let norm: Vec<String> = joints
        .iter()
        .map(|n| {
            n.chars()
                .filter(|c| *c != '_' && *c != ' ')
                .collect::<String>()
                .to_ascii_lowercase()
        })
        .collect();
    let map: Vec<Option<usize>> = crate::skeleton::COCO17_JOINTS
        .iter()
        .enumerate()
        .map(|(ci, cname)| {
            joints.iter().position(|j| j == cname).or_else(|| {
                BVH_COCO_ALIASES[ci]
                    .iter()
                    .find_map(|a| norm.iter().position(|n| n == a))
            })
        })
        .collect();
    if map.iter().any(|m| m.is_some()) {
        map
    } else {
        Vec::new()
    }
}

impl Bvh {
    /// Reads a BVH file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| GeomError::io(path, e))?;
        Self::parse(&text, path)
    }

    /// Parses BVH text; `path` names the source in messages.
    pub fn parse(text: &str, path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let mut tk = Tokens::new(text, path);
        tk.expect("HIERARCHY")?;
        let mut joints = Vec::new();
        let mut n_channels = 0usize;
        while tk.peek().is_some_and(|t| t.eq_ignore_ascii_case("ROOT")) {
            tk.next("ROOT")?;
            parse_joint(&mut tk, None, &mut joints, &mut n_channels, 0)?;
        }
        if joints.is_empty() {
            return Err(tk.err("no ROOT joint"));
        }
        tk.expect("MOTION")?;
        tk.expect("Frames:")?;
        let n = tk.number("frame count")?;
        if n < 0.0 || n.fract() != 0.0 {
            return Err(tk.err(format!("frame count {n} is not a whole number")));
        }
        let n_frames = n as usize;
        tk.expect("Frame")?;
        tk.expect("Time:")?;
        let frame_time_s = tk.number("frame time")?;
        if frame_time_s <= 0.0 {
            return Err(tk.err(format!("frame time {frame_time_s} must be > 0")));
        }
        let available = tk.toks.len() - tk.pos;
        let needed = n_frames
            .checked_mul(n_channels)
            .ok_or_else(|| tk.err("frame count overflows"))?;
        if available < needed {
            let frame = available / n_channels.max(1);
            return Err(GeomError::format(
                path,
                format!(
                    "MOTION ends in frame {frame}: header says {n_frames} frames of {n_channels} channels \
                     ({needed} values), file has {available}"
                ),
            ));
        }
        if available > needed {
            tk.pos += needed;
            return Err(tk.err(format!(
                "{} values after the {n_frames} frames the header announces",
                available - needed
            )));
        }
        let mut motion = Array2::<f64>::zeros((n_frames, n_channels));
        for f in 0..n_frames {
            for c in 0..n_channels {
                let t = tk.toks[tk.pos];
                let v =
                    t.0.parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| {
                            GeomError::format(
                                path,
                                format!(
                                    "line {}: frame {f}, channel {c}: `{}` is not a finite number",
                                    t.1, t.0
                                ),
                            )
                        })?;
                motion[[f, c]] = v;
                tk.pos += 1;
            }
        }
        Ok(Bvh {
            joints,
            frame_time_s,
            motion,
        })
    }

    /// Builds a BVH from parts, checking that the motion has one column per channel.
    pub fn from_parts(
        joints: Vec<BvhJoint>,
        frame_time_s: f64,
        motion: Array2<f64>,
    ) -> Result<Self> {
        let mut n = 0;
        for (i, j) in joints.iter().enumerate() {
            if j.parent.is_some_and(|p| p >= i) {
                return Err(GeomError::param(
                    "joints",
                    format!("joint {i} `{}` comes before its parent", j.name),
                ));
            }
            if j.first_channel != n {
                return Err(GeomError::param(
                    "joints",
                    format!(
                        "joint {i} `{}`: first channel {} should be {n}",
                        j.name, j.first_channel
                    ),
                ));
            }
            n += j.channels.len();
        }
        if motion.ncols() != n {
            return Err(GeomError::Shape(format!(
                "motion has {} columns, hierarchy has {n} channels",
                motion.ncols()
            )));
        }
        if !(frame_time_s.is_finite() && frame_time_s > 0.0) {
            return Err(GeomError::param("frame_time_s", "must be finite and > 0"));
        }
        if motion.iter().any(|v| !v.is_finite()) {
            return Err(GeomError::NonFinite("BVH motion values".into()));
        }
        Ok(Bvh {
            joints,
            frame_time_s,
            motion,
        })
    }

    /// The joints in file order.
    pub fn joints(&self) -> &[BvhJoint] {
        &self.joints
    }
    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.motion.nrows()
    }
    /// Number of channels per frame.
    pub fn n_channels(&self) -> usize {
        self.motion.ncols()
    }
    /// Seconds per frame (`Frame Time`).
    pub fn frame_time_s(&self) -> f64 {
        self.frame_time_s
    }
    /// Frames per second, `1 / Frame Time`.
    pub fn fps(&self) -> f64 {
        1.0 / self.frame_time_s
    }
    /// Channel values, `frames × channels`.
    pub fn motion(&self) -> ArrayView2<'_, f64> {
        self.motion.view()
    }
    /// Index of a joint by name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Root translation channels of frame `f` (x, y, z; 0 for absent channels);
    /// None when `f` is outside the motion.
    pub fn root_channels(&self, f: usize) -> Option<[f64; 3]> {
        let root = self.joints.first()?;
        if f >= self.n_frames() {
            return None;
        }
        let row = self.motion.row(f);
        let mut p = [0.0; 3];
        for (k, ch) in root.channels.iter().enumerate() {
            if ch.is_position() {
                p[ch.axis()] = row[root.first_channel + k];
            }
        }
        Some(p)
    }

    /// Adds `delta` (file units) to the first root's translation channels in every frame.
    pub fn translate_root(&mut self, delta: [f64; 3]) {
        if let Some(root) = self.joints.first() {
            for (k, ch) in root.channels.iter().enumerate() {
                if ch.is_position() {
                    let col = root.first_channel + k;
                    self.motion
                        .column_mut(col)
                        .mapv_inplace(|v| v + delta[ch.axis()]);
                }
            }
        }
    }

    /// Frames `start..end` (end exclusive).
    pub fn slice_frames(&self, start: usize, end: usize) -> Result<Self> {
        if start >= end || end > self.n_frames() {
            return Err(GeomError::param(
                "frames",
                format!(
                    "range {start}..{end} is empty or outside 0..{}",
                    self.n_frames()
                ),
            ));
        }
        Ok(Bvh {
            joints: self.joints.clone(),
            frame_time_s: self.frame_time_s,
            motion: self.motion.slice(s![start..end, ..]).to_owned(),
        })
    }

    /// `self` followed by `other`. Both need the same joint names, parents
    /// and channels, and the same frame time (within 1e-9 s); the offsets of
    /// `self` are kept.
    pub fn concat(&self, other: &Bvh) -> Result<Self> {
        if self.joints.len() != other.joints.len() {
            return Err(GeomError::Shape(format!(
                "cannot join BVHs of {} and {} joints",
                self.joints.len(),
                other.joints.len()
            )));
        }
        for (a, b) in self.joints.iter().zip(&other.joints) {
            if a.name != b.name || a.parent != b.parent || a.channels != b.channels {
                return Err(GeomError::Shape(format!(
                    "cannot join BVHs: joint `{}` differs from `{}` (name, parent or channels)",
                    a.name, b.name
                )));
            }
        }
        if (self.frame_time_s - other.frame_time_s).abs() > 1e-9 {
            return Err(GeomError::param(
                "frame_time_s",
                format!(
                    "cannot join BVHs with frame times {} and {}",
                    self.frame_time_s, other.frame_time_s
                ),
            ));
        }
        let motion =
            ndarray::concatenate(ndarray::Axis(0), &[self.motion.view(), other.motion.view()])
                .map_err(|e| GeomError::Shape(e.to_string()))?;
        Ok(Bvh {
            joints: self.joints.clone(),
            frame_time_s: self.frame_time_s,
            motion,
        })
    }

    /// The BVH text (numbers in their shortest exact form, so parsing it
    /// gives back the same values).
    pub fn to_bvh_string(&self) -> String {
        let mut s = String::with_capacity(64 * self.joints.len() + 16 * self.motion.len());
        s.push_str("HIERARCHY\n");
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); self.joints.len()];
        for (i, j) in self.joints.iter().enumerate() {
            if let Some(p) = j.parent {
                children[p].push(i);
            }
        }
        fn write_joint(s: &mut String, b: &Bvh, children: &[Vec<usize>], i: usize, depth: usize) {
            let j = &b.joints[i];
            let ind = "\t".repeat(depth);
            let kw = if j.parent.is_none() { "ROOT" } else { "JOINT" };
            let _ = writeln!(s, "{ind}{kw} {}", j.name);
            let _ = writeln!(s, "{ind}{{");
            let _ = write!(s, "{ind}\tOFFSET");
            for v in j.offset {
                s.push(' ');
                fmt_num(s, v);
            }
            s.push('\n');
            if !j.channels.is_empty() {
                let _ = write!(s, "{ind}\tCHANNELS {}", j.channels.len());
                for c in &j.channels {
                    let _ = write!(s, " {}", c.as_str());
                }
                s.push('\n');
            }
            for &c in &children[i] {
                write_joint(s, b, children, c, depth + 1);
            }
            if let Some(e) = j.end_site {
                let _ = writeln!(s, "{ind}\tEnd Site");
                let _ = writeln!(s, "{ind}\t{{");
                let _ = write!(s, "{ind}\t\tOFFSET");
                for v in e {
                    s.push(' ');
                    fmt_num(s, v);
                }
                s.push('\n');
                let _ = writeln!(s, "{ind}\t}}");
            }
            let _ = writeln!(s, "{ind}}}");
        }
        for (i, j) in self.joints.iter().enumerate() {
            if j.parent.is_none() {
                write_joint(&mut s, self, &children, i, 0);
            }
        }
        s.push_str("MOTION\n");
        let _ = writeln!(s, "Frames: {}", self.n_frames());
        let _ = write!(s, "Frame Time: ");
        fmt_num(&mut s, self.frame_time_s);
        s.push('\n');
        for row in self.motion.outer_iter() {
            for (k, v) in row.iter().enumerate() {
                if k > 0 {
                    s.push(' ');
                }
                fmt_num(&mut s, *v);
            }
            s.push('\n');
        }
        s
    }

    /// Writes the BVH file (atomic).
    pub fn write_bvh(&self, path: impl AsRef<Path>) -> Result<()> {
        write_atomic(path, self.to_bvh_string().as_bytes())
    }

    /// The skeleton of the hierarchy: joint names (plus `<joint>_end` for end
    /// sites when asked), parent→child bones, root 0, COCO-17 mapping by name.
    pub fn skeleton(&self, include_end_sites: bool) -> Skeleton {
        let mut names: Vec<String> = self.joints.iter().map(|j| j.name.clone()).collect();
        let mut bones: Vec<(usize, usize)> = self
            .joints
            .iter()
            .enumerate()
            .filter_map(|(i, j)| j.parent.map(|p| (p, i)))
            .collect();
        if include_end_sites {
            for (i, j) in self.joints.iter().enumerate() {
                if j.end_site.is_some() {
                    names.push(format!("{}_end", j.name));
                    bones.push((i, names.len() - 1));
                }
            }
        }
        let mut sk = Skeleton::custom("bvh", names, bones, Some(0));
        let n_real = self.joints.len();
        let real: Vec<String> = sk.joints[..n_real].to_vec();
        sk.coco17 = bvh_coco17_mapping(&real);
        sk
    }

    /// World positions `frames × joints × 3` by forward kinematics (end sites
    /// appended after the joints when asked), scaled by `length_scale`.
    pub fn world_positions(
        &self,
        length_scale: f64,
        include_end_sites: bool,
    ) -> Result<Array3<f64>> {
        if !(length_scale.is_finite() && length_scale > 0.0) {
            return Err(GeomError::param(
                "length_scale",
                format!("must be finite and > 0, got {length_scale}"),
            ));
        }
        let nj = self.joints.len();
        let ends: Vec<(usize, [f64; 3])> = if include_end_sites {
            self.joints
                .iter()
                .enumerate()
                .filter_map(|(i, j)| j.end_site.map(|e| (i, e)))
                .collect()
        } else {
            Vec::new()
        };
        let t = self.n_frames();
        let mut out = Array3::<f64>::zeros((t, nj + ends.len(), 3));
        // World transform of each joint in the current frame (parents come first).
        let mut world = vec![DAffine3::IDENTITY; nj];
        for f in 0..t {
            let row = self.motion.row(f);
            for (i, j) in self.joints.iter().enumerate() {
                let mut translation = DVec3::from_array(j.offset);
                let mut rotation = DMat3::IDENTITY;
                for (k, ch) in j.channels.iter().enumerate() {
                    let v = row[j.first_channel + k];
                    if ch.is_position() {
                        translation[ch.axis()] += v;
                    } else {
                        rotation *= rot(ch.axis(), v);
                    }
                }
                let local = DAffine3::from_mat3_translation(rotation, translation * length_scale);
                world[i] = match j.parent {
                    Some(p) => world[p] * local,
                    None => local,
                };
                let wp = world[i].translation;
                for k in 0..3 {
                    out[[f, i, k]] = wp[k];
                }
            }
            for (e, (i, off)) in ends.iter().enumerate() {
                let p = world[*i].transform_point3(DVec3::from_array(*off) * length_scale);
                for k in 0..3 {
                    out[[f, nj + e, k]] = p[k];
                }
            }
        }
        Ok(out)
    }

    /// Forward kinematics to a track (skeleton from the hierarchy, fps = 1 / Frame Time).
    pub fn to_track(&self, params: &BvhTrackParams) -> Result<Track> {
        let pos = self.world_positions(params.length_scale, params.include_end_sites)?;
        Track::new(
            pos,
            None,
            self.fps(),
            params.units,
            self.skeleton(params.include_end_sites),
        )
    }
}
