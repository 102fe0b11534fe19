//! An output folder whose files appear complete or not at all.
//!
//! Every file is written into a hidden staging folder inside the output
//! folder (`.mp-partial-<pid>`) and renamed into place when complete. A
//! cancelled run (its [`CancelToken`], e.g. from a Ctrl-C handler) stops at
//! the next write, and dropping the [`OutputDir`] removes the staging folder;
//! if the program has to exit at once, [`emergency_cleanup`] removes every
//! staging folder of the process while holding the lock that file writes
//! take, so no write can be half done at that moment.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use mp_geom::CancelToken;

use crate::error::{ReportError, Result};

static STAGING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn registry() -> MutexGuard<'static, Vec<PathBuf>> {
    STAGING.lock().unwrap_or_else(|e| e.into_inner())
}

/// `Err(ReportError::Interrupted)` once `cancel` was cancelled.
pub fn check_cancel(cancel: &CancelToken) -> Result<()> {
    if cancel.is_cancelled() {
        Err(ReportError::Interrupted)
    } else {
        Ok(())
    }
}

/// Removes every staging folder of this process and returns the lock that
/// file writes take: hold it until the process exits so that no new file
/// appears.
pub fn emergency_cleanup() -> MutexGuard<'static, Vec<PathBuf>> {
    let mut reg = registry();
    for p in reg.drain(..) {
        let _ = std::fs::remove_dir_all(&p);
    }
    reg
}

/// The list of the files the last run wrote into an output folder
/// ([`OutputDir::replace_previous_run`]).
pub const RUN_FILES: &str = "mp-run-files.txt";

/// Name of the staging folder of this process inside an output folder.
pub(crate) fn staging_name() -> String {
    format!(".mp-partial-{}", std::process::id())
}

/// An output folder written through a staging folder (see the module docs).
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    staging: PathBuf,
    cancel: CancelToken,
}

impl OutputDir {
    /// Creates `dir` (and its parents) and a fresh staging folder in it; the
    /// folder is never cancelled.
    pub fn create(dir: impl AsRef<Path>) -> Result<Self> {
        Self::create_with_cancel(dir, CancelToken::new())
    }

    /// Like [`OutputDir::create`]; once `cancel` is cancelled every write
    /// fails with [`ReportError::Interrupted`].
    pub fn create_with_cancel(dir: impl AsRef<Path>, cancel: CancelToken) -> Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        std::fs::create_dir_all(&dir).map_err(|e| ReportError::io(&dir, e))?;
        let staging = dir.join(staging_name());
        let mut reg = registry();
        check_cancel(&cancel)?;
        if staging.exists() {
            std::fs::remove_dir_all(&staging).map_err(|e| ReportError::io(&staging, e))?;
        }
        std::fs::create_dir(&staging).map_err(|e| ReportError::io(&staging, e))?;
        reg.push(staging.clone());
        Ok(OutputDir {
            dir,
            staging,
            cancel,
        })
    }

    /// The token that cancels this folder's writes.
    pub fn cancel_token(&self) -> &CancelToken {
        &self.cancel
    }

    /// The output folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Final path of `rel` inside the output folder.
    pub fn path(&self, rel: &str) -> PathBuf {
        self.dir.join(rel)
    }

    /// A path in the staging folder for a file that another program writes
    /// (e.g. an encoder); move it into place with [`OutputDir::commit`].
    pub fn staging_file(&self, name: &str) -> PathBuf {
        self.staging.join(name.replace(['/', '\\'], "__"))
    }

    fn check_rel(rel: &str) -> Result<()> {
        let p = Path::new(rel);
        if rel.is_empty()
            || p.is_absolute()
            || p.components()
                .any(|c| !matches!(c, std::path::Component::Normal(_)))
        {
            return Err(ReportError::param(
                "file name",
                format!("`{rel}` is not a plain relative path"),
            ));
        }
        Ok(())
    }

    /// Writes `bytes` to `rel` (a relative path; folders are created) through
    /// the staging folder. Returns the final path.
    pub fn write(&self, rel: &str, bytes: &[u8]) -> Result<PathBuf> {
        use std::io::Write;
        Self::check_rel(rel)?;
        let _lock = registry();
        check_cancel(&self.cancel)?;
        let tmp = self.staging_file(rel);
        let mut f = std::fs::File::create(&tmp).map_err(|e| ReportError::io(&tmp, e))?;
        f.write_all(bytes).map_err(|e| ReportError::io(&tmp, e))?;
        f.sync_all().map_err(|e| ReportError::io(&tmp, e))?;
        drop(f);
        self.rename_into_place(&tmp, rel)
    }

    /// Moves a finished file from the staging folder to `rel`.
    pub fn commit(&self, staged: &Path, rel: &str) -> Result<PathBuf> {
        Self::check_rel(rel)?;
        let _lock = registry();
        check_cancel(&self.cancel)?;
        self.rename_into_place(staged, rel)
    }

    /// Records `files` (relative paths) as what this run wrote, in the
    /// list [`RUN_FILES`], and removes the files the previous run into the
    /// same folder listed there and this one did not write (a person seen
    /// then but not now, plots of other joints, an overlay of an earlier
    /// video), with the folders they leave empty; files the folder holds
    /// besides are never touched. Returns the removed files.
    pub fn replace_previous_run(&self, files: &[String]) -> Result<Vec<String>> {
        let list_path = self.dir.join(RUN_FILES);
        let previous: Vec<String> = std::fs::read_to_string(&list_path)
            .map(|t| t.lines().map(str::to_string).collect())
            .unwrap_or_default();
        let mut text = files.join("\n");
        text.push('\n');
        self.write(RUN_FILES, text.as_bytes())?;
        let keep: std::collections::HashSet<&str> = files.iter().map(String::as_str).collect();
        let mut removed = Vec::new();
        for rel in previous {
            if rel.is_empty() || keep.contains(rel.as_str()) || Self::check_rel(&rel).is_err() {
                continue;
            }
            let p = self.dir.join(&rel);
            if p.is_file() && std::fs::remove_file(&p).is_ok() {
                // Folders the file leaves empty go too (never the output folder).
                let mut dir = p.parent();
                while let Some(d) = dir.filter(|d| *d != self.dir && d.starts_with(&self.dir)) {
                    if std::fs::remove_dir(d).is_err() {
                        break;
                    }
                    dir = d.parent();
                }
                removed.push(rel);
            }
        }
        Ok(removed)
    }

    fn rename_into_place(&self, tmp: &Path, rel: &str) -> Result<PathBuf> {
        let dst = self.dir.join(rel);
        if let Some(parent) = dst.parent() {
            std::fs::create_dir_all(parent).map_err(|e| ReportError::io(parent, e))?;
        }
        std::fs::rename(tmp, &dst).map_err(|e| ReportError::io(&dst, e))?;
        Ok(dst)
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        let mut reg = registry();
        let _ = std::fs::remove_dir_all(&self.staging);
        reg.retain(|p| p != &self.staging);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_appear_complete_and_staging_goes_away() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("run");
        {
            let o = OutputDir::create(&out).unwrap();
            let p = o.write("plots/a.svg", b"<svg/>").unwrap();
            assert_eq!(std::fs::read(&p).unwrap(), b"<svg/>");
            assert!(out.join(staging_name()).is_dir());
            assert!(o.write("../escape.txt", b"x").is_err());
            assert!(o.write("/abs.txt", b"x").is_err());
            let staged = o.staging_file("video.mp4");
            std::fs::write(&staged, b"v").unwrap();
            o.commit(&staged, "video.mp4").unwrap();
        }
        assert!(!out.join(staging_name()).exists());
        let mut names: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, vec!["plots", "video.mp4"]);
    }

    #[test]
    fn a_new_run_removes_what_the_last_one_wrote_and_it_did_not() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("run");
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join("notes.md"), b"mine").unwrap();
        let first = ["a.txt", "people/3/program.txt", "overlay.mp4"].map(String::from);
        {
            let o = OutputDir::create(&out).unwrap();
            for f in &first {
                o.write(f, b"1").unwrap();
            }
            assert!(o.replace_previous_run(&first).unwrap().is_empty());
        }
        let second = ["a.txt".to_string()];
        let o = OutputDir::create(&out).unwrap();
        o.write("a.txt", b"2").unwrap();
        let mut removed = o.replace_previous_run(&second).unwrap();
        removed.sort();
        assert_eq!(removed, vec!["overlay.mp4", "people/3/program.txt"]);
        assert!(!out.join("people").exists(), "the emptied folders go");
        assert_eq!(std::fs::read(out.join("a.txt")).unwrap(), b"2");
        assert_eq!(std::fs::read(out.join("notes.md")).unwrap(), b"mine");
        assert_eq!(
            std::fs::read_to_string(out.join(RUN_FILES)).unwrap(),
            "a.txt\n"
        );
    }

    #[test]
    fn a_cancelled_folder_writes_nothing_and_others_go_on() {
        let tmp = tempfile::tempdir().unwrap();
        let token = CancelToken::new();
        let a = OutputDir::create_with_cancel(tmp.path().join("a"), token.clone()).unwrap();
        let b = OutputDir::create(tmp.path().join("b")).unwrap();
        a.write("x.txt", b"1").unwrap();
        token.cancel();
        assert!(matches!(
            a.write("y.txt", b"2"),
            Err(ReportError::Interrupted)
        ));
        b.write("y.txt", b"2").unwrap();
        drop(a);
        assert!(!tmp.path().join("a/y.txt").exists());
        assert!(tmp.path().join("a/x.txt").exists() && tmp.path().join("b/y.txt").exists());
        assert!(OutputDir::create_with_cancel(tmp.path().join("c"), token).is_err());
    }
}
