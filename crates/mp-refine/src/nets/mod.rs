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
//!
//! The contract itself (names, shapes, the manifest) is in `contract`.

use std::path::{Path, PathBuf};

use mp_onnx::{Network, SessionParams, TensorInput};

use crate::error::{RefineError, Result};
use crate::motion::{FRAME_FEATURES, MSR_JOINTS, NET_FRAMES};
use serde_json::Value;

mod contract;
mod generate;

use contract::check_spec;
pub use contract::*;
pub use generate::generate_clips;

/// One network of the folder and its place in the contract.
struct Net {
    kind: NetKind,
    net: Network,
}

/// A named input: name, shape, row-major data.
pub(crate) type NamedInput<'a> = (&'a str, Vec<usize>, &'a [f32]);
/// A named output: name, shape, row-major data.
pub(crate) type NamedOutput = (String, Vec<usize>, Vec<f32>);

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
        let inputs: Vec<TensorInput<'_>> = inputs
            .iter()
            .map(|(name, shape, data)| TensorInput::new(name, shape, data))
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

    /// Loads the folder found by [`RefineNets::find_dir`] with default session
    /// settings (2 intra-op threads, no spinning).
    pub fn load_default() -> Result<Self> {
        Self::load(RefineNets::find_dir()?, &SessionParams::default())
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
