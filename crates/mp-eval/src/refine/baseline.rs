//! The non-learned refinement baseline ([`mp_refine::refine`]) on
//! MSR Action3D clips with injected flaws: MPJPE to the clean clip before
//! and after.

use mp_geom::nanmean;
use mp_geom::MsrAction3D;
use mp_geom::Track;
use serde::{Deserialize, Serialize};

use crate::refine::RefineResult as Result;
use mp_refine::RefineError;
use mp_refine::{full_confidence, refine, RefineParams};
use mp_refine::{inject, AnchorSource, Flaw, FootSlide, Injected};
use mp_refine::{per_frame_error, segment_track};

/// A flaw to inject in [`evaluate_injected`].
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum EvalFlaw {
    /// The same flaw for every clip.
    Fixed(Flaw),
    /// A wrong anchor pose taken from a clip of a different action.
    WrongAnchorOtherAction {
        /// Blended frames on each side.
        half_width_frames: usize,
    },
}

impl EvalFlaw {
    fn name(&self) -> &'static str {
        match self {
            EvalFlaw::Fixed(f) => f.name(),
            EvalFlaw::WrongAnchorOtherAction { .. } => "wrong_anchor_clip",
        }
    }

    /// Injects this flaw into `clean`, clip `clip` of `data` (of action
    /// `action`), with seed `seed + clip`. A wrong anchor of another action
    /// comes from the first clip of a different action from half-way round
    /// the data set. `None` when the clip is too short for the flaw or the
    /// flaw changed no frame.
    pub fn inject_into(
        &self,
        clean: &Track,
        data: &MsrAction3D,
        clip: usize,
        action: u32,
        seed: u64,
    ) -> Result<Option<Injected>> {
        let flaw = match self {
            EvalFlaw::Fixed(f) => f.clone(),
            EvalFlaw::WrongAnchorOtherAction { half_width_frames } => {
                let n = data.len();
                let mut d = (clip + n / 2) % n;
                while data.clip_info(d)?.action == action {
                    d = (d + 1) % n;
                }
                Flaw::WrongAnchor {
                    half_width_frames: *half_width_frames,
                    source: AnchorSource::OtherClip(full_confidence(&data.clip(d)?)?),
                }
            }
        };
        let inj = match inject(clean, &flaw, seed.wrapping_add(clip as u64)) {
            Ok(x) => x,
            Err(RefineError::TooShort { .. }) => return Ok(None),
            Err(e) => return Err(e),
        };
        Ok(inj.mask.iter().any(|&m| m).then_some(inj))
    }
}

/// Parameters of [`evaluate_injected`].
#[derive(Debug, Clone, PartialEq)]
pub struct EvalParams {
    /// Clips evaluated: every `clip_stride`-th clip. Default 1.
    pub clip_stride: usize,
    /// At most this many clips. Default `None` (all).
    pub max_clips: Option<usize>,
    /// Flaws, each injected once per clip.
    pub flaws: Vec<EvalFlaw>,
    /// Refinement parameters.
    pub refine: RefineParams,
    /// Learn anchor concepts from the clips *not* evaluated and use their
    /// GMM scores in the detection. Default false.
    pub use_concepts: bool,
    /// Concept parameters (when `use_concepts`).
    pub concepts: mp_refine::ConceptParams,
    /// Seed; clip `i` uses `seed + i`.
    pub seed: u64,
}

impl Default for EvalParams {
    fn default() -> Self {
        EvalParams {
            clip_stride: 1,
            max_clips: None,
            flaws: vec![
                EvalFlaw::Fixed(Flaw::Frozen { frames: 6 }),
                EvalFlaw::Fixed(Flaw::Jitter {
                    frames: 4,
                    std_m: 0.05,
                }),
                EvalFlaw::Fixed(Flaw::Jump {
                    frames: 4,
                    skip_frames: 8,
                }),
                EvalFlaw::Fixed(Flaw::FootSlide(FootSlide {
                    frames: 10,
                    drift_m: 0.1,
                    up_axis: 1,
                })),
                EvalFlaw::Fixed(Flaw::WrongAnchor {
                    half_width_frames: 2,
                    source: AnchorSource::OtherPhase,
                }),
                EvalFlaw::WrongAnchorOtherAction {
                    half_width_frames: 2,
                },
            ],
            refine: RefineParams::default(),
            use_concepts: false,
            concepts: mp_refine::ConceptParams::default(),
            seed: 0,
        }
    }
}

/// Figures for one flaw kind (means over clips; distances in track units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlawReport {
    /// Flaw name.
    pub flaw: String,
    /// Clips evaluated (clips too short for the flaw are skipped).
    pub n_clips: usize,
    /// MPJPE (no alignment) flawed vs clean, all frames.
    pub mpjpe_before_m: f64,
    /// MPJPE refined vs clean, all frames.
    pub mpjpe_after_m: f64,
    /// MPJPE flawed vs clean over the flawed frames only.
    pub masked_before_m: f64,
    /// MPJPE refined vs clean over the flawed frames only.
    pub masked_after_m: f64,
    /// Share of flagged frames that are flawed.
    pub detection_precision: f64,
    /// Share of flawed frames that are flagged.
    pub detection_recall: f64,
}

/// Result of [`evaluate_injected`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    /// Clips evaluated.
    pub n_clips: usize,
    /// Mean anchors per clip of the spline segmentation (first/last included).
    pub mean_anchors: f64,
    /// Mean frames per clip.
    pub mean_frames: f64,
    /// MPJPE (no alignment) of the spline reconstruction, mean over clips.
    pub reconstruction_mpjpe_m: f64,
    /// MPJPE between a clean clip and its refinement (how much refinement
    /// disturbs clean motion), mean over clips.
    pub clean_change_m: f64,
    /// Per flaw.
    pub flaws: Vec<FlawReport>,
}

/// Injects each flaw of `params` into MSR Action3D clips, refines with
/// [`refine`], and reports MPJPE to the clean clip before and after.
pub fn evaluate_injected(data: &MsrAction3D, params: &EvalParams) -> Result<EvalReport> {
    params.refine.validate()?;
    if params.clip_stride == 0 {
        return Err(RefineError::param("clip_stride", "must be ≥ 1"));
    }
    let mut idx: Vec<usize> = (0..data.len()).step_by(params.clip_stride).collect();
    if let Some(m) = params.max_clips {
        idx.truncate(m);
    }
    if idx.is_empty() {
        return Err(RefineError::TooShort {
            what: "evaluate_injected (clips)".into(),
            needed: 1,
            got: 0,
        });
    }
    let concepts = if params.use_concepts {
        let mut samples = Vec::new();
        for i in (0..data.len()).filter(|i| !idx.contains(i)) {
            let tr = full_confidence(&data.clip(i)?)?;
            if tr.n_frames() < 2 {
                continue;
            }
            let action = data.clip_info(i)?.action;
            samples.extend(mp_refine::collect_anchors(
                &tr,
                action,
                &params.refine.segment,
                &params.concepts,
            )?);
        }
        Some(mp_refine::learn_concepts(&samples, &params.concepts)?)
    } else {
        None
    };
    let mut anchors = Vec::new();
    let mut frames = Vec::new();
    let mut recon = Vec::new();
    let mut clean_change = Vec::new();
    let nf = params.flaws.len();
    let mut acc: Vec<[Vec<f64>; 6]> = (0..nf).map(|_| Default::default()).collect();
    for &i in &idx {
        let clean = full_confidence(&data.clip(i)?)?;
        let info = data.clip_info(i)?;
        let cref = concepts
            .as_ref()
            .filter(|c| c.actions.contains_key(&info.action))
            .map(|c| (c, info.action));
        let seg = segment_track(&clean, &params.refine.segment)?;
        anchors.push(seg.anchors.len() as f64);
        frames.push(clean.n_frames() as f64);
        recon.push(mp_refine::mpjpe_abs(
            &seg.reconstruct_track(&clean)?,
            &clean,
        )?);
        let rc = refine(&clean, cref, &params.refine)?;
        clean_change.push(mp_refine::mpjpe_abs(&rc.track, &clean)?);
        for (fi, ef) in params.flaws.iter().enumerate() {
            let Some(inj) = ef.inject_into(&clean, data, i, info.action, params.seed)? else {
                continue;
            };
            let r = refine(&inj.track, cref, &params.refine)?;
            let before = per_frame_error(inj.track.positions(), &clean);
            let after = per_frame_error(r.track.positions(), &clean);
            let fin = |v: &[f64], sel: &dyn Fn(usize) -> bool| {
                let x: Vec<f64> = v
                    .iter()
                    .enumerate()
                    .filter(|(f, e)| sel(*f) && e.is_finite())
                    .map(|(_, e)| *e)
                    .collect();
                nanmean(&x)
            };
            let all = |_: usize| true;
            let masked = |f: usize| inj.mask[f];
            let tp = (0..clean.n_frames())
                .filter(|&f| inj.mask[f] && r.flagged[f])
                .count() as f64;
            let n_flag = r.flagged.iter().filter(|&&x| x).count() as f64;
            let n_mask = inj.mask.iter().filter(|&&x| x).count() as f64;
            let a = &mut acc[fi];
            a[0].push(fin(&before, &all));
            a[1].push(fin(&after, &all));
            a[2].push(fin(&before, &masked));
            a[3].push(fin(&after, &masked));
            if n_flag > 0.0 {
                a[4].push(tp / n_flag);
            }
            a[5].push(tp / n_mask);
        }
    }
    let flaws = params
        .flaws
        .iter()
        .zip(&acc)
        .map(|(f, a)| FlawReport {
            flaw: f.name().to_string(),
            n_clips: a[0].len(),
            mpjpe_before_m: nanmean(&a[0]),
            mpjpe_after_m: nanmean(&a[1]),
            masked_before_m: nanmean(&a[2]),
            masked_after_m: nanmean(&a[3]),
            detection_precision: nanmean(&a[4]),
            detection_recall: nanmean(&a[5]),
        })
        .collect();
    Ok(EvalReport {
        n_clips: idx.len(),
        mean_anchors: nanmean(&anchors),
        mean_frames: nanmean(&frames),
        reconstruction_mpjpe_m: nanmean(&recon),
        clean_change_m: nanmean(&clean_change),
        flaws,
    })
}
