//! Which MSR Action3D subjects an evaluation may score.
//!
//! The refinement networks' `manifest.json` records the subjects whose clips
//! shaped them: `training.train_subjects` (the six networks of the paper's
//! pipeline), `training.val_subjects` (validation losses only, never a
//! choice), and per network `networks.<name>.training.train_subjects` and
//! `select_subjects` (the flaw detector: trained on some subjects, its epoch
//! chosen on another). [`TrainingSubjects`] reads them; [`split_params`]
//! turns a data set into evaluation parameters: every clip of a subject in
//! none of the training or selection lists is scored (or the subjects named
//! explicitly), parameters would be chosen on the recorded selection
//! subjects, and the clustering ablation relearns concepts on the recorded
//! training subjects where the data hold them.

use std::collections::BTreeSet;
use std::path::Path;

use mp_geom::MsrAction3D;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::refine::evaluation::RefineEvalParams;
use crate::refine::RefineResult as Result;
use mp_refine::read_manifest;
use mp_refine::RefineError;

/// The subjects recorded in a training manifest (ascending, no repeats).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TrainingSubjects {
    /// Subjects whose clips any network was trained on.
    pub train: Vec<u32>,
    /// Subjects on which a network's epochs or thresholds were chosen
    /// (a subject may also be a training subject of another network).
    pub select: Vec<u32>,
    /// Subjects whose clips only reported validation losses.
    pub validation: Vec<u32>,
}

fn subject_list(v: &Value, key: &str, out: &mut BTreeSet<u32>) -> Result<bool> {
    let Some(list) = v.get(key) else {
        return Ok(false);
    };
    let items = list.as_array().ok_or_else(|| RefineError::Model {
        model: "manifest.json".into(),
        reason: format!("`{key}` is not a list of subject numbers"),
    })?;
    for s in items {
        let n = s
            .as_u64()
            .and_then(|n| u32::try_from(n).ok())
            .ok_or_else(|| RefineError::Model {
                model: "manifest.json".into(),
                reason: format!("`{key}` holds `{s}`, not a subject number"),
            })?;
        out.insert(n);
    }
    Ok(true)
}

impl TrainingSubjects {
    /// The subjects of a parsed manifest. Errors when it records no
    /// training subjects at all (a manifest written before they were
    /// recorded): the caller then has to name the evaluation subjects.
    pub fn from_manifest(manifest: &Value) -> Result<Self> {
        let (mut train, mut select, mut validation) =
            (BTreeSet::new(), BTreeSet::new(), BTreeSet::new());
        let mut found = false;
        let blocks = std::iter::once(manifest.get("training")).chain(
            manifest
                .get("networks")
                .and_then(Value::as_object)
                .into_iter()
                .flat_map(|n| n.values().map(|net| net.get("training"))),
        );
        for block in blocks.flatten() {
            found |= subject_list(block, "train_subjects", &mut train)?;
            subject_list(block, "select_subjects", &mut select)?;
            subject_list(block, "val_subjects", &mut validation)?;
        }
        if !found {
            return Err(RefineError::Model {
                model: "manifest.json".into(),
                reason: "the manifest records no training subjects (`training.train_subjects`); \
                         name the evaluation subjects explicitly"
                    .into(),
            });
        }
        let seen: BTreeSet<u32> = train.union(&select).copied().collect();
        Ok(TrainingSubjects {
            select: select.into_iter().collect(),
            validation: validation.difference(&seen).copied().collect(),
            train: train.into_iter().collect(),
        })
    }

    /// Reads `manifest.json` of a model folder.
    pub fn read(model_dir: &Path) -> Result<Self> {
        Self::from_manifest(&read_manifest(&model_dir.join("manifest.json"))?)
    }

    /// Subjects that shaped the networks or their settings: training and
    /// selection subjects, ascending.
    pub fn seen(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.train.iter().chain(&self.select).copied().collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The subjects of `data` that are neither training nor selection
    /// subjects, ascending.
    pub fn unseen_in(&self, data: &MsrAction3D) -> Vec<u32> {
        let seen = self.seen();
        subjects_of(data)
            .into_iter()
            .filter(|s| !seen.contains(s))
            .collect()
    }
}

/// Every subject of `data`, ascending.
pub fn subjects_of(data: &MsrAction3D) -> Vec<u32> {
    let s: BTreeSet<u32> = data.clips().iter().map(|c| c.subject).collect();
    s.into_iter().collect()
}

/// The evaluation split of a data set.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct EvalSplit {
    /// Subjects scored ([`RefineEvalParams::val_subjects`]).
    pub eval_subjects: Vec<u32>,
    /// Evaluation subjects that the networks were trained on or tuned with
    /// (only when named explicitly): their figures are not held out.
    pub seen_eval_subjects: Vec<u32>,
    /// Selection subjects for parameter grids (recorded selection subjects
    /// that are not evaluated).
    pub select_subjects: Vec<u32>,
    /// Training subjects present in the data (the clustering ablation
    /// relearns its concepts on their clips).
    pub concept_subjects: Vec<u32>,
}

/// The split of `data` for networks trained as `trained` records: the
/// subjects in `explicit` when given (each must have clips in `data`),
/// otherwise every subject of `data` the networks never saw. Errors when
/// no subject is left to score, naming the data's subjects.
pub fn split_for(
    data: &MsrAction3D,
    trained: &TrainingSubjects,
    explicit: Option<&[u32]>,
) -> Result<EvalSplit> {
    let present = subjects_of(data);
    let eval_subjects: Vec<u32> = match explicit {
        Some(list) => {
            if let Some(s) = list.iter().find(|s| !present.contains(s)) {
                return Err(RefineError::param(
                    "eval_subjects",
                    format!(
                        "subject {s} has no clip in {} (its subjects: {present:?})",
                        data.path().display()
                    ),
                ));
            }
            let set: BTreeSet<u32> = list.iter().copied().collect();
            set.into_iter().collect()
        }
        None => trained.unseen_in(data),
    };
    if eval_subjects.is_empty() {
        return Err(RefineError::param(
            "eval_subjects",
            format!(
                "every subject of {} ({present:?}) was used for training or selection \
                 (training {:?}, selection {:?}); name the subjects to score explicitly",
                data.path().display(),
                trained.train,
                trained.select
            ),
        ));
    }
    let seen = trained.seen();
    Ok(EvalSplit {
        seen_eval_subjects: eval_subjects
            .iter()
            .copied()
            .filter(|s| seen.contains(s))
            .collect(),
        select_subjects: trained
            .select
            .iter()
            .copied()
            .filter(|s| !eval_subjects.contains(s))
            .collect(),
        concept_subjects: trained
            .train
            .iter()
            .copied()
            .filter(|s| present.contains(s) && !eval_subjects.contains(s))
            .collect(),
        eval_subjects,
    })
}

/// `base` with the subjects of `split`.
pub fn split_params(base: RefineEvalParams, split: &EvalSplit) -> RefineEvalParams {
    RefineEvalParams {
        val_subjects: split.eval_subjects.clone(),
        select_subjects: split.select_subjects.clone(),
        concept_subjects: Some(split.concept_subjects.clone()),
        ..base
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn subjects_are_read_from_every_training_block() {
        let m = json!({
            "training": {"train_subjects": [1, 3, 5, 7], "val_subjects": [9]},
            "networks": {
                "flaw_detector": {"training": {"train_subjects": [1, 3, 5], "select_subjects": [7]}},
                "evaluator": {"file": "evaluator.onnx"}
            }
        });
        let t = TrainingSubjects::from_manifest(&m).unwrap();
        // 7 trains the six networks and chooses the flaw detector's epoch
        assert_eq!(t.train, vec![1, 3, 5, 7]);
        assert_eq!(t.select, vec![7]);
        assert_eq!(t.validation, vec![9]);
        assert_eq!(t.seen(), vec![1, 3, 5, 7]);
    }

    #[test]
    fn a_manifest_without_subjects_is_refused_with_a_clear_message() {
        let m = json!({"training": {"val_subjects": [9]}});
        let e = TrainingSubjects::from_manifest(&m).unwrap_err().to_string();
        assert!(e.contains("train_subjects"), "{e}");
        let bad = json!({"training": {"train_subjects": ["one"]}});
        assert!(TrainingSubjects::from_manifest(&bad).is_err());
    }
}
