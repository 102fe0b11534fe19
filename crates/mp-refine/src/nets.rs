//! The seven refinement networks, run with ONNX Runtime.
//!
//! A model folder (`models/refine/`, see its `README.md`) holds
//! `manifest.json` and seven ONNX files. Every tensor is `f32` with a dynamic
//! batch dimension `B`; clips are canonical ([`crate::motion`]): 60 frames of
//! 60 features.
//!
//! | network | inputs | outputs |
//! |---|---|---|
//! | [`NetKind::AnchorRecognition`] | `motion [B,60,60]` | `anchor_logit [B,60]` |
//! | [`NetKind::AnchorRefinement`] | `motion [B,60,60]`, `mask [B,60]`, `target [B,60]` | `concept_logits [B,K]`, `anchor [B,60]` |
//! | [`NetKind::TransitionGenerator`] | `anchor_a [B,60]`, `anchor_b [B,60]`, `duration [B,1]`, `z [B,Zt]` | `coeffs [B,4,60]` |
//! | [`NetKind::TransitionRefinement`] | `transition [B,16,60]`, `anchor_a`, `anchor_b`, `duration` | `coeffs [B,4,60]` |
//! | [`NetKind::Generator`] | `action [B,20]`, `z [B,Zg]` | `motion [B,60,60]` |
//! | [`NetKind::Evaluator`] | `motion [B,60,60]` | `logits [B,20]`, `features [B,F]` |
//! | [`NetKind::FlawDetector`] | `motion [B,60,60]` | `flaw_logit [B,60,20]` |
//!
//! [`RefineNets::load`] checks every input and output name and every fixed
//! dimension against this contract when the sessions are opened, so a wrong
//! model is reported once, by file and tensor, instead of failing at run time.
//! The open sizes (`K` concepts, latent sizes `Zt`, `Zg`, feature size `F`)
//! are read from the graphs, or from the manifest (`concepts`,
//! `transition_latent`, `generator_latent`) when a graph leaves them open.

use std::path::{Path, PathBuf};

use mp_onnx::{Input, ModelDirs, Network, SessionParams, TensorInfo};
use serde_json::Value;

use crate::error::{RefineError, Result};
use crate::motion::{FRAME_FEATURES, MSR_JOINTS, NET_FRAMES};

/// Environment variable naming the model folder.
pub const MODEL_DIR_ENV: &str = "MP_REFINE_MODELS";
/// Where the models live, relative to the workspace root.
pub const MODEL_DIR_IN_WORKSPACE: &str = "models/refine";
/// Frames of the transition input of the transition refinement network.
pub const TRANSITION_FRAMES: usize = 16;
/// Cubic coefficients per feature.
pub const N_COEFFS: usize = 4;
/// Action classes of the generator and the evaluator (MSR Action3D).
pub const N_ACTIONS: usize = 20;

/// One of the seven networks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
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
enum Dim {
    /// The batch dimension (any size).
    Batch,
    /// A fixed size.
    Fixed(usize),
    /// A size read from the graph (concepts, latent, features).
    Open,
}

use Dim::{Batch, Fixed, Open};

type Spec = (&'static str, &'static [Dim]);

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

    fn inputs(self) -> &'static [Spec] {
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

    fn outputs(self) -> &'static [Spec] {
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

/// Candidate model folders, in search order: `MP_REFINE_MODELS`,
/// `<workspace>/models/refine`, and `models/refine` above the current
/// directory (where it exists).
pub fn model_dir_candidates() -> Vec<PathBuf> {
    ModelDirs::standard(MODEL_DIR_ENV, MODEL_DIR_IN_WORKSPACE)
        .dirs()
        .to_vec()
}

/// The first candidate folder holding a `manifest.json`.
pub fn find_model_dir() -> Result<PathBuf> {
    let dirs = ModelDirs::standard(MODEL_DIR_ENV, MODEL_DIR_IN_WORKSPACE);
    dirs.find_dir_with("manifest.json")
        .ok_or_else(|| RefineError::ModelMissing {
            file: "manifest.json".into(),
            searched: dirs.describe(3),
        })
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

fn model_err(path: &Path, reason: impl std::fmt::Display) -> RefineError {
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
fn check_spec(path: &Path, infos: &[TensorInfo], spec: &Spec, role: &str) -> Result<usize> {
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

/// One network of the folder and its place in the contract.
struct Net {
    kind: NetKind,
    net: Network,
}

/// A named input: name, shape, row-major data.
pub type NamedInput<'a> = (&'a str, Vec<usize>, &'a [f32]);
/// A named output: name, shape, row-major data.
pub type NamedOutput = (String, Vec<usize>, Vec<f32>);

impl Net {
    fn open(dir: &Path, kind: NetKind, params: &SessionParams) -> Result<(Self, Vec<usize>)> {
        let path = dir.join(kind.file_name());
        if !path.is_file() {
            return Err(RefineError::ModelMissing {
                file: kind.file_name(),
                searched: dir.display().to_string(),
            });
        }
        let net = Network::open(&path, params)?;
        let mut open = Vec::new();
        for s in kind.inputs() {
            open.push(check_spec(&path, net.inputs(), s, "input")?);
        }
        for s in kind.outputs() {
            open.push(check_spec(&path, net.outputs(), s, "output")?);
        }
        Ok((Net { kind, net }, open))
    }

    /// Runs the network; inputs whose shape or length does not fit the
    /// graph are [`RefineError::Shape`] errors naming the network and input.
    fn run(&self, inputs: &[NamedInput<'_>]) -> Result<Vec<NamedOutput>> {
        let inputs: Vec<Input<'_>> = inputs
            .iter()
            .map(|(name, shape, data)| Input::new(name, shape, data))
            .collect();
        let names = self.kind.output_names();
        let out = self.net.run(&inputs, &names).map_err(|e| {
            if e.is_shape_mismatch() {
                RefineError::Shape(e.to_string())
            } else {
                RefineError::Runtime(e)
            }
        })?;
        Ok(out.into_iter().map(|o| (o.name, o.shape, o.data)).collect())
    }
}

/// Outputs of the anchor refinement network for a batch.
#[derive(Debug, Clone, PartialEq)]
pub struct AnchorRefinementOut {
    /// `B × K` concept logits, row-major.
    pub concept_logits: Vec<f32>,
    /// `B × 60` anchor poses, row-major.
    pub anchors: Vec<f32>,
}

/// Outputs of the evaluator for a batch.
#[derive(Debug, Clone, PartialEq)]
pub struct EvaluatorOut {
    /// `B × 20` action logits, row-major.
    pub logits: Vec<f32>,
    /// `B × F` features, row-major.
    pub features: Vec<f32>,
}

/// The seven networks of one model folder, loaded once and shared
/// (`Send + Sync`; each session runs one batch at a time).
pub struct RefineNets {
    dir: PathBuf,
    manifest: Value,
    sizes: NetSizes,
    nets: Vec<Net>,
}

impl std::fmt::Debug for RefineNets {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RefineNets")
            .field("dir", &self.dir)
            .field("sizes", &self.sizes)
            .finish()
    }
}

impl RefineNets {
    /// Loads a model folder with the given session settings.
    ///
    /// Errors: a missing folder, manifest or network file
    /// ([`RefineError::ModelMissing`]); a manifest for another joint count
    /// ([`RefineError::JointCount`]) or frame count; a network whose inputs or
    /// outputs break the contract ([`RefineError::Model`]); ONNX Runtime not
    /// found ([`RefineError::Runtime`]).
    pub fn load(dir: impl AsRef<Path>, session: &SessionParams) -> Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        if !dir.is_dir() {
            return Err(RefineError::ModelMissing {
                file: dir.display().to_string(),
                searched: "(the folder itself)".into(),
            });
        }
        let mpath = dir.join("manifest.json");
        if !mpath.is_file() {
            return Err(RefineError::ModelMissing {
                file: "manifest.json".into(),
                searched: dir.display().to_string(),
            });
        }
        let manifest = read_manifest(&mpath)?;
        // Every file is checked for presence before ONNX Runtime is touched.
        for k in NetKind::ALL {
            if !dir.join(k.file_name()).is_file() {
                return Err(RefineError::ModelMissing {
                    file: k.file_name(),
                    searched: dir.display().to_string(),
                });
            }
        }
        let mut sizes = NetSizes::default();
        let from_manifest = |key: &str, fallback: usize| {
            manifest
                .get(key)
                .and_then(Value::as_u64)
                .map_or(fallback, |v| v as usize)
        };
        sizes.concepts = from_manifest("concepts", sizes.concepts);
        sizes.transition_latent = from_manifest("transition_latent", sizes.transition_latent);
        sizes.generator_latent = from_manifest("generator_latent", sizes.generator_latent);
        let mut nets = Vec::with_capacity(NetKind::ALL.len());
        for k in NetKind::ALL {
            let (net, open) = Net::open(&dir, k, session)?;
            let pick = |i: usize, fallback: usize| match open.get(i) {
                Some(&v) if v > 0 => v,
                _ => fallback,
            };
            match k {
                NetKind::AnchorRefinement => sizes.concepts = pick(3, sizes.concepts),
                NetKind::TransitionGenerator => {
                    sizes.transition_latent = pick(3, sizes.transition_latent)
                }
                NetKind::Generator => sizes.generator_latent = pick(1, sizes.generator_latent),
                NetKind::Evaluator => sizes.features = pick(2, sizes.features),
                _ => {}
            }
            nets.push(net);
        }
        Ok(RefineNets {
            dir,
            manifest,
            sizes,
            nets,
        })
    }

    /// Loads the folder found by [`find_model_dir`] with default session
    /// settings (2 intra-op threads, no spinning).
    pub fn load_default() -> Result<Self> {
        Self::load(find_model_dir()?, &SessionParams::default())
    }

    /// The folder the networks came from.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The manifest as JSON.
    pub fn manifest(&self) -> &Value {
        &self.manifest
    }

    /// Open sizes read from the graphs.
    pub fn sizes(&self) -> NetSizes {
        self.sizes
    }

    fn net(&self, kind: NetKind) -> Result<&Net> {
        self.nets
            .iter()
            .find(|n| n.kind == kind)
            .ok_or_else(|| RefineError::ModelMissing {
                file: kind.file_name(),
                searched: self.dir.display().to_string(),
            })
    }

    /// Runs a network on named inputs and returns every output of the
    /// contract (name, shape, data). Used by the parity tests; the typed
    /// methods below are the everyday interface.
    pub fn run_named(&self, kind: NetKind, inputs: &[NamedInput<'_>]) -> Result<Vec<NamedOutput>> {
        self.net(kind)?.run(inputs)
    }

    fn run_expect(
        &self,
        kind: NetKind,
        inputs: &[NamedInput<'_>],
        sizes: &[usize],
    ) -> Result<Vec<Vec<f32>>> {
        let out = self.run_named(kind, inputs)?;
        out.into_iter()
            .zip(sizes)
            .map(|((name, shape, data), &n)| {
                if data.len() != n {
                    return Err(RefineError::Model {
                        model: kind.file_name(),
                        reason: format!("output `{name}` has shape {shape:?}, expected {n} values"),
                    });
                }
                Ok(data)
            })
            .collect()
    }

    fn batch_of(what: &str, len: usize, per: usize) -> Result<usize> {
        if per == 0 || !len.is_multiple_of(per) || len == 0 {
            return Err(RefineError::Shape(format!(
                "{what}: {len} values is not a non-empty batch of {per}"
            )));
        }
        Ok(len / per)
    }

    /// Anchor logits (`B × 60`) of a batch of canonical clips (`B × 60 × 60`).
    pub fn anchor_logits(&self, motion: &[f32]) -> Result<Vec<f32>> {
        let per = NET_FRAMES * FRAME_FEATURES;
        let b = Self::batch_of("anchor recognition motion", motion.len(), per)?;
        let mut o = self.run_expect(
            NetKind::AnchorRecognition,
            &[("motion", vec![b, NET_FRAMES, FRAME_FEATURES], motion)],
            &[b * NET_FRAMES],
        )?;
        Ok(o.swap_remove(0))
    }

    /// Flaw logits (`B × 60 × 20`: frame, joint) of a batch of canonical
    /// clips (`B × 60 × 60`).
    pub fn flaw_logits(&self, motion: &[f32]) -> Result<Vec<f32>> {
        let per = NET_FRAMES * FRAME_FEATURES;
        let b = Self::batch_of("flaw detector motion", motion.len(), per)?;
        let mut o = self.run_expect(
            NetKind::FlawDetector,
            &[("motion", vec![b, NET_FRAMES, FRAME_FEATURES], motion)],
            &[b * NET_FRAMES * MSR_JOINTS],
        )?;
        Ok(o.swap_remove(0))
    }

    /// Anchor refinement on a batch: masked clips (`B × 60 × 60`, masked
    /// frames zero), masks and one-hot targets (`B × 60` each).
    pub fn refine_anchors(
        &self,
        motion: &[f32],
        mask: &[f32],
        target: &[f32],
    ) -> Result<AnchorRefinementOut> {
        let b = Self::batch_of(
            "anchor refinement motion",
            motion.len(),
            NET_FRAMES * FRAME_FEATURES,
        )?;
        for (n, v) in [("mask", mask), ("target", target)] {
            if v.len() != b * NET_FRAMES {
                return Err(RefineError::Shape(format!(
                    "anchor refinement {n}: expected {} values, got {}",
                    b * NET_FRAMES,
                    v.len()
                )));
            }
        }
        let mut o = self.run_expect(
            NetKind::AnchorRefinement,
            &[
                ("motion", vec![b, NET_FRAMES, FRAME_FEATURES], motion),
                ("mask", vec![b, NET_FRAMES], mask),
                ("target", vec![b, NET_FRAMES], target),
            ],
            &[b * self.sizes.concepts, b * FRAME_FEATURES],
        )?;
        let anchors = o.pop().unwrap_or_default();
        let concept_logits = o.pop().unwrap_or_default();
        Ok(AnchorRefinementOut {
            concept_logits,
            anchors,
        })
    }

    fn check_pair(what: &str, a: &[f32], b: &[f32], duration: &[f32]) -> Result<usize> {
        let n = Self::batch_of(what, a.len(), FRAME_FEATURES)?;
        if b.len() != a.len() || duration.len() != n {
            return Err(RefineError::Shape(format!(
                "{what}: anchor_a has {} values, anchor_b {}, duration {} (batch {n})",
                a.len(),
                b.len(),
                duration.len()
            )));
        }
        Ok(n)
    }

    /// Transition CVAE decoder: cubic coefficients (`B × 4 × 60`) from
    /// anchors (`B × 60` each), durations (`B`, `(b − a) / 60`) and latents
    /// (`B × Zt`; zeros give the mean transition).
    pub fn generate_transitions(
        &self,
        anchor_a: &[f32],
        anchor_b: &[f32],
        duration: &[f32],
        z: &[f32],
    ) -> Result<Vec<f32>> {
        let b = Self::check_pair("transition generator", anchor_a, anchor_b, duration)?;
        let zt = self.sizes.transition_latent;
        if z.len() != b * zt {
            return Err(RefineError::Shape(format!(
                "transition generator z: expected {} values, got {}",
                b * zt,
                z.len()
            )));
        }
        let mut o = self.run_expect(
            NetKind::TransitionGenerator,
            &[
                ("anchor_a", vec![b, FRAME_FEATURES], anchor_a),
                ("anchor_b", vec![b, FRAME_FEATURES], anchor_b),
                ("duration", vec![b, 1], duration),
                ("z", vec![b, zt], z),
            ],
            &[b * N_COEFFS * FRAME_FEATURES],
        )?;
        Ok(o.swap_remove(0))
    }

    /// Transition refinement: cubic coefficients (`B × 4 × 60`) from flawed
    /// transitions resampled to 16 frames (`B × 16 × 60`), anchors and durations.
    pub fn refine_transitions(
        &self,
        transition: &[f32],
        anchor_a: &[f32],
        anchor_b: &[f32],
        duration: &[f32],
    ) -> Result<Vec<f32>> {
        let b = Self::check_pair("transition refinement", anchor_a, anchor_b, duration)?;
        if transition.len() != b * TRANSITION_FRAMES * FRAME_FEATURES {
            return Err(RefineError::Shape(format!(
                "transition refinement transition: expected {} values, got {}",
                b * TRANSITION_FRAMES * FRAME_FEATURES,
                transition.len()
            )));
        }
        let mut o = self.run_expect(
            NetKind::TransitionRefinement,
            &[
                (
                    "transition",
                    vec![b, TRANSITION_FRAMES, FRAME_FEATURES],
                    transition,
                ),
                ("anchor_a", vec![b, FRAME_FEATURES], anchor_a),
                ("anchor_b", vec![b, FRAME_FEATURES], anchor_b),
                ("duration", vec![b, 1], duration),
            ],
            &[b * N_COEFFS * FRAME_FEATURES],
        )?;
        Ok(o.swap_remove(0))
    }

    /// Motion generator: canonical clips (`B × 60 × 60`) from one-hot
    /// actions (`B × 20`) and latents (`B × Zg`).
    pub fn generate_motion(&self, action_one_hot: &[f32], z: &[f32]) -> Result<Vec<f32>> {
        let b = Self::batch_of("generator action", action_one_hot.len(), N_ACTIONS)?;
        let zg = self.sizes.generator_latent;
        if z.len() != b * zg {
            return Err(RefineError::Shape(format!(
                "generator z: expected {} values, got {}",
                b * zg,
                z.len()
            )));
        }
        let mut o = self.run_expect(
            NetKind::Generator,
            &[
                ("action", vec![b, N_ACTIONS], action_one_hot),
                ("z", vec![b, zg], z),
            ],
            &[b * NET_FRAMES * FRAME_FEATURES],
        )?;
        Ok(o.swap_remove(0))
    }

    /// Evaluator: action logits and features of canonical clips (`B × 60 × 60`).
    pub fn evaluate(&self, motion: &[f32]) -> Result<EvaluatorOut> {
        let b = Self::batch_of(
            "evaluator motion",
            motion.len(),
            NET_FRAMES * FRAME_FEATURES,
        )?;
        let mut o = self.run_expect(
            NetKind::Evaluator,
            &[("motion", vec![b, NET_FRAMES, FRAME_FEATURES], motion)],
            &[b * N_ACTIONS, b * self.sizes.features],
        )?;
        let features = o.pop().unwrap_or_default();
        let logits = o.pop().unwrap_or_default();
        Ok(EvaluatorOut { logits, features })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_folder_and_files_are_typed_errors() {
        let e =
            RefineNets::load("/nonexistent/refine/models", &SessionParams::default()).unwrap_err();
        assert!(matches!(e, RefineError::ModelMissing { .. }), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let e = RefineNets::load(dir.path(), &SessionParams::default()).unwrap_err();
        assert!(
            matches!(&e, RefineError::ModelMissing { file, .. } if file == "manifest.json"),
            "{e}"
        );
        std::fs::write(dir.path().join("manifest.json"), "{\"joints\": 20}").unwrap();
        let e = RefineNets::load(dir.path(), &SessionParams::default()).unwrap_err();
        assert!(
            matches!(&e, RefineError::ModelMissing { file, .. } if file == "anchor_recognition.onnx"),
            "{e}"
        );
    }

    #[test]
    fn manifest_with_wrong_joint_count_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("manifest.json");
        std::fs::write(&p, "{\"joints\": 17, \"frames\": 60}").unwrap();
        assert!(matches!(
            read_manifest(&p),
            Err(RefineError::JointCount {
                expected: 20,
                got: 17,
                ..
            })
        ));
        std::fs::write(&p, "{\"representation\": {\"frames\": 64}}").unwrap();
        assert!(matches!(read_manifest(&p), Err(RefineError::Model { .. })));
        std::fs::write(&p, "[1, 2]").unwrap();
        assert!(matches!(read_manifest(&p), Err(RefineError::Model { .. })));
        std::fs::write(&p, "{\"joints\": 20, \"frames\": 60, \"features\": 60}").unwrap();
        assert!(read_manifest(&p).is_ok());
        // Sizes of the wrong type or not positive are named, not skipped.
        for (text, field) in [
            ("{\"joints\": \"20\"}", "`joints`"),
            ("{\"frames\": 60.5}", "`frames`"),
            ("{\"concepts\": 0}", "`concepts`"),
            ("{\"transition_latent\": -16}", "`transition_latent`"),
            (
                "{\"representation\": {\"features\": null}}",
                "`representation.features`",
            ),
        ] {
            std::fs::write(&p, text).unwrap();
            let e = read_manifest(&p).unwrap_err();
            let msg = e.to_string();
            assert!(
                matches!(e, RefineError::Model { .. })
                    && msg.contains(field)
                    && msg.contains(&p.display().to_string()),
                "{text}: {msg}"
            );
        }
        // The shipped manifest passes.
        let shipped =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/refine/manifest.json");
        if shipped.is_file() {
            read_manifest(&shipped).unwrap();
        }
    }

    #[test]
    fn contract_names() {
        assert_eq!(
            NetKind::AnchorRefinement.input_names(),
            vec!["motion", "mask", "target"]
        );
        assert_eq!(
            NetKind::Evaluator.output_names(),
            vec!["logits", "features"]
        );
        assert_eq!(NetKind::Generator.file_name(), "generator.onnx");
    }
}
