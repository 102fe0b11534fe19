//! The training sets of the refinement networks.
//!
//! [`build_training_set`] turns MSR Action3D clips (and, optionally, CMU BVH
//! takes cut into windows) into canonical 60-frame clips
//! ([`mp_refine::to_features`]) with, per frame, the anchor flag of the spline DP
//! segmentation of the canonical clip and the global concept id of each
//! anchor. Concepts are learned ([`learn_concepts`]) on the anchors of the
//! training subjects only, so the held-out subjects never shape them.
//! [`TrainingSet::write_npz`] writes everything `tools/refine/train.py` reads.
//!
//! Concept ids are global: `(action − 1) · concepts_per_action + cluster`,
//! where the cluster is the nearest concept of the clip's action. Clips
//! without an action (mocap windows) take the nearest concept over every
//! action.
//!
//! The flaw detector's training set — clean clips and flawed copies with a
//! per-frame, per-joint flaw mask ([`build_flaw_set`], [`FlawSet`],
//! [`mp_refine::canonical_mask`], [`mp_refine::changed_joints`]) — is in `flaw_set` and
//! re-exported here.

/// The shared MSR Action3D file, or returns from the test (recording the
/// skip) where it is absent.
#[cfg(test)]
macro_rules! msr_or_return {
    () => {
        MsrAction3D::open(mp_geom::data_or_return!(MsrAction3D::FILE)).unwrap()
    };
}

mod flaw_set;

use std::path::{Path, PathBuf};

use mp_geom::Bvh;
use mp_geom::MsrAction3D;
use mp_geom::NpzOut;
use mp_geom::{GeomError, Skeleton, Track, Units};
use ndarray::{s, Array1, Array2, Array3, ArrayView3};
use serde::{Deserialize, Serialize};

use crate::refine::RefineResult as Result;
use mp_refine::Concepts;
use mp_refine::RefineError;
use mp_refine::{
    anchor_feature, learn_concepts, AnchorSample, ConceptParams, HELD_OUT_SUBJECTS, MIN_CLIP_FRAMES,
};
use mp_refine::{
    bvh_to_msr20, canonicalize, to_features, DEFAULT_BVH_LENGTH_SCALE, FRAME_FEATURES, HIP_CENTRE,
    MSR_JOINTS, NET_FRAMES,
};
use mp_refine::{segment_track, SegmentParams};

pub use flaw_set::{build_flaw_set, FlawSet, FlawSetParams};

/// Writes a finished archive to `path` atomically, creating its folder.
fn write_npz_file(path: &Path, z: NpzOut) -> Result<()> {
    let bytes = z.finish()?;
    if let Some(dir) = path.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).map_err(|e| GeomError::io(dir, e))?;
        }
    }
    mp_geom::write_atomic(path, &bytes)?;
    Ok(())
}

/// Parameters of [`build_training_set`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DatasetParams {
    /// Segmentation that defines anchors (default λ = 200 mm).
    pub segment: SegmentParams,
    /// Concept learning (default k-means, 4 concepts per action). Its seed
    /// is replaced by [`Self::seed`].
    pub concepts: ConceptParams,
    /// Subjects held out for validation. Default `[9]`; every other MSR
    /// subject is a training subject.
    pub val_subjects: Vec<u32>,
    /// When set, only the MSR clips of these subjects are used. Default `None` (all).
    pub subjects: Option<Vec<u32>>,
    /// Frame rate the BVH takes are resampled to. Default 15 (MSR's rate).
    pub bvh_fps: f64,
    /// BVH length unit → metres. Default 1 (the CMU salsa files are in metres).
    pub bvh_length_scale: f64,
    /// Frames of one BVH window (at `bvh_fps`). Default 60.
    pub bvh_window_frames: usize,
    /// Step between BVH windows. Default 30.
    pub bvh_stride_frames: usize,
    /// Clips shorter than this (source frames) are skipped. Default 8.
    pub min_clip_frames: usize,
    /// Seed of the concept clustering.
    pub seed: u64,
}

impl Default for DatasetParams {
    fn default() -> Self {
        DatasetParams {
            segment: SegmentParams::default(),
            concepts: ConceptParams::default(),
            val_subjects: HELD_OUT_SUBJECTS.to_vec(),
            subjects: None,
            bvh_fps: 15.0,
            bvh_length_scale: DEFAULT_BVH_LENGTH_SCALE,
            bvh_window_frames: NET_FRAMES,
            bvh_stride_frames: 30,
            min_clip_frames: MIN_CLIP_FRAMES,
            seed: 0,
        }
    }
}

impl DatasetParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        self.segment.validate()?;
        self.concepts.validate()?;
        if !(self.bvh_fps.is_finite() && self.bvh_fps > 0.0) {
            return Err(RefineError::param(
                "bvh_fps",
                format!("must be finite and > 0, got {}", self.bvh_fps),
            ));
        }
        if !(self.bvh_length_scale.is_finite() && self.bvh_length_scale > 0.0) {
            return Err(RefineError::param(
                "bvh_length_scale",
                format!("must be finite and > 0, got {}", self.bvh_length_scale),
            ));
        }
        if self.bvh_window_frames < 2 {
            return Err(RefineError::param("bvh_window_frames", "must be ≥ 2"));
        }
        if self.bvh_stride_frames == 0 {
            return Err(RefineError::param("bvh_stride_frames", "must be ≥ 1"));
        }
        if self.min_clip_frames < 2 {
            return Err(RefineError::param("min_clip_frames", "must be ≥ 2"));
        }
        Ok(())
    }

    /// Concepts per action (the k of k-means or of hierarchical clustering;
    /// 0 for DBSCAN and OPTICS, which have no fixed count).
    pub fn concepts_per_action(&self) -> usize {
        self.concepts.method.max_concepts().unwrap_or(0)
    }
}

/// Number of MSR Action3D actions.
pub const MSR_ACTIONS: usize = 20;

/// Canonical clips with per-frame anchor flags and concept ids.
#[derive(Debug, Clone)]
pub struct TrainingSet {
    /// Canonical clips, `N × 60 × 60` features ([`to_features`]).
    pub motion: Array3<f32>,
    /// Action, 0-based (MSR action − 1); −1 for mocap windows.
    pub action: Array1<i64>,
    /// MSR subject; −1 for mocap windows.
    pub subject: Array1<i64>,
    /// 0 = training clip, 1 = validation clip (held-out subject).
    pub split: Array1<i64>,
    /// Frame rate of the canonical clip (60 frames over the source's duration).
    pub fps: Array1<f64>,
    /// 1 on anchor frames (first and last included), else 0, `N × 60`.
    pub anchor: Array2<i64>,
    /// Global concept id on anchor frames, −1 elsewhere, `N × 60`.
    pub concept: Array2<i64>,
    /// Clip name (`a01_s01_e01`) or `file.bvh@start_frame`.
    pub source: Vec<String>,
    /// The concepts, learned on the training subjects' anchors.
    pub concepts: Concepts,
    /// Concepts per action used in the global ids.
    pub concepts_per_action: usize,
}

/// One canonical clip before concepts are assigned.
struct Clip {
    features: ndarray::Array2<f32>,
    canonical: Array3<f64>,
    action: i64,
    subject: i64,
    split: i64,
    fps: f64,
    anchors: Vec<usize>,
    source: String,
}

fn canonical_clip(
    track: &Track,
    seg: &SegmentParams,
    what: &str,
) -> Result<(Array3<f64>, f64, Vec<usize>)> {
    let (c, frame) = canonicalize(track)?;
    let duration_s = (frame.source_frames.saturating_sub(1)) as f64 / frame.source_fps;
    let fps = if duration_s > 0.0 {
        (NET_FRAMES - 1) as f64 / duration_s
    } else {
        frame.source_fps
    };
    let t = Track::new(c.clone(), None, fps, Units::Metres, Skeleton::msr20())?;
    let s = segment_track(&t, seg).map_err(|e| match e {
        RefineError::Geom(g) => RefineError::Geom(GeomError::format(what, g.to_string())),
        other => other,
    })?;
    Ok((c, fps, s.anchors))
}

fn feature_of(c: ArrayView3<'_, f64>, frame: usize, params: &ConceptParams) -> Result<Vec<f64>> {
    let pose = c.slice(s![frame, .., ..]);
    anchor_feature(
        pose,
        Some(params.root_joint.unwrap_or(HIP_CENTRE)),
        params.scale_normalise,
    )
}

/// Builds the training set from every MSR clip and the BVH takes in `bvh_paths`.
///
/// Errors: invalid parameters; a clip or take that cannot be canonicalised
/// or segmented (named); a BVH that does not read or lacks the CMU joints;
/// too few training anchors for the concepts of an action.
pub fn build_training_set(
    msr: &MsrAction3D,
    bvh_paths: &[PathBuf],
    params: &DatasetParams,
) -> Result<TrainingSet> {
    params.validate()?;
    let mut cparams = params.concepts.clone();
    cparams.seed = params.seed;
    cparams.root_joint = Some(cparams.root_joint.unwrap_or(HIP_CENTRE));
    let per_action = params.concepts_per_action().max(1);

    let mut clips: Vec<Clip> = Vec::new();
    for info in msr.clips() {
        if info.rows.len() < params.min_clip_frames {
            continue;
        }
        if let Some(keep) = &params.subjects {
            if !keep.contains(&info.subject) {
                continue;
            }
        }
        if !(1..=MSR_ACTIONS as u32).contains(&info.action) {
            return Err(RefineError::param(
                "action",
                format!("clip {}: action {} outside 1–20", info.name, info.action),
            ));
        }
        let track = msr.clip(info.index)?;
        let (c, fps, anchors) = canonical_clip(&track, &params.segment, &info.name)?;
        clips.push(Clip {
            features: to_features(c.view()),
            canonical: c,
            action: i64::from(info.action) - 1,
            subject: i64::from(info.subject),
            split: i64::from(params.val_subjects.contains(&info.subject)),
            fps,
            anchors,
            source: info.name.clone(),
        });
    }
    for path in bvh_paths {
        let bvh = Bvh::read(path)?;
        let track = bvh_to_msr20(&bvh, params.bvh_length_scale, params.bvh_fps)?;
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        let t = track.n_frames();
        let w = params.bvh_window_frames;
        let mut start = 0;
        while start + w <= t {
            let pos = track
                .positions()
                .slice(s![start..start + w, .., ..])
                .to_owned();
            let win = Track::new(pos, None, params.bvh_fps, Units::Metres, Skeleton::msr20())?;
            let what = format!("{name}@{start}");
            let (c, fps, anchors) = canonical_clip(&win, &params.segment, &what)?;
            clips.push(Clip {
                features: to_features(c.view()),
                canonical: c,
                action: -1,
                subject: -1,
                split: 0,
                fps,
                anchors,
                source: what,
            });
            start += params.bvh_stride_frames;
        }
    }
    if clips.is_empty() {
        return Err(RefineError::TooShort {
            what: "training set (clips)".into(),
            needed: 1,
            got: 0,
        });
    }

    // Concepts from the training subjects' MSR anchors only.
    let mut samples = Vec::new();
    for clip in clips.iter().filter(|c| c.split == 0 && c.action >= 0) {
        for &a in &clip.anchors {
            samples.push(AnchorSample {
                action: (clip.action + 1) as u32,
                feature: feature_of(clip.canonical.view(), a, &cparams)?,
            });
        }
    }
    let concepts = learn_concepts(&samples, &cparams)?;

    let n = clips.len();
    let mut motion = Array3::<f32>::zeros((n, NET_FRAMES, FRAME_FEATURES));
    let mut anchor = Array2::<i64>::zeros((n, NET_FRAMES));
    let mut concept = Array2::<i64>::from_elem((n, NET_FRAMES), -1);
    for (i, clip) in clips.iter().enumerate() {
        motion.slice_mut(s![i, .., ..]).assign(&clip.features);
        for &a in &clip.anchors {
            let f = feature_of(clip.canonical.view(), a, &cparams)?;
            let id =
                if clip.action >= 0 {
                    let act = (clip.action + 1) as u32;
                    let (k, _) = concepts.action(act)?.nearest(&f).ok_or_else(|| {
                        RefineError::Clustering {
                            action: act,
                            reason: "no concepts".into(),
                        }
                    })?;
                    clip.action as usize * per_action + k
                } else {
                    let mut best: Option<(usize, f64)> = None;
                    for (act, ac) in &concepts.actions {
                        if let Some((k, d)) = ac.nearest(&f) {
                            if best.is_none_or(|(_, bd)| d < bd) {
                                best = Some(((*act as usize - 1) * per_action + k, d));
                            }
                        }
                    }
                    best.map(|b| b.0).ok_or(RefineError::UnknownAction(0))?
                };
            anchor[[i, a]] = 1;
            concept[[i, a]] = id as i64;
        }
    }
    Ok(TrainingSet {
        motion,
        action: clips.iter().map(|c| c.action).collect(),
        subject: clips.iter().map(|c| c.subject).collect(),
        split: clips.iter().map(|c| c.split).collect(),
        fps: clips.iter().map(|c| c.fps).collect(),
        anchor,
        concept,
        source: clips.iter().map(|c| c.source.clone()).collect(),
        concepts,
        concepts_per_action: per_action,
    })
}

impl TrainingSet {
    /// Number of clips.
    pub fn len(&self) -> usize {
        self.motion.dim().0
    }

    /// True when there are no clips.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Writes `motion`, `action`, `subject`, `split`, `fps`, `anchor`,
    /// `concept`, `source`, `n_concepts` and `joints`/`frames` as an npz.
    pub fn write_npz(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let mut z = NpzOut::new(true);
        z.add("motion", &self.motion)?;
        z.add("action", &self.action)?;
        z.add("subject", &self.subject)?;
        z.add("split", &self.split)?;
        z.add("fps", &self.fps)?;
        z.add("anchor", &self.anchor)?;
        z.add("concept", &self.concept)?;
        z.add(
            "n_concepts",
            &ndarray::arr0((MSR_ACTIONS * self.concepts_per_action) as i64),
        )?;
        z.add("joints", &ndarray::arr0(MSR_JOINTS as i64))?;
        z.add_strings("source", &self.source, &[self.source.len()])?;
        write_npz_file(path, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_geom::Npz;
    use mp_refine::ClusterMethod;

    fn small_params(seed: u64) -> DatasetParams {
        DatasetParams {
            concepts: ConceptParams {
                method: ClusterMethod::KMeans {
                    n_clusters: 4,
                    n_runs: 2,
                    max_iterations: 100,
                },
                gmm_n_runs: 1,
                ..ConceptParams::default()
            },
            // One training and the validation subject keep the test fast.
            subjects: Some(vec![1, 9]),
            seed,
            ..DatasetParams::default()
        }
    }

    #[test]
    fn training_set_shapes_anchors_and_concepts() {
        let msr = msr_or_return!();
        let bvh = mp_geom::data_or_return!("cmu_salsa_bvh/60_01_scaled.bvh");
        let set = build_training_set(&msr, &[bvh], &small_params(3)).unwrap();
        let n = set.len();
        let n_msr = msr
            .clips()
            .iter()
            .filter(|c| c.subject == 1 || c.subject == 9)
            .count();
        assert!(n > n_msr, "{n} clips from {n_msr} MSR clips and one take");
        assert_eq!(set.motion.dim(), (n, NET_FRAMES, FRAME_FEATURES));
        assert_eq!(set.anchor.dim(), (n, NET_FRAMES));
        assert_eq!(set.concept.dim(), (n, NET_FRAMES));
        assert_eq!(set.action.len(), n);
        assert_eq!(set.source.len(), n);
        let n_bvh = set.action.iter().filter(|&&a| a < 0).count();
        assert!(n_bvh >= 4, "{n_bvh} mocap windows");
        assert!(set.split.iter().any(|&s| s == 1));
        for i in 0..n {
            assert_eq!(set.anchor[[i, 0]], 1, "clip {i}: first frame");
            assert_eq!(set.anchor[[i, NET_FRAMES - 1]], 1, "clip {i}: last frame");
            for f in 0..NET_FRAMES {
                let c = set.concept[[i, f]];
                if set.anchor[[i, f]] == 1 {
                    assert!((0..80).contains(&c), "clip {i} frame {f}: concept {c}");
                    if set.action[i] >= 0 {
                        assert_eq!(c / 4, set.action[i], "clip {i}: concept of another action");
                    }
                } else {
                    assert_eq!(c, -1);
                }
            }
            // Canonical frame: hip centre of frame 0 at the origin.
            for k in 0..3 {
                assert!(set.motion[[i, 0, HIP_CENTRE * 3 + k]].abs() < 1e-6);
            }
        }
        for ac in set.concepts.actions.values() {
            assert_eq!(ac.centroids.len(), 4);
        }
        // Round trip through the npz.
        let dir = std::env::temp_dir().join(format!("mp-refine-ds-{}", std::process::id()));
        let p = dir.join("set.npz");
        set.write_npz(&p).unwrap();
        let z = Npz::open(&p).unwrap();
        let m = z.array_f64("motion").unwrap();
        assert_eq!(m.shape(), &[n, NET_FRAMES, FRAME_FEATURES]);
        assert!((m[[1, 5, 7]] - f64::from(set.motion[[1, 5, 7]])).abs() < 1e-9);
        assert_eq!(z.strings("source").unwrap(), set.source);
        assert_eq!(z.scalar_f64("n_concepts").unwrap(), 80.0);
        std::fs::remove_dir_all(dir).ok();

        // Same seed → same set, and the held-out subject does not shape the
        // concepts: without subject 9 (and the mocap take) they are identical.
        let mut p1 = small_params(3);
        p1.subjects = Some(vec![1]);
        let again = build_training_set(&msr, &[], &p1).unwrap();
        assert_eq!(again.concepts, set.concepts);
        let rows: Vec<usize> = (0..n).filter(|&i| set.subject[i] == 1).collect();
        assert_eq!(rows.len(), again.len());
        for (k, &i) in rows.iter().enumerate() {
            assert_eq!(
                again.motion.slice(s![k, .., ..]),
                set.motion.slice(s![i, .., ..])
            );
            assert_eq!(again.concept.row(k), set.concept.row(i));
        }
    }

    #[test]
    fn invalid_params_are_rejected() {
        let msr = msr_or_return!();
        let p = DatasetParams {
            bvh_stride_frames: 0,
            ..DatasetParams::default()
        };
        assert!(matches!(
            build_training_set(&msr, &[], &p),
            Err(RefineError::InvalidParam {
                name: "bvh_stride_frames",
                ..
            })
        ));
    }
}
