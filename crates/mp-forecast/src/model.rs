//! The learned forecasters, run with ONNX Runtime.
//!
//! A model folder (`models/forecast/<dataset>/`, written by
//! `cargo xtask train-forecast`) holds:
//!
//! | file | input | outputs |
//! |---|---|---|
//! | `encoder.onnx` | `frames (B, T, F)` | `latent (B, T, C)`, `pose (B, T, P)` |
//! | `ar_step.onnx` | `latents (B, 13, C)` | `next_latent (B, C)`, `next_pose (B, P)` |
//! | `pose_ar_step.onnx` | `frames (B, 13, F)` | `next_pose (B, P)` |
//! | `manifest.json` | joints, dims, channels, context, training record | |
//!
//! `F = J·D + J` (normalised coordinates then masks, see `normalize`),
//! `P = J·D`, `C` latent channels. Every network is causal with a receptive
//! field of 13 frames, so a step model sees exactly the last 13 frames.
//!
//! **AR on Φ** ([`ArSpace::Latent`]): encode the context, then repeat
//! `next = step(last 13 latents)`, reading the pose out of each predicted
//! latent. **AR on Θ** ([`ArSpace::Pose`]): repeat `next = step(last 13 frames)`
//! directly on poses; a predicted pose re-enters as a frame with every joint valid.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use mp_geom::Track;
use mp_onnx::{ModelDirs, Network, SessionParams, TensorInput};
use ndarray::{Array2, Array3};
use serde::Deserialize;

use crate::error::{ForecastError, Result};
use crate::forecaster::{check_horizon, predicted_track, Forecaster};
use crate::normalize::{push_features, BodyJoints, Normalizer};

/// Environment variable naming a model folder (holding `manifest.json`) or a
/// folder of per-dataset model folders.
pub const MODEL_DIR_ENV: &str = "MP_FORECAST_MODELS";
/// Where the committed models live, relative to the workspace root.
pub const MODEL_DIR_IN_WORKSPACE: &str = "models/forecast";

/// The parts of `manifest.json` that inference needs.
#[derive(Debug, Clone, Deserialize, PartialEq)]
pub struct Manifest {
    /// `penn_action` or `msr_action3d`.
    pub dataset: String,
    /// Joint names, in order.
    pub joints: Vec<String>,
    /// Dimensions per joint.
    pub dims: usize,
    /// Features per frame (`J·D + J`).
    pub features: usize,
    /// Pose values per frame (`J·D`).
    pub pose_values: usize,
    /// Latent channels.
    pub channels: usize,
    /// Frames the models were trained to condition on (15).
    pub context_frames: usize,
    /// Receptive field of every causal network (13).
    pub receptive_field_frames: usize,
    /// Training seed.
    #[serde(default)]
    pub seed: u64,
}

impl Manifest {
    /// Reads and checks a manifest.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| ForecastError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let m: Manifest = serde_json::from_str(&text).map_err(|e| ForecastError::Format {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        m.validate().map_err(|reason| ForecastError::Format {
            path: path.to_path_buf(),
            reason,
        })?;
        Ok(m)
    }

    /// Checks the sizes against each other: at least one joint, joint names
    /// non-empty and distinct, `dims` ≥ 1, `pose_values` = joints × `dims`,
    /// `features` = joints × `dims` + joints, `channels` ≥ 1,
    /// `receptive_field_frames` ≥ 1 and `context_frames` ≥
    /// `receptive_field_frames`. The error names the field.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let j = self.joints.len();
        if j == 0 {
            return Err("field `joints` is empty".into());
        }
        for (i, name) in self.joints.iter().enumerate() {
            if name.trim().is_empty() {
                return Err(format!("field `joints`: joint {i} has an empty name"));
            }
            if self.joints[..i].contains(name) {
                return Err(format!(
                    "field `joints`: joint {i} repeats the name `{name}`"
                ));
            }
        }
        if self.dims == 0 {
            return Err("field `dims` is 0".into());
        }
        if self.pose_values != j * self.dims {
            return Err(format!(
                "field `pose_values` is {}, {j} joints × {} dims = {}",
                self.pose_values,
                self.dims,
                j * self.dims
            ));
        }
        if self.features != j * self.dims + j {
            return Err(format!(
                "field `features` is {}, {j} joints × ({} dims + 1) = {}",
                self.features,
                self.dims,
                j * self.dims + j
            ));
        }
        if self.channels == 0 {
            return Err("field `channels` is 0".into());
        }
        if self.receptive_field_frames == 0 {
            return Err("field `receptive_field_frames` is 0".into());
        }
        if self.context_frames < self.receptive_field_frames {
            return Err(format!(
                "field `context_frames` is {}, less than `receptive_field_frames` = {}",
                self.context_frames, self.receptive_field_frames
            ));
        }
        Ok(())
    }
}

/// Candidate model folders for a data set, in search order: `MP_FORECAST_MODELS`
/// (itself or its `<dataset>` subfolder), `<workspace>/models/forecast/<dataset>`,
/// and `models/forecast/<dataset>` above the current directory (where it exists).
fn model_search(dataset: &str) -> ModelDirs {
    ModelDirs::new()
        .with_env(MODEL_DIR_ENV, &[dataset])
        .with_workspace(Path::new(MODEL_DIR_IN_WORKSPACE).join(dataset))
}

impl ForecastModels {
    /// The first candidate folder with a `manifest.json` for `dataset`.
    pub fn find_dir(dataset: &str) -> Result<PathBuf> {
        let dirs = model_search(dataset);
        dirs.find_dir_with("manifest.json")
            .ok_or_else(|| ForecastError::ModelMissing {
                file: format!("{dataset}/manifest.json"),
                searched: dirs.describe(4),
            })
    }
}

/// One network of a model folder.
struct Net {
    net: Network,
}

impl Net {
    fn open(dir: &Path, file: &str, params: &SessionParams) -> Result<Self> {
        let path = dir.join(file);
        if !path.is_file() {
            return Err(ForecastError::ModelMissing {
                file: file.to_string(),
                searched: dir.display().to_string(),
            });
        }
        Ok(Net {
            net: Network::open(&path, params)?,
        })
    }

    /// Runs the model on one f32 input; returns the named outputs as flat vectors.
    fn run(
        &self,
        input: &str,
        shape: [usize; 3],
        data: &[f32],
        outputs: &[&str],
    ) -> Result<Vec<Vec<f32>>> {
        let out = self
            .net
            .run(&[TensorInput::new(input, &shape, data)], outputs)?;
        Ok(out.into_iter().map(|o| o.data).collect())
    }
}

/// The three networks of one model folder, loaded once and shared.
pub struct ForecastModels {
    dir: PathBuf,
    manifest: Manifest,
    encoder: Net,
    step: Net,
    pose_step: Net,
}

impl std::fmt::Debug for ForecastModels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ForecastModels")
            .field("dir", &self.dir)
            .field("manifest", &self.manifest)
            .finish()
    }
}

impl ForecastModels {
    /// Loads a model folder (`manifest.json`, `encoder.onnx`, `ar_step.onnx`, `pose_ar_step.onnx`).
    pub fn load(dir: impl AsRef<Path>, session: &SessionParams) -> Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        let manifest = Manifest::read(&dir.join("manifest.json"))?;
        Ok(ForecastModels {
            encoder: Net::open(&dir, "encoder.onnx", session)?,
            step: Net::open(&dir, "ar_step.onnx", session)?,
            pose_step: Net::open(&dir, "pose_ar_step.onnx", session)?,
            dir,
            manifest,
        })
    }

    /// Loads the models of a data set from [`Self::find_dir`] with default session settings
    /// (2 intra-op threads, no spinning).
    pub fn load_default(dataset: &str) -> Result<Self> {
        Self::load(Self::find_dir(dataset)?, &SessionParams::default())
    }

    /// The manifest.
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The folder the models came from.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Encoder on a batch of normalised feature windows `(B, T, F)`: returns latents `(B·T·C)` and poses `(B·T·P)`.
    pub fn encode(
        &self,
        batch: usize,
        frames: usize,
        features: &[f32],
    ) -> Result<(Vec<f32>, Vec<f32>)> {
        let m = &self.manifest;
        self.check_len("encoder input", features.len(), batch * frames * m.features)?;
        let mut o = self.encoder.run(
            "frames",
            [batch, frames, m.features],
            features,
            &["latent", "pose"],
        )?;
        let pose = o.pop().unwrap_or_default();
        let lat = o.pop().unwrap_or_default();
        self.check_len("encoder latent", lat.len(), batch * frames * m.channels)?;
        self.check_len("encoder pose", pose.len(), batch * frames * m.pose_values)?;
        Ok((lat, pose))
    }

    /// One latent AR step on `(B, 13, C)` latents: next latents `(B·C)` and their poses `(B·P)`.
    pub fn latent_step(&self, batch: usize, latents: &[f32]) -> Result<(Vec<f32>, Vec<f32>)> {
        let m = &self.manifest;
        let rf = m.receptive_field_frames;
        self.check_len("latent step input", latents.len(), batch * rf * m.channels)?;
        let mut o = self.step.run(
            "latents",
            [batch, rf, m.channels],
            latents,
            &["next_latent", "next_pose"],
        )?;
        let pose = o.pop().unwrap_or_default();
        let lat = o.pop().unwrap_or_default();
        self.check_len("latent step output", lat.len(), batch * m.channels)?;
        self.check_len("latent step pose", pose.len(), batch * m.pose_values)?;
        Ok((lat, pose))
    }

    /// One pose AR step on `(B, 13, F)` feature frames: next poses `(B·P)`.
    pub fn pose_step(&self, batch: usize, frames: &[f32]) -> Result<Vec<f32>> {
        let m = &self.manifest;
        let rf = m.receptive_field_frames;
        self.check_len("pose step input", frames.len(), batch * rf * m.features)?;
        let mut o =
            self.pose_step
                .run("frames", [batch, rf, m.features], frames, &["next_pose"])?;
        let pose = o.pop().unwrap_or_default();
        self.check_len("pose step output", pose.len(), batch * m.pose_values)?;
        Ok(pose)
    }

    fn check_len(&self, what: &str, got: usize, expected: usize) -> Result<()> {
        if got != expected {
            return Err(ForecastError::model(
                self.dir.display().to_string(),
                format!("{what} has {got} values, expected {expected}"),
            ));
        }
        Ok(())
    }

    /// Autoregressive rollout on already-normalised feature windows `(B, T, F)`
    /// (`T` ≥ the receptive field): `horizon` predicted poses per window, `(B, H, P)`
    /// flattened, in normalised units.
    pub fn rollout_normalised(
        &self,
        space: ArSpace,
        batch: usize,
        frames: usize,
        features: &[f32],
        horizon: usize,
    ) -> Result<Vec<f32>> {
        Ok(self
            .rollout_inner(space, batch, frames, features, horizon)?
            .0)
    }

    /// [`Self::rollout_normalised`] plus, in latent space, the read-out of the
    /// last context frame's latent `(B·P)` (empty in pose space).
    fn rollout_inner(
        &self,
        space: ArSpace,
        batch: usize,
        frames: usize,
        features: &[f32],
        horizon: usize,
    ) -> Result<(Vec<f32>, Vec<f32>)> {
        let m = &self.manifest;
        let rf = m.receptive_field_frames;
        if frames < rf {
            return Err(ForecastError::TooShort {
                what: "the learned forecaster (receptive field)",
                needed: rf,
                got: frames,
            });
        }
        let (p, f, c) = (m.pose_values, m.features, m.channels);
        let mut out = vec![0f32; batch * horizon * p];
        let mut last_readout = Vec::new();
        match space {
            ArSpace::Latent => {
                let (lat, poses) = self.encode(batch, frames, features)?;
                last_readout.reserve(batch * p);
                for b in 0..batch {
                    let r = (b * frames + frames - 1) * p;
                    last_readout.extend_from_slice(&poses[r..r + p]);
                }
                // window of the last rf latents per batch item
                let mut win = vec![0f32; batch * rf * c];
                for b in 0..batch {
                    let src = &lat[(b * frames + frames - rf) * c..(b * frames + frames) * c];
                    win[b * rf * c..(b + 1) * rf * c].copy_from_slice(src);
                }
                for h in 0..horizon {
                    let (next, pose) = self.latent_step(batch, &win)?;
                    for b in 0..batch {
                        let w = &mut win[b * rf * c..(b + 1) * rf * c];
                        w.copy_within(c.., 0);
                        w[(rf - 1) * c..].copy_from_slice(&next[b * c..(b + 1) * c]);
                        out[(b * horizon + h) * p..(b * horizon + h + 1) * p]
                            .copy_from_slice(&pose[b * p..(b + 1) * p]);
                    }
                }
            }
            ArSpace::Pose => {
                let mut win = vec![0f32; batch * rf * f];
                for b in 0..batch {
                    let src = &features[(b * frames + frames - rf) * f..(b * frames + frames) * f];
                    win[b * rf * f..(b + 1) * rf * f].copy_from_slice(src);
                }
                for h in 0..horizon {
                    let pose = self.pose_step(batch, &win)?;
                    for b in 0..batch {
                        let w = &mut win[b * rf * f..(b + 1) * rf * f];
                        w.copy_within(f.., 0);
                        let last = &mut w[(rf - 1) * f..];
                        last[..p].copy_from_slice(&pose[b * p..(b + 1) * p]);
                        last[p..].fill(1.0);
                        out[(b * horizon + h) * p..(b * horizon + h + 1) * p]
                            .copy_from_slice(&pose[b * p..(b + 1) * p]);
                    }
                }
            }
        }
        Ok((out, last_readout))
    }
}

/// Where the autoregressive model runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ArSpace {
    /// AR on the latent "movie strip" Φ (the paper's model).
    Latent,
    /// AR directly on poses Θ (the paper's ablation).
    Pose,
}

/// Parameters of [`ArForecaster`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ArParams {
    /// Latest observed frames used as context. Default 15; at least the receptive field (13).
    pub context_frames: usize,
    /// Largest batch passed to ONNX Runtime at once. Default 256.
    pub max_batch: usize,
    /// Latent space only: decode the future relative to the last observed
    /// pose, `pose(t+h) = observed(t) + R(φ(t+h)) − R(φ(t))` with `R` the
    /// read-out, instead of `R(φ(t+h))` alone. The read-out's per-frame error
    /// then cancels at the start of the rollout and the prediction continues
    /// from the pose actually seen (joints missing in the last observed frame
    /// keep the plain read-out). Default true.
    pub anchored_readout: bool,
    /// Also predict the left–right mirror image of the context (x negated,
    /// `left_*` and `right_*` joints swapped), mirror that prediction back and
    /// average the two (test-time augmentation matching the mirror augmentation
    /// of training). Twice the inference cost. Ignored for models without
    /// left/right joint pairs. Default true: on the Penn Action validation
    /// clips it adds 0.3–0.5 PCK points at every horizon ≥ 5 (`docs/results/forecasting.md`).
    pub mirror_average: bool,
}

impl Default for ArParams {
    fn default() -> Self {
        ArParams {
            context_frames: 15,
            max_batch: 256,
            anchored_readout: true,
            mirror_average: true,
        }
    }
}

/// The joint that each joint becomes in the left–right mirror image
/// (`left_x` ↔ `right_x`); `None` when no joint has a partner.
fn mirror_permutation(joints: &[String]) -> Option<Vec<usize>> {
    let partner = |name: &str| -> Option<usize> {
        let other = if let Some(rest) = name.strip_prefix("left_") {
            format!("right_{rest}")
        } else if let Some(rest) = name.strip_prefix("right_") {
            format!("left_{rest}")
        } else {
            return None;
        };
        joints.iter().position(|j| *j == other)
    };
    let perm: Vec<usize> = joints
        .iter()
        .enumerate()
        .map(|(i, n)| partner(n).unwrap_or(i))
        .collect();
    perm.iter()
        .enumerate()
        .any(|(i, &p)| i != p)
        .then_some(perm)
}

/// The left–right mirror image of `track`: joint `j` takes joint `perm[j]`
/// with its first coordinate negated. An involution when `perm` is.
fn mirror_track(track: &Track, perm: &[usize]) -> Result<Track> {
    let (t, j, d) = track.positions().dim();
    let src = track.positions();
    let conf = track.confidence();
    let mut pos = Array3::zeros((t, j, d));
    let mut c = Array2::zeros((t, j));
    for f in 0..t {
        for (jj, &pj) in perm.iter().enumerate().take(j) {
            for k in 0..d {
                let v = src[[f, pj, k]];
                pos[[f, jj, k]] = if k == 0 { -v } else { v };
            }
            c[[f, jj]] = conf[[f, pj]];
        }
    }
    Ok(Track::new(
        pos,
        Some(c),
        track.fps(),
        track.units(),
        track.skeleton().clone(),
    )?)
}

/// The learned autoregressive forecaster (latent or pose space).
#[derive(Debug, Clone)]
pub struct ArForecaster {
    models: Arc<ForecastModels>,
    space: ArSpace,
    params: ArParams,
    body: BodyJoints,
    mirror: Option<Vec<usize>>,
}

impl ArForecaster {
    /// A forecaster over loaded models; checks the parameters against the models.
    pub fn new(models: Arc<ForecastModels>, space: ArSpace, params: ArParams) -> Result<Self> {
        let rf = models.manifest.receptive_field_frames;
        if params.context_frames < rf {
            return Err(ForecastError::param(
                "context_frames",
                format!(
                    "must be ≥ the receptive field ({rf} frames), got {}",
                    params.context_frames
                ),
            ));
        }
        if params.max_batch == 0 {
            return Err(ForecastError::param("max_batch", "must be ≥ 1"));
        }
        let skeleton =
            mp_geom::Skeleton::custom("model", models.manifest.joints.clone(), Vec::new(), None);
        let body = BodyJoints::from_skeleton(&skeleton);
        let mirror = mirror_permutation(&models.manifest.joints);
        Ok(ArForecaster {
            models,
            space,
            params,
            body,
            mirror,
        })
    }

    /// The models.
    pub fn models(&self) -> &Arc<ForecastModels> {
        &self.models
    }

    fn check_track(&self, past: &Track) -> Result<usize> {
        let m = &self.models.manifest;
        if past.n_joints() != m.joints.len() || past.dims() != m.dims {
            return Err(ForecastError::mismatch(
                format!("the {} forecasting model", m.dataset),
                format!("{} joints × {} dims", m.joints.len(), m.dims),
                format!("{} joints × {} dims", past.n_joints(), past.dims()),
            ));
        }
        let rf = m.receptive_field_frames;
        if past.n_frames() < rf {
            return Err(ForecastError::TooShort {
                what: "the learned forecaster (receptive field)",
                needed: rf,
                got: past.n_frames(),
            });
        }
        Ok(past.n_frames().min(self.params.context_frames))
    }

    /// Predicts a group of tracks that share the same context length (with
    /// the mirror average when [`ArParams::mirror_average`] is set).
    fn predict_group(&self, pasts: &[&Track], ctx: usize, horizon: usize) -> Result<Vec<Track>> {
        let direct = self.predict_group_once(pasts, ctx, horizon)?;
        let Some(perm) = self
            .mirror
            .as_deref()
            .filter(|_| self.params.mirror_average)
        else {
            return Ok(direct);
        };
        let mirrored = pasts
            .iter()
            .map(|t| mirror_track(t, perm))
            .collect::<Result<Vec<Track>>>()?;
        let refs: Vec<&Track> = mirrored.iter().collect();
        let back = self.predict_group_once(&refs, ctx, horizon)?;
        direct
            .into_iter()
            .zip(back)
            .map(|(a, b)| {
                let b = mirror_track(&b, perm)?;
                let (pos, conf, fps, units, skeleton) = a.into_parts();
                let avg = (pos + b.positions()) * 0.5;
                Ok(Track::new(avg, Some(conf), fps, units, skeleton)?)
            })
            .collect()
    }

    /// One rollout of a group of tracks that share the same context length.
    fn predict_group_once(
        &self,
        pasts: &[&Track],
        ctx: usize,
        horizon: usize,
    ) -> Result<Vec<Track>> {
        let m = &self.models.manifest;
        let (j, d, p) = (m.joints.len(), m.dims, m.pose_values);
        let mut feats = Vec::with_capacity(pasts.len() * ctx * m.features);
        let mut norms = Vec::with_capacity(pasts.len());
        for past in pasts {
            let t = past.n_frames();
            let norm = Normalizer::from_track_tail(past, ctx, &self.body)?;
            push_features(past, t - ctx, t, &norm, &mut feats);
            norms.push(norm);
        }
        let (mut out, last_readout) =
            self.models
                .rollout_inner(self.space, pasts.len(), ctx, &feats, horizon)?;
        if self.params.anchored_readout && self.space == ArSpace::Latent {
            anchor_readout(
                &mut out,
                &last_readout,
                &feats,
                (pasts.len(), ctx, horizon),
                (m.features, p, d),
            );
        }
        let mut res = Vec::with_capacity(pasts.len());
        for (b, (past, norm)) in pasts.iter().zip(&norms).enumerate() {
            let mut pos = Array3::zeros((horizon, j, d));
            for h in 0..horizon {
                let row = &out[(b * horizon + h) * p..(b * horizon + h + 1) * p];
                for jj in 0..j {
                    for k in 0..d {
                        let v = row[jj * d + k] as f64;
                        if !v.is_finite() {
                            return Err(ForecastError::model(
                                self.models.dir.display().to_string(),
                                format!("non-finite prediction at step {h}, joint {jj}"),
                            ));
                        }
                        pos[[h, jj, k]] = norm.inverse(k, v);
                    }
                }
            }
            res.push(predicted_track(past, pos, Array2::ones((horizon, j)))?);
        }
        Ok(res)
    }
}

impl Forecaster for ArForecaster {
    fn name(&self) -> &str {
        match (
            self.space,
            self.params.anchored_readout,
            self.params.mirror_average,
        ) {
            (ArSpace::Latent, true, true) => "ar",
            (ArSpace::Latent, true, false) => "ar_single",
            (ArSpace::Latent, false, _) => "ar_free",
            (ArSpace::Pose, _, _) => "ar_pose",
        }
    }
    fn context_frames(&self) -> Option<usize> {
        Some(self.params.context_frames)
    }
    fn predict(&self, past: &Track, horizon: usize) -> Result<Track> {
        check_horizon(horizon)?;
        let ctx = self.check_track(past)?;
        let mut v = self.predict_group(&[past], ctx, horizon)?;
        v.pop()
            .ok_or_else(|| ForecastError::model("rollout", "no prediction returned"))
    }
    fn predict_batch(&self, pasts: &[Track], horizon: usize) -> Result<Vec<Track>> {
        check_horizon(horizon)?;
        let ctxs = pasts
            .iter()
            .map(|p| self.check_track(p))
            .collect::<Result<Vec<usize>>>()?;
        let mut out: Vec<Option<Track>> = vec![None; pasts.len()];
        let mut lens: Vec<usize> = ctxs.clone();
        lens.sort_unstable();
        lens.dedup();
        for ctx in lens {
            let idx: Vec<usize> = (0..pasts.len()).filter(|&i| ctxs[i] == ctx).collect();
            for chunk in idx.chunks(self.params.max_batch) {
                let group: Vec<&Track> = chunk.iter().map(|&i| &pasts[i]).collect();
                let preds = self.predict_group(&group, ctx, horizon)?;
                for (&i, p) in chunk.iter().zip(preds) {
                    out[i] = Some(p);
                }
            }
        }
        out.into_iter()
            .map(|o| o.ok_or_else(|| ForecastError::model("rollout", "a prediction is missing")))
            .collect()
    }
}

/// Re-anchors latent-space predictions on the last observed frame (see
/// [`ArParams::anchored_readout`]). `out` is `(B, H, P)`, `last_readout`
/// `(B, P)`, `feats` the normalised context windows `(B, T, F)` whose last
/// frame holds the observed coordinates followed by the joint mask.
fn anchor_readout(
    out: &mut [f32],
    last_readout: &[f32],
    feats: &[f32],
    (batch, frames, horizon): (usize, usize, usize),
    (f, p, d): (usize, usize, usize),
) {
    for b in 0..batch {
        let last = &feats[(b * frames + frames - 1) * f..(b * frames + frames) * f];
        let (coords, mask) = last.split_at(p);
        let r = &last_readout[b * p..(b + 1) * p];
        for h in 0..horizon {
            let row = &mut out[(b * horizon + h) * p..(b * horizon + h + 1) * p];
            for (i, v) in row.iter_mut().enumerate() {
                if mask.get(i / d).copied().unwrap_or(0.0) > 0.5 {
                    *v = coords[i] + (*v - r[i]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn good() -> serde_json::Value {
        serde_json::json!({
            "dataset": "msr_action3d",
            "joints": ["a", "b", "c"],
            "dims": 3,
            "features": 12,
            "pose_values": 9,
            "channels": 8,
            "context_frames": 15,
            "receptive_field_frames": 13,
        })
    }

    fn read_with(v: &serde_json::Value) -> (PathBuf, Result<Manifest>, tempfile::TempDir) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("manifest.json");
        std::fs::write(&p, v.to_string()).unwrap();
        let r = Manifest::read(&p);
        (p, r, dir)
    }

    #[test]
    fn consistent_manifests_load() {
        let (_, r, _d) = read_with(&good());
        assert_eq!(r.unwrap().joints.len(), 3);
        for ds in ["msr_action3d", "penn_action"] {
            let p = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../models/forecast")
                .join(ds)
                .join("manifest.json");
            if p.is_file() {
                Manifest::read(&p).unwrap();
            }
        }
    }

    #[test]
    fn inconsistent_manifests_name_the_file_and_the_field() {
        let cases: [(&str, serde_json::Value, &str); 9] = [
            ("joints", serde_json::json!([]), "`joints` is empty"),
            ("joints", serde_json::json!(["a", "a", "c"]), "repeats"),
            ("joints", serde_json::json!(["a", "", "c"]), "empty name"),
            ("dims", serde_json::json!(0), "`dims` is 0"),
            ("pose_values", serde_json::json!(10), "`pose_values` is 10"),
            ("features", serde_json::json!(9), "`features` is 9"),
            ("channels", serde_json::json!(0), "`channels` is 0"),
            (
                "receptive_field_frames",
                serde_json::json!(0),
                "`receptive_field_frames` is 0",
            ),
            (
                "context_frames",
                serde_json::json!(5),
                "`context_frames` is 5",
            ),
        ];
        for (field, value, needle) in cases {
            let mut v = good();
            v[field] = value;
            let (p, r, _d) = read_with(&v);
            let e = r.unwrap_err();
            let msg = e.to_string();
            assert!(
                matches!(e, ForecastError::Format { .. })
                    && msg.contains(needle)
                    && msg.contains(&p.display().to_string()),
                "{field}: {msg}"
            );
        }
        // Wrong types and negative sizes are refused by the parser, naming the field.
        for (field, value) in [
            ("dims", serde_json::json!(-3)),
            ("channels", serde_json::json!(2.5)),
            ("context_frames", serde_json::json!("15")),
        ] {
            let mut v = good();
            v[field] = value;
            let (p, r, _d) = read_with(&v);
            let msg = r.unwrap_err().to_string();
            assert!(msg.contains(&p.display().to_string()), "{field}: {msg}");
        }
    }
}
