//! Readers for the shared data sets (layouts in `data/README.md`).
//!
//! | reader | file | tracks |
//! |---|---|---|
//! | [`PennAction`] | `penn_action/penn_action_train.npz` | one per clip, Penn-13, px, 30 fps |
//! | [`AistPlusPlus`] | `aistpp_keypoints2d/*.npz` | 9 camera views, COCO-17, px, 60 fps |
//! | [`MsrAction3D`] | `msr_action3d/*.npz` | one per clip, MSR-20, m, 15 fps |
//! | [`CmuFeatures`] | `cmu_mocap6_exercise/*_features10fps.npz` | 12 angle channels, unitless, 10 fps |
//! | [`MediaPipeReference`] | `reference_keypoints/*.npz` | BlazePose-33 px + world m |

use std::ops::Range;
use std::path::{Path, PathBuf};

use ndarray::{s, Array1, Array2, Array3, Array4, Ix2};

use super::npz::Npz;
use crate::error::{GeomError, Result};
use crate::skeleton::Skeleton;
use crate::track::{Track, Units};

/// The array `name` of `z`, checked against `shape` (`None`: any size) and
/// given its static dimensionality.
fn shaped<D: ndarray::Dimension>(
    z: &Npz,
    name: &str,
    shape: &[Option<usize>],
) -> Result<ndarray::Array<f64, D>> {
    z.array_f64_shaped(name, shape)?
        .into_dimensionality::<D>()
        .map_err(|e| GeomError::format(z.path(), format!("array `{name}`: {e}")))
}

/// Reads `offsets (C+1,)` and checks it partitions `n_rows`.
fn read_offsets(z: &Npz, n_rows: usize) -> Result<Vec<Range<usize>>> {
    let path = z.path();
    let off = z.array_i64("offsets")?;
    if off.ndim() != 1 || off.len() < 2 {
        return Err(GeomError::format(
            path,
            format!("`offsets` must be (C+1,) with C ≥ 1, got {:?}", off.shape()),
        ));
    }
    let off: Vec<i64> = off.iter().copied().collect();
    let mut ranges = Vec::with_capacity(off.len() - 1);
    for (i, w) in off.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        if a < 0 || b <= a || b as usize > n_rows {
            return Err(GeomError::format(
                path,
                format!(
                    "clip {i}: offsets {a}..{b} are not an increasing range inside 0..{n_rows}"
                ),
            ));
        }
        ranges.push(a as usize..b as usize);
    }
    if off[0] != 0 || off[off.len() - 1] as usize != n_rows {
        return Err(GeomError::format(
            path,
            format!(
                "offsets run {}..{}, frames are 0..{n_rows}",
                off[0],
                off[off.len() - 1]
            ),
        ));
    }
    Ok(ranges)
}

fn check_len<T>(v: &[T], n: usize, name: &str, path: &Path) -> Result<()> {
    if v.len() == n {
        Ok(())
    } else {
        Err(GeomError::format(
            path,
            format!(
                "`{name}` has {} entries, expected one per clip ({n})",
                v.len()
            ),
        ))
    }
}

fn data_path(rel: &str) -> Result<PathBuf> {
    crate::paths::data_file(rel).ok_or_else(|| {
        GeomError::NoData(format!(
            "shared data file `{rel}` not found (set MP_DATA_DIR or put `shared/data` beside the workspace)"
        ))
    })
}

// ---------------------------------------------------------------- Penn Action

/// Metadata of one Penn Action clip.
#[derive(Debug, Clone, PartialEq)]
pub struct PennClip {
    /// Position in the file (0-based).
    pub index: usize,
    /// Clip identifier, e.g. `0002`.
    pub clip_id: String,
    /// Action class, e.g. `baseball_pitch`.
    pub action: String,
    /// Camera view, e.g. `front`.
    pub view: String,
    /// Frame height in pixels.
    pub height_px: usize,
    /// Frame width in pixels.
    pub width_px: usize,
    /// Number of frames.
    pub n_frames: usize,
    /// Whether the clip is in the official train split.
    pub train: bool,
    /// Rows of the clip in the file's frame arrays.
    pub rows: Range<usize>,
}

/// Penn Action (one npz with every clip).
#[derive(Debug, Clone)]
pub struct PennAction {
    path: PathBuf,
    clips: Vec<PennClip>,
    keypoints: Array3<f64>,
    visibility: Array2<f64>,
    bbox: Array2<f64>,
}

impl PennAction {
    /// Frame rate of Penn Action videos.
    pub const FPS: f64 = 30.0;
    /// Path of the shared train split, relative to the data folder.
    pub const TRAIN_FILE: &'static str = "penn_action/penn_action_train.npz";

    /// Opens the shared train split (`MP_DATA_DIR` / `shared/data`).
    pub fn open_default() -> Result<Self> {
        Self::open(data_path(Self::TRAIN_FILE)?)
    }

    /// Reads a Penn Action npz (`keypoints (F,13,2)`, `visibility (F,13)`,
    /// `bbox (F,4)`, `offsets (C+1,)`, per clip `action`, `view`,
    /// `dimensions (C,3)`, `clip_id`, optional `train`).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let z = Npz::open(path)?;
        let path = z.path().to_path_buf();
        let keypoints: Array3<f64> = shaped(&z, "keypoints", &[None, Some(13), Some(2)])?;
        let f = keypoints.dim().0;
        let visibility: Array2<f64> = shaped(&z, "visibility", &[Some(f), Some(13)])?;
        let bbox: Array2<f64> = shaped(&z, "bbox", &[Some(f), Some(4)])?;
        let rows = read_offsets(&z, f)?;
        let c = rows.len();
        let action = z.strings("action")?;
        let view = z.strings("view")?;
        let clip_id = z.strings("clip_id")?;
        check_len(&action, c, "action", &path)?;
        check_len(&view, c, "view", &path)?;
        check_len(&clip_id, c, "clip_id", &path)?;
        let dims = z.array("dimensions")?;
        dims.expect_shape("dimensions", &[Some(c), Some(3)])?;
        let dims = dims.to_i64()?;
        let train: Vec<bool> = if z.contains("train") {
            let t: Vec<bool> = z.array_i64("train")?.iter().map(|&v| v != 0).collect();
            check_len(&t, c, "train", &path)?;
            t
        } else {
            vec![true; c]
        };
        let mut clips = Vec::with_capacity(c);
        for i in 0..c {
            let r = rows[i].clone();
            let (h, w, n) = (dims[[i, 0]], dims[[i, 1]], dims[[i, 2]]);
            if h <= 0 || w <= 0 || n as usize != r.len() {
                return Err(GeomError::format(
                    &path,
                    format!(
                        "clip {i} (`{}`): dimensions ({h}, {w}, {n}) disagree with its {} frames",
                        clip_id[i],
                        r.len()
                    ),
                ));
            }
            clips.push(PennClip {
                index: i,
                clip_id: clip_id[i].clone(),
                action: action[i].clone(),
                view: view[i].clone(),
                height_px: h as usize,
                width_px: w as usize,
                n_frames: r.len(),
                train: train[i],
                rows: r,
            });
        }
        Ok(PennAction {
            path,
            clips,
            keypoints,
            visibility,
            bbox,
        })
    }

    /// The file read.
    pub fn path(&self) -> &Path {
        &self.path
    }
    /// Number of clips.
    pub fn len(&self) -> usize {
        self.clips.len()
    }
    /// True when there are no clips.
    pub fn is_empty(&self) -> bool {
        self.clips.is_empty()
    }
    /// Metadata of every clip.
    pub fn clips(&self) -> &[PennClip] {
        &self.clips
    }
    /// Metadata of clip `i`.
    pub fn clip_info(&self, i: usize) -> Result<&PennClip> {
        self.clips.get(i).ok_or_else(|| {
            GeomError::param("clip", format!("index {i} outside 0..{}", self.clips.len()))
        })
    }
    /// Index of the clip with this id (e.g. `"0002"`).
    pub fn find_clip(&self, clip_id: &str) -> Option<usize> {
        self.clips.iter().position(|c| c.clip_id == clip_id)
    }
    /// Clip `i` as a track (Penn-13, pixels, visibility as confidence, 30 fps).
    pub fn clip(&self, i: usize) -> Result<Track> {
        let r = self.clip_info(i)?.rows.clone();
        Track::new(
            self.keypoints.slice(s![r.clone(), .., ..]).to_owned(),
            Some(self.visibility.slice(s![r, ..]).to_owned()),
            Self::FPS,
            Units::Pixels,
            Skeleton::penn13(),
        )
    }
    /// Bounding boxes `(n_frames, 4)` of clip `i`: x1, y1, x2, y2 in pixels.
    pub fn bbox(&self, i: usize) -> Result<Array2<f64>> {
        let r = self.clip_info(i)?.rows.clone();
        Ok(self.bbox.slice(s![r, ..]).to_owned())
    }
    /// Indices of the clips of one action class.
    pub fn clips_of_action(&self, action: &str) -> Vec<usize> {
        self.clips
            .iter()
            .filter(|c| c.action == action)
            .map(|c| c.index)
            .collect()
    }
    /// The action classes, sorted.
    pub fn actions(&self) -> Vec<String> {
        let mut a: Vec<String> = self.clips.iter().map(|c| c.action.clone()).collect();
        a.sort();
        a.dedup();
        a
    }
}

// ---------------------------------------------------------------- AIST++

/// One AIST++ sequence: nine synchronised camera views.
#[derive(Debug, Clone)]
pub struct AistPlusPlus {
    /// One COCO-17 pixel track per camera (score as confidence).
    pub views: Vec<Track>,
    /// Person detection score per view and frame `(views, T)`, if stored.
    pub det_scores: Option<Array2<f64>>,
    /// Frame timestamps in microseconds.
    pub timestamps_us: Vec<i64>,
    /// Frame rate from the timestamps.
    pub fps: f64,
}

/// Frame rate from timestamps in µs: (n − 1) / (last − first), snapped to the
/// nearest integer when within 0.01 % of it (timestamps are rounded to 1 µs).
pub fn fps_from_timestamps_us(ts: &[i64]) -> Option<f64> {
    let (&first, &last) = (ts.first()?, ts.last()?);
    if ts.len() < 2 || last <= first || ts.windows(2).any(|w| w[1] <= w[0]) {
        return None;
    }
    let fps = (ts.len() - 1) as f64 * 1e6 / (last - first) as f64;
    let r = fps.round();
    Some(if (fps - r).abs() <= 1e-4 * r { r } else { fps })
}

impl AistPlusPlus {
    /// Reads an AIST++ keypoints2d npz (`keypoints2d (V,T,17,3)`, `timestamps (T,)` µs,
    /// optional `det_scores (V,T)`).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let z = Npz::open(path)?;
        let path = z.path().to_path_buf();
        let kp: Array4<f64> = shaped(&z, "keypoints2d", &[None, None, Some(17), Some(3)])?;
        let (v, t, _, _) = kp.dim();
        let ts: Vec<i64> = z.array_i64("timestamps")?.iter().copied().collect();
        check_len(&ts, t, "timestamps", &path).map_err(|_| {
            GeomError::format(&path, format!("{} timestamps for {t} frames", ts.len()))
        })?;
        let fps = fps_from_timestamps_us(&ts)
            .ok_or_else(|| GeomError::format(&path, "timestamps are not strictly increasing"))?;
        let det_scores = if z.contains("det_scores") {
            Some(shaped::<Ix2>(&z, "det_scores", &[Some(v), Some(t)])?)
        } else {
            None
        };
        let mut views = Vec::with_capacity(v);
        for vi in 0..v {
            let pos = kp.slice(s![vi, .., .., 0..2]).to_owned();
            let conf = kp.slice(s![vi, .., .., 2]).to_owned();
            views.push(Track::new(
                pos,
                Some(conf),
                fps,
                Units::Pixels,
                Skeleton::coco17(),
            )?);
        }
        Ok(AistPlusPlus {
            views,
            det_scores,
            timestamps_us: ts,
            fps,
        })
    }
}

// ---------------------------------------------------------------- MSR Action3D

/// The 20 MSR Action3D action names, action `a` at index `a − 1`.
pub const MSR_ACTION_NAMES: [&str; 20] = [
    "high_arm_wave",
    "horizontal_arm_wave",
    "hammer",
    "hand_catch",
    "forward_punch",
    "high_throw",
    "draw_x",
    "draw_tick",
    "draw_circle",
    "hand_clap",
    "two_hand_wave",
    "side_boxing",
    "bend",
    "forward_kick",
    "side_kick",
    "jogging",
    "tennis_swing",
    "tennis_serve",
    "golf_swing",
    "pick_up_and_throw",
];

/// Metadata of one MSR Action3D clip.
#[derive(Debug, Clone, PartialEq)]
pub struct MsrClip {
    /// Position in the file.
    pub index: usize,
    /// Action number 1–20.
    pub action: u32,
    /// Action name (from `MSR_ACTION_NAMES`; `unknown` outside 1–20).
    pub action_name: &'static str,
    /// Subject number.
    pub subject: u32,
    /// Repetition number.
    pub rep: u32,
    /// Clip name, e.g. `a01_s01_e01`.
    pub name: String,
    /// Rows of the clip in the file's frame arrays.
    pub rows: Range<usize>,
}

/// MSR Action3D skeletons (one npz with every clip).
#[derive(Debug, Clone)]
pub struct MsrAction3D {
    path: PathBuf,
    clips: Vec<MsrClip>,
    joints: Array3<f64>,
    conf: Array2<f64>,
}

impl MsrAction3D {
    /// Frame rate of the Kinect recordings.
    pub const FPS: f64 = 15.0;
    /// Path of the shared file, relative to the data folder.
    pub const FILE: &'static str = "msr_action3d/msr_action3d_odd_subjects.npz";

    /// Opens the shared file.
    pub fn open_default() -> Result<Self> {
        Self::open(data_path(Self::FILE)?)
    }

    /// Reads an MSR Action3D npz (`joints (F,20,3)`, `conf (F,20)`, `offsets`,
    /// per clip `action`, `subject`, `rep`, `name`).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let z = Npz::open(path)?;
        let path = z.path().to_path_buf();
        let joints: Array3<f64> = shaped(&z, "joints", &[None, Some(20), Some(3)])?;
        let f = joints.dim().0;
        let conf: Array2<f64> = shaped(&z, "conf", &[Some(f), Some(20)])?;
        let rows = read_offsets(&z, f)?;
        let c = rows.len();
        let int_list = |name: &str| -> Result<Vec<u32>> {
            let v: Vec<i64> = z.array_i64(name)?.iter().copied().collect();
            check_len(&v, c, name, &path)?;
            v.into_iter()
                .map(|x| {
                    u32::try_from(x).map_err(|_| {
                        GeomError::format(&path, format!("`{name}` has a negative value {x}"))
                    })
                })
                .collect()
        };
        let action = int_list("action")?;
        let subject = int_list("subject")?;
        let rep = int_list("rep")?;
        let name = z.strings("name")?;
        check_len(&name, c, "name", &path)?;
        let clips = (0..c)
            .map(|i| MsrClip {
                index: i,
                action: action[i],
                action_name: msr_action_name(action[i]),
                subject: subject[i],
                rep: rep[i],
                name: name[i].clone(),
                rows: rows[i].clone(),
            })
            .collect();
        Ok(MsrAction3D {
            path,
            clips,
            joints,
            conf,
        })
    }

    /// Reads an MSR Action3D npz, or every `*.npz` of a folder (in name
    /// order) as one set: the clips of each file follow those of the files
    /// before it. A folder without any npz is an error naming the folder.
    pub fn open_path(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        if !path.is_dir() {
            return Self::open(path);
        }
        let mut files: Vec<PathBuf> = std::fs::read_dir(path)
            .map_err(|e| GeomError::io(path, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("npz")))
            .collect();
        files.sort();
        let mut sets = files.iter().map(Self::open);
        let mut all = match sets.next() {
            Some(first) => first?,
            None => {
                return Err(GeomError::NoData(format!(
                    "{}: no MSR Action3D npz in this folder",
                    path.display()
                )))
            }
        };
        for s in sets {
            all.append(s?)?;
        }
        if files.len() > 1 {
            all.path = path.to_path_buf();
        }
        Ok(all)
    }

    /// Appends the clips of `other` after those of `self`.
    fn append(&mut self, other: MsrAction3D) -> Result<()> {
        let rows = self.joints.dim().0;
        let n = self.clips.len();
        let shape =
            |e: ndarray::ShapeError| GeomError::Shape(format!("{}: {e}", other.path.display()));
        self.joints =
            ndarray::concatenate(ndarray::Axis(0), &[self.joints.view(), other.joints.view()])
                .map_err(shape)?;
        self.conf = ndarray::concatenate(ndarray::Axis(0), &[self.conf.view(), other.conf.view()])
            .map_err(shape)?;
        self.clips.extend(other.clips.into_iter().map(|c| MsrClip {
            index: c.index + n,
            rows: c.rows.start + rows..c.rows.end + rows,
            ..c
        }));
        Ok(())
    }

    /// The file read (the folder, for a set read from several files).
    pub fn path(&self) -> &Path {
        &self.path
    }
    /// Number of clips.
    pub fn len(&self) -> usize {
        self.clips.len()
    }
    /// True when there are no clips.
    pub fn is_empty(&self) -> bool {
        self.clips.is_empty()
    }
    /// Metadata of every clip.
    pub fn clips(&self) -> &[MsrClip] {
        &self.clips
    }
    /// The clips of `subjects` with `min_frames..=max_frames` frames and a
    /// tracked joint in every frame (the Kinect lost the body in none).
    pub fn clips_of_subjects(
        &self,
        subjects: &[u32],
        min_frames: usize,
        max_frames: usize,
    ) -> Vec<usize> {
        self.clips
            .iter()
            .filter(|c| {
                subjects.contains(&c.subject)
                    && c.rows.len() >= min_frames
                    && c.rows.len() <= max_frames
            })
            .filter(|c| {
                self.clip(c.index)
                    .map(|t| {
                        t.confidence()
                            .outer_iter()
                            .all(|row| row.iter().any(|&v| v > 0.0))
                    })
                    .unwrap_or(false)
            })
            .map(|c| c.index)
            .collect()
    }
    /// Metadata of clip `i`.
    pub fn clip_info(&self, i: usize) -> Result<&MsrClip> {
        self.clips.get(i).ok_or_else(|| {
            GeomError::param("clip", format!("index {i} outside 0..{}", self.clips.len()))
        })
    }
    /// Clip `i` as a track (MSR-20, metres, camera space y up, 15 fps).
    pub fn clip(&self, i: usize) -> Result<Track> {
        let r = self.clip_info(i)?.rows.clone();
        Track::new(
            self.joints.slice(s![r.clone(), .., ..]).to_owned(),
            Some(self.conf.slice(s![r, ..]).to_owned()),
            Self::FPS,
            Units::Metres,
            Skeleton::msr20(),
        )
    }
    /// Indices of the clips of action `action` (1–20).
    pub fn clips_of_action(&self, action: u32) -> Vec<usize> {
        self.clips
            .iter()
            .filter(|c| c.action == action)
            .map(|c| c.index)
            .collect()
    }
}

/// Name of MSR Action3D action `a` (1–20), `unknown` otherwise.
pub fn msr_action_name(a: u32) -> &'static str {
    (a as usize)
        .checked_sub(1)
        .and_then(|i| MSR_ACTION_NAMES.get(i))
        .copied()
        .unwrap_or("unknown")
}

// ---------------------------------------------------------------- CMU features

/// CMU mocap exercise features: 12 joint-angle channels at 10 fps with a
/// hand-made action label per frame.
#[derive(Debug, Clone)]
pub struct CmuFeatures {
    /// `T × 12 × 1` angle features, [`Units::Unitless`], 10 fps.
    pub track: Track,
    /// Label per frame (1-based index into `action_names`).
    pub labels: Vec<i64>,
    /// Action names, label `l` at index `l − 1`.
    pub action_names: Vec<String>,
}

impl CmuFeatures {
    /// Frame rate of the features.
    pub const FPS: f64 = 10.0;

    /// Reads a `*_features10fps.npz` (`X (T,12)`, `labels (T,)`, `action_names`).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_npz(&Npz::open(path)?)
    }

    /// Decodes an opened npz.
    pub fn from_npz(z: &Npz) -> Result<Self> {
        let path = z.path().to_path_buf();
        let x: Array2<f64> = shaped(z, "X", &[None, None])?;
        let (t, c) = x.dim();
        let labels: Vec<i64> = z.array_i64("labels")?.iter().copied().collect();
        if labels.len() != t {
            return Err(GeomError::format(
                &path,
                format!("{} labels for {t} frames", labels.len()),
            ));
        }
        let action_names = if z.contains("action_names") {
            z.strings("action_names")?
        } else {
            Vec::new()
        };
        let pos = x
            .into_shape_with_order((t, c, 1))
            .map_err(|e| GeomError::format(&path, format!("X: {e}")))?;
        let mut skeleton = Skeleton::generic(c);
        skeleton.name = "cmu_angles".into();
        let track = Track::new(pos, None, Self::FPS, Units::Unitless, skeleton)?;
        Ok(CmuFeatures {
            track,
            labels,
            action_names,
        })
    }

    /// Name of the action at frame `t` (None outside the track or for an unknown label).
    pub fn label_name(&self, t: usize) -> Option<&str> {
        let l = *self.labels.get(t)?;
        let i = usize::try_from(l).ok()?.checked_sub(1)?;
        self.action_names.get(i).map(|s| s.as_str())
    }

    /// Runs of equal labels: `(label, frames)` in order.
    pub fn segments(&self) -> Vec<(i64, Range<usize>)> {
        let mut out: Vec<(i64, Range<usize>)> = Vec::new();
        for (t, &l) in self.labels.iter().enumerate() {
            match out.last_mut() {
                Some((pl, r)) if *pl == l => r.end = t + 1,
                _ => out.push((l, t..t + 1)),
            }
        }
        out
    }
}

// ---------------------------------------------------------------- MediaPipe reference

/// Output of the reference MediaPipe BlazePose run on one video.
#[derive(Debug, Clone)]
pub struct MediaPipeReference {
    /// Image landmarks: BlazePose-33, pixels, visibility as confidence;
    /// frames without a pose have confidence 0.
    pub image: Track,
    /// World landmarks: BlazePose-33, metres (origin at hip centre, y down),
    /// same confidence as `image`.
    pub world: Track,
    /// Relative depth `z_norm · width` per landmark (NaN where no pose).
    pub z: Array2<f64>,
    /// Presence per landmark (NaN where no pose).
    pub presence: Array2<f64>,
    /// Whether a pose was returned for each frame.
    pub found: Vec<bool>,
    /// Frame rate of the video.
    pub fps: f64,
    /// Frame width in pixels.
    pub width_px: usize,
    /// Frame height in pixels.
    pub height_px: usize,
}

impl MediaPipeReference {
    /// Reads the plain (`smooth_landmarks=False`) run.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_npz(&Npz::open(path)?, false)
    }

    /// Reads the `smooth_landmarks=True` run (the `*_smooth` arrays).
    pub fn open_smooth(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_npz(&Npz::open(path)?, true)
    }

    /// Decodes an opened npz; `smooth` selects the `_smooth` arrays.
    pub fn from_npz(z: &Npz, smooth: bool) -> Result<Self> {
        let path = z.path().to_path_buf();
        let sfx = if smooth { "_smooth" } else { "" };
        let key = |k: &str| format!("{k}{sfx}");
        let lm: Array3<f64> = shaped(z, &key("landmarks_px"), &[None, Some(33), Some(2)])?;
        let t = lm.dim().0;
        let vis: Array2<f64> = shaped(z, &key("visibility"), &[Some(t), Some(33)])?;
        let world: Array3<f64> = shaped(z, &key("world"), &[Some(t), Some(33), Some(3)])?;
        let zz: Array2<f64> = shaped(z, &key("z"), &[Some(t), Some(33)])?;
        let presence: Array2<f64> = if z.contains(&key("presence")) {
            shaped(z, &key("presence"), &[Some(t), Some(33)])?
        } else {
            Array2::from_elem((t, 33), f64::NAN)
        };
        let found_a: Array1<f64> = shaped(z, &key("found"), &[Some(t)])?;
        let found: Vec<bool> = found_a.iter().map(|&v| v != 0.0).collect();
        let fps = z.scalar_f64("fps")?;
        let width = z.scalar_f64("width")?;
        let height = z.scalar_f64("height")?;
        if !(width >= 1.0 && height >= 1.0) {
            return Err(GeomError::format(
                &path,
                format!("frame size {width}×{height} is not positive"),
            ));
        }
        let mut conf = vis;
        for (ti, &f) in found.iter().enumerate() {
            if !f {
                conf.row_mut(ti).fill(0.0);
            }
        }
        let image = Track::new(
            lm,
            Some(conf.clone()),
            fps,
            Units::Pixels,
            Skeleton::blazepose33(),
        )
        .map_err(|e| GeomError::format(&path, e.to_string()))?;
        let world = Track::new(
            world,
            Some(conf),
            fps,
            Units::Metres,
            Skeleton::blazepose33(),
        )
        .map_err(|e| GeomError::format(&path, e.to_string()))?;
        Ok(MediaPipeReference {
            image,
            world,
            z: zz,
            presence,
            found,
            fps,
            width_px: width as usize,
            height_px: height as usize,
        })
    }
}
