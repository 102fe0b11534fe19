//! Evaluation of the learned refinement ([`mp_refine::NetRefiner`]).
//!
//! * **Injected flaws** ([`evaluate_injected_nets`]): clips of the held-out
//!   subjects of MSR Action3D (subject 9 by default; any subjects the
//!   networks never saw with [`crate::refine::split`]; parameters are chosen
//!   on the selection subjects, 7 by default, with [`selection_grid`]) get
//!   one known flaw each
//!   ([`mp_refine::inject`]); MPJPE (absolute, no alignment) to the clean clip
//!   before and after refinement, per flaw and overall, next to the
//!   non-learned baseline ([`mp_refine::refine`]); and the MPJPE
//!   between each clean clip and its refinement (how much refinement
//!   disturbs clean motion), and the flaw detector's frame-level precision
//!   and recall against the injected frames.
//! * **Generated motion** (in [`evaluate`]): `samples_per_action`
//!   clips per action from the generator network (seeded latents), refined
//!   with their action; FID, per-action FID, accuracy, diversity and
//!   multimodality on the evaluator's features against the real clips,
//!   before and after refinement.
//! * **Ablation** ([`crate::refine::ablation`]): anchor-only vs anchors +
//!   transitions, and the anchor quality score — the Gaussian mixture (which
//!   does not depend on the clustering) vs the distance to the nearest
//!   concept with concepts from k-means or DBSCAN.

use mp_geom::nanmean;

use mp_geom::MsrAction3D;
use mp_geom::Track;
use ndarray::{Array2, Axis};
use serde::{Deserialize, Serialize};

use crate::refine::baseline::EvalFlaw;
use crate::refine::quality::QualityParams;
use crate::refine::split::subjects_of;
use crate::refine::RefineResult as Result;
use mp_refine::full_confidence;
use mp_refine::RefineError;
use mp_refine::{foot_contacts, foot_slide, FootContactParams, NetRefineParams, NetRefiner};
use mp_refine::{foot_joints, AnchorSource, Flaw, FootSlide};
use mp_refine::{generate_clips, RefineNets};
use mp_refine::{mpjpe_abs, SegmentParams};
use mp_refine::{ClusterMethod, Concepts};

/// Parameters of the evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct RefineEvalParams {
    /// Subjects whose clips are evaluated with injected flaws. Default `[9]`
    /// (held out from training and from every choice of parameters).
    pub val_subjects: Vec<u32>,
    /// Subjects on which parameters are chosen ([`selection_grid`]).
    /// Default `[7]`; must not overlap [`Self::val_subjects`].
    pub select_subjects: Vec<u32>,
    /// Subjects whose clips the clustering ablation relearns concepts from,
    /// and the "rest" the real held-out clips are compared with. Default
    /// `None`: every subject of the data outside [`Self::val_subjects`].
    /// Must not overlap [`Self::val_subjects`].
    pub concept_subjects: Option<Vec<u32>>,
    /// At most this many clips for the injected flaws (spread evenly). Default `None`.
    pub max_clips: Option<usize>,
    /// Flaws, each injected once per clip (clip `i` uses seed `seed + i`).
    pub flaws: Vec<EvalFlaw>,
    /// Generated clips per action. Default 50.
    pub samples_per_action: usize,
    /// Refinement parameters of the injected flaws (real captured motion).
    pub refine: NetRefineParams,
    /// Refinement parameters of the generated motion. Default
    /// [`NetRefineParams::for_generated`].
    pub generated_refine: NetRefineParams,
    /// Seed of the generated clips on which the generated-motion settings
    /// are chosen ([`generated_selection_grid`]). Default 1; must differ from
    /// [`Self::seed`], the seed of the reported clips.
    pub generated_select_seed: u64,
    /// Random-pair metrics.
    pub quality: QualityParams,
    /// Run the ablation. Default true.
    pub ablation: bool,
    /// Segmentation of the canonical clips for concept learning (ablation).
    pub segment: SegmentParams,
    /// DBSCAN of the clustering ablation. Default 4 points, tolerance 0.35
    /// (scale-normalised feature units).
    pub dbscan: ClusterMethod,
    /// OPTICS of the clustering ablation. Default 4 points, ordering radius
    /// 1.0, cut at 0.35 (as DBSCAN).
    pub optics: ClusterMethod,
    /// Hierarchical clustering of the ablation. Default 4 concepts per
    /// action (as k-means), Ward linkage.
    pub hierarchical: ClusterMethod,
    /// Quantile of the training anchors' scores used as the flaw threshold
    /// of the nearest-concept scores. Default 0.05.
    pub score_quantile: f64,
    /// Clips shorter than this (source frames) are skipped. Default 8.
    pub min_clip_frames: usize,
    /// Clips longer than this (source frames) are skipped. Default 180
    /// (12 s at 15 fps, 3 source frames per canonical frame): a handful of
    /// MSR Action3D recordings run on for hundreds of frames of a held pose,
    /// which the 60-frame representation cannot resolve.
    pub max_clip_frames: usize,
    /// Seed.
    pub seed: u64,
}

impl Default for RefineEvalParams {
    fn default() -> Self {
        RefineEvalParams {
            val_subjects: vec![9],
            select_subjects: vec![7],
            concept_subjects: None,
            max_clips: None,
            flaws: vec![
                EvalFlaw::Fixed(Flaw::WrongAnchor {
                    half_width_frames: 2,
                    source: AnchorSource::OtherPhase,
                }),
                EvalFlaw::WrongAnchorOtherAction {
                    half_width_frames: 2,
                },
                EvalFlaw::Fixed(Flaw::Jump {
                    frames: 4,
                    skip_frames: 8,
                }),
                EvalFlaw::Fixed(Flaw::Jitter {
                    frames: 4,
                    std_m: 0.05,
                }),
                EvalFlaw::Fixed(Flaw::Frozen { frames: 6 }),
                EvalFlaw::Fixed(Flaw::FootSlide(FootSlide {
                    frames: 10,
                    drift_m: 0.1,
                    up_axis: 1,
                })),
            ],
            samples_per_action: 50,
            refine: NetRefineParams::default(),
            generated_refine: NetRefineParams::for_generated(),
            generated_select_seed: 1,
            quality: QualityParams::default(),
            ablation: true,
            segment: SegmentParams::default(),
            dbscan: ClusterMethod::default_dbscan(),
            optics: ClusterMethod::default_optics(),
            hierarchical: ClusterMethod::default_hierarchical(),
            score_quantile: 0.05,
            min_clip_frames: 8,
            max_clip_frames: 180,
            seed: 0,
        }
    }
}

impl RefineEvalParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        self.refine.validate()?;
        self.generated_refine.validate()?;
        if self.generated_select_seed == self.seed {
            return Err(RefineError::param(
                "generated_select_seed",
                format!("must differ from seed = {}", self.seed),
            ));
        }
        self.quality.validate()?;
        self.segment.validate()?;
        if let Some(s) = self
            .select_subjects
            .iter()
            .find(|s| self.val_subjects.contains(s))
        {
            return Err(RefineError::param(
                "select_subjects",
                format!("subject {s} is also an evaluation subject"),
            ));
        }
        if let Some(s) = self
            .concept_subjects
            .iter()
            .flatten()
            .find(|s| self.val_subjects.contains(s))
        {
            return Err(RefineError::param(
                "concept_subjects",
                format!("subject {s} is also an evaluation subject"),
            ));
        }
        if self.samples_per_action < 2 {
            return Err(RefineError::param("samples_per_action", "must be ≥ 2"));
        }
        if !(0.0..=1.0).contains(&self.score_quantile) {
            return Err(RefineError::param(
                "score_quantile",
                format!("must be in [0, 1], got {}", self.score_quantile),
            ));
        }
        if self.max_clip_frames < self.min_clip_frames {
            return Err(RefineError::param(
                "max_clip_frames",
                format!("must be ≥ min_clip_frames ({})", self.min_clip_frames),
            ));
        }
        if self.min_clip_frames < self.refine.min_frames {
            return Err(RefineError::param(
                "min_clip_frames",
                format!("must be ≥ refine.min_frames ({})", self.refine.min_frames),
            ));
        }
        Ok(())
    }
}

/// Figures of one flaw kind (metres; means over clips).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InjectedFlawReport {
    /// Flaw name.
    pub flaw: String,
    /// Clips.
    pub n_clips: usize,
    /// MPJPE flawed vs clean.
    pub mpjpe_before_m: f64,
    /// MPJPE refined vs clean.
    pub mpjpe_after_m: f64,
    /// MPJPE after the non-learned baseline.
    pub baseline_after_m: f64,
    /// Share of clips where the refinement changed something.
    pub changed_share: f64,
    /// Flaw detector: flagged frames that were injected / flagged frames.
    pub detector_precision: f64,
    /// Flaw detector: injected frames that were flagged / injected frames.
    pub detector_recall: f64,
    /// Foot slide of the flawed clips ([`mp_refine::foot_slide`]: horizontal
    /// travel of the feet, track units per second, over the frames where the
    /// clean clip's feet are in contact).
    pub foot_slide_before: f64,
    /// Foot slide of the refined clips (same frames).
    pub foot_slide_after: f64,
}

/// Injected-flaw results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InjectedReport {
    /// Clean clips evaluated.
    pub n_clips: usize,
    /// MPJPE flawed vs clean, mean over every (clip, flaw).
    pub mpjpe_before_m: f64,
    /// MPJPE refined vs clean, mean over every (clip, flaw).
    pub mpjpe_after_m: f64,
    /// MPJPE after the non-learned baseline.
    pub baseline_after_m: f64,
    /// Relative reduction `1 − after / before`.
    pub reduction: f64,
    /// MPJPE between clean clips and their refinement.
    pub clean_change_m: f64,
    /// Share of clean clips the refinement changed.
    pub clean_changed_share: f64,
    /// Share of the clean clips' frames the flaw detector flagged.
    pub clean_flagged_frame_share: f64,
    /// Flaw detector, frame level over every flawed clip: flagged frames
    /// that were injected / flagged frames (a frame is flagged when any
    /// joint is).
    pub detector_precision: f64,
    /// Flaw detector, frame level: injected frames flagged / injected frames.
    pub detector_recall: f64,
    /// Per flaw.
    pub per_flaw: Vec<InjectedFlawReport>,
}

fn spread(v: Vec<usize>, n: Option<usize>) -> Vec<usize> {
    match n {
        Some(n) if n > 0 && n < v.len() => (0..n).map(|i| v[i * v.len() / n]).collect(),
        _ => v,
    }
}

/// Injected-flaw evaluation on the held-out clips
/// ([`RefineEvalParams::val_subjects`], see the module docs).
pub fn evaluate_injected_nets(
    data: &MsrAction3D,
    refiner: &NetRefiner<'_>,
    params: &RefineEvalParams,
) -> Result<InjectedReport> {
    evaluate_injected_on(data, refiner, params, &params.val_subjects)
}

/// Frame-level detector counts: (true positives, flagged, injected).
fn detector_counts(flagged: &[usize], mask: &[bool]) -> [f64; 3] {
    let tp = flagged
        .iter()
        .filter(|&&f| mask.get(f).copied().unwrap_or(false))
        .count();
    let inj = mask.iter().filter(|&&m| m).count();
    [tp as f64, flagged.len() as f64, inj as f64]
}

/// Injected-flaw evaluation on the clips of `subjects`.
pub fn evaluate_injected_on(
    data: &MsrAction3D,
    refiner: &NetRefiner<'_>,
    params: &RefineEvalParams,
    subjects: &[u32],
) -> Result<InjectedReport> {
    params.validate()?;
    let idx = spread(usable_clips(data, subjects, params), params.max_clips);
    if idx.is_empty() {
        return Err(RefineError::TooShort {
            what: format!("injected evaluation (clips of subjects {subjects:?})"),
            needed: 1,
            got: 0,
        });
    }
    let base = mp_refine::RefineParams::default();
    let nf = params.flaws.len();
    let mut acc: Vec<[Vec<f64>; 6]> = (0..nf).map(|_| Default::default()).collect();
    let slide_params = FootContactParams::default();
    let mut det: Vec<[f64; 3]> = vec![[0.0; 3]; nf];
    let mut clean_change = Vec::new();
    let mut clean_changed = Vec::new();
    let (mut clean_flagged, mut clean_frames) = (0usize, 0usize);
    for &i in &idx {
        let clean = full_confidence(&data.clip(i)?)?;
        let action = data.clip_info(i)?.action;
        let rc = refiner.refine_track(&clean, Some(action))?;
        clean_change.push(mpjpe_abs(&rc.track, &clean)?);
        clean_changed.push(f64::from(u8::from(rc.report.changed())));
        clean_flagged += rc.report.flagged_frames.len();
        clean_frames += clean.n_frames();
        let feet = foot_joints(&clean);
        let contacts = foot_contacts(clean.positions(), &feet, clean.fps(), &slide_params)?;
        let slide = |t: &Track| {
            foot_slide(
                t.positions(),
                &feet,
                &contacts,
                clean.fps(),
                slide_params.up_axis,
            )
        };
        for (fi, ef) in params.flaws.iter().enumerate() {
            let Some(inj) = ef.inject_into(&clean, data, i, action, params.seed)? else {
                continue;
            };
            let r = refiner.refine_track(&inj.track, Some(action))?;
            let b = mp_refine::refine(&inj.track, None, &base)?;
            let a = &mut acc[fi];
            a[0].push(mpjpe_abs(&inj.track, &clean)?);
            a[1].push(mpjpe_abs(&r.track, &clean)?);
            a[2].push(mpjpe_abs(&b.track, &clean)?);
            a[3].push(f64::from(u8::from(r.report.changed())));
            a[4].push(slide(&inj.track)?);
            a[5].push(slide(&r.track)?);
            let c = detector_counts(&r.report.flagged_frames, &inj.mask);
            for k in 0..3 {
                det[fi][k] += c[k];
            }
        }
    }
    let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { f64::NAN };
    let per_flaw: Vec<InjectedFlawReport> = params
        .flaws
        .iter()
        .zip(&acc)
        .zip(&det)
        .map(|((f, a), d)| InjectedFlawReport {
            flaw: match f {
                EvalFlaw::Fixed(fl) => fl.name().to_string(),
                EvalFlaw::WrongAnchorOtherAction { .. } => "wrong_anchor_clip".into(),
            },
            n_clips: a[0].len(),
            mpjpe_before_m: nanmean(&a[0]),
            mpjpe_after_m: nanmean(&a[1]),
            baseline_after_m: nanmean(&a[2]),
            changed_share: nanmean(&a[3]),
            detector_precision: ratio(d[0], d[1]),
            detector_recall: ratio(d[0], d[2]),
            foot_slide_before: nanmean(&a[4]),
            foot_slide_after: nanmean(&a[5]),
        })
        .collect();
    let tot = det.iter().fold([0.0; 3], |mut t, d| {
        for k in 0..3 {
            t[k] += d[k];
        }
        t
    });
    let all = |k: usize| -> Vec<f64> { acc.iter().flat_map(|a| a[k].clone()).collect() };
    let before = nanmean(&all(0));
    let after = nanmean(&all(1));
    Ok(InjectedReport {
        n_clips: idx.len(),
        mpjpe_before_m: before,
        mpjpe_after_m: after,
        baseline_after_m: nanmean(&all(2)),
        reduction: 1.0 - after / before,
        clean_change_m: nanmean(&clean_change),
        clean_changed_share: nanmean(&clean_changed),
        clean_flagged_frame_share: ratio(clean_flagged as f64, clean_frames as f64),
        detector_precision: ratio(tot[0], tot[1]),
        detector_recall: ratio(tot[0], tot[2]),
        per_flaw,
    })
}

use crate::refine::generated::set_quality;
pub use crate::refine::generated::{
    evaluator_outputs, real_clips, refine_clips, refine_clips_report, RefinedClips, SetQuality,
};

/// Generated-motion results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GeneratedReport {
    /// Generated clips.
    pub n_samples: usize,
    /// Real clips the features are compared with.
    pub n_real: usize,
    /// The real clips themselves (accuracy of the evaluator, diversity, …; FID of
    /// the held-out subjects' clips against the clips of
    /// [`RefineEvalParams::concept_subjects`]); `None` when the data hold no
    /// such clips.
    pub real: Option<SetQuality>,
    /// Before refinement.
    pub before: SetQuality,
    /// After refinement.
    pub after: SetQuality,
    /// Share of generated clips the refinement changed.
    pub changed_share: f64,
    /// Share of generated clips in which the flaw repair refilled something.
    pub detector_changed_share: f64,
    /// Mean (frame, joint) cells the flaw detector flagged per generated clip.
    pub flagged_cells_per_clip: f64,
    /// Mean anchors repaired per generated clip.
    pub repaired_anchors_per_clip: f64,
    /// Mean joint displacement of the generated clips by the refinement
    /// (canonical frame, metres).
    pub mean_change_m: f64,
    /// Mean refinement time per clip (ms, this machine, inside the evaluation).
    pub refine_ms_per_clip: f64,
}

pub use crate::refine::ablation::AblationRow;

/// The full evaluation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefineEvalReport {
    /// Injected flaws on held-out clips.
    pub injected: InjectedReport,
    /// Generated motion.
    pub generated: GeneratedReport,
    /// Ablation rows (empty when disabled).
    pub ablation: Vec<AblationRow>,
}

/// The clips of `subjects` whose length is within the evaluation's bounds.
pub(crate) fn usable_clips(
    data: &MsrAction3D,
    subjects: &[u32],
    params: &RefineEvalParams,
) -> Vec<usize> {
    data.clips_of_subjects(subjects, params.min_clip_frames, params.max_clip_frames)
}

/// Runs the whole evaluation with `concepts` (GMM scoring) and the networks.
pub fn evaluate(
    data: &MsrAction3D,
    nets: &RefineNets,
    concepts: &Concepts,
    params: &RefineEvalParams,
) -> Result<RefineEvalReport> {
    params.validate()?;
    let refiner = NetRefiner::new(nets, concepts, &params.refine)?;
    let injected = evaluate_injected_nets(data, &refiner, params)?;

    // Real clips: every clip long enough; held-out subjects for the "real" row.
    let subjects = subjects_of(data);
    let all_idx = usable_clips(data, &subjects, params);
    let (real, real_labels) = real_clips(data, &all_idx)?;
    let (real_f, real_l) = evaluator_outputs(nets, &real)?;
    let val_rows: Vec<usize> = all_idx
        .iter()
        .enumerate()
        .filter(|(_, &i)| {
            data.clip_info(i)
                .map(|c| params.val_subjects.contains(&c.subject))
                .unwrap_or(false)
        })
        .map(|(r, _)| r)
        .collect();
    let rest = |c: &mp_geom::MsrClip| match &params.concept_subjects {
        Some(s) => s.contains(&c.subject),
        None => !params.val_subjects.contains(&c.subject),
    };
    let train_rows: Vec<usize> = all_idx
        .iter()
        .enumerate()
        .filter(|(_, &i)| data.clip_info(i).map(rest).unwrap_or(false))
        .map(|(r, _)| r)
        .collect();
    let pick = |x: &Array2<f64>, rows: &[usize]| x.select(Axis(0), rows);
    let pick_l = |rows: &[usize]| rows.iter().map(|&r| real_labels[r]).collect::<Vec<u32>>();
    let real_q = if train_rows.is_empty() {
        None
    } else {
        let vf = pick(&real_f, &val_rows);
        let vl = pick(&real_l, &val_rows);
        let lab = pick_l(&val_rows);
        let tf = pick(&real_f, &train_rows);
        Some(set_quality(
            &vf,
            &vl,
            &lab,
            &tf,
            &pick_l(&train_rows),
            &params.quality,
        )?)
    };

    let (gen, labels) = generate_clips(nets, params.samples_per_action, params.seed)?;
    let (gf, gl) = evaluator_outputs(nets, &gen)?;
    let before = set_quality(&gf, &gl, &labels, &real_f, &real_labels, &params.quality)?;
    let gen_refiner = NetRefiner::new(nets, concepts, &params.generated_refine)?;
    let rc = refine_clips_report(&gen_refiner, &gen, &labels)?;
    let (rf, rl) = evaluator_outputs(nets, &rc.clips)?;
    let after = set_quality(&rf, &rl, &labels, &real_f, &real_labels, &params.quality)?;
    let generated = GeneratedReport {
        n_samples: labels.len(),
        n_real: real_labels.len(),
        real: real_q,
        before,
        after,
        changed_share: rc.changed_share,
        detector_changed_share: rc.detector_changed_share,
        flagged_cells_per_clip: rc.flagged_cells_per_clip,
        repaired_anchors_per_clip: rc.repaired_anchors_per_clip,
        mean_change_m: rc.mean_change_m,
        refine_ms_per_clip: rc.ms_per_clip,
    };

    let ablation = if params.ablation {
        crate::refine::ablation::ablation_rows(
            data,
            nets,
            concepts,
            params,
            &crate::refine::ablation::GeneratedSet {
                clips: &gen,
                labels: &labels,
                real_features: &real_f,
            },
        )?
    } else {
        Vec::new()
    };
    Ok(RefineEvalReport {
        injected,
        generated,
        ablation,
    })
}

/// One setting of [`generated_selection_grid`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GeneratedSelectionRow {
    /// Setting.
    pub name: String,
    /// The refinement parameters.
    pub params: NetRefineParams,
    /// Quality of the refined selection clips.
    pub after: SetQuality,
    /// Share of the clips changed.
    pub changed_share: f64,
    /// Mean anchors repaired per clip.
    pub repaired_anchors_per_clip: f64,
    /// Mean joint displacement by the refinement (metres).
    pub mean_change_m: f64,
}

/// Quality of the generated selection clips (seed
/// [`RefineEvalParams::generated_select_seed`], never the reported seed)
/// before refinement and after each named parameter set: the figures
/// [`NetRefineParams::for_generated`] is chosen from. FID is against every
/// usable real clip, as in [`evaluate`].
pub fn generated_selection_grid(
    data: &MsrAction3D,
    nets: &RefineNets,
    concepts: &Concepts,
    params: &RefineEvalParams,
    grid: &[(String, NetRefineParams)],
) -> Result<(SetQuality, Vec<GeneratedSelectionRow>)> {
    params.validate()?;
    let idx = usable_clips(data, &subjects_of(data), params);
    let (real, real_labels) = real_clips(data, &idx)?;
    let (real_f, _) = evaluator_outputs(nets, &real)?;
    let (gen, labels) = generate_clips(
        nets,
        params.samples_per_action,
        params.generated_select_seed,
    )?;
    let (gf, gl) = evaluator_outputs(nets, &gen)?;
    let before = set_quality(&gf, &gl, &labels, &real_f, &real_labels, &params.quality)?;
    let rows = grid
        .iter()
        .map(|(name, p)| {
            let r = NetRefiner::new(nets, concepts, p)?;
            let rc = refine_clips_report(&r, &gen, &labels)?;
            let (rf, rl) = evaluator_outputs(nets, &rc.clips)?;
            Ok(GeneratedSelectionRow {
                name: name.clone(),
                params: p.clone(),
                after: set_quality(&rf, &rl, &labels, &real_f, &real_labels, &params.quality)?,
                changed_share: rc.changed_share,
                repaired_anchors_per_clip: rc.repaired_anchors_per_clip,
                mean_change_m: rc.mean_change_m,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((before, rows))
}

/// One setting of [`selection_grid`] on the selection subjects.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SelectionRow {
    /// Setting.
    pub name: String,
    /// The refinement parameters.
    pub params: NetRefineParams,
    /// Injected flaws on the selection subjects.
    pub injected: InjectedReport,
}

/// Evaluates each named parameter set with injected flaws on
/// [`RefineEvalParams::select_subjects`] (never on the evaluation subjects):
/// the figures the defaults of [`NetRefineParams`] are chosen from.
pub fn selection_grid(
    data: &MsrAction3D,
    nets: &RefineNets,
    concepts: &Concepts,
    params: &RefineEvalParams,
    grid: &[(String, NetRefineParams)],
) -> Result<Vec<SelectionRow>> {
    params.validate()?;
    grid.iter()
        .map(|(name, p)| {
            let r = NetRefiner::new(nets, concepts, p)?;
            Ok(SelectionRow {
                name: name.clone(),
                params: p.clone(),
                injected: evaluate_injected_on(data, &r, params, &params.select_subjects)?,
            })
        })
        .collect()
}
