//! The flaw detector's training set.
//!
//! [`build_flaw_set`] gives every clip of the training and selection
//! subjects (and every BVH window) flawed copies ([`mp_refine::inject`])
//! next to the clean clip, canonicalised to 60 frames ([`mp_refine::motion`]),
//! with a per-frame, per-joint mask of the joints a flaw moved
//! ([`changed_joints`] on the source frames, carried to the canonical
//! frames by [`canonical_mask`]). [`FlawSet::write_npz`] writes what
//! `tools/refine/train.py --flaw-dataset` reads.

use std::path::{Path, PathBuf};

use mp_geom::Bvh;
use mp_geom::MsrAction3D;
use mp_geom::NpzOut;
use mp_geom::{GeomError, Skeleton, Track, Units};
use ndarray::{s, Array1, Array2, Array3};
use serde::{Deserialize, Serialize};

use super::write_npz_file;
use crate::refine::RefineResult as Result;
use mp_refine::RefineError;
use mp_refine::{
    bvh_to_msr20, canonical_mask, canonicalize, changed_joints, to_features,
    DEFAULT_BVH_LENGTH_SCALE, FRAME_FEATURES, MSR_JOINTS, NET_FRAMES,
};

/// Parameters of [`build_flaw_set`], the training set of the flaw detector.
///
/// Every clip of the training and selection subjects (and every BVH window,
/// as training data) gets [`Self::copies_per_clip`] flawed copies, each with
/// one or two flaws ([`mp_refine::inject`]) of random kind and random
/// size, plus the clean clip itself. Sizes are drawn from ranges around
/// the sizes of the evaluation ([`crate::refine::evaluation::RefineEvalParams`]),
/// so the detector does not learn one size per flaw.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlawSetParams {
    /// Subjects whose clips train the detector. Default `[1, 3, 5]`.
    pub train_subjects: Vec<u32>,
    /// Subjects whose clips select thresholds and epochs. Default `[7]`.
    /// Subjects in neither list (the evaluation subject 9) are never read.
    /// May be empty (a cross-validation set: every subject in
    /// [`Self::train_subjects`], folds cut by subject later).
    pub select_subjects: Vec<u32>,
    /// Flawed copies per clip. Default 20.
    pub copies_per_clip: usize,
    /// Most flaws per copy (1 or 2 drawn uniformly up to this). Default 2.
    pub max_flaws_per_copy: usize,
    /// Flawed frames of frozen, jitter and jump flaws (inclusive range). Default 2–10.
    pub frames: (usize, usize),
    /// Jitter standard deviation, metres. Default 0.02–0.08.
    pub jitter_std_m: (f64, f64),
    /// Jump distance, frames. Default 4–12.
    pub skip_frames: (usize, usize),
    /// Foot-slide frames. Default 5–14.
    pub slide_frames: (usize, usize),
    /// Foot-slide peak drift, metres. Default 0.05–0.15.
    pub slide_drift_m: (f64, f64),
    /// Half width of blended wrong anchors, frames. Default 1–3.
    pub anchor_half_width_frames: (usize, usize),
    /// A source joint is flawed when a flaw moved it by more than this
    /// (metres). Default 0.02: smaller changes are within the frame-to-frame
    /// noise of the Kinect skeletons, and labelling them teaches the
    /// detector to flag that noise in clean clips.
    pub change_epsilon_m: f64,
    /// Clips outside this frame range are skipped. Default 8–180 (as the evaluation).
    pub clip_frames: (usize, usize),
    /// BVH resampling rate. Default 15.
    pub bvh_fps: f64,
    /// BVH length unit → metres. Default 1.
    pub bvh_length_scale: f64,
    /// Frames of a BVH window. Default 60.
    pub bvh_window_frames: usize,
    /// Step between BVH windows. Default 30.
    pub bvh_stride_frames: usize,
    /// Seed of the flaws (clip `i`, copy `c` uses a stream derived from it).
    pub seed: u64,
}

impl Default for FlawSetParams {
    fn default() -> Self {
        FlawSetParams {
            train_subjects: vec![1, 3, 5],
            select_subjects: vec![7],
            copies_per_clip: 20,
            max_flaws_per_copy: 2,
            frames: (2, 10),
            jitter_std_m: (0.02, 0.08),
            skip_frames: (4, 12),
            slide_frames: (5, 14),
            slide_drift_m: (0.05, 0.15),
            anchor_half_width_frames: (1, 3),
            change_epsilon_m: 0.02,
            clip_frames: (8, 180),
            bvh_fps: 15.0,
            bvh_length_scale: DEFAULT_BVH_LENGTH_SCALE,
            bvh_window_frames: NET_FRAMES,
            bvh_stride_frames: 30,
            seed: 0,
        }
    }
}

impl FlawSetParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        if self.train_subjects.is_empty() {
            return Err(RefineError::param("train_subjects", "must not be empty"));
        }
        if let Some(s) = self
            .select_subjects
            .iter()
            .find(|s| self.train_subjects.contains(s))
        {
            return Err(RefineError::param(
                "select_subjects",
                format!("subject {s} is also a training subject"),
            ));
        }
        if self.max_flaws_per_copy == 0 {
            return Err(RefineError::param("max_flaws_per_copy", "must be ≥ 1"));
        }
        let urange = |name: &'static str, r: (usize, usize)| {
            if r.0 == 0 || r.0 > r.1 {
                Err(RefineError::param(
                    name,
                    format!("must be 1 ≤ low ≤ high, got {r:?}"),
                ))
            } else {
                Ok(())
            }
        };
        let frange = |name: &'static str, r: (f64, f64)| {
            if r.0.is_finite() && r.1.is_finite() && r.0 > 0.0 && r.0 <= r.1 {
                Ok(())
            } else {
                Err(RefineError::param(
                    name,
                    format!("must be 0 < low ≤ high, finite, got {r:?}"),
                ))
            }
        };
        urange("frames", self.frames)?;
        urange("skip_frames", self.skip_frames)?;
        urange("slide_frames", self.slide_frames)?;
        urange("anchor_half_width_frames", self.anchor_half_width_frames)?;
        urange("clip_frames", self.clip_frames)?;
        frange("jitter_std_m", self.jitter_std_m)?;
        frange("slide_drift_m", self.slide_drift_m)?;
        if !(self.change_epsilon_m.is_finite() && self.change_epsilon_m >= 0.0) {
            return Err(RefineError::param(
                "change_epsilon_m",
                format!("must be finite and ≥ 0, got {}", self.change_epsilon_m),
            ));
        }
        if !(self.bvh_fps.is_finite() && self.bvh_fps > 0.0) {
            return Err(RefineError::param("bvh_fps", "must be finite and > 0"));
        }
        if !(self.bvh_length_scale.is_finite() && self.bvh_length_scale > 0.0) {
            return Err(RefineError::param(
                "bvh_length_scale",
                "must be finite and > 0",
            ));
        }
        if self.bvh_window_frames < 2 || self.bvh_stride_frames == 0 {
            return Err(RefineError::param(
                "bvh_window_frames",
                "windows need ≥ 2 frames and a stride ≥ 1",
            ));
        }
        Ok(())
    }
}

/// Canonical clips with a per-frame, per-joint flaw mask.
#[derive(Debug, Clone)]
pub struct FlawSet {
    /// Canonical clips, `N × 60 × 60` features ([`to_features`]).
    pub motion: Array3<f32>,
    /// 1 where a canonical frame is flawed for a joint, `N × 60 × 20`.
    pub mask: Array3<u8>,
    /// 0 = training, 1 = selection.
    pub split: Array1<i64>,
    /// MSR subject; −1 for mocap windows.
    pub subject: Array1<i64>,
    /// Index of the clean clip each row was made from.
    pub clip: Array1<i64>,
    /// Flaw names joined by `+` (`clean` for clean clips).
    pub flaws: Vec<String>,
    /// Clip name (`a01_s01_e01`) or `file.bvh@start_frame`.
    pub source: Vec<String>,
}

fn random_flaw(
    rng: &mut rand_chacha::ChaCha8Rng,
    p: &FlawSetParams,
    others: &[Track],
) -> mp_refine::Flaw {
    use mp_refine::{AnchorSource, Flaw, FootSlide};
    use rand::Rng;
    let ur = |rng: &mut rand_chacha::ChaCha8Rng, r: (usize, usize)| rng.random_range(r.0..=r.1);
    let fr = |rng: &mut rand_chacha::ChaCha8Rng, r: (f64, f64)| {
        if r.1 > r.0 {
            rng.random_range(r.0..r.1)
        } else {
            r.0
        }
    };
    let kinds = if others.is_empty() { 5 } else { 6 };
    match rng.random_range(0..kinds) {
        0 => Flaw::Frozen {
            frames: ur(rng, p.frames),
        },
        1 => Flaw::Jitter {
            frames: ur(rng, p.frames),
            std_m: fr(rng, p.jitter_std_m),
        },
        2 => Flaw::Jump {
            frames: ur(rng, p.frames),
            skip_frames: ur(rng, p.skip_frames),
        },
        3 => Flaw::FootSlide(FootSlide {
            frames: ur(rng, p.slide_frames),
            drift_m: fr(rng, p.slide_drift_m),
            up_axis: 1,
        }),
        4 => Flaw::WrongAnchor {
            half_width_frames: ur(rng, p.anchor_half_width_frames),
            source: AnchorSource::OtherPhase,
        },
        _ => Flaw::WrongAnchor {
            half_width_frames: ur(rng, p.anchor_half_width_frames),
            source: AnchorSource::OtherClip(others[rng.random_range(0..others.len())].clone()),
        },
    }
}

/// Builds the flaw detector's training set from the MSR clips of
/// [`FlawSetParams::train_subjects`] and [`FlawSetParams::select_subjects`]
/// and the BVH takes in `bvh_paths` (training split). Clips of other
/// subjects are never read. A wrong anchor "from another clip" takes a clip
/// of another action of the same subject (mocap windows get none). For
/// cross-validation every subject can be a training subject with no
/// selection subject: the rows carry their subject, and the folds are cut
/// from it (`tools/refine/train.py --flaw-train-subjects`).
///
/// Errors: invalid parameters; a clip or take that cannot be read or
/// canonicalised (named); no clip at all.
pub fn build_flaw_set(
    msr: &MsrAction3D,
    bvh_paths: &[PathBuf],
    params: &FlawSetParams,
) -> Result<FlawSet> {
    use rand::{Rng, SeedableRng};
    params.validate()?;
    // (track, action (0 = none), subject (−1 = mocap), split, name)
    let mut clean: Vec<(Track, u32, i64, i64, String)> = Vec::new();
    for (split, subjects) in [(0i64, &params.train_subjects), (1, &params.select_subjects)] {
        let idx = msr.clips_of_subjects(subjects, params.clip_frames.0, params.clip_frames.1);
        for i in idx {
            let info = msr.clip_info(i)?;
            let t = mp_refine::full_confidence(&msr.clip(i)?)?;
            clean.push((
                t,
                info.action,
                i64::from(info.subject),
                split,
                info.name.clone(),
            ));
        }
    }
    for path in bvh_paths {
        let bvh = Bvh::read(path)?;
        let track = bvh_to_msr20(&bvh, params.bvh_length_scale, params.bvh_fps)?;
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        let w = params.bvh_window_frames;
        let mut start = 0;
        while start + w <= track.n_frames() {
            let pos = track
                .positions()
                .slice(s![start..start + w, .., ..])
                .to_owned();
            let win = Track::new(pos, None, params.bvh_fps, Units::Metres, Skeleton::msr20())?;
            clean.push((win, 0, -1, 0, format!("{name}@{start}")));
            start += params.bvh_stride_frames;
        }
    }
    if clean.is_empty() {
        return Err(RefineError::TooShort {
            what: "flaw set (clips)".into(),
            needed: 1,
            got: 0,
        });
    }
    let mut motion: Vec<Array2<f32>> = Vec::new();
    let mut masks: Vec<Array2<bool>> = Vec::new();
    let (mut split, mut subject, mut clip_i) = (Vec::new(), Vec::new(), Vec::new());
    let (mut flaws, mut source) = (Vec::new(), Vec::new());
    for (ci, (track, action, subj, sp, name)) in clean.iter().enumerate() {
        // Other-action clips of the same subject (MSR only) for wrong anchors,
        // so that no row carries a pose of another subject (cross-validation
        // folds split by subject); mocap windows get the other five kinds.
        let others: Vec<Track> = clean
            .iter()
            .filter(|o| *subj >= 0 && o.2 == *subj && o.1 != 0 && o.1 != *action)
            .step_by(7)
            .map(|o| o.0.clone())
            .collect();
        let mut push = |t: &Track, m: Array2<bool>, what: String| -> Result<()> {
            let (c, _) = canonicalize(t).map_err(|e| match e {
                RefineError::Geom(g) => RefineError::Geom(GeomError::format(name, g.to_string())),
                other => other,
            })?;
            motion.push(to_features(c.view()));
            masks.push(canonical_mask(&m, NET_FRAMES));
            split.push(*sp);
            subject.push(*subj);
            clip_i.push(ci as i64);
            flaws.push(what);
            source.push(name.clone());
            Ok(())
        };
        let none = Array2::from_elem((track.n_frames(), MSR_JOINTS), false);
        push(track, none, "clean".into())?;
        for copy in 0..params.copies_per_clip {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(
                params
                    .seed
                    .wrapping_mul(1_000_003)
                    .wrapping_add((ci * 1009 + copy) as u64),
            );
            let n = rng.random_range(1..=params.max_flaws_per_copy);
            let mut cur = track.clone();
            let mut names = Vec::new();
            for _ in 0..n {
                let flaw = random_flaw(&mut rng, params, &others);
                let seed: u64 = rng.random();
                match mp_refine::inject(&cur, &flaw, seed) {
                    Ok(inj) => {
                        cur = inj.track;
                        names.push(flaw.name());
                    }
                    Err(RefineError::TooShort { .. }) => {}
                    Err(e) => return Err(e),
                }
            }
            let m = changed_joints(track, &cur, params.change_epsilon_m);
            if names.is_empty() || !m.iter().any(|&v| v) {
                continue;
            }
            push(&cur, m, names.join("+"))?;
        }
    }
    let n = motion.len();
    let mut mo = Array3::<f32>::zeros((n, NET_FRAMES, FRAME_FEATURES));
    let mut ma = Array3::<u8>::zeros((n, NET_FRAMES, MSR_JOINTS));
    for i in 0..n {
        mo.slice_mut(s![i, .., ..]).assign(&motion[i]);
        ma.slice_mut(s![i, .., ..]).assign(&masks[i].mapv(u8::from));
    }
    Ok(FlawSet {
        motion: mo,
        mask: ma,
        split: Array1::from(split),
        subject: Array1::from(subject),
        clip: Array1::from(clip_i),
        flaws,
        source,
    })
}

impl FlawSet {
    /// Rows.
    pub fn len(&self) -> usize {
        self.motion.dim().0
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Writes `motion`, `mask`, `split`, `subject`, `clip`, `flaws`, `source`
    /// and `joints` as an npz (read by `tools/refine/train.py --flaw-dataset`).
    pub fn write_npz(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let mut z = NpzOut::new(true);
        z.add("motion", &self.motion)?;
        z.add("mask", &self.mask)?;
        z.add("split", &self.split)?;
        z.add("subject", &self.subject)?;
        z.add("clip", &self.clip)?;
        z.add("joints", &ndarray::arr0(MSR_JOINTS as i64))?;
        z.add_strings("flaws", &self.flaws, &[self.flaws.len()])?;
        z.add_strings("source", &self.source, &[self.source.len()])?;
        write_npz_file(path, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_refine::HIP_CENTRE;

    #[test]
    fn canonical_mask_flags_the_frames_whose_support_changed() {
        // 31 source frames → 60 canonical: frame f reads source f/2 (rounded both ways).
        let mut src = Array2::from_elem((31, 2), false);
        src[[10, 1]] = true;
        let m = canonical_mask(&src, 60);
        let on: Vec<usize> = (0..60).filter(|&f| m[[f, 1]]).collect();
        // u = f·30/59: frames with 9 < u < 11 read source 10.
        let want: Vec<usize> = (0..60)
            .filter(|&f| {
                let u = f as f64 * 30.0 / 59.0;
                u > 9.0 && u < 11.0
            })
            .collect();
        assert_eq!(on, want);
        assert!(!m.column(0).iter().any(|&v| v));
        // Identity when the frame counts agree.
        let mut s60 = Array2::from_elem((60, 1), false);
        s60[[7, 0]] = true;
        assert_eq!(canonical_mask(&s60, 60), s60);
    }

    #[test]
    fn flaw_set_marks_flawed_joints_and_never_reads_the_evaluation_subject() {
        let msr = msr_or_return!();
        let p = FlawSetParams {
            train_subjects: vec![1],
            select_subjects: vec![7],
            copies_per_clip: 2,
            clip_frames: (8, 40),
            seed: 5,
            ..FlawSetParams::default()
        };
        let set = build_flaw_set(&msr, &[], &p).unwrap();
        let n = set.len();
        assert_eq!(set.motion.dim(), (n, NET_FRAMES, FRAME_FEATURES));
        assert_eq!(set.mask.dim(), (n, NET_FRAMES, MSR_JOINTS));
        assert!(set.subject.iter().all(|&s| s == 1 || s == 7));
        assert!(set.split.iter().any(|&s| s == 1) && set.split.iter().any(|&s| s == 0));
        for i in 0..n {
            let flagged: u32 = set
                .mask
                .slice(s![i, .., ..])
                .iter()
                .map(|&v| u32::from(v))
                .sum();
            if set.flaws[i] == "clean" {
                assert_eq!(flagged, 0, "row {i}");
            } else {
                assert!(flagged > 0, "row {i}: {}", set.flaws[i]);
                // Foot slides move the feet only.
                if set.flaws[i] == "foot_slide" {
                    for f in 0..NET_FRAMES {
                        assert_eq!(set.mask[[i, f, HIP_CENTRE]], 0, "row {i} frame {f}");
                    }
                }
            }
        }
        let again = build_flaw_set(&msr, &[], &p).unwrap();
        assert_eq!(again.mask, set.mask);
        assert_eq!(again.flaws, set.flaws);
        let bad = FlawSetParams {
            select_subjects: vec![1],
            train_subjects: vec![1],
            ..FlawSetParams::default()
        };
        assert!(matches!(
            build_flaw_set(&msr, &[], &bad),
            Err(RefineError::InvalidParam {
                name: "select_subjects",
                ..
            })
        ));
    }
}
