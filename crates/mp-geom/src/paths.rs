//! Where shared data lives: `MP_DATA_DIR` / `MP_SHARED_DIR`, or a `shared/`
//! folder beside the workspace (found by walking up from the current
//! directory and from the workspace root recorded at build time).

use std::path::{Path, PathBuf};

fn candidates() -> Vec<PathBuf> {
    let mut starts = Vec::new();
    if let Ok(cwd) = std::env::current_dir() {
        starts.push(cwd);
    }
    if let Some(root) = option_env!("MP_WORKSPACE_ROOT") {
        if !root.is_empty() {
            starts.push(PathBuf::from(root));
        }
    }
    starts.push(PathBuf::from(env!("CARGO_MANIFEST_DIR")));
    let mut out = Vec::new();
    for s in starts {
        for anc in s.ancestors() {
            out.push(anc.join("shared"));
            out.push(anc.join("../shared"));
        }
    }
    out
}

/// The shared folder (`…/shared`, holding `data/`, `models/`, `docs/`), if any.
///
/// `MP_SHARED_DIR` wins when set.
pub fn shared_dir() -> Option<PathBuf> {
    if let Ok(p) = std::env::var("MP_SHARED_DIR") {
        let p = PathBuf::from(p);
        return p.is_dir().then_some(p);
    }
    candidates()
        .into_iter()
        .find(|p| p.join("data").is_dir() || p.join("models").is_dir())
        .map(|p| p.canonicalize().unwrap_or(p))
}

/// The shared data folder: `MP_DATA_DIR` when set, else `shared_dir()/data`.
pub fn data_dir() -> Option<PathBuf> {
    if let Ok(p) = std::env::var("MP_DATA_DIR") {
        let p = PathBuf::from(p);
        return p.is_dir().then_some(p);
    }
    shared_dir().map(|s| s.join("data")).filter(|p| p.is_dir())
}

/// A file under the shared data folder, if that file exists.
pub fn data_file(rel: impl AsRef<Path>) -> Option<PathBuf> {
    data_dir().map(|d| d.join(rel)).filter(|p| p.exists())
}

/// The workspace root recorded at build time, when built inside the workspace.
pub fn workspace_root() -> Option<PathBuf> {
    option_env!("MP_WORKSPACE_ROOT")
        .filter(|s| !s.is_empty())
        .map(PathBuf::from)
}
