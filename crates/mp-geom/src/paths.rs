//! Where shared data lives: `MP_DATA_DIR` / `MP_SHARED_DIR`, or a `shared/`
//! folder beside the workspace (found by walking up from the current
//! directory and from the workspace root recorded at build time).
//! `MP_NO_SHARED_DATA=1` hides the whole shared folder, its data sets and its
//! converted models (as on a clone without it); tests then skip through the
//! helpers of `test_support`, logging to `MP_SKIP_LOG`.

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
/// `MP_SHARED_DIR` wins when set; `MP_NO_SHARED_DATA` hides it.
pub fn shared_dir() -> Option<PathBuf> {
    if shared_data_disabled() {
        return None;
    }
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
    if shared_data_disabled() {
        return None;
    }
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

/// True when `MP_NO_SHARED_DATA` is set to a non-empty value other than `0`:
/// [`data_dir`] (and so [`data_file`]) then reports no data sets, so a test
/// run can behave as on a clone without `../shared/data`.
pub(crate) fn shared_data_disabled() -> bool {
    std::env::var("MP_NO_SHARED_DATA").is_ok_and(|v| !v.is_empty() && v != "0")
}

/// The workspace root recorded at build time, when built inside the workspace.
pub fn workspace_root() -> Option<PathBuf> {
    option_env!("MP_WORKSPACE_ROOT")
        .filter(|s| !s.is_empty())
        .map(PathBuf::from)
}

/// Where `scripts/setup.sh` puts public test footage that packages ship
/// (under the workspace root): `MP_FOOTAGE_DIR` when set.
pub(crate) const FOOTAGE_DIR_IN_WORKSPACE: &str = ".cache/footage";

/// A public test video fetched by the set-up (`.cache/footage/{name}` or
/// `MP_FOOTAGE_DIR/{name}`), if present.
pub fn footage_file(name: &str) -> Option<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(d) = std::env::var_os("MP_FOOTAGE_DIR").filter(|s| !s.is_empty()) {
        dirs.push(PathBuf::from(d));
    }
    if let Some(root) = workspace_root() {
        dirs.push(root.join(FOOTAGE_DIR_IN_WORKSPACE));
    }
    if let Ok(cwd) = std::env::current_dir() {
        dirs.extend(cwd.ancestors().map(|a| a.join(FOOTAGE_DIR_IN_WORKSPACE)));
    }
    dirs.into_iter().map(|d| d.join(name)).find(|p| p.is_file())
}
