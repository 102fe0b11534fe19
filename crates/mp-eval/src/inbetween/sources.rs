//! The keypoint tracks of `cargo xtask eval inbetween`: real motion from the
//! shared data, each track with its frame size, the person's size and its
//! part (validation or held-out).

use std::path::Path;

use anyhow::{bail, Context};
use mp_geom::SkeletonMap;
use mp_geom::{AistPlusPlus, MediaPipeReference, MsrAction3D, PennAction};
use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array2, Array3};

use crate::synth_sources::{files, stem, to_30fps};

/// Which part of a source a track belongs to.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// Both parts.
    All,
    /// Where settings are chosen.
    Validation,
    /// Where they are reported.
    HeldOut,
}

impl Part {
    /// Name in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Part::All => "all",
            Part::Validation => "validation",
            Part::HeldOut => "held-out",
        }
    }

    fn admits(self, part: Part) -> bool {
        self == Part::All || self == part
    }
}

/// One real track (2D pixels).
pub struct Clip {
    /// Source (`penn`, `aist`, `quva`, `msr`).
    pub source: &'static str,
    /// Name within the source.
    pub name: String,
    /// Validation or held-out.
    pub part: Part,
    /// The keypoints at the source's frame rate.
    pub track: Track,
    /// The larger side of the frame (px).
    pub frame_px: f64,
    /// The person's size: the median over frames of the larger side of the
    /// box of the seen keypoints (px).
    pub person_px: f64,
}

/// Confidence above which a keypoint is seen (the toolkit's threshold).
pub const MIN_CONF: f64 = 0.3;

/// Median over frames (with at least two seen joints) of the larger side of
/// the seen keypoints' box.
pub fn person_size(track: &Track) -> f64 {
    let mut sizes: Vec<f64> = (0..track.n_frames())
        .filter_map(|t| {
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            let mut n = 0;
            for j in (0..track.n_joints()).filter(|&j| track.is_valid(t, j, MIN_CONF)) {
                let p = track.point(t, j);
                for d in 0..2 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
                n += 1;
            }
            (n >= 2).then(|| (hi[0] - lo[0]).max(hi[1] - lo[1]))
        })
        .filter(|s| *s > 0.0)
        .collect();
    if sizes.is_empty() {
        return f64::NAN;
    }
    sizes.sort_by(f64::total_cmp);
    sizes[sizes.len() / 2]
}

fn clip(
    source: &'static str,
    name: String,
    part: Part,
    track: Track,
    frame_px: f64,
) -> Option<Clip> {
    let person_px = person_size(&track);
    (person_px.is_finite() && track.n_frames() >= 3).then_some(Clip {
        source,
        name,
        part,
        track,
        frame_px,
        person_px,
    })
}

/// The `.npz` files of a folder, sorted; an error names a missing folder.
fn npz_files(dir: &Path) -> anyhow::Result<Vec<std::path::PathBuf>> {
    anyhow::ensure!(dir.is_dir(), "reading {}: no such folder", dir.display());
    Ok(files(dir, "npz"))
}

/// The part of the next clip of group `key`: the clips of each group go to
/// validation and held-out in turn.
fn alternate<K: Ord>(seen: &mut std::collections::BTreeMap<K, usize>, key: K) -> Part {
    let n = seen.entry(key).or_insert(0);
    let part = if (*n).is_multiple_of(2) {
        Part::Validation
    } else {
        Part::HeldOut
    };
    *n += 1;
    part
}

/// Penn Action train split (hand-labelled, ~30 fps): within each action the
/// 1st, 3rd, … clip is validation, the 2nd, 4th, … held-out (as
/// `cargo xtask eval concrete --split`).
fn penn(data: &Path, want: Part) -> anyhow::Result<Vec<Clip>> {
    let pa = PennAction::open(data.join(PennAction::TRAIN_FILE))?;
    let mut pos = std::collections::BTreeMap::<String, usize>::new();
    let mut out = Vec::new();
    for (i, c) in pa.clips().iter().enumerate() {
        let part = alternate(&mut pos, c.action.clone());
        if !want.admits(part) {
            continue;
        }
        let frame_px = c.height_px.max(c.width_px) as f64;
        out.extend(clip(
            "penn",
            format!("{}/{}", c.action, c.clip_id),
            part,
            pa.clip(i)?,
            frame_px,
        ));
    }
    Ok(out)
}

/// AIST++ break-dance basic moves, 9 cameras, taken every other frame (30
/// fps, the rate of the videos): moves ch01–ch03 validation, ch04–ch07
/// held-out.
fn aist(data: &Path, want: Part) -> anyhow::Result<Vec<Clip>> {
    let dir = data.join("aistpp_keypoints2d");
    let mut out = Vec::new();
    for f in npz_files(&dir)? {
        let stem = stem(&f);
        let ch: usize = stem
            .rsplit("ch")
            .next()
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        let part = if ch <= 3 {
            Part::Validation
        } else {
            Part::HeldOut
        };
        if !want.admits(part) {
            continue;
        }
        let a = AistPlusPlus::open(&f)?;
        for (v, track) in a.views.iter().enumerate() {
            out.extend(clip(
                "aist",
                format!("ch{ch:02}/c{:02}", v + 1),
                part,
                to_30fps(track)?,
                1920.0,
            ));
        }
    }
    Ok(out)
}

/// The QUVA videos and the golf swing, keypoints of the reference MediaPipe
/// BlazePose mapped to COCO-17: golf, 007, 023 and 090 validation (as in
/// `cargo xtask eval interpolation`), the others held-out.
fn quva(data: &Path, want: Part) -> anyhow::Result<Vec<Clip>> {
    const VALIDATION: [&str; 4] = [
        "golf_swing",
        "007_pommel_practice",
        "023_fitness",
        "090_hoolahoop",
    ];
    let dir = data.join("reference_keypoints");
    let map = SkeletonMap::to_coco17(&Skeleton::blazepose33())?;
    let mut out = Vec::new();
    for f in npz_files(&dir)? {
        let stem = stem(&f);
        let part = if VALIDATION.contains(&stem.as_str()) {
            Part::Validation
        } else {
            Part::HeldOut
        };
        if !want.admits(part) {
            continue;
        }
        let r = MediaPipeReference::open(&f)?;
        let frame_px = r.width_px.max(r.height_px) as f64;
        out.extend(clip("quva", stem, part, map.apply(&r.image)?, frame_px));
    }
    Ok(out)
}

/// MSR Action3D (odd subjects, 15 fps), projected into a 640 × 480 image
/// (pinhole, focal length 525 px, as a Kinect's): within each action the
/// 1st, 3rd, … clip validation, the others held-out.
fn msr(data: &Path, want: Part) -> anyhow::Result<Vec<Clip>> {
    let m = MsrAction3D::open(data.join(MsrAction3D::FILE))?;
    let mut pos = std::collections::BTreeMap::<u32, usize>::new();
    let mut out = Vec::new();
    for (i, c) in m.clips().iter().enumerate() {
        let part = alternate(&mut pos, c.action);
        if !want.admits(part) {
            continue;
        }
        let t3 = m.clip(i)?;
        let (nt, nj) = (t3.n_frames(), t3.n_joints());
        let mut p2 = Array3::<f64>::zeros((nt, nj, 2));
        let mut conf = Array2::<f64>::zeros((nt, nj));
        for t in 0..nt {
            for j in 0..nj {
                let p = t3.point(t, j);
                if p[2] > 0.1 && t3.confidence()[[t, j]] > 0.0 {
                    p2[[t, j, 0]] = 320.0 + 525.0 * p[0] / p[2];
                    p2[[t, j, 1]] = 240.0 - 525.0 * p[1] / p[2];
                    conf[[t, j]] = t3.confidence()[[t, j]];
                }
            }
        }
        let track = Track::new(
            p2,
            Some(conf),
            t3.fps(),
            Units::Pixels,
            t3.skeleton().clone(),
        )?;
        out.extend(clip("msr", c.name.clone(), part, track, 640.0));
    }
    Ok(out)
}

/// The tracks of the named sources (`penn`, `aist`, `quva`, `msr`) in part `want`.
pub fn load(data: &Path, sources: &[String], want: Part) -> anyhow::Result<Vec<Clip>> {
    let mut out = Vec::new();
    for s in sources {
        let clips = match s.as_str() {
            "penn" => penn(data, want),
            "aist" => aist(data, want),
            "quva" => quva(data, want),
            "msr" => msr(data, want),
            other => bail!("unknown source {other} (penn, aist, quva, msr)"),
        }
        .with_context(|| format!("loading {s}"))?;
        eprintln!("{s}: {} tracks ({})", clips.len(), want.as_str());
        out.extend(clips);
    }
    Ok(out)
}
