//! The real recordings that synthetic repetition cases are cut from
//! ([`crate::synth_reps`]): every keypoint source of the shared data folder,
//! as clips where a person is found.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use mp_geom::Track;
use mp_geom::{AistPlusPlus, MediaPipeReference, MsrAction3D, PennAction};
#[cfg(test)]
use mp_geom::{Skeleton, Units};
use ndarray::{Array2, Array3};

use crate::synth_reps::{Source, SourceClip};

/// Clips shorter than this (seconds) are dropped: no 0.5 s cycle with
/// frames around it fits.
const MIN_CLIP_S: f64 = 0.8;

/// A clip from positions and confidence: the joints seen (confidence > 0) in
/// at least half of the frames, and the median diagonal of their bounding
/// box as body scale. `None` when nothing is seen.
pub fn make_clip(name: &str, pos: Array3<f64>, conf: Array2<f64>, fps: f64) -> Option<SourceClip> {
    let (t, j, d) = pos.dim();
    let joints: Vec<usize> = (0..j)
        .filter(|&jj| (0..t).filter(|&ti| conf[[ti, jj]] > 0.0).count() * 2 >= t)
        .collect();
    let mut diags: Vec<f64> = (0..t)
        .filter_map(|ti| {
            let seen: Vec<usize> = joints
                .iter()
                .copied()
                .filter(|&jj| conf[[ti, jj]] > 0.0)
                .collect();
            (seen.len() >= 2).then(|| {
                (0..d)
                    .map(|k| {
                        let v = seen.iter().map(|&jj| pos[[ti, jj, k]]);
                        let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                            (a.min(x), b.max(x))
                        });
                        (hi - lo).powi(2)
                    })
                    .sum::<f64>()
                    .sqrt()
            })
        })
        .collect();
    if diags.is_empty() || joints.is_empty() {
        return None;
    }
    diags.sort_by(f64::total_cmp);
    let scale = diags[diags.len() / 2];
    (scale > 0.0).then(|| SourceClip {
        name: name.to_string(),
        pos,
        conf,
        fps,
        scale,
        joints,
    })
}

/// The runs of frames of a track where at least half of the joints are seen,
/// each at least `MIN_CLIP_S` long, gaps filled, as clips named
/// `name` (`name@start` for a run that does not start at frame 0).
pub fn clips_of(name: &str, track: &Track) -> Vec<SourceClip> {
    let (t, j) = (track.n_frames(), track.n_joints());
    let conf = track.confidence();
    let ok: Vec<bool> = (0..t)
        .map(|ti| (0..j).filter(|&jj| conf[[ti, jj]] > 0.0).count() * 2 >= j)
        .collect();
    let min_len = (MIN_CLIP_S * track.fps()).ceil() as usize;
    let mut out = Vec::new();
    let mut ti = 0;
    while ti < t {
        if !ok[ti] {
            ti += 1;
            continue;
        }
        let start = ti;
        while ti < t && ok[ti] {
            ti += 1;
        }
        if ti - start < min_len.max(4) {
            continue;
        }
        let Ok(mut run) = track.slice_frames(start, ti) else {
            continue;
        };
        run.fill_missing();
        let label = if start == 0 {
            name.to_string()
        } else {
            format!("{name}@{start}")
        };
        if let Some(c) = make_clip(
            &label,
            run.positions().to_owned(),
            run.confidence().to_owned(),
            track.fps(),
        ) {
            out.push(c);
        }
    }
    out
}

/// Every k-th frame of a track recorded at k × 30 fps (AIST++ 60 fps, CMU
/// BVH 120 fps), so that cases run at 30 fps like the videos people film.
pub(crate) fn to_30fps(t: &Track) -> std::result::Result<Track, mp_geom::GeomError> {
    t.subsample(((t.fps() / 30.0).round() as usize).max(1))
}

/// Files of `dir` with extension `ext`, sorted.
pub(crate) fn files(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    v.retain(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)));
    v.sort();
    v
}

/// A path's file name without its extension.
pub(crate) fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default()
}

/// Adds a track's clips to `src`, the first track fixing the skeleton and
/// units; a track of another joint count or units is skipped.
fn add(src: &mut Option<Source>, source: &str, name: &str, track: &Track) {
    let s = src.get_or_insert_with(|| Source {
        name: source.to_string(),
        units: track.units(),
        skeleton: track.skeleton().clone(),
        clips: Vec::new(),
    });
    if track.n_joints() != s.skeleton.len() || track.units() != s.units {
        eprintln!(
            "{source}: {name} skipped ({} joints, {} — the source has {} joints, {})",
            track.n_joints(),
            track.units().as_str(),
            s.skeleton.len(),
            s.units.as_str()
        );
        return;
    }
    s.clips.extend(clips_of(name, track));
}

/// Every keypoint source of the data folder `data` that is present: Penn
/// Action, AIST++ (nine views, 30 fps), CMU salsa BVH (30 fps), MSR Action3D
/// and the MediaPipe reference keypoints of real exercise videos. A missing
/// source is reported and left out; none at all is an error.
pub fn load_sources(data: &Path) -> anyhow::Result<Vec<Source>> {
    let mut out = Vec::new();
    let mut missing = Vec::new();
    let penn_file = data.join(PennAction::TRAIN_FILE);
    if penn_file.is_file() {
        let penn = PennAction::open(&penn_file)
            .with_context(|| format!("reading {}", penn_file.display()))?;
        let mut src = None;
        for (i, c) in penn.clips().iter().enumerate() {
            add(
                &mut src,
                "penn_action",
                &format!("{}_{}", c.clip_id, c.action),
                &penn.clip(i)?,
            );
        }
        out.extend(src);
    } else {
        missing.push(penn_file);
    }
    let aist_dir = data.join("aistpp_keypoints2d");
    let mut src = None;
    for f in files(&aist_dir, "npz") {
        let a = AistPlusPlus::open(&f).with_context(|| format!("reading {}", f.display()))?;
        for (v, view) in a.views.iter().enumerate() {
            add(
                &mut src,
                "aistpp",
                &format!("{}_v{v}", stem(&f)),
                &to_30fps(view)?,
            );
        }
    }
    if src.is_none() {
        missing.push(aist_dir);
    }
    out.extend(src);
    let bvh_dir = data.join("cmu_salsa_bvh");
    let mut src = None;
    for f in files(&bvh_dir, "bvh") {
        let t = mp_geom::read_track(&f).with_context(|| format!("reading {}", f.display()))?;
        add(&mut src, "cmu_salsa", &stem(&f), &to_30fps(&t)?);
    }
    if src.is_none() {
        missing.push(bvh_dir);
    }
    out.extend(src);
    let msr_dir = data.join("msr_action3d");
    if !files(&msr_dir, "npz").is_empty() {
        let msr = MsrAction3D::open_path(&msr_dir)
            .with_context(|| format!("reading {}", msr_dir.display()))?;
        let mut src = None;
        for (i, c) in msr.clips().iter().enumerate() {
            add(&mut src, "msr_action3d", &c.name, &msr.clip(i)?);
        }
        out.extend(src);
    } else {
        missing.push(msr_dir);
    }
    let ref_dir = data.join("reference_keypoints");
    let mut src = None;
    for f in files(&ref_dir, "npz") {
        let r = MediaPipeReference::open(&f).with_context(|| format!("reading {}", f.display()))?;
        add(&mut src, "reference_keypoints", &stem(&f), &r.image);
    }
    if src.is_none() {
        missing.push(ref_dir);
    }
    out.extend(src);
    for m in &missing {
        eprintln!(
            "warning: {} not found: that source is left out",
            m.display()
        );
    }
    out.retain(|s| !s.clips.is_empty());
    if out.is_empty() {
        bail!("no keypoint source found in {} (expected penn_action/, aistpp_keypoints2d/, cmu_salsa_bvh/, msr_action3d/, reference_keypoints/)", data.display());
    }
    Ok(out)
}

/// A source of clips made of given arrays (tests).
#[cfg(test)]
pub fn source_of(name: &str, clips: Vec<SourceClip>, units: Units, skeleton: Skeleton) -> Source {
    Source {
        name: name.into(),
        units,
        skeleton,
        clips,
    }
}
