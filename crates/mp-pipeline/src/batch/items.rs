//! Listing the inputs of a batch: a folder's videos and track files or a
//! text list of paths ([`batch_items`]), their output folder names
//! ([`output_names`]), and the work estimate that orders them when several
//! jobs run at once.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use super::{BatchError, ItemReport, Result, TRACK_EXTENSIONS};
use crate::input::Input;

/// Whether [`batch_items`] lists a file of a folder: a video by its
/// extension ([`crate::Input::VIDEO_EXTENSIONS`]) or a track file
/// ([`TRACK_EXTENSIONS`]), not hidden.
pub fn is_batch_input(path: &Path) -> bool {
    let hidden = path
        .file_name()
        .map(|n| n.to_string_lossy().starts_with('.'))
        .unwrap_or(true);
    !hidden && (Input::is_video(path) || is_track_file(path))
}

fn is_track_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .is_some_and(|e| TRACK_EXTENSIONS.contains(&e.as_str()))
}

/// The inputs of a batch:
///
/// * a folder: its videos and track files (`is_batch_input`), sorted by
///   path; hidden files and subfolders (the output folder among them) are
///   not read;
/// * a video or track file: that one input;
/// * any other file: a text list of inputs, one path per line; blank lines
///   and lines starting with `#` are ignored, relative paths are relative to
///   the list's folder. Whether the listed files exist is checked per item
///   (a missing one fails alone).
pub fn batch_items(path: impl AsRef<Path>) -> Result<Vec<PathBuf>> {
    let path = path.as_ref();
    if path.is_dir() {
        let rd = std::fs::read_dir(path).map_err(|e| BatchError::io("read the folder", path, e))?;
        let mut items = Vec::new();
        for entry in rd {
            let entry = entry.map_err(|e| BatchError::io("read the folder", path, e))?;
            let p = entry.path();
            // Follows links: a linked file counts as a file.
            if p.is_file() && is_batch_input(&p) {
                items.push(p);
            }
        }
        items.sort();
        if items.is_empty() {
            return Err(BatchError::NoItems {
                path: path.to_path_buf(),
            });
        }
        return Ok(items);
    }
    if !path.is_file() {
        return Err(BatchError::Missing {
            path: path.to_path_buf(),
        });
    }
    if Input::is_video(path) || is_track_file(path) {
        return Ok(vec![path.to_path_buf()]);
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| BatchError::io("read the list of inputs", path, e))?;
    let base = path.parent().unwrap_or(Path::new(""));
    let items: Vec<PathBuf> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| {
            let p = Path::new(l);
            if p.is_absolute() {
                p.to_path_buf()
            } else {
                base.join(p)
            }
        })
        .collect();
    if items.is_empty() {
        return Err(BatchError::EmptyList {
            path: path.to_path_buf(),
        });
    }
    Ok(items)
}

/// The output folder names of `items`, in order: the file stem, or
/// `<stem>-<extension>` where stems are equal (compared without case), then
/// a numeric suffix `-2`, `-3`, … where names are still equal. Depends only
/// on the list, so a batch run again maps every input to the same folder.
pub fn output_names(items: &[PathBuf]) -> Vec<String> {
    let stem = |p: &PathBuf| -> String {
        let s = p
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if s.is_empty() || s == "." || s == ".." {
            "item".to_string()
        } else {
            s
        }
    };
    let stems: Vec<String> = items.iter().map(stem).collect();
    let mut seen: HashMap<String, usize> = HashMap::new();
    for s in &stems {
        *seen.entry(s.to_lowercase()).or_default() += 1;
    }
    let mut used: HashSet<String> = HashSet::new();
    used.insert(ItemReport::MANIFEST.to_lowercase());
    let mut names = Vec::with_capacity(items.len());
    for (p, s) in items.iter().zip(&stems) {
        let mut name = s.clone();
        if seen[&s.to_lowercase()] > 1 {
            if let Some(ext) = p.extension() {
                name = format!("{s}-{}", ext.to_string_lossy());
            }
        }
        let mut candidate = name.clone();
        let mut k = 2;
        while used.contains(&candidate.to_lowercase()) {
            candidate = format!("{name}-{k}");
            k += 1;
        }
        used.insert(candidate.to_lowercase());
        names.push(candidate);
    }
    names
}

/// How long an item will take, for ordering: videos (frames, from the
/// container) before track files (bytes), which need no pose model.
pub(super) fn work_estimate(path: &Path, max_frames: Option<usize>) -> (bool, u64) {
    if Input::is_video(path) {
        let frames = mp_pose::probe(path)
            .ok()
            .and_then(|info| {
                info.frame_count
                    .or_else(|| info.duration_s.map(|d| (d * info.fps).round() as usize))
            })
            .unwrap_or(0);
        let frames = max_frames.map_or(frames, |m| frames.min(m));
        (true, frames as u64)
    } else {
        (false, std::fs::metadata(path).map(|m| m.len()).unwrap_or(0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_names_are_unique_and_deterministic() {
        let items: Vec<PathBuf> = ["a/x.npz", "b/x.json", "c/y.mp4", "d/x.npz", "e/x-npz.csv"]
            .iter()
            .map(PathBuf::from)
            .collect();
        let names = output_names(&items);
        assert_eq!(names, vec!["x-npz", "x-json", "y", "x-npz-2", "x-npz-3"]);
        assert_eq!(output_names(&items), names);
        let m = output_names(&[PathBuf::from("manifest.jsonl.csv")]);
        assert_eq!(m, vec!["manifest.jsonl-2"]);
    }
}
