//! Where shared data lives: `MP_DATA_DIR` / `MP_SHARED_DIR`, or a `shared/`
//! folder beside the workspace (found by walking up from the current
//! directory and from the workspace root recorded at build time).
//! `MP_NO_SHARED_DATA=1` hides the whole shared folder, its data sets and its
//! converted models (as on a clone without it); tests then skip through
//! [`data_file_or_skip`] or [`skip_test`], logging to `MP_SKIP_LOG`.

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

/// For tests: the shared data file `rel` when present; otherwise prints
/// `skipped (no shared data): {test} needs {rel}` to stderr, appends
/// `{test}\t{rel}` to the file named by `MP_SKIP_LOG` (when set; write errors
/// are ignored) and returns `None`, so the caller can return early.
pub fn data_file_or_skip(rel: impl AsRef<Path>, test: &str) -> Option<PathBuf> {
    let rel = rel.as_ref();
    if let Some(p) = data_file(rel) {
        return Some(p);
    }
    record_skip(rel, test);
    None
}

/// For tests: the shared data folder when present, else records the skip of
/// `test` (see [`data_file_or_skip`]) and returns `None`.
pub fn data_dir_or_skip(test: &str) -> Option<PathBuf> {
    if let Some(d) = data_dir() {
        return Some(d);
    }
    record_skip(Path::new("."), test);
    None
}

/// The running test's name: libtest names each test's thread after it.
pub fn current_test_name() -> String {
    std::thread::current()
        .name()
        .unwrap_or("unnamed test")
        .to_string()
}

/// In a test: the shared data file `rel` as a `PathBuf`, or, when it is
/// missing, records the skip ([`data_file_or_skip`], named after the running
/// test) and `return`s from the enclosing test.
#[macro_export]
macro_rules! data_or_return {
    ($rel:expr) => {
        match $crate::paths::data_file_or_skip($rel, &$crate::paths::current_test_name()) {
            Some(p) => p,
            None => return,
        }
    };
}

/// In a test: the shared data folder, or records the skip and `return`s.
#[macro_export]
macro_rules! data_dir_or_return {
    () => {
        match $crate::paths::data_dir_or_skip(&$crate::paths::current_test_name()) {
            Some(p) => p,
            None => return,
        }
    };
}

fn record_skip(rel: &Path, test: &str) {
    skip_test(test, &rel.display().to_string());
}

/// For tests: records that `test` is skipped because `needs` (a shared data
/// file, a model file) is missing: prints `skipped: {test} needs {needs}` to
/// stderr and appends `{test}\t{needs}` to the file named by `MP_SKIP_LOG`
/// (when set; write errors are ignored).
pub fn skip_test(test: &str, needs: &str) {
    let rel = needs;
    eprintln!("skipped: {test} needs {rel}");
    if let Some(log) = std::env::var_os("MP_SKIP_LOG").filter(|s| !s.is_empty()) {
        use std::io::Write;
        if let Ok(mut f) = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(log)
        {
            // One write per line (an O_APPEND write is atomic), so lines of
            // tests skipping in parallel never interleave.
            let _ = f.write_all(format!("{test}\t{rel}\n").as_bytes());
        }
    }
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

/// For tests: [`footage_file`], or the skip of `test` recorded (as
/// [`skip_test`], needing `footage/{name}`) and `None`.
pub fn footage_file_or_skip(name: &str, test: &str) -> Option<PathBuf> {
    let found = footage_file(name);
    if found.is_none() {
        skip_test(test, &format!("footage/{name} (bash scripts/setup.sh)"));
    }
    found
}
