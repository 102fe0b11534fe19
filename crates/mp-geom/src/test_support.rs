//! Helpers for tests: a test that needs shared
//! data or a model the machine lacks records its skip, to stderr and to the
//! file named by `MP_SKIP_LOG`, and returns early.

use std::path::{Path, PathBuf};

use crate::paths::{data_dir, data_file, footage_file};

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
#[doc(hidden)]
#[macro_export]
macro_rules! data_or_return {
    ($rel:expr) => {
        match $crate::test_support::data_file_or_skip(
            $rel,
            &$crate::test_support::current_test_name(),
        ) {
            Some(p) => p,
            None => return,
        }
    };
}

/// In a test: the shared data folder, or records the skip and `return`s.
#[doc(hidden)]
#[macro_export]
macro_rules! data_dir_or_return {
    () => {
        match $crate::test_support::data_dir_or_skip(&$crate::test_support::current_test_name()) {
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

/// For tests: [`footage_file`](crate::footage_file), or the skip of `test` recorded (as
/// [`skip_test`], needing `footage/{name}`) and `None`.
pub fn footage_file_or_skip(name: &str, test: &str) -> Option<PathBuf> {
    let found = footage_file(name);
    if found.is_none() {
        skip_test(test, &format!("footage/{name} (bash scripts/setup.sh)"));
    }
    found
}
