//! Injection of known flaws into clean motion.
//!
//! Each flaw is placed at a seeded random position
//! (`ChaCha8Rng::seed_from_u64(seed)`) and returns the flawed track with a
//! mask of the frames it changed: frames outside the mask are bit-identical
//! to the clean track. Distances are in track units (metres for 3D tracks);
//! "horizontal" means the two axes other than [`FootSlide::up_axis`].
//!
//! The flaws imitate what synthesis produces (paper 004, Fig. 1):
//! a wrong anchor pose, frozen frames, jitter, a temporal discontinuity
//! (the motion skips ahead, then back), and foot sliding.

#![allow(clippy::needless_range_loop, clippy::manual_memcpy)]

use mp_geom::Track;
use ndarray::{s, Array3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::error::{RefineError, Result};

/// Where a wrong anchor pose comes from.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum AnchorSource {
    /// A frame of the same clip at least a third of its length away (another phase).
    OtherPhase,
    /// A random frame of another clip (e.g. a different action), with its
    /// root moved onto the clean pose's root (mean of the joints).
    OtherClip(Track),
}

/// A flaw and its size.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Flaw {
    /// `frames` consecutive frames repeat the pose before them.
    Frozen {
        /// Frozen frames.
        frames: usize,
    },
    /// Gaussian noise of standard deviation `std_m` on every joint and axis
    /// of `frames` consecutive frames.
    Jitter {
        /// Noisy frames.
        frames: usize,
        /// Noise standard deviation, track units.
        std_m: f64,
    },
    /// `frames` consecutive frames show the motion `skip_frames` later
    /// (clamped to the last frame): a jump ahead and back.
    Jump {
        /// Frames shown out of time.
        frames: usize,
        /// How far ahead they come from.
        skip_frames: usize,
    },
    /// Foot joints drift horizontally along a random direction for `frames`
    /// frames, with a triangular profile peaking at `drift_m`.
    FootSlide(FootSlide),
    /// The pose at a random interior frame is replaced by a wrong one,
    /// blended into the `half_width_frames` frames on each side with a
    /// raised-cosine weight.
    WrongAnchor {
        /// Frames on each side of the anchor that are blended.
        half_width_frames: usize,
        /// Where the wrong pose comes from.
        source: AnchorSource,
    },
}

/// Foot-sliding parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FootSlide {
    /// Sliding frames.
    pub frames: usize,
    /// Peak drift, track units.
    pub drift_m: f64,
    /// Vertical axis (1 = y up, MSR Action3D's camera space).
    pub up_axis: usize,
}

impl Flaw {
    /// Short name for reports.
    pub fn name(&self) -> &'static str {
        match self {
            Flaw::Frozen { .. } => "frozen",
            Flaw::Jitter { .. } => "jitter",
            Flaw::Jump { .. } => "jump",
            Flaw::FootSlide(_) => "foot_slide",
            Flaw::WrongAnchor {
                source: AnchorSource::OtherPhase,
                ..
            } => "wrong_anchor_phase",
            Flaw::WrongAnchor {
                source: AnchorSource::OtherClip(_),
                ..
            } => "wrong_anchor_clip",
        }
    }

    /// Frames the flaw needs at least.
    fn needed_frames(&self) -> usize {
        match self {
            Flaw::Frozen { frames } => frames + 2,
            Flaw::Jitter { frames, .. } => frames + 2,
            Flaw::Jump {
                frames,
                skip_frames,
            } => frames + skip_frames + 2,
            Flaw::FootSlide(f) => f.frames + 2,
            Flaw::WrongAnchor {
                half_width_frames, ..
            } => 2 * half_width_frames + 3,
        }
    }

    /// Checks the sizes.
    pub fn validate(&self) -> Result<()> {
        let pos = |name: &'static str, v: usize| {
            if v == 0 {
                Err(RefineError::param(name, "must be ≥ 1"))
            } else {
                Ok(())
            }
        };
        let fin = RefineError::check_positive;
        match self {
            Flaw::Frozen { frames } => pos("frames", *frames),
            Flaw::Jitter { frames, std_m } => {
                pos("frames", *frames)?;
                fin("std_m", *std_m)
            }
            Flaw::Jump {
                frames,
                skip_frames,
            } => {
                pos("frames", *frames)?;
                pos("skip_frames", *skip_frames)
            }
            Flaw::FootSlide(f) => {
                pos("frames", f.frames)?;
                fin("drift_m", f.drift_m)
            }
            Flaw::WrongAnchor { .. } => Ok(()),
        }
    }
}

/// A flawed track and the frames that were changed.
#[derive(Debug, Clone, PartialEq)]
pub struct Injected {
    /// The flawed track (same shape, confidence, frame rate as the clean one).
    pub track: Track,
    /// `mask[t]` is true when frame t was changed.
    pub mask: Vec<bool>,
}

/// Indices of joints whose name contains `ankle`, `foot`, `heel` or `toe`.
pub fn foot_joints(track: &Track) -> Vec<usize> {
    track
        .skeleton()
        .joints
        .iter()
        .enumerate()
        .filter(|(_, n)| {
            let n = n.to_lowercase();
            ["ankle", "foot", "heel", "toe"]
                .iter()
                .any(|k| n.contains(k))
        })
        .map(|(i, _)| i)
        .collect()
}

/// Injects one flaw into `clean` at a position drawn from `seed`.
///
/// Errors: invalid flaw sizes; a track shorter than the flaw needs; for
/// foot sliding, a skeleton without foot joints or an `up_axis` outside the
/// dimensions; for a wrong anchor from another clip, a joint or dimension
/// count that differs from `clean`'s.
pub fn inject(clean: &Track, flaw: &Flaw, seed: u64) -> Result<Injected> {
    flaw.validate()?;
    let t = clean.n_frames();
    let need = flaw.needed_frames();
    if t < need {
        return Err(RefineError::TooShort {
            what: format!("flaw `{}`", flaw.name()),
            needed: need,
            got: t,
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pos: Array3<f64> = clean.positions().to_owned();
    let (_, nj, d) = pos.dim();
    let mut mask = vec![false; t];
    match flaw {
        Flaw::Frozen { frames } => {
            let a = rng.random_range(1..=t - frames - 1);
            let held = clean.positions().slice(s![a - 1, .., ..]).to_owned();
            for f in a..a + frames {
                pos.slice_mut(s![f, .., ..]).assign(&held);
                mask[f] = true;
            }
        }
        Flaw::Jitter { frames, std_m } => {
            let a = rng.random_range(1..=t - frames - 1);
            let normal =
                Normal::new(0.0, *std_m).map_err(|e| RefineError::param("std_m", e.to_string()))?;
            for f in a..a + frames {
                for v in pos.slice_mut(s![f, .., ..]).iter_mut() {
                    *v += normal.sample(&mut rng);
                }
                mask[f] = true;
            }
        }
        Flaw::Jump {
            frames,
            skip_frames,
        } => {
            let a = rng.random_range(1..=t - frames - skip_frames - 1);
            for f in a..a + frames {
                let src = (f + skip_frames).min(t - 1);
                let p = clean.positions().slice(s![src, .., ..]).to_owned();
                pos.slice_mut(s![f, .., ..]).assign(&p);
                mask[f] = true;
            }
        }
        Flaw::FootSlide(fs) => {
            if fs.up_axis >= d || d < 2 {
                return Err(RefineError::param(
                    "up_axis",
                    format!("axis {} is outside 0..{d}", fs.up_axis),
                ));
            }
            let feet = foot_joints(clean);
            if feet.is_empty() {
                return Err(RefineError::param(
                    "FootSlide",
                    format!("skeleton `{}` names no foot joint", clean.skeleton().name),
                ));
            }
            let a = rng.random_range(1..=t - fs.frames - 1);
            let theta: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let horiz: Vec<usize> = (0..d).filter(|&k| k != fs.up_axis).collect();
            let mut dir = vec![0.0; d];
            if let [h0, h1, ..] = horiz[..] {
                dir[h0] = theta.cos();
                dir[h1] = theta.sin();
            } else if let [h0] = horiz[..] {
                dir[h0] = 1.0;
            }
            let n = fs.frames as f64;
            for (i, f) in (a..a + fs.frames).enumerate() {
                // Triangle 0 → 1 → 0 over the block, never 0 inside it.
                let x = (i as f64 + 1.0) / (n + 1.0);
                let amp = fs.drift_m * (1.0 - (2.0 * x - 1.0).abs());
                for &j in &feet {
                    for k in 0..d {
                        pos[[f, j, k]] += amp * dir[k];
                    }
                }
                mask[f] = true;
            }
        }
        Flaw::WrongAnchor {
            half_width_frames,
            source,
        } => {
            let h = *half_width_frames;
            let a = rng.random_range(h + 1..=t - h - 2);
            let wrong: Array3<f64> = match source {
                AnchorSource::OtherPhase => {
                    let min_gap = (t / 3).max(1);
                    let cands: Vec<usize> = (0..t).filter(|&b| b.abs_diff(a) >= min_gap).collect();
                    let b = cands[rng.random_range(0..cands.len())];
                    clean.positions().slice(s![b..b + 1, .., ..]).to_owned()
                }
                AnchorSource::OtherClip(other) => {
                    if other.n_joints() != nj {
                        return Err(RefineError::JointCount {
                            what: "wrong-anchor source clip".into(),
                            expected: nj,
                            got: other.n_joints(),
                        });
                    }
                    if other.dims() != d || other.n_frames() == 0 {
                        return Err(RefineError::Dims {
                            what: "wrong-anchor source clip".into(),
                            expected: d,
                            got: other.dims(),
                        });
                    }
                    let b = rng.random_range(0..other.n_frames());
                    let mut p = other.positions().slice(s![b..b + 1, .., ..]).to_owned();
                    for k in 0..d {
                        let shift = clean.positions().slice(s![a, .., k]).mean().unwrap_or(0.0)
                            - p.slice(s![0, .., k]).mean().unwrap_or(0.0);
                        p.slice_mut(s![0, .., k]).mapv_inplace(|v| v + shift);
                    }
                    p
                }
            };
            for f in a - h..=a + h {
                let x = (f as f64 - a as f64) / (h as f64 + 1.0);
                let w = 0.5 * (1.0 + (std::f64::consts::PI * x).cos());
                for j in 0..nj {
                    for k in 0..d {
                        let c = clean.positions()[[f, j, k]];
                        pos[[f, j, k]] = (1.0 - w) * c + w * wrong[[0, j, k]];
                    }
                }
                mask[f] = true;
            }
        }
    }
    // Only frames that really changed are flawed.
    for (f, m) in mask.iter_mut().enumerate() {
        if *m && pos.slice(s![f, .., ..]) == clean.positions().slice(s![f, .., ..]) {
            *m = false;
        }
    }
    let track = Track::new(
        pos,
        Some(clean.confidence().to_owned()),
        clean.fps(),
        clean.units(),
        clean.skeleton().clone(),
    )?;
    Ok(Injected { track, mask })
}
