//! Data sets for forecasting: Penn Action (2D) and MSR Action3D (3D) clips,
//! and the validation split.
//!
//! **Split.** Only the official Penn Action *train* split is available here, so
//! a validation set is carved out of it **by clip**: clip `i` (0-based position
//! in the file) is a validation clip when `i % 10 == 0` (126 of 1,258 clips,
//! every action represented because the file is ordered by action). The other
//! clips train the learned models and form the nearest-neighbour index. The
//! same rule splits MSR Action3D. `tools/forecast/train.py` uses the same rule.

use std::path::Path;

use mp_geom::Npz;
use mp_geom::Track;
use mp_geom::{MsrAction3D, PennAction};

use crate::error::{ForecastError, Result};

/// One clip of a data set: the whole motion and its action.
#[derive(Debug, Clone)]
pub struct Clip {
    /// Identifier (clip id or name).
    pub name: String,
    /// Action class.
    pub action: String,
    /// The whole clip.
    pub track: Track,
    /// 2D only: the PCK reference size of every frame (e.g. the larger side
    /// of the data set's annotated person box, as the paper's evaluation
    /// uses). `None`: the extent of the visible true joints.
    pub box_sizes: Option<Vec<f64>>,
}

/// Every `VALIDATION_EVERY`-th clip (index % 10 == 0) is a validation clip.
pub const VALIDATION_EVERY: usize = 10;

/// Whether clip `index` belongs to the validation split.
pub fn is_validation_clip(index: usize) -> bool {
    index.is_multiple_of(VALIDATION_EVERY)
}

/// A forecasting data set read from one npz.
#[derive(Debug, Clone)]
pub struct ForecastDataset {
    /// `penn_action` or `msr_action3d` (the model-folder name).
    pub kind: &'static str,
    /// Every clip, in file order.
    pub clips: Vec<Clip>,
}

impl ForecastDataset {
    /// Reads a Penn Action npz (`keypoints`) or an MSR Action3D npz (`joints`).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let z = Npz::open(path)?;
        if z.contains("keypoints") {
            drop(z);
            let d = PennAction::open(path)?;
            let clips = d
                .clips()
                .iter()
                .map(|c| {
                    Ok(Clip {
                        name: c.clip_id.clone(),
                        action: c.action.clone(),
                        track: d.clip(c.index)?,
                        box_sizes: Some(
                            d.bbox(c.index)?
                                .outer_iter()
                                .map(|b| (b[2] - b[0]).max(b[3] - b[1]))
                                .collect(),
                        ),
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            Ok(ForecastDataset {
                kind: "penn_action",
                clips,
            })
        } else if z.contains("joints") {
            drop(z);
            let d = MsrAction3D::open(path)?;
            let clips = d
                .clips()
                .iter()
                .map(|c| {
                    Ok(Clip {
                        name: c.name.clone(),
                        action: c.action_name.to_string(),
                        track: d.clip(c.index)?,
                        box_sizes: None,
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            Ok(ForecastDataset {
                kind: "msr_action3d",
                clips,
            })
        } else {
            Err(ForecastError::Format {
                path: path.to_path_buf(),
                reason:
                    "neither `keypoints` (Penn Action) nor `joints` (MSR Action3D) is in the file"
                        .into(),
            })
        }
    }

    /// (training clips, validation clips) by `is_validation_clip`.
    pub fn split(&self) -> (Vec<&Clip>, Vec<&Clip>) {
        let (mut tr, mut va) = (Vec::new(), Vec::new());
        for (i, c) in self.clips.iter().enumerate() {
            if is_validation_clip(i) {
                va.push(c);
            } else {
                tr.push(c);
            }
        }
        (tr, va)
    }
}
