//! The one atomic file writer of the workspace.
//!
//! [`write_atomic`] writes into a temporary file (`.mp-tmp-*`) in the
//! destination folder, syncs it and renames it into place, so a reader sees
//! the old file or the new one, never part of one. The temporary files in
//! flight are registered: a process that must exit at once (a second Ctrl-C)
//! calls [`abandon_partial_writes`], which removes them while holding the
//! lock that renames take, so nothing new appears after it.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use crate::error::{GeomError, Result};

static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn in_flight() -> MutexGuard<'static, Vec<PathBuf>> {
    IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner())
}

/// Writes `bytes` to `path` through a temporary file in the same folder that
/// is renamed into place (see the module docs).
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    let path = path.as_ref();
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut tmp = {
        let mut reg = in_flight();
        let mut builder = tempfile::Builder::new();
        builder.prefix(".mp-tmp-");
        // An ordinary file's permissions (0666 less the umask, as
        // `File::create` gives), not the temporary file's private 0600,
        // which the rename would keep.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let tmp = builder
            .tempfile_in(&dir)
            .map_err(|e| GeomError::io(&dir, e))?;
        reg.push(tmp.path().to_path_buf());
        tmp
    };
    let tmp_path = tmp.path().to_path_buf();
    let written = tmp
        .write_all(bytes)
        .and_then(|()| tmp.as_file().sync_all())
        .map_err(|e| GeomError::io(path, e));
    let mut reg = in_flight();
    reg.retain(|p| p != &tmp_path);
    written?;
    tmp.persist(path)
        .map_err(|e| GeomError::io(path, e.error))?;
    Ok(())
}

/// A file that another writer fills (e.g. an encoder process) at a
/// temporary path in the target's folder, registered like the temporary
/// files of [`write_atomic`]: [`PartialFile::commit`] renames it onto the
/// target; dropped uncommitted, or abandoned at an interruption, it is
/// removed and the target is left as it was.
#[derive(Debug)]
pub struct PartialFile {
    temp: PathBuf,
    target: PathBuf,
    committed: bool,
}

impl PartialFile {
    /// Registers a temporary path beside `target` (same extension, so tools
    /// that pick a format by extension keep working). The folder must exist.
    pub fn new(target: impl AsRef<Path>) -> Result<Self> {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let target = target.as_ref().to_path_buf();
        let dir = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !dir.is_dir() {
            return Err(GeomError::io(
                &dir,
                std::io::Error::new(std::io::ErrorKind::NotFound, "no such folder"),
            ));
        }
        let ext = target
            .extension()
            .map(|e| format!(".{}", e.to_string_lossy()))
            .unwrap_or_default();
        let temp = dir.join(format!(
            ".mp-tmp-{}-{}{ext}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        in_flight().push(temp.clone());
        Ok(PartialFile {
            temp,
            target,
            committed: false,
        })
    }

    /// The temporary path to write to.
    pub fn path(&self) -> &Path {
        &self.temp
    }

    /// The final path.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Renames the finished file onto the target.
    pub fn commit(mut self) -> Result<()> {
        let mut reg = in_flight();
        reg.retain(|p| p != &self.temp);
        std::fs::rename(&self.temp, &self.target).map_err(|e| GeomError::io(&self.target, e))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for PartialFile {
    fn drop(&mut self) {
        if !self.committed {
            let mut reg = in_flight();
            reg.retain(|p| p != &self.temp);
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

/// Removes every temporary file that [`write_atomic`] has not yet renamed
/// into place and returns the lock that renames take: hold it until the
/// process exits, so that no output appears after this call.
pub fn abandon_partial_writes() -> MutexGuard<'static, Vec<PathBuf>> {
    let mut reg = in_flight();
    for p in reg.drain(..) {
        let _ = std::fs::remove_file(&p);
    }
    reg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"old").unwrap();
        write_atomic(&p, b"new").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        assert!(in_flight().is_empty());
    }

    #[cfg(unix)]
    #[test]
    fn written_files_have_ordinary_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain.txt");
        std::fs::File::create(&plain).unwrap();
        let atomic = dir.path().join("atomic.txt");
        write_atomic(&atomic, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        // As `File::create` (0666 less the umask), not a temporary file's 0600.
        assert_eq!(mode(&atomic), mode(&plain));
    }

    #[test]
    fn a_partial_file_is_renamed_on_commit_and_removed_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("v.mp4");
        std::fs::write(&target, b"old").unwrap();
        let p = PartialFile::new(&target).unwrap();
        assert!(p.path().extension().is_some_and(|e| e == "mp4"));
        std::fs::write(p.path(), b"half").unwrap();
        drop(p);
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let p = PartialFile::new(&target).unwrap();
        std::fs::write(p.path(), b"new").unwrap();
        p.commit().unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_missing_folder_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/folder/a.txt");
        let e = write_atomic(&p, b"x").unwrap_err().to_string();
        assert!(e.contains("no/such/folder"), "{e}");
    }
}
