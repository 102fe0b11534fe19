//! The networks' contract: the seven [`NetKind`]s, the name and shape of
//! every input and output, where the model folder is found, its
//! `manifest.json`, and the checks of a graph against the contract.

use std::path::{Path, PathBuf};

use mp_onnx::{ModelDirs, TensorInfo};
use serde_json::Value;

use super::RefineNets;
use crate::error::{RefineError, Result};
use crate::motion::{FRAME_FEATURES, MSR_JOINTS, NET_FRAMES};

/// Environment variable naming the model folder.
pub const MODEL_DIR_ENV: &str = "MP_REFINE_MODELS";
/// Where the models live, relative to the workspace root.
pub const MODEL_DIR_IN_WORKSPACE: &str = "models/refine";
/// Frames of the transition input of the transition refinement network.
pub const TRANSITION_FRAMES: usize = 16;
/// Cubic coefficients per feature.
pub(crate) const N_COEFFS: usize = 4;
/// Action classes of the generator and the evaluator (MSR Action3D).
pub const N_ACTIONS: usize = 20;

/// One of the seven networks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum NetKind {
    /// Per-frame anchor logits.
    AnchorRecognition,
    /// Masked anchor → concept logits and a new anchor pose.
    AnchorRefinement,
    /// Transition CVAE decoder: anchors + duration + z → cubic coefficients.
    TransitionGenerator,
    /// Flawed transition + anchors + duration → cubic coefficients.
    TransitionRefinement,
    /// Action-conditioned motion generator (CVAE decoder).
    Generator,
    /// Action classifier on real motion; its features feed FID etc.
    Evaluator,
    /// Per-frame, per-joint flaw logits.
    FlawDetector,
}

/// A dimension of the contract.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Dim {
    /// The batch dimension (any size).
    Batch,
    /// A fixed size.
    Fixed(usize),
    /// A size read from the graph (concepts, latent, features).
    Open,
}

use Dim::{Batch, Fixed, Open};

pub(super) type Spec = (&'static str, &'static [Dim]);

const MOTION: &[Dim] = &[Batch, Fixed(NET_FRAMES), Fixed(FRAME_FEATURES)];
const FRAME: &[Dim] = &[Batch, Fixed(FRAME_FEATURES)];
const PER_FRAME: &[Dim] = &[Batch, Fixed(NET_FRAMES)];
const DURATION: &[Dim] = &[Batch, Fixed(1)];
const LATENT: &[Dim] = &[Batch, Open];
const COEFFS: &[Dim] = &[Batch, Fixed(N_COEFFS), Fixed(FRAME_FEATURES)];
const TRANSITION: &[Dim] = &[Batch, Fixed(TRANSITION_FRAMES), Fixed(FRAME_FEATURES)];
const ACTIONS: &[Dim] = &[Batch, Fixed(N_ACTIONS)];
const PER_JOINT: &[Dim] = &[Batch, Fixed(NET_FRAMES), Fixed(MSR_JOINTS)];

impl NetKind {
    /// All seven, in the order of the README.
    pub const ALL: [NetKind; 7] = [
        NetKind::AnchorRecognition,
        NetKind::AnchorRefinement,
        NetKind::TransitionGenerator,
        NetKind::TransitionRefinement,
        NetKind::Generator,
        NetKind::Evaluator,
        NetKind::FlawDetector,
    ];

    /// Base name (file stem, and prefix of the `parity.npz` keys).
    pub fn name(self) -> &'static str {
        match self {
            NetKind::AnchorRecognition => "anchor_recognition",
            NetKind::AnchorRefinement => "anchor_refinement",
            NetKind::TransitionGenerator => "transition_generator",
            NetKind::TransitionRefinement => "transition_refinement",
            NetKind::Generator => "generator",
            NetKind::Evaluator => "evaluator",
            NetKind::FlawDetector => "flaw_detector",
        }
    }

    /// File name in the model folder.
    pub fn file_name(self) -> String {
        format!("{}.onnx", self.name())
    }

    pub(super) fn inputs(self) -> &'static [Spec] {
        match self {
            NetKind::AnchorRecognition | NetKind::Evaluator | NetKind::FlawDetector => {
                &[("motion", MOTION)]
            }
            NetKind::AnchorRefinement => &[
                ("motion", MOTION),
                ("mask", PER_FRAME),
                ("target", PER_FRAME),
            ],
            NetKind::TransitionGenerator => &[
                ("anchor_a", FRAME),
                ("anchor_b", FRAME),
                ("duration", DURATION),
                ("z", LATENT),
            ],
            NetKind::TransitionRefinement => &[
                ("transition", TRANSITION),
                ("anchor_a", FRAME),
                ("anchor_b", FRAME),
                ("duration", DURATION),
            ],
            NetKind::Generator => &[("action", ACTIONS), ("z", LATENT)],
        }
    }

    pub(super) fn outputs(self) -> &'static [Spec] {
        match self {
            NetKind::AnchorRecognition => &[("anchor_logit", PER_FRAME)],
            NetKind::AnchorRefinement => &[("concept_logits", LATENT), ("anchor", FRAME)],
            NetKind::TransitionGenerator | NetKind::TransitionRefinement => &[("coeffs", COEFFS)],
            NetKind::Generator => &[("motion", MOTION)],
            NetKind::Evaluator => &[("logits", ACTIONS), ("features", LATENT)],
            NetKind::FlawDetector => &[("flaw_logit", PER_JOINT)],
        }
    }

    /// Input names, in order.
    pub fn input_names(self) -> Vec<&'static str> {
        self.inputs().iter().map(|s| s.0).collect()
    }

    /// Output names, in order.
    pub fn output_names(self) -> Vec<&'static str> {
        self.outputs().iter().map(|s| s.0).collect()
    }
}

impl RefineNets {
    /// The first candidate folder holding a `manifest.json`.
    pub fn find_dir() -> Result<PathBuf> {
        let dirs = ModelDirs::standard(MODEL_DIR_ENV, MODEL_DIR_IN_WORKSPACE);
        dirs.find_dir_with("manifest.json")
            .ok_or_else(|| RefineError::ModelMissing {
                file: "manifest.json".into(),
                searched: dirs.describe(3),
            })
    }
}

/// Open sizes of the networks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NetSizes {
    /// Anchor concepts `K` (classes of the anchor refinement classifier).
    pub concepts: usize,
    /// Latent size of the transition generator.
    pub transition_latent: usize,
    /// Latent size of the motion generator.
    pub generator_latent: usize,
    /// Evaluator feature size.
    pub features: usize,
}

impl Default for NetSizes {
    /// The sizes of `models/refine/README.md`.
    fn default() -> Self {
        NetSizes {
            concepts: 80,
            transition_latent: 16,
            generator_latent: 32,
            features: 64,
        }
    }
}

fn io_err(path: &Path, source: std::io::Error) -> RefineError {
    RefineError::Io {
        path: path.to_path_buf(),
        source,
    }
}

pub(super) fn model_err(path: &Path, reason: impl std::fmt::Display) -> RefineError {
    RefineError::Model {
        model: path.display().to_string(),
        reason: reason.to_string(),
    }
}

/// Reads `manifest.json` and checks the sizes it states (when present)
/// against the canonical representation: `joints` must be 20, `frames` 60,
/// `features` 60. Returns the manifest as JSON.
pub fn read_manifest(path: &Path) -> Result<Value> {
    let text = std::fs::read_to_string(path).map_err(|e| io_err(path, e))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| model_err(path, e))?;
    if !v.is_object() {
        return Err(model_err(path, "the manifest is not a JSON object"));
    }
    // Every size the manifest states must be a positive integer.
    for k in [
        "joints",
        "n_joints",
        "frames",
        "n_frames",
        "net_frames",
        "features",
        "frame_features",
        "concepts",
        "transition_frames",
        "transition_latent",
        "generator_latent",
        "d_model",
    ] {
        let top = v.get(k).map(|x| (x, k.to_string()));
        let nested = v
            .get("representation")
            .and_then(|r| r.get(k))
            .map(|x| (x, format!("representation.{k}")));
        for (x, field) in top.into_iter().chain(nested) {
            if !matches!(x.as_u64(), Some(n) if n > 0) {
                return Err(model_err(
                    path,
                    format!("manifest field `{field}` must be a positive integer, got {x}"),
                ));
            }
        }
    }
    let find = |keys: &[&str]| -> Option<u64> {
        keys.iter().find_map(|k| {
            v.get(*k)
                .or_else(|| v.get("representation").and_then(|r| r.get(*k)))
                .and_then(Value::as_u64)
        })
    };
    if let Some(j) = find(&["joints", "n_joints"]) {
        if j as usize != MSR_JOINTS {
            return Err(RefineError::JointCount {
                what: format!("refinement models ({})", path.display()),
                expected: MSR_JOINTS,
                got: j as usize,
            });
        }
    }
    if let Some(f) = find(&["frames", "n_frames", "net_frames"]) {
        if f as usize != NET_FRAMES {
            return Err(model_err(
                path,
                format!("the networks use {f} frames, this build {NET_FRAMES}"),
            ));
        }
    }
    if let Some(f) = find(&["features", "frame_features"]) {
        if f as usize != FRAME_FEATURES {
            return Err(model_err(
                path,
                format!("the networks use {f} features per frame, this build {FRAME_FEATURES}"),
            ));
        }
    }
    Ok(v)
}

/// Checks one tensor of a session against its contract; returns the
/// graph's size of an [`Dim::Open`] dimension (0 when the graph leaves it open).
pub(super) fn check_spec(
    path: &Path,
    infos: &[TensorInfo],
    spec: &Spec,
    role: &str,
) -> Result<usize> {
    let (name, dims) = spec;
    let Some(info) = infos.iter().find(|i| i.name == *name) else {
        let have: Vec<&str> = infos.iter().map(|i| i.name.as_str()).collect();
        return Err(model_err(
            path,
            format!("no {role} `{name}` (the graph has {have:?})"),
        ));
    };
    if info.dtype != "f32" {
        return Err(model_err(
            path,
            format!("{role} `{name}` is {}, expected f32", info.dtype),
        ));
    }
    if info.shape.len() != dims.len() {
        return Err(model_err(
            path,
            format!(
                "{role} `{name}` has shape {:?}, expected {} dimensions",
                info.shape,
                dims.len()
            ),
        ));
    }
    let mut open = 0;
    for (i, (d, g)) in dims.iter().zip(&info.shape).enumerate() {
        match d {
            Fixed(n) if *g >= 0 && *g as usize != *n => {
                return Err(model_err(
                    path,
                    format!(
                        "{role} `{name}` has size {g} in dimension {i}, expected {n} (shape {:?})",
                        info.shape
                    ),
                ));
            }
            Open if *g > 0 => open = *g as usize,
            _ => {}
        }
    }
    Ok(open)
}
