//! `cargo xtask eval refine`: the learned refinement of `mp_refine::learned`
//! on MSR Action3D — injected flaws on every subject the networks never saw
//! (the training manifest next to the models names the training and
//! selection subjects; subject 9 of the shared file) or on the subjects of
//! `--eval-subjects`, with the flaw detector's precision and recall, generated
//! motion (FID, accuracy, diversity, multimodality, per action) and the
//! ablation (anchor-only vs anchors + transitions; GMM vs nearest-concept
//! scores with k-means or DBSCAN concepts). `--select` adds the grid of
//! settings on the selection subject (7) that the defaults are chosen from.
//!
//! The evaluation's steps are submodules: [`evaluation`] (injected flaws on
//! held-out clips, generated motion, the selection grids), [`baseline`]
//! (the non-learned baseline on injected flaws), [`generated`] and
//! [`quality`] (FID, accuracy, diversity, multimodality), [`ablation`],
//! [`split`] (the subjects an evaluation scores: those the training
//! manifest does not name), [`cv`] (cross-validation folds) and
//! [`dataset`] (the training sets the networks learn from).

/// The result of the refinement evaluations (their errors are mp-refine's).
pub(crate) type RefineResult<T, E = mp_refine::RefineError> = std::result::Result<T, E>;

pub mod ablation;
pub mod baseline;
pub mod cv;
pub mod dataset;
pub mod evaluation;
pub mod generated;
pub mod quality;
pub mod split;

use std::path::PathBuf;
use std::time::Instant;

use crate::refine::evaluation::{
    evaluate, generated_selection_grid, selection_grid, RefineEvalParams, SetQuality,
};
use crate::refine::split::{split_for, split_params, subjects_of, TrainingSubjects};
use anyhow::{Context, Result};
use clap::Args;
use mp_geom::MsrAction3D;
use mp_pose::SessionParams;
use mp_refine::Concepts;
use mp_refine::RefineNets;
use mp_refine::{AnchorDetection, AnchorRepair, FlawRepair, NetRefineParams, RefineMode};
use serde_json::{json, Value};

/// Arguments of `cargo xtask eval refine`.
#[derive(Args, Debug)]
pub struct EvalRefineArgs {
    /// MSR Action3D npz, or a folder of them read as one set (default: the
    /// shared odd-subjects file).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Subjects whose clips get the injected flaws (comma separated; default:
    /// every subject of the data that the training manifest next to the
    /// models names neither as a training nor as a selection subject).
    #[arg(long, value_delimiter = ',')]
    pub eval_subjects: Option<Vec<u32>>,
    /// Output JSON report.
    #[arg(long)]
    pub out: PathBuf,
    /// Model folder (default: models/refine).
    #[arg(long)]
    pub models: Option<PathBuf>,
    /// Anchor concepts (default: concepts.json in the model folder).
    #[arg(long)]
    pub concepts: Option<PathBuf>,
    /// Generated clips per action.
    #[arg(long, default_value_t = 50)]
    pub samples_per_action: usize,
    /// At most this many held-out clips for the injected flaws.
    #[arg(long)]
    pub max_clips: Option<usize>,
    /// Skip the ablation.
    #[arg(long)]
    pub no_ablation: bool,
    /// Transition deviation threshold (metres).
    #[arg(long)]
    pub deviation_m: Option<f64>,
    /// Anchor score margin (log-likelihood units).
    #[arg(long)]
    pub score_margin: Option<f64>,
    /// Flaw detector probability threshold.
    #[arg(long)]
    pub flaw_probability: Option<f64>,
    /// Dilation of the flagged frames (frames).
    #[arg(long)]
    pub flaw_dilation: Option<usize>,
    /// Flaw detector hysteresis (grow flags into frames above this probability).
    #[arg(long)]
    pub flaw_extend: Option<f64>,
    /// Longest refilled run (frames).
    #[arg(long)]
    pub max_run: Option<usize>,
    /// Share of flagged joints that flags a whole frame.
    #[arg(long)]
    pub frame_share: Option<f64>,
    /// Flagged-frame repair: linear, cubic or fit (least-squares cubic, 3 context frames).
    #[arg(long)]
    pub repair: Option<String>,
    /// Switch the flaw detector off.
    #[arg(long)]
    pub no_detector: bool,
    /// Also evaluate the grid of settings on the selection subject (7).
    #[arg(long)]
    pub select: bool,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Evaluate the cross-validation folds of `cargo xtask train-refine
    /// --cv-subjects` over these subjects instead (held-out figure per fold).
    #[arg(long, value_delimiter = ',')]
    pub cv_subjects: Option<Vec<u32>>,
    /// The shipped fold (its held-out subject) whose default threshold is
    /// reported (default: the last of `--cv-subjects`).
    #[arg(long)]
    pub cv_ship: Option<u32>,
}

/// The settings the defaults are chosen from, evaluated on the selection subject.
fn grid(base: &NetRefineParams) -> Vec<(String, NetRefineParams)> {
    let mut g = Vec::new();
    // The anchor and transition steps without the detector.
    for margin in [50.0, 100.0, 200.0, 400.0] {
        for dev in [0.1, 0.2] {
            g.push((
                format!("steps_only/margin{margin}/dev{dev}"),
                NetRefineParams {
                    flaw_detection: false,
                    mode: RefineMode::AnchorsAndTransitions,
                    score_margin: margin,
                    transition_deviation_m: dev,
                    ..base.clone()
                },
            ));
        }
    }
    let det = |repair: FlawRepair, seed: f64, extend: f64, dil: usize, run: usize, share: f64| {
        (
            format!("detector_only/{repair:?}/p{seed}/ext{extend}/dil{dil}/run{run}/share{share}"),
            NetRefineParams {
                mode: RefineMode::DetectorOnly,
                flaw_detection: true,
                flaw_repair: repair,
                flaw_probability: seed,
                flaw_extend_probability: extend.min(seed),
                flaw_dilation_frames: dil,
                max_repair_run_frames: run,
                flaw_frame_share: share,
                ..base.clone()
            },
        )
    };
    for repair in [
        FlawRepair::Linear,
        FlawRepair::Cubic,
        FlawRepair::CubicFit { context: 3 },
    ] {
        for seed in [0.5, 0.7, 0.8, 0.9] {
            for extend in [seed, 0.3] {
                g.push(det(repair, seed, extend, 0, 8, 1.0));
            }
        }
    }
    let r = base.flaw_repair;
    for seed in [0.6, 0.7, 0.8] {
        for run in [6, 8, 10] {
            g.push(det(r, seed, seed, 0, run, 1.0));
        }
        for dil in [1, 2] {
            g.push(det(r, seed, seed, dil, 8, 1.0));
        }
        for share in [0.25, 0.5] {
            g.push(det(r, seed, seed, 0, 8, share));
        }
    }
    // The held-pose rule with the base detector settings.
    for tol in [None, Some(1e-5), Some(1e-4), Some(1e-3)] {
        g.push((
            format!("held_pose/{tol:?}"),
            NetRefineParams {
                held_pose_tolerance: tol,
                ..base.clone()
            },
        ));
    }
    // The anchor and transition steps after the detector (base detector settings).
    for margin in [50.0, 100.0, 200.0, 400.0] {
        for dev in [0.1, 0.2] {
            g.push((
                format!("detector+steps/margin{margin}/dev{dev}"),
                NetRefineParams {
                    mode: RefineMode::AnchorsAndTransitions,
                    score_margin: margin,
                    transition_deviation_m: dev,
                    ..base.clone()
                },
            ));
        }
    }
    g
}

/// The settings the generated-motion parameters are chosen from, evaluated
/// on generated clips of the selection seed.
fn generated_grid(base: &NetRefineParams) -> Vec<(String, NetRefineParams)> {
    let mut g = vec![(
        "detector_only".to_string(),
        NetRefineParams {
            mode: RefineMode::DetectorOnly,
            ..base.clone()
        },
    )];
    for repair in [
        AnchorRepair::NearestConcept,
        AnchorRepair::Network,
        AnchorRepair::Bridge,
    ] {
        for margin in [-50.0, -25.0, 0.0, 25.0, 50.0, 200.0] {
            g.push((
                format!("anchors/{repair:?}/margin{margin}"),
                NetRefineParams {
                    mode: RefineMode::AnchorsOnly,
                    anchor_repair: repair,
                    score_margin: margin,
                    ..base.clone()
                },
            ));
        }
    }
    for margin in [-25.0, 0.0, 25.0] {
        g.push((
            format!("anchors+transitions/NearestConcept/margin{margin}"),
            NetRefineParams {
                mode: RefineMode::AnchorsAndTransitions,
                anchor_repair: AnchorRepair::NearestConcept,
                score_margin: margin,
                ..base.clone()
            },
        ));
        g.push((
            format!("segmentation_anchors/NearestConcept/margin{margin}"),
            NetRefineParams {
                mode: RefineMode::AnchorsOnly,
                anchor_repair: AnchorRepair::NearestConcept,
                anchor_source: AnchorDetection::Segmentation,
                score_margin: margin,
                ..base.clone()
            },
        ));
        g.push((
            format!("no_detector/NearestConcept/margin{margin}"),
            NetRefineParams {
                mode: RefineMode::AnchorsOnly,
                anchor_repair: AnchorRepair::NearestConcept,
                flaw_detection: false,
                score_margin: margin,
                ..base.clone()
            },
        ));
    }
    g
}

fn quality_json(q: &SetQuality) -> Value {
    json!({
        "fid": q.fid,
        "accuracy": q.accuracy,
        "diversity": q.diversity,
        "multimodality": q.multimodality,
    })
}

/// Runs the evaluation and writes the report.
pub fn run(a: &EvalRefineArgs) -> Result<()> {
    let t0 = Instant::now();
    let data = match &a.data {
        Some(p) => MsrAction3D::open_path(p).with_context(|| format!("reading {}", p.display()))?,
        None => MsrAction3D::open_default().context("MSR Action3D (pass --data)")?,
    };
    let dir = match &a.models {
        Some(d) => d.clone(),
        None => RefineNets::find_dir()?,
    };
    let cpath = a
        .concepts
        .clone()
        .unwrap_or_else(|| dir.join("concepts.json"));
    let concepts = Concepts::from_json(
        &std::fs::read_to_string(&cpath).with_context(|| format!("reading {}", cpath.display()))?,
    )?;
    if let Some(subjects) = &a.cv_subjects {
        let ship = a
            .cv_ship
            .unwrap_or(*subjects.last().context("--cv-subjects is empty")?);
        let base = RefineEvalParams {
            max_clips: a.max_clips,
            seed: a.seed,
            ablation: false,
            ..RefineEvalParams::default()
        };
        let v = crate::refine_cv::run_cv(&data, &concepts, subjects, &base, ship)?;
        crate::refine_cv::write(&a.out, &v)?;
        println!(
            "wrote {} ({:.0} s)",
            a.out.display(),
            t0.elapsed().as_secs_f64()
        );
        return Ok(());
    }
    let nets = RefineNets::load(&dir, &SessionParams::default())
        .with_context(|| format!("loading {}", dir.display()))?;
    let trained = match (TrainingSubjects::read(&dir), &a.eval_subjects) {
        (Ok(t), _) => t,
        (Err(e), Some(eval)) => {
            // No record: the data's other subjects stand in for the training subjects.
            println!("eval refine: {e}; scoring the subjects of --eval-subjects");
            TrainingSubjects {
                train: subjects_of(&data)
                    .into_iter()
                    .filter(|s| !eval.contains(s))
                    .collect(),
                select: Vec::new(),
                validation: Vec::new(),
            }
        }
        (Err(e), None) => {
            return Err(e).context("the evaluation subjects (or pass --eval-subjects)")
        }
    };
    let split = split_for(&data, &trained, a.eval_subjects.as_deref())?;
    println!(
        "eval refine: {} — scoring subjects {:?} (training subjects {:?}, selection {:?})",
        data.path().display(),
        split.eval_subjects,
        trained.train,
        trained.select
    );
    if !split.seen_eval_subjects.is_empty() {
        println!(
            "eval refine: subjects {:?} shaped the networks or their settings: their figures are not held out",
            split.seen_eval_subjects
        );
    }
    let present = subjects_of(&data);
    if a.select && !split.select_subjects.iter().any(|s| present.contains(s)) {
        anyhow::bail!(
            "--select needs clips of a selection subject that is not evaluated (recorded: {:?}; the data hold {:?})",
            trained.select,
            present
        );
    }
    let mut params = split_params(
        RefineEvalParams {
            samples_per_action: a.samples_per_action,
            max_clips: a.max_clips,
            ablation: !a.no_ablation,
            seed: a.seed,
            ..RefineEvalParams::default()
        },
        &split,
    );
    if let Some(d) = a.deviation_m {
        params.refine.transition_deviation_m = d;
    }
    if let Some(m) = a.score_margin {
        params.refine.score_margin = m;
    }
    if let Some(p) = a.flaw_probability {
        params.refine.flaw_probability = p;
    }
    if let Some(e) = a.flaw_extend {
        params.refine.flaw_extend_probability = e;
    }
    if let Some(f) = a.frame_share {
        params.refine.flaw_frame_share = f;
    }
    if let Some(r) = &a.repair {
        params.refine.flaw_repair = match r.as_str() {
            "linear" => FlawRepair::Linear,
            "cubic" => FlawRepair::Cubic,
            "fit" => FlawRepair::CubicFit { context: 3 },
            other => anyhow::bail!("--repair: unknown method `{other}` (linear, cubic, fit)"),
        };
    }
    if let Some(r) = a.max_run {
        params.refine.max_repair_run_frames = r;
    }
    if let Some(d) = a.flaw_dilation {
        params.refine.flaw_dilation_frames = d;
    }
    if a.no_detector {
        params.refine.flaw_detection = false;
    }
    let selection = if a.select {
        let rows = selection_grid(&data, &nets, &concepts, &params, &grid(&params.refine))?;
        for r in &rows {
            println!(
                "select (subjects {:?}) {:<44} MPJPE {:.2} → {:.2} mm ({:.1} %), clean {:.2} mm, clean flagged {:.1} %, P {:.2} R {:.2}",
                params.select_subjects,
                r.name,
                r.injected.mpjpe_before_m * 1e3,
                r.injected.mpjpe_after_m * 1e3,
                r.injected.reduction * 100.0,
                r.injected.clean_change_m * 1e3,
                r.injected.clean_flagged_frame_share * 100.0,
                r.injected.detector_precision,
                r.injected.detector_recall,
            );
        }
        let (before, grows) = generated_selection_grid(
            &data,
            &nets,
            &concepts,
            &params,
            &generated_grid(&params.generated_refine),
        )?;
        println!(
            "select generated (seed {}) before refinement                  FID {:.3}, accuracy {:.3}",
            params.generated_select_seed, before.fid, before.accuracy
        );
        for r in &grows {
            println!(
                "select generated (seed {}) {:<52} FID {:.3} ({:+.1} %), accuracy {:.3}, diversity {:.3}, multimodality {:.3}, changed {:.0} %, anchors {:.1}/clip, moved {:.1} mm",
                params.generated_select_seed,
                r.name,
                r.after.fid,
                (r.after.fid / before.fid - 1.0) * 100.0,
                r.after.accuracy,
                r.after.diversity,
                r.after.multimodality,
                r.changed_share * 100.0,
                r.repaired_anchors_per_clip,
                r.mean_change_m * 1e3,
            );
        }
        json!({
            "injected": serde_json::to_value(&rows)?,
            "generated_before": serde_json::to_value(&before)?,
            "generated": serde_json::to_value(&grows)?,
        })
    } else {
        Value::Null
    };
    let r = evaluate(&data, &nets, &concepts, &params)?;
    let g = &r.generated;
    let per_action: serde_json::Map<String, Value> = g
        .before
        .per_action_fid
        .iter()
        .map(|(act, before)| {
            (
                act.to_string(),
                json!({
                    "name": mp_geom::msr_action_name(*act),
                    "fid_before": before,
                    "fid_after": g.after.per_action_fid.get(act),
                    "fid_real": g.real.as_ref().and_then(|r| r.per_action_fid.get(act)),
                }),
            )
        })
        .collect();
    let report = json!({
        "data": data.path().display().to_string(),
        "models": dir.display().to_string(),
        "concepts": cpath.display().to_string(),
        "params": {
            "refine": serde_json::to_value(&params.refine)?,
            "generated_refine": serde_json::to_value(&params.generated_refine)?,
            "generated_select_seed": params.generated_select_seed,
            "quality": serde_json::to_value(&params.quality)?,
            "samples_per_action": params.samples_per_action,
            "val_subjects": params.val_subjects,
            "select_subjects": params.select_subjects,
            "concept_subjects": params.concept_subjects,
            "training_subjects": serde_json::to_value(&trained)?,
            "seed": params.seed,
        },
        "injected": {
            "n_clips": r.injected.n_clips,
            "mpjpe_before": r.injected.mpjpe_before_m,
            "mpjpe_after": r.injected.mpjpe_after_m,
            "baseline_after": r.injected.baseline_after_m,
            "reduction": r.injected.reduction,
            "clean_change": r.injected.clean_change_m,
            "clean_changed_share": r.injected.clean_changed_share,
            "clean_flagged_frame_share": r.injected.clean_flagged_frame_share,
            "detector_precision": r.injected.detector_precision,
            "detector_recall": r.injected.detector_recall,
            "per_flaw": serde_json::to_value(&r.injected.per_flaw)?,
            "kinds_made_worse": r.injected.per_flaw.iter()
                .filter(|f| f.mpjpe_after_m > f.mpjpe_before_m)
                .map(|f| f.flaw.clone())
                .collect::<Vec<_>>(),
            "units": "metres",
        },
        "generated": {
            "n_samples": g.n_samples,
            "n_real": g.n_real,
            "fid_before": g.before.fid,
            "fid_after": g.after.fid,
            "fid_reduction": 1.0 - g.after.fid / g.before.fid,
            "accuracy_before": g.before.accuracy,
            "accuracy_after": g.after.accuracy,
            "changed_share": g.changed_share,
            "detector_changed_share": g.detector_changed_share,
            "flagged_cells_per_clip": g.flagged_cells_per_clip,
            "repaired_anchors_per_clip": g.repaired_anchors_per_clip,
            "mean_change": g.mean_change_m,
            "refine_ms_per_clip": g.refine_ms_per_clip,
            "real_heldout": g.real.as_ref().map(quality_json),
        },
        "diversity": {
            "before": g.before.diversity,
            "after": g.after.diversity,
            "real_heldout": g.real.as_ref().map(|r| r.diversity),
        },
        "multimodality": {
            "before": g.before.multimodality,
            "after": g.after.multimodality,
            "real_heldout": g.real.as_ref().map(|r| r.multimodality),
        },
        "per_action": per_action,
        "ablation": serde_json::to_value(&r.ablation)?,
        "selection": selection,
        "seconds": t0.elapsed().as_secs_f64(),
    });
    if let Some(parent) = a.out.parent() {
        if !parent.as_os_str().is_empty() {
            std::fs::create_dir_all(parent)?;
        }
    }
    crate::write_file(&a.out, serde_json::to_string_pretty(&report)?)
        .with_context(|| format!("writing {}", a.out.display()))?;
    println!(
        "injected (subjects {:?}): MPJPE {:.2} → {:.2} mm ({:.1} % less; baseline {:.2} mm), clean change {:.2} mm, detector P {:.3} R {:.3}, clean frames flagged {:.1} %",
        params.val_subjects,
        r.injected.mpjpe_before_m * 1e3,
        r.injected.mpjpe_after_m * 1e3,
        r.injected.reduction * 100.0,
        r.injected.baseline_after_m * 1e3,
        r.injected.clean_change_m * 1e3,
        r.injected.detector_precision,
        r.injected.detector_recall,
        r.injected.clean_flagged_frame_share * 100.0
    );
    for f in &r.injected.per_flaw {
        println!(
            "  {:<20} {:.2} → {:.2} mm{} (baseline {:.2}), changed {:.0} %, detector P {:.2} R {:.2}, foot slide {:.1} → {:.1} mm/s",
            f.flaw,
            f.mpjpe_before_m * 1e3,
            f.mpjpe_after_m * 1e3,
            if f.mpjpe_after_m > f.mpjpe_before_m { " (WORSE)" } else { "" },
            f.baseline_after_m * 1e3,
            f.changed_share * 100.0,
            f.detector_precision,
            f.detector_recall,
            f.foot_slide_before * 1e3,
            f.foot_slide_after * 1e3
        );
    }
    println!(
        "generated: FID {:.3} → {:.3}, accuracy {:.3} → {:.3}, diversity {:.3} → {:.3}, multimodality {:.3} → {:.3} ({:.2} ms/clip; {:.1} anchors moved to a concept per clip, mean joint displacement {:.1} mm)",
        g.before.fid,
        g.after.fid,
        g.before.accuracy,
        g.after.accuracy,
        g.before.diversity,
        g.after.diversity,
        g.before.multimodality,
        g.after.multimodality,
        g.refine_ms_per_clip,
        g.repaired_anchors_per_clip,
        g.mean_change_m * 1e3
    );
    for row in &r.ablation {
        println!(
            "ablation {:<38} FID {:.3} acc {:.3} injected {:.1} mm ({:.0} %) clean {:.2} mm",
            row.name,
            row.fid_after,
            row.accuracy_after,
            row.injected_mpjpe_after_m * 1e3,
            row.injected_reduction * 100.0,
            row.clean_change_m * 1e3
        );
    }
    println!(
        "wrote {} ({:.0} s)",
        a.out.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
