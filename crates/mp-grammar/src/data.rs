//! Loading motions for the grammar pipeline: tracks of any format that
//! `mp_geom::io` reads, BVH files kept alongside their track (so that
//! synthesis can write BVH), and folders of BVH takes joined into one motion.

use std::ops::Range;
use std::path::{Path, PathBuf};

use mp_geom::Track;
use mp_geom::{Bvh, BvhTrackParams};

use crate::error::{GrammarError, Result};

/// A motion read from one or more files: its track and, for BVH input, the
/// BVH itself (so that synthesis can write BVH).
#[derive(Debug, Clone)]
pub struct Motion {
    /// Joint positions (or features).
    pub track: Track,
    /// The BVH, when the input is BVH.
    pub bvh: Option<Bvh>,
    /// The files it was read from, joined in this order.
    pub paths: Vec<PathBuf>,
    /// Every `frame_step`-th frame of the files was kept.
    pub frame_step: usize,
}

fn is_bvh(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"))
}

/// Every `step`-th frame of a BVH, starting at frame 0 (frame time × step).
pub fn subsample_bvh(bvh: &Bvh, step: usize) -> Result<Bvh> {
    if step == 0 {
        return Err(GrammarError::param("frame_step", "must be ≥ 1"));
    }
    if step == 1 {
        return Ok(bvh.clone());
    }
    let motion = bvh.motion().slice(ndarray::s![..;step, ..]).to_owned();
    Ok(Bvh::from_parts(
        bvh.joints().to_vec(),
        bvh.frame_time_s() * step as f64,
        motion,
    )?)
}

/// Frame step of [`read_motions`] when none is chosen: 1, every frame is kept.
pub const DEFAULT_FRAME_STEP: usize = 1;

/// Reads files (or one folder of `.bvh` files, sorted by name), keeps every
/// `frame_step`-th frame of each and joins them in time. BVH files must
/// share one hierarchy (joint names, parents, channels; the offsets of the
/// first are kept) and are joined at the channel level, so the result keeps
/// its BVH; other tracks are joined with [`concat_tracks`].
pub fn read_motions(paths: &[PathBuf], frame_step: usize) -> Result<Motion> {
    if frame_step == 0 {
        return Err(GrammarError::param("frame_step", "must be ≥ 1"));
    }
    let files: Vec<PathBuf> = match paths {
        [one] if one.is_dir() => bvh_files(one)?,
        [] => return Err(GrammarError::Empty("no motion file given".into())),
        many => many.to_vec(),
    };
    if files.iter().all(|f| is_bvh(f)) {
        let mut joined: Option<Bvh> = None;
        for f in &files {
            let b = subsample_bvh(&Bvh::read(f)?, frame_step)?;
            joined = Some(match joined {
                None => b,
                Some(j) => j.concat(&b).map_err(|e| {
                    GrammarError::Invalid(format!(
                        "{}: cannot follow {}: {e}",
                        f.display(),
                        files[0].display()
                    ))
                })?,
            });
        }
        let bvh = joined.ok_or_else(|| GrammarError::Empty("no motion file given".into()))?;
        let track = bvh.to_track(&BvhTrackParams::default())?;
        Ok(Motion {
            track,
            bvh: Some(bvh),
            paths: files,
            frame_step,
        })
    } else {
        let mut tracks = Vec::with_capacity(files.len());
        for f in &files {
            let t = mp_geom::read_track(f)?;
            tracks.push(if frame_step > 1 {
                t.subsample(frame_step)?
            } else {
                t
            });
        }
        Ok(Motion {
            track: concat_tracks(&tracks)?,
            bvh: None,
            paths: files,
            frame_step,
        })
    }
}

/// Joins tracks in time. They need the same joints, dimensions, units and
/// frame rate; the skeleton of the first is kept.
pub fn concat_tracks(tracks: &[Track]) -> Result<Track> {
    let parts: Vec<&Track> = tracks.iter().collect();
    Ok(Track::concat(&parts)?)
}

/// Frame range of each take in a joined track.
pub(crate) type TakeRanges = Vec<(PathBuf, Range<usize>)>;

/// The `.bvh` files of a folder, sorted by name.
pub fn bvh_files(dir: impl AsRef<Path>) -> Result<Vec<PathBuf>> {
    let dir = dir.as_ref();
    let rd = std::fs::read_dir(dir).map_err(|e| GrammarError::Io {
        path: dir.to_path_buf(),
        source: e,
    })?;
    let mut files: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| is_bvh(p))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(GrammarError::Empty(format!(
            "{}: no .bvh file",
            dir.display()
        )));
    }
    Ok(files)
}

/// Joins the BVH takes of a folder (sorted by name; each through its own
/// forward kinematics) into one track of at most `max_frames` frames
/// (`usize::MAX` = all). Returns the track and the frame range of each take
/// used.
pub fn bvh_folder_track(dir: impl AsRef<Path>, max_frames: usize) -> Result<(Track, TakeRanges)> {
    let mut tracks = Vec::new();
    let mut ranges = Vec::new();
    let mut total = 0;
    for f in bvh_files(dir)? {
        if total >= max_frames {
            break;
        }
        let t = Bvh::read(&f)?.to_track(&BvhTrackParams::default())?;
        let take = t.n_frames().min(max_frames - total);
        let t = if take < t.n_frames() {
            t.slice_frames(0, take)?
        } else {
            t
        };
        ranges.push((f, total..total + take));
        total += take;
        tracks.push(t);
    }
    Ok((concat_tracks(&tracks)?, ranges))
}

/// The CMU salsa takes of a folder joined into one track of at most
/// `max_frames` frames (see `bvh_folder_track`).
pub fn salsa_track(dir: impl AsRef<Path>, max_frames: usize) -> Result<Track> {
    Ok(bvh_folder_track(dir, max_frames)?.0)
}
