//! `cargo xtask eval refine`: the learned refinement of `mp_refine::pipeline`
//! on MSR Action3D — injected flaws on the held-out subject, generated
//! motion (FID, accuracy, diversity, multimodality, per action) and the
//! ablation (anchor-only vs anchors + transitions; GMM vs nearest-concept
//! scores with k-means or DBSCAN concepts).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use mp_geom::io::datasets::MsrAction3D;
use mp_pose::SessionParams;
use mp_refine::eval_refine::{evaluate, RefineEvalParams, SetQuality};
use mp_refine::nets::{find_model_dir, RefineNets};
use mp_refine::Concepts;
use serde_json::{json, Value};

/// Arguments of `cargo xtask eval refine`.
#[derive(Args, Debug)]
pub struct EvalRefineArgs {
    /// MSR Action3D npz (default: the shared odd-subjects file).
    #[arg(long)]
    pub data: Option<PathBuf>,
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
    /// Seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
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
        Some(p) => MsrAction3D::open(p).with_context(|| format!("reading {}", p.display()))?,
        None => MsrAction3D::open_default().context("MSR Action3D (pass --data)")?,
    };
    let dir = match &a.models {
        Some(d) => d.clone(),
        None => find_model_dir()?,
    };
    let cpath = a
        .concepts
        .clone()
        .unwrap_or_else(|| dir.join("concepts.json"));
    let concepts = Concepts::from_json(
        &std::fs::read_to_string(&cpath).with_context(|| format!("reading {}", cpath.display()))?,
    )?;
    let nets = RefineNets::load(&dir, &SessionParams::default())
        .with_context(|| format!("loading {}", dir.display()))?;
    let mut params = RefineEvalParams {
        samples_per_action: a.samples_per_action,
        max_clips: a.max_clips,
        ablation: !a.no_ablation,
        seed: a.seed,
        ..RefineEvalParams::default()
    };
    if let Some(d) = a.deviation_m {
        params.refine.transition_deviation_m = d;
    }
    if let Some(m) = a.score_margin {
        params.refine.score_margin = m;
    }
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
                    "name": mp_geom::io::datasets::msr_action_name(*act),
                    "fid_before": before,
                    "fid_after": g.after.per_action_fid.get(act),
                    "fid_real": g.real.per_action_fid.get(act),
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
            "quality": serde_json::to_value(&params.quality)?,
            "samples_per_action": params.samples_per_action,
            "val_subjects": params.val_subjects,
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
            "per_flaw": serde_json::to_value(&r.injected.per_flaw)?,
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
            "refine_ms_per_clip": g.refine_ms_per_clip,
            "real_heldout": quality_json(&g.real),
        },
        "diversity": {
            "before": g.before.diversity,
            "after": g.after.diversity,
            "real_heldout": g.real.diversity,
        },
        "multimodality": {
            "before": g.before.multimodality,
            "after": g.after.multimodality,
            "real_heldout": g.real.multimodality,
        },
        "per_action": per_action,
        "ablation": serde_json::to_value(&r.ablation)?,
        "seconds": t0.elapsed().as_secs_f64(),
    });
    if let Some(parent) = a.out.parent() {
        if !parent.as_os_str().is_empty() {
            std::fs::create_dir_all(parent)?;
        }
    }
    std::fs::write(&a.out, serde_json::to_string_pretty(&report)?)
        .with_context(|| format!("writing {}", a.out.display()))?;
    println!(
        "injected: MPJPE {:.1} → {:.1} mm ({:.0} % less; baseline {:.1} mm), clean change {:.2} mm",
        r.injected.mpjpe_before_m * 1e3,
        r.injected.mpjpe_after_m * 1e3,
        r.injected.reduction * 100.0,
        r.injected.baseline_after_m * 1e3,
        r.injected.clean_change_m * 1e3
    );
    println!(
        "generated: FID {:.3} → {:.3}, accuracy {:.3} → {:.3}, diversity {:.3} → {:.3}, multimodality {:.3} → {:.3} ({:.2} ms/clip)",
        g.before.fid,
        g.after.fid,
        g.before.accuracy,
        g.after.accuracy,
        g.before.diversity,
        g.after.diversity,
        g.before.multimodality,
        g.after.multimodality,
        g.refine_ms_per_clip
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
