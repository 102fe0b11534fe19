//! `cargo xtask eval refine --cv-subjects 1,3,5,7,9 --out cv.json`: the
//! cross-validated flaw detectors of `cargo xtask train-refine --cv-subjects`
//! (`.cache/refine/cv/test<S>/`). Every fold's network refines its selection
//! subject's and its held-out subject's clips with injected flaws under each
//! detector threshold of the grid; the threshold is chosen on the pooled
//! selection subjects (`crate::refine::cv::choose_setting`), for each
//! held-out figure without the fold that selected on that subject, and the
//! held-out subject of each fold is reported at its choice.

use std::path::Path;

use crate::refine::cv::{choose_setting, fold_dir, folds, pool, Pooled};
use crate::refine::evaluation::{evaluate_injected_on, InjectedReport, RefineEvalParams};
use anyhow::{Context, Result};
use mp_geom::MsrAction3D;
use mp_pose::SessionParams;
use mp_refine::Concepts;
use mp_refine::RefineNets;
use mp_refine::{NetRefineParams, NetRefiner};
use serde_json::{json, Value};

/// Detector thresholds of the grid.
const THRESHOLDS: [f64; 5] = [0.5, 0.6, 0.7, 0.8, 0.9];

fn pooled_json(p: &Pooled) -> Value {
    json!({
        "cases": p.cases,
        "before_mm": p.before_m * 1e3,
        "after_mm": p.after_m * 1e3,
        "reduction": p.reduction,
        "worse": p.worse,
        "clean_change_mm": p.clean_change_m * 1e3,
        "per_flaw": p.per_flaw.iter().map(|(n, c, b, a)| json!({
            "flaw": n, "cases": c, "before_mm": b * 1e3, "after_mm": a * 1e3,
        })).collect::<Vec<_>>(),
    })
}

/// Runs the cross-validated evaluation and returns its JSON.
pub fn run_cv(
    data: &MsrAction3D,
    concepts: &Concepts,
    subjects: &[u32],
    base: &RefineEvalParams,
    ship: u32,
) -> Result<Value> {
    let plan = folds(subjects)?;
    let cv = crate::train_refine_cv::cv_base(&crate::workspace_dir()?);
    let grid: Vec<NetRefineParams> = THRESHOLDS
        .iter()
        .map(|&p| NetRefineParams {
            flaw_probability: p,
            flaw_extend_probability: p,
            ..base.refine.clone()
        })
        .collect();
    // rows[fold][setting] = (selection report, held-out report)
    let mut rows: Vec<Vec<(InjectedReport, InjectedReport)>> = Vec::new();
    for f in &plan {
        let dir = fold_dir(&cv, f.test);
        let nets = RefineNets::load(&dir, &SessionParams::default())
            .with_context(|| format!("loading fold {} ({})", f.test, dir.display()))?;
        let mut per = Vec::new();
        for p in &grid {
            let r = NetRefiner::new(&nets, concepts, p)?;
            let params = RefineEvalParams {
                val_subjects: vec![f.test],
                select_subjects: vec![f.select],
                refine: p.clone(),
                ..base.clone()
            };
            let sel = evaluate_injected_on(data, &r, &params, &[f.select])?;
            let test = evaluate_injected_on(data, &r, &params, &[f.test])?;
            println!(
                "cv fold test {} (train {:?}, select {}) p > {}: select {:.2} → {:.2} mm ({:.1} %), held out {:.2} → {:.2} mm ({:.1} %)",
                f.test,
                f.train,
                f.select,
                p.flaw_probability,
                sel.mpjpe_before_m * 1e3,
                sel.mpjpe_after_m * 1e3,
                sel.reduction * 100.0,
                test.mpjpe_before_m * 1e3,
                test.mpjpe_after_m * 1e3,
                test.reduction * 100.0
            );
            per.push((sel, test));
        }
        rows.push(per);
    }
    // The choice without the folds that selected on `exclude`.
    let choose = |exclude: u32| -> Result<(usize, bool, Vec<Pooled>)> {
        let pooled = (0..grid.len())
            .map(|g| {
                let reps: Vec<&InjectedReport> = plan
                    .iter()
                    .zip(&rows)
                    .filter(|(f, _)| f.select != exclude)
                    .map(|(_, r)| &r[g].0)
                    .collect();
                pool(&reps)
            })
            .collect::<std::result::Result<Vec<_>, mp_refine::RefineError>>()?;
        let (i, ok) = choose_setting(&pooled)?;
        Ok((i, ok, pooled))
    };
    let mut folds_json = Vec::new();
    let mut held: Vec<&InjectedReport> = Vec::new();
    for (f, r) in plan.iter().zip(&rows) {
        let (i, ok, _) = choose(f.test)?;
        let t = &r[i].1;
        held.push(t);
        println!(
            "cv held out subject {} (train {:?}, select {}; threshold {} chosen on subjects {:?}{}): {:.2} → {:.2} mm ({:.1} % less), clean change {:.2} mm, detector P {:.2} R {:.2}",
            f.test,
            f.train,
            f.select,
            THRESHOLDS[i],
            plan.iter().filter(|g| g.select != f.test).map(|g| g.select).collect::<Vec<_>>(),
            if ok { "" } else { ", every setting makes a kind worse" },
            t.mpjpe_before_m * 1e3,
            t.mpjpe_after_m * 1e3,
            t.reduction * 100.0,
            t.clean_change_m * 1e3,
            t.detector_precision,
            t.detector_recall
        );
        for k in &t.per_flaw {
            println!(
                "    {:<20} {:.2} → {:.2} mm, foot slide {:.1} → {:.1} mm/s, P {:.2} R {:.2}",
                k.flaw,
                k.mpjpe_before_m * 1e3,
                k.mpjpe_after_m * 1e3,
                k.foot_slide_before * 1e3,
                k.foot_slide_after * 1e3,
                k.detector_precision,
                k.detector_recall
            );
        }
        folds_json.push(json!({
            "test": f.test, "select": f.select, "train": f.train,
            "threshold": THRESHOLDS[i], "no_kind_worse_on_selection": ok,
            "held_out": serde_json::to_value(t)?,
            "grid": r.iter().zip(THRESHOLDS).map(|((s, h), p)| Ok(json!({
                "threshold": p,
                "select": serde_json::to_value(s)?,
                "held_out": serde_json::to_value(h)?,
            }))).collect::<Result<Vec<_>>>()?,
        }));
    }
    let all = pool(&held)?;
    println!(
        "cv held out, all folds pooled: {:.2} → {:.2} mm ({:.1} % less), kinds made worse: {:?}",
        all.before_m * 1e3,
        all.after_m * 1e3,
        all.reduction * 100.0,
        all.worse
    );
    for (n, c, b, a) in &all.per_flaw {
        println!("    {n:<20} {c} cases: {:.2} → {:.2} mm", b * 1e3, a * 1e3);
    }
    let (di, dok, dpooled) = choose(ship)?;
    println!(
        "cv default for the shipped fold (test {ship}): threshold {} chosen on subjects {:?} pooled ({:.2} → {:.2} mm, {:.1} %){}",
        THRESHOLDS[di],
        plan.iter().filter(|g| g.select != ship).map(|g| g.select).collect::<Vec<_>>(),
        dpooled[di].before_m * 1e3,
        dpooled[di].after_m * 1e3,
        dpooled[di].reduction * 100.0,
        if dok { "" } else { "; every setting makes a kind worse" }
    );
    Ok(json!({
        "subjects": subjects,
        "thresholds": THRESHOLDS,
        "folds": folds_json,
        "held_out_pooled": pooled_json(&all),
        "shipped_fold": ship,
        "default_threshold": THRESHOLDS[di],
        "default_selection_pooled": dpooled.iter().map(pooled_json).collect::<Vec<_>>(),
    }))
}

/// Writes `v` to `out`.
pub fn write(out: &Path, v: &Value) -> Result<()> {
    crate::write_file(out, serde_json::to_string_pretty(v)?)
        .with_context(|| format!("writing {}", out.display()))
}
