//! The manifest: one [`ItemReport`] per finished item, a JSON line each,
//! written to disk before the next ([`Manifest`]), read back by
//! [`ItemReport::read_manifest`] to find the items an earlier batch completed
//! ([`resume`]).

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{BatchError, Result, RESULT_FILE};

/// What became of an item.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum ItemStatus {
    /// Run now, and complete.
    Ok,
    /// Failed; the report holds the message.
    Failed,
    /// Complete from an earlier batch, not run again.
    Skipped,
    /// Interrupted or not started because the batch was cancelled; never
    /// written to the manifest.
    Cancelled,
}

impl ItemStatus {
    /// Lower-case name, as in the manifest.
    pub fn as_str(self) -> &'static str {
        match self {
            ItemStatus::Ok => "ok",
            ItemStatus::Failed => "failed",
            ItemStatus::Skipped => "skipped",
            ItemStatus::Cancelled => "cancelled",
        }
    }
}

/// One item of a batch: a line of the manifest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ItemReport {
    /// The input file, as given.
    #[serde(serialize_with = "lossy_path")]
    pub input: PathBuf,
    /// Its output folder.
    #[serde(serialize_with = "lossy_path")]
    pub output: PathBuf,
    /// What became of it.
    pub status: ItemStatus,
    /// For a failed item, the error message followed by its causes.
    #[serde(default)]
    pub error: Option<String>,
    /// Frames of the motion.
    #[serde(default)]
    pub frames: Option<usize>,
    /// Frame rate of the motion.
    #[serde(default)]
    pub fps: Option<f64>,
    /// Wall time of the item in seconds (reading the input, the analysis and
    /// every output file); for a skipped item, that of the run it skips.
    #[serde(default)]
    pub seconds: Option<f64>,
    /// Repetitions counted in the whole motion.
    #[serde(default)]
    pub total_repetitions: Option<usize>,
    /// Repetitions per counted interval, in time order.
    #[serde(default)]
    pub counts: Vec<usize>,
    /// The signal that decided the count (`keypoints` or `frames`).
    #[serde(default)]
    pub signal: Option<String>,
    /// How the count was reached (`period`, `intervals` or `none`).
    #[serde(default)]
    pub method: Option<String>,
}

fn lossy_path<S: serde::Serializer>(p: &Path, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(&p.to_string_lossy())
}

impl ItemReport {
    /// File name of the manifest inside a batch's output folder.
    pub const MANIFEST: &str = "manifest.jsonl";

    /// Reads a manifest; lines that do not parse (a line cut short by a crash)
    /// are ignored. A missing manifest is empty.
    pub fn read_manifest(path: &Path) -> Result<Vec<ItemReport>> {
        let bytes = match std::fs::read(path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
            Err(e) => return Err(BatchError::io("read the manifest", path, e)),
        };
        Ok(bytes
            .split(|&b| b == b'\n')
            .filter_map(|line| serde_json::from_slice::<ItemReport>(line).ok())
            .collect())
    }

    pub(super) fn empty(input: &Path, output: &Path, status: ItemStatus) -> Self {
        ItemReport {
            input: input.to_path_buf(),
            output: output.to_path_buf(),
            status,
            error: None,
            frames: None,
            fps: None,
            seconds: None,
            total_repetitions: None,
            counts: Vec::new(),
            signal: None,
            method: None,
        }
    }

    /// The report as one line of JSON (no newline).
    pub fn to_json_line(&self) -> String {
        // Serialising plain strings, numbers and enums cannot fail.
        serde_json::to_string(self).unwrap_or_else(|e| {
            serde_json::json!({ "input": self.input.to_string_lossy(), "error": e.to_string() })
                .to_string()
        })
    }
}

/// Same file when both can be resolved, else the same path.
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// The items complete from an earlier batch and those still to run: an item
/// is skipped when its output folder holds [`RESULT_FILE`] and the last
/// manifest line for the same input and folder says `ok` or `skipped`;
/// its report then carries the earlier counts. Returns the reports
/// (`Some` for skipped items, in input order) and the indices to run.
pub(super) fn resume(
    items: &[PathBuf],
    outputs: &[PathBuf],
    earlier: &[ItemReport],
) -> (Vec<Option<ItemReport>>, Vec<usize>) {
    // Skipped items: complete folder and an ok line for the same input.
    let mut reports: Vec<Option<ItemReport>> = vec![None; items.len()];
    let mut pending = Vec::new();
    for (i, (input, output)) in items.iter().zip(outputs).enumerate() {
        let name = output.file_name();
        let last = earlier
            .iter()
            .rev()
            .find(|l| l.output.file_name() == name && same_file(&l.input, input));
        let done = last.is_some_and(|l| {
            matches!(l.status, ItemStatus::Ok | ItemStatus::Skipped)
                && output.join(RESULT_FILE).is_file()
        });
        match (done, last) {
            (true, Some(l)) => {
                reports[i] = Some(ItemReport {
                    input: input.clone(),
                    output: output.clone(),
                    status: ItemStatus::Skipped,
                    error: None,
                    ..l.clone()
                })
            }
            _ => pending.push(i),
        }
    }
    (reports, pending)
}

/// The manifest, appended line by line, each on disk before the next.
pub(super) struct Manifest {
    file: File,
    path: PathBuf,
}

impl Manifest {
    /// Replaces the manifest with `lines` (through a temporary file renamed
    /// into place) and opens it for appending.
    pub(super) fn start(path: &Path, lines: &[ItemReport]) -> Result<Self> {
        let mut text = String::new();
        for l in lines {
            text.push_str(&l.to_json_line());
            text.push('\n');
        }
        mp_geom::write_atomic(path, text.as_bytes())
            .map_err(|e| BatchError::io("write the manifest", path, std::io::Error::other(e)))?;
        if let Some(dir) = path.parent() {
            // Makes the rename durable where folders can be synced.
            if let Ok(d) = File::open(dir) {
                let _ = d.sync_all();
            }
        }
        let file = OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(|e| BatchError::io("open the manifest", path, e))?;
        Ok(Manifest {
            file,
            path: path.to_path_buf(),
        })
    }

    pub(super) fn append(&mut self, report: &ItemReport) -> Result<()> {
        let mut line = report.to_json_line();
        line.push('\n');
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .and_then(|()| self.file.sync_data())
            .map_err(|e| BatchError::io("append to the manifest", &self.path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cut_line_in_the_manifest_is_ignored() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join(ItemReport::MANIFEST);
        let ok = ItemReport {
            frames: Some(10),
            total_repetitions: Some(3),
            counts: vec![3],
            ..ItemReport::empty(Path::new("in/a.npz"), Path::new("out/a"), ItemStatus::Ok)
        };
        let line = ok.to_json_line();
        std::fs::write(&path, format!("{line}\n{}", &line[..line.len() / 2])).unwrap();
        let read = ItemReport::read_manifest(&path).unwrap();
        assert_eq!(read, vec![ok]);
    }
}
