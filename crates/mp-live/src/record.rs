//! What a live run keeps for its output folder (`LiveParams::out`): every
//! analysed frame, pose and tracker event, appended to a spool file in the
//! folder as they happen (so memory stays flat however long the stream),
//! and read back when the stream ends into the people of the stream, which
//! `mp run`'s pipeline then analyses and writes
//! ([`mp_pipeline::Input::People`]).

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

use mp_geom::{People, Skeleton};
use mp_pose::Pose;
use mp_pose::{PeopleCollector, TrackEvent, TrackedPose};
use serde::{Deserialize, Serialize};

use crate::{LiveError, Result};

/// The spool's name in the output folder (removed once the folder is written).
pub(crate) const SPOOL_NAME: &str = ".mp-live-poses.spool";

/// One entry of the spool.
#[derive(Serialize, Deserialize)]
enum Row {
    /// The pose model saw stream frame `0`.
    Frame(u64),
    /// A track's pose on a frame (pixels and visibility, as f32).
    Pose {
        key: u64,
        frame: u64,
        xy: Vec<[f32; 2]>,
        vis: Vec<f32>,
    },
    Confirmed {
        key: u64,
        id: u32,
    },
    Dropped {
        key: u64,
        keep_until: u64,
    },
    Ended {
        key: u64,
    },
}

fn config() -> bincode::config::Configuration {
    bincode::config::standard()
}

fn io_error(path: &Path, what: &str, e: impl std::fmt::Display) -> LiveError {
    LiveError::Output(format!("{what} {}: {e}", path.display()))
}

/// The spool being written.
pub(crate) struct Recorder {
    path: PathBuf,
    file: BufWriter<File>,
    frames: u64,
}

impl Recorder {
    /// Creates `dir` (and its parents) and a new spool in it. Errors: `dir`
    /// is a file, or cannot be created or written.
    pub(crate) fn create(dir: &Path) -> Result<Self> {
        if dir.is_file() {
            return Err(LiveError::Output(format!(
                "--out names the folder to write into, but {} is a file",
                dir.display()
            )));
        }
        std::fs::create_dir_all(dir).map_err(|e| io_error(dir, "cannot create", e))?;
        let path = dir.join(SPOOL_NAME);
        let file = File::create(&path).map_err(|e| io_error(&path, "cannot create", e))?;
        Ok(Recorder {
            path,
            file: BufWriter::new(file),
            frames: 0,
        })
    }

    fn write(&mut self, row: &Row) -> Result<()> {
        bincode::serde::encode_into_std_write(row, &mut self.file, config())
            .map(|_| ())
            .map_err(|e| io_error(&self.path, "cannot write", e))
    }

    /// Stream frame `frame`, seen by the pose model, with the poses and
    /// events the tracker gave on it.
    pub(crate) fn frame(
        &mut self,
        frame: usize,
        poses: &[TrackedPose<Pose>],
        events: &[TrackEvent],
    ) -> Result<()> {
        self.frames = self.frames.max(frame as u64 + 1);
        self.write(&Row::Frame(frame as u64))?;
        for tp in poses {
            self.write(&Row::Pose {
                key: tp.key,
                frame: frame as u64,
                xy: tp
                    .pose
                    .keypoints_px
                    .iter()
                    .map(|p| [p[0] as f32, p[1] as f32])
                    .collect(),
                vis: tp.pose.visibility.iter().map(|&v| v as f32).collect(),
            })?;
        }
        for e in events {
            let row = match *e {
                TrackEvent::Confirmed { key, id, .. } => Row::Confirmed { key, id },
                TrackEvent::Dropped { key, keep_until } => Row::Dropped {
                    key,
                    keep_until: keep_until as u64,
                },
                TrackEvent::Ended { key } => Row::Ended { key },
            };
            self.write(&row)?;
        }
        Ok(())
    }

    /// Stream frame `frame` came, but the pose model did not see it (the
    /// pose rate skipped it): it is filled at the end.
    pub(crate) fn skipped(&mut self, frame: usize) {
        self.frames = self.frames.max(frame as u64 + 1);
    }

    /// Frames of the stream so far (the last one seen, plus one).
    pub(crate) fn frames(&self) -> usize {
        self.frames as usize
    }

    /// Removes the spool unread.
    pub(crate) fn discard(self) {
        drop(self.file);
        let _ = std::fs::remove_file(&self.path);
    }

    /// Finishes the spool and reads it back: the people of the stream at
    /// `fps` in `skeleton`, numbered with the ids the run reported, and per
    /// frame whether the pose model saw it. The spool is removed.
    pub(crate) fn people(mut self, fps: f64, skeleton: &Skeleton) -> Result<(People, Vec<bool>)> {
        self.file
            .flush()
            .map_err(|e| io_error(&self.path, "cannot write", e))?;
        drop(self.file);
        let result = read_spool(&self.path, self.frames as usize, fps, skeleton);
        let _ = std::fs::remove_file(&self.path);
        result
    }
}

fn read_spool(path: &Path, n: usize, fps: f64, skeleton: &Skeleton) -> Result<(People, Vec<bool>)> {
    if n == 0 {
        return Err(LiveError::Output("no frame came: nothing to write".into()));
    }
    let file = File::open(path).map_err(|e| io_error(path, "cannot read", e))?;
    let mut reader = BufReader::new(file);
    let mut collector = PeopleCollector::new(skeleton.len());
    let mut posed = vec![false; n];
    // Rows until the end of the file (a row cut short is an error).
    while !reader
        .fill_buf()
        .map_err(|e| io_error(path, "cannot read", e))?
        .is_empty()
    {
        let row: Row = bincode::serde::decode_from_std_read(&mut reader, config())
            .map_err(|e| io_error(path, "cannot read", e))?;
        match row {
            Row::Frame(f) => {
                if let Some(p) = posed.get_mut(f as usize) {
                    *p = true;
                }
            }
            Row::Pose {
                key,
                frame,
                xy,
                vis,
            } => {
                let xy = xy.iter().map(|p| [p[0] as f64, p[1] as f64]).collect();
                let vis = vis.iter().map(|&v| v as f64).collect();
                collector.pose(key, frame as usize, xy, vis, "the pose model")?;
            }
            Row::Confirmed { key, id } => collector.event(&TrackEvent::Confirmed {
                key,
                id,
                first_frame: 0,
            }),
            Row::Dropped { key, keep_until } => collector.event(&TrackEvent::Dropped {
                key,
                keep_until: keep_until as usize,
            }),
            Row::Ended { key } => collector.event(&TrackEvent::Ended { key }),
        }
    }
    let mut per_frame = vec![0usize; n];
    let people = collector.finish(n, fps, skeleton, true, &mut per_frame)?;
    Ok((people, posed))
}
