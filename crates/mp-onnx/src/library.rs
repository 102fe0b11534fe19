//! Finding and loading the ONNX Runtime shared library.
//!
//! The library is looked up, in order, at `ORT_DYLIB_PATH` (when set, the
//! only candidate), at `<workspace>/.cache/onnxruntime/lib/libonnxruntime.so`
//! (installed by `cargo xtask setup`), in `.cache/onnxruntime/lib` above the
//! current directory, and next to the executable (or in its `lib/` folder).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use mp_geom::workspace_root;

use crate::error::{OnnxError, Result};

/// File name of the ONNX Runtime library on this platform.
pub const LIBRARY_FILE: &str = if cfg!(target_os = "windows") {
    "onnxruntime.dll"
} else if cfg!(target_os = "macos") {
    "libonnxruntime.dylib"
} else {
    "libonnxruntime.so"
};

/// Where `cargo xtask setup` installs the library, relative to the workspace root.
pub const LIBRARY_DIR_IN_WORKSPACE: &str = ".cache/onnxruntime/lib";

/// Name given to the ONNX Runtime environment (shown in its logs).
const ENVIRONMENT_NAME: &str = "mp";

/// Paths as one comma-separated string for messages.
pub(crate) fn join_paths(paths: &[PathBuf]) -> String {
    if paths.is_empty() {
        return "(no candidate folder)".into();
    }
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Candidate paths of the ONNX Runtime library, in search order.
pub fn library_candidates() -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(p) = std::env::var("ORT_DYLIB_PATH") {
        if !p.is_empty() {
            // An explicit path is the only candidate: a wrong value should be reported, not skipped.
            out.push(PathBuf::from(p));
            return out;
        }
    }
    if let Some(root) = workspace_root() {
        out.push(root.join(LIBRARY_DIR_IN_WORKSPACE).join(LIBRARY_FILE));
    }
    if let Ok(cwd) = std::env::current_dir() {
        for anc in cwd.ancestors() {
            let p = anc.join(LIBRARY_DIR_IN_WORKSPACE).join(LIBRARY_FILE);
            if !out.contains(&p) {
                out.push(p);
            }
        }
    }
    if let Some(dir) = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_path_buf))
    {
        out.push(dir.join(LIBRARY_FILE));
        out.push(dir.join("lib").join(LIBRARY_FILE));
    }
    out
}

/// The ONNX Runtime library that would be loaded, if one exists.
pub fn find_library() -> Result<PathBuf> {
    let cands = library_candidates();
    if let Some(found) = cands.iter().find(|c| c.is_file()) {
        return Ok(found.clone());
    }
    // Only show the most useful candidates (the ancestors list can be long).
    let shown: Vec<PathBuf> = cands.into_iter().take(4).collect();
    Err(OnnxError::RuntimeMissing {
        searched: join_paths(&shown),
    })
}

static ENVIRONMENT: Mutex<Option<ort::environment::Environment>> = Mutex::new(None);

/// Loads ONNX Runtime (once per process) and returns its environment.
///
/// Errors: [`OnnxError::RuntimeMissing`] when no candidate of
/// `library_candidates` exists, [`OnnxError::RuntimeLoad`] when the file
/// exists but cannot be loaded.
pub fn environment() -> Result<ort::environment::Environment> {
    let mut guard = ENVIRONMENT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(env) = guard.as_ref() {
        return Ok(env.clone());
    }
    let path = find_library()?;
    let load_err = |reason: String| OnnxError::RuntimeLoad {
        path: path.clone(),
        reason,
    };
    let builder = ort::init_from(&path).map_err(|e| load_err(e.to_string()))?;
    let env = builder
        .with_name(ENVIRONMENT_NAME)
        .build()
        .map_err(|e| load_err(e.to_string()))?;
    *guard = Some(env.clone());
    Ok(env)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_end_next_to_the_executable() {
        // ORT_DYLIB_PATH is not touched here: other tests of this binary load the library.
        if std::env::var_os("ORT_DYLIB_PATH").is_some() {
            return;
        }
        let cands = library_candidates();
        assert!(cands.iter().all(|c| c.ends_with(LIBRARY_FILE)), "{cands:?}");
        let exe_dir = std::env::current_exe()
            .ok()
            .and_then(|e| e.parent().map(Path::to_path_buf));
        if let Some(dir) = exe_dir {
            assert!(cands.contains(&dir.join(LIBRARY_FILE)), "{cands:?}");
        }
    }

    #[test]
    fn joined_paths_name_every_path() {
        assert_eq!(join_paths(&[]), "(no candidate folder)");
        let s = join_paths(&[PathBuf::from("/a"), PathBuf::from("/b")]);
        assert_eq!(s, "/a, /b");
    }
}
