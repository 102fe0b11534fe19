//! Loading motions for the grammar pipeline: tracks of any format that
//! `mp_geom::io` reads, BVH files kept alongside their track (so that
//! synthesis can write BVH), and folders of BVH takes joined into one motion.

use std::ops::Range;
use std::path::{Path, PathBuf};

use mp_geom::io::bvh::{Bvh, BvhTrackParams};
use mp_geom::Track;
use ndarray::{concatenate, Axis};

use crate::error::{GrammarError, Result};

/// A motion read from a file: its track and, for BVH input, the BVH itself.
#[derive(Debug, Clone)]
pub struct Motion {
    /// Joint positions (or features).
    pub track: Track,
    /// The BVH, when the file was one.
    pub bvh: Option<Bvh>,
    /// Where it was read from.
    pub path: PathBuf,
}

fn is_bvh(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"))
}

/// Reads a motion: BVH files keep their [`Bvh`]; everything else goes
/// through [`mp_geom::io::read_track`].
pub fn read_motion(path: impl AsRef<Path>) -> Result<Motion> {
    let path = path.as_ref();
    if is_bvh(path) {
        let bvh = Bvh::read(path)?;
        let track = bvh.to_track(&BvhTrackParams::default())?;
        Ok(Motion {
            track,
            bvh: Some(bvh),
            path: path.to_path_buf(),
        })
    } else {
        Ok(Motion {
            track: mp_geom::io::read_track(path)?,
            bvh: None,
            path: path.to_path_buf(),
        })
    }
}

/// Joins tracks in time. They need the same joints, dimensions, units and
/// frame rate; the skeleton of the first is kept.
pub fn concat_tracks(tracks: &[Track]) -> Result<Track> {
    let first = tracks
        .first()
        .ok_or_else(|| GrammarError::Empty("no track to join".into()))?;
    for (i, t) in tracks.iter().enumerate().skip(1) {
        if t.n_joints() != first.n_joints()
            || t.dims() != first.dims()
            || t.units() != first.units()
            || (t.fps() - first.fps()).abs() > 1e-9 * first.fps()
        {
            return Err(GrammarError::Invalid(format!(
                "track {i} ({} joints × {} dims, {} fps, {}) cannot follow track 0 \
                 ({} joints × {} dims, {} fps, {})",
                t.n_joints(),
                t.dims(),
                t.fps(),
                t.units().as_str(),
                first.n_joints(),
                first.dims(),
                first.fps(),
                first.units().as_str()
            )));
        }
    }
    let pos: Vec<_> = tracks.iter().map(|t| t.positions()).collect();
    let conf: Vec<_> = tracks.iter().map(|t| t.confidence()).collect();
    let pos = concatenate(Axis(0), &pos).map_err(|e| GrammarError::Invalid(e.to_string()))?;
    let conf = concatenate(Axis(0), &conf).map_err(|e| GrammarError::Invalid(e.to_string()))?;
    Ok(Track::new(
        pos,
        Some(conf),
        first.fps(),
        first.units(),
        first.skeleton().clone(),
    )?)
}

/// Frame range of each take in a joined track.
pub type TakeRanges = Vec<(PathBuf, Range<usize>)>;

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
/// `max_frames` frames (see [`bvh_folder_track`]).
pub fn salsa_track(dir: impl AsRef<Path>, max_frames: usize) -> Result<Track> {
    Ok(bvh_folder_track(dir, max_frames)?.0)
}
