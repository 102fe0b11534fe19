//! Where model files are looked for.
//!
//! Each family of models has its own environment variable and its own
//! folder in the workspace (the pose models: `MP_MODEL_DIR` and
//! `.cache/models`; the forecasting models: `MP_FORECAST_MODELS` and
//! `models/forecast/<dataset>`; the refinement networks: `MP_REFINE_MODELS`
//! and `models/refine`). [`ModelDirs`] builds the search list in the same
//! order for all of them:
//!
//! 1. the folder named by the environment variable (and chosen subfolders of it),
//! 2. the folder in the workspace the crate was built in,
//! 3. the same relative folder above the current directory (those that exist),
//! 4. any further folders the caller adds.

use std::path::{Path, PathBuf};

use crate::error::{OnnxError, Result};
use mp_geom::workspace_root;

use crate::library::join_paths;

/// An ordered list of folders searched for model files (no duplicates).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ModelDirs {
    dirs: Vec<PathBuf>,
}

impl ModelDirs {
    /// An empty list.
    pub fn new() -> Self {
        ModelDirs::default()
    }

    /// The usual search for one family of models: the folder named by
    /// `env_var` (when set and non-empty), `<workspace>/<rel>`, and `<rel>`
    /// under each ancestor of the current directory where that folder exists.
    pub fn standard(env_var: &str, rel: impl AsRef<Path>) -> Self {
        ModelDirs::new().with_env(env_var, &[]).with_workspace(rel)
    }

    /// Adds the folder named by `env_var` (when set and non-empty), followed
    /// by each of its `subdirs` (e.g. a data set's name).
    pub fn with_env(self, env_var: &str, subdirs: &[&str]) -> Self {
        let dir = std::env::var_os(env_var)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from);
        self.with_optional_dir(dir, subdirs)
    }

    /// Adds `dir` (when given) followed by each of its `subdirs`.
    fn with_optional_dir(mut self, dir: Option<PathBuf>, subdirs: &[&str]) -> Self {
        if let Some(dir) = dir {
            self.push(dir.clone());
            for s in subdirs {
                self.push(dir.join(s));
            }
        }
        self
    }

    /// Adds `<workspace>/<rel>` (the workspace the crate was built in), then
    /// `<rel>` under each ancestor of the current directory where that
    /// folder exists.
    pub fn with_workspace(mut self, rel: impl AsRef<Path>) -> Self {
        let rel = rel.as_ref();
        if let Some(root) = workspace_root() {
            self.push(root.join(rel));
        }
        if let Ok(cwd) = std::env::current_dir() {
            for anc in cwd.ancestors() {
                let d = anc.join(rel);
                if d.is_dir() {
                    self.push(d);
                }
            }
        }
        self
    }

    /// Adds one folder.
    pub fn with_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.push(dir.into());
        self
    }

    /// Appends a folder unless it is already in the list.
    pub fn push(&mut self, dir: PathBuf) {
        if !self.dirs.contains(&dir) {
            self.dirs.push(dir);
        }
    }

    /// The folders, in search order.
    pub fn dirs(&self) -> &[PathBuf] {
        &self.dirs
    }

    /// Path of `file` in the first folder that has it.
    pub fn find_file(&self, file: impl AsRef<Path>) -> Option<PathBuf> {
        let file = file.as_ref();
        self.dirs.iter().map(|d| d.join(file)).find(|p| p.is_file())
    }

    /// Path of the first of `files` in the first folder that has any of them:
    /// a folder's preferred file wins over its fallback, and an earlier
    /// folder over a later one.
    pub fn find_first_of(&self, files: &[&str]) -> Option<PathBuf> {
        self.dirs
            .iter()
            .find_map(|d| files.iter().map(|f| d.join(f)).find(|p| p.is_file()))
    }

    /// The first folder that has `file` (e.g. the folder of a `manifest.json`).
    pub fn find_dir_with(&self, file: impl AsRef<Path>) -> Option<PathBuf> {
        let file = file.as_ref();
        self.dirs.iter().find(|d| d.join(file).is_file()).cloned()
    }

    /// Like [`ModelDirs::find_file`], with [`OnnxError::ModelMissing`]
    /// (naming the file and every folder searched) when no folder has it.
    pub fn require_file(&self, file: &str) -> Result<PathBuf> {
        self.find_file(file).ok_or_else(|| OnnxError::ModelMissing {
            file: file.to_string(),
            searched: self.describe(usize::MAX),
        })
    }

    /// The first `max` folders as one comma-separated string, for messages.
    pub fn describe(&self, max: usize) -> String {
        let shown: Vec<PathBuf> = self.dirs.iter().take(max).cloned().collect();
        join_paths(&shown)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_prefers_its_first_file_and_earlier_folders_win() {
        let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        std::fs::write(a.path().join("plain.onnx"), b"x").unwrap();
        std::fs::write(b.path().join("cut.onnx"), b"x").unwrap();
        std::fs::write(b.path().join("plain.onnx"), b"x").unwrap();
        let dirs = ModelDirs::new()
            .with_dir(a.path().to_path_buf())
            .with_dir(b.path().to_path_buf());
        let files = ["cut.onnx", "plain.onnx"];
        assert_eq!(
            dirs.find_first_of(&files),
            Some(a.path().join("plain.onnx"))
        );
        let only_b = ModelDirs::new().with_dir(b.path().to_path_buf());
        assert_eq!(
            only_b.find_first_of(&files),
            Some(b.path().join("cut.onnx"))
        );
        assert_eq!(only_b.find_first_of(&["none.onnx"]), None);
    }

    #[test]
    fn first_folder_with_the_file_wins() {
        let tmp = tempfile::tempdir().unwrap();
        let (a, b, c) = (
            tmp.path().join("a"),
            tmp.path().join("b"),
            tmp.path().join("c"),
        );
        for d in [&a, &b, &c] {
            std::fs::create_dir_all(d).unwrap();
        }
        std::fs::write(b.join("net.onnx"), b"x").unwrap();
        std::fs::write(c.join("net.onnx"), b"x").unwrap();
        std::fs::create_dir_all(a.join("manifest.json")).unwrap(); // a folder, not a file
        std::fs::write(c.join("manifest.json"), b"{}").unwrap();
        let dirs = ModelDirs::new()
            .with_dir(&a)
            .with_dir(&b)
            .with_dir(&c)
            .with_dir(&a);
        assert_eq!(dirs.dirs().len(), 3, "duplicates are dropped");
        assert_eq!(dirs.find_file("net.onnx"), Some(b.join("net.onnx")));
        assert_eq!(dirs.find_dir_with("manifest.json"), Some(c.clone()));
        assert_eq!(dirs.find_file("other.onnx"), None);
        assert_eq!(dirs.require_file("net.onnx").unwrap(), b.join("net.onnx"));
    }

    #[test]
    fn missing_file_names_the_file_and_the_folders() {
        let tmp = tempfile::tempdir().unwrap();
        let dirs = ModelDirs::new().with_dir(tmp.path());
        let e = dirs.require_file("absent.onnx").unwrap_err();
        assert!(matches!(e, OnnxError::ModelMissing { .. }), "{e}");
        let msg = e.to_string();
        assert!(msg.contains("absent.onnx"), "{msg}");
        assert!(msg.contains(&tmp.path().display().to_string()), "{msg}");
        assert_eq!(ModelDirs::new().describe(3), "(no candidate folder)");
    }

    #[test]
    fn environment_folder_comes_first_then_its_subfolders() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(tmp.path().join("penn_action")).unwrap();
        std::fs::write(tmp.path().join("penn_action").join("manifest.json"), b"{}").unwrap();
        // What `with_env` adds for a variable set to `tmp`.
        let dirs = ModelDirs::new()
            .with_optional_dir(Some(tmp.path().to_path_buf()), &["penn_action"])
            .with_workspace("models/forecast/penn_action");
        assert_eq!(dirs.dirs()[0], tmp.path());
        assert_eq!(dirs.dirs()[1], tmp.path().join("penn_action"));
        assert_eq!(
            dirs.find_dir_with("manifest.json"),
            Some(tmp.path().join("penn_action"))
        );
        if let Some(root) = workspace_root() {
            assert_eq!(dirs.dirs()[2], root.join("models/forecast/penn_action"));
        }
        // An unset variable adds nothing.
        let unset = ModelDirs::new().with_env("MP_ONNX_TEST_UNSET_VARIABLE", &["x"]);
        assert!(unset.dirs().is_empty());
    }

    #[test]
    fn the_workspace_models_are_found() {
        let Some(root) = workspace_root() else {
            return;
        };
        let dirs = ModelDirs::standard("MP_ONNX_TEST_UNSET_VARIABLE", "models/refine");
        assert_eq!(dirs.dirs()[0], root.join("models/refine"));
        assert_eq!(
            dirs.find_dir_with("manifest.json"),
            Some(root.join("models/refine"))
        );
    }
}
