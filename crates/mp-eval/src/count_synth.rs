//! `cargo xtask eval count --synthetic --out FILE.json [--seed S] [--cases N]`:
//! the product's counter (`mp_pipeline::count` with `Params::default()`, as
//! `mp run` / `mp loops` call it on a keypoint track) on synthetic cases of
//! known count built from real motion ([`crate::synth_reps`]).

use std::path::Path;
use std::time::Instant;

use anyhow::anyhow;
use mp_pipeline::Params;
use rayon::prelude::*;
use serde_json::{json, Value};

use crate::synth_reps::{generate, Case, SynthOpts};
use crate::synth_sources::load_sources;

/// One case's outcome.
struct Scored {
    source: String,
    truth: usize,
    count: usize,
    confidence: f64,
    features: mp_abstract::CountFeatures,
    json: Value,
}

fn score(c: &Case, params: &Params) -> anyhow::Result<Scored> {
    let t0 = Instant::now();
    let k = mp_pipeline::count(&c.track, None, params)?;
    let secs = t0.elapsed().as_secs_f64();
    let err = (k.total as f64 - c.truth as f64).abs() / c.truth.max(1) as f64;
    let obo = (k.total as i64 - c.truth as i64).abs() <= 1;
    let fps = c.track.fps();
    let json = json!({
        "id": c.id, "source": c.source, "truth": c.truth, "count": k.total,
        "abs_rel_error": err, "obo": obo, "confidence": k.confidence,
        "periodicity": k.periodicity, "features": k.features,
        "signal": k.signal.as_str(), "method": k.method.as_str(),
        "frames": c.track.n_frames(), "fps": fps, "seconds_of_motion": c.track.n_frames() as f64 / fps,
        "rep_start_frame": c.rep_start, "rep_end_frame": c.rep_end, "rep_boundaries": c.boundaries,
        "cycle": c.cycle.as_ref().map(|(clip, cy)| json!({
            "clip": clip, "start_frame": cy.a, "end_frame": cy.b, "frames": cy.b - cy.a,
            "seam": cy.seam, "motion": cy.amp, "sub_period_ratio": cy.sub_period})),
        "padding": c.padding, "padding_periodicity": c.pad_periodicity,
        "intervals": k.intervals.iter().map(|i| json!({
            "start_frame": i.start_frame, "end_frame": i.end_frame, "count": i.count,
            "period_frames": i.period_frames})).collect::<Vec<_>>(),
        "count_seconds": secs,
    });
    Ok(Scored {
        source: c.source.clone(),
        truth: c.truth,
        count: k.total,
        confidence: k.confidence,
        features: k.features,
        json,
    })
}

/// Cases, MAE (over truth ≥ 1, QUVA's) and OBO (same cases) of a group,
/// and for its N = 0 cases how many were counted 0.
fn figures(items: &[&Scored]) -> Value {
    let rep: Vec<&&Scored> = items.iter().filter(|s| s.truth >= 1).collect();
    let k = rep.len().max(1) as f64;
    let mae = rep
        .iter()
        .map(|s| (s.count as f64 - s.truth as f64).abs() / s.truth as f64)
        .sum::<f64>()
        / k;
    let obo = rep
        .iter()
        .filter(|s| (s.count as i64 - s.truth as i64).abs() <= 1)
        .count() as f64
        / k;
    let zero: Vec<&&Scored> = items.iter().filter(|s| s.truth == 0).collect();
    let by_n = |lo: usize, hi: usize| {
        let g: Vec<&&Scored> = rep
            .iter()
            .filter(|s| (lo..=hi).contains(&s.truth))
            .copied()
            .collect();
        let m = g.len().max(1) as f64;
        json!({"cases": g.len(),
               "mae": g.iter().map(|s| (s.count as f64 - s.truth as f64).abs() / s.truth as f64).sum::<f64>() / m,
               "obo": g.iter().filter(|s| (s.count as i64 - s.truth as i64).abs() <= 1).count() as f64 / m})
    };
    json!({
        "cases": items.len(), "cases_truth_ge_1": rep.len(), "mae": mae, "obo": obo,
        "exact": rep.iter().filter(|s| s.count == s.truth).count() as f64 / k,
        "truth_ge_2": by_n(2, usize::MAX),
        "truth_0_cases": zero.len(), "truth_0_counted_0": zero.iter().filter(|s| s.count == 0).count(),
        "by_truth": {"1": by_n(1, 1), "2-5": by_n(2, 5), "6-10": by_n(6, 10), "11-20": by_n(11, 20)},
    })
}

/// Confidence bins [0, 0.1) … [0.9, 1.0] over cases with truth ≥ 2: cases and
/// share within ±1.
fn reliability(items: &[Scored]) -> Value {
    let mut bins = [(0usize, 0usize); 10];
    for s in items.iter().filter(|s| s.truth >= 2) {
        let b = ((s.confidence.clamp(0.0, 1.0) * 10.0).floor() as usize).min(9);
        bins[b].0 += 1;
        if (s.count as i64 - s.truth as i64).abs() <= 1 {
            bins[b].1 += 1;
        }
    }
    Value::Array(
        bins.iter()
            .enumerate()
            .map(|(i, &(n, ok))| {
                json!({"bin": format!("[{:.1}, {:.1}{}", i as f64 / 10.0, (i + 1) as f64 / 10.0, if i == 9 { "]" } else { ")" }),
                       "cases": n, "obo": if n > 0 { json!(ok as f64 / n as f64) } else { Value::Null }})
            })
            .collect(),
    )
}

/// The calibration curve over every case: by confidence bin, the share of
/// cases that repeat (N ≥ 2) and were counted within ±1 — what the
/// confidence stands for — and the same for confidence ≥ 0.9.
fn calibration(items: &[Scored]) -> Value {
    let right = |s: &Scored| s.truth >= 2 && (s.count as i64 - s.truth as i64).abs() <= 1;
    let mut bins = [(0usize, 0usize, 0.0f64); 10];
    for s in items {
        let b = ((s.confidence.clamp(0.0, 1.0) * 10.0).floor() as usize).min(9);
        bins[b].0 += 1;
        bins[b].1 += usize::from(right(s));
        bins[b].2 += s.confidence;
    }
    let high: Vec<&Scored> = items.iter().filter(|s| s.confidence >= 0.9).collect();
    let brier = items
        .iter()
        .map(|s| (s.confidence - f64::from(u8::from(right(s)))).powi(2))
        .sum::<f64>()
        / items.len().max(1) as f64;
    json!({
        "bins": bins.iter().enumerate().map(|(i, &(n, ok, c))| json!({
            "bin": format!("[{:.1}, {:.1}{}", i as f64 / 10.0, (i + 1) as f64 / 10.0, if i == 9 { "]" } else { ")" }),
            "cases": n,
            "mean_confidence": if n > 0 { json!(c / n as f64) } else { Value::Null },
            "share_right": if n > 0 { json!(ok as f64 / n as f64) } else { Value::Null }})).collect::<Vec<_>>(),
        "confidence_ge_0_9": {"cases": high.len(),
            "share_right": if high.is_empty() { Value::Null } else { json!(high.iter().filter(|s| right(s)).count() as f64 / high.len() as f64) }},
        "brier": brier,
    })
}

/// Confidence of the N = 0 and N = 1 cases: how many, the share at ≥ 0.5,
/// quantiles, and their counts.
fn non_repetitive(items: &[Scored]) -> Value {
    let group = |n: usize| {
        let g: Vec<&Scored> = items.iter().filter(|s| s.truth == n).collect();
        let mut conf: Vec<f64> = g.iter().map(|s| s.confidence).collect();
        conf.sort_by(f64::total_cmp);
        let q = |p: f64| {
            conf.get(((conf.len() as f64 - 1.0) * p).round() as usize)
                .copied()
        };
        let mut counts = std::collections::BTreeMap::new();
        for s in &g {
            *counts.entry(s.count.to_string()).or_insert(0usize) += 1;
        }
        json!({"cases": g.len(),
               "share_confidence_ge_0_5": g.iter().filter(|s| s.confidence >= 0.5).count() as f64 / g.len().max(1) as f64,
               "confidence_min_median_max": [q(0.0), q(0.5), q(1.0)],
               "confidence_quartiles": [q(0.25), q(0.75)],
               "counts": counts})
    };
    json!({"truth_0": group(0), "truth_1": group(1)})
}

/// `params`: the product's defaults unless `--count-param` changed them
/// (for choosing a default; the overrides are written into the report).
/// With `fit_seeds`, the confidence model is first fitted on the cases of
/// those seeds ([`crate::fit_confidence`]) and the cases of `seed` are then
/// scored with it; the report gives the fitted coefficients.
pub fn run(
    out: &Path,
    seed: u64,
    n_cases: usize,
    params: &Params,
    overrides: &[String],
    fit_seeds: &[u64],
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let data = mp_geom::data_dir().ok_or_else(|| {
        anyhow!("the shared data folder was not found: set MP_DATA_DIR to it, or put `shared/data` (penn_action/, aistpp_keypoints2d/, cmu_salsa_bvh/, msr_action3d/, reference_keypoints/) beside the workspace")
    })?;
    let sources = load_sources(&data)?;
    for s in &sources {
        eprintln!("{}: {} clips", s.name, s.clips.len());
    }
    let opts = SynthOpts::default();
    let mut params = params.clone();
    let mut fitted = Value::Null;
    if !fit_seeds.is_empty() {
        if fit_seeds.contains(&seed) {
            anyhow::bail!("--seed {seed} is one of the --fit-confidence seeds: score on a seed the fit did not see");
        }
        let mut examples = Vec::new();
        for &s in fit_seeds {
            let fit_cases = generate(&sources, n_cases, s, &opts);
            let scored: Vec<Scored> = fit_cases
                .par_iter()
                .map(|c| score(c, &params))
                .collect::<anyhow::Result<_>>()?;
            examples.extend(
                scored
                    .iter()
                    .map(|x| crate::fit_confidence::Example::new(x.features, x.truth, x.count)),
            );
        }
        let model = crate::fit_confidence::fit(&examples)?;
        eprintln!("confidence fitted on {} cases: {model:?}", examples.len());
        fitted = json!({"seeds": fit_seeds, "cases": examples.len(), "model": model});
        params.count.confidence = model;
    }
    let params = &params;
    let cases = generate(&sources, n_cases, seed, &opts);
    let t_gen = t0.elapsed().as_secs_f64();
    eprintln!(
        "{} cases generated in {t_gen:.1} s; counting …",
        cases.len()
    );
    let scored: Vec<Scored> = cases
        .par_iter()
        .map(|c| score(c, params))
        .collect::<anyhow::Result<_>>()?;
    let all: Vec<&Scored> = scored.iter().collect();
    let mut by_source = serde_json::Map::new();
    for s in &sources {
        let g: Vec<&Scored> = scored.iter().filter(|x| x.source == s.name).collect();
        by_source.insert(s.name.clone(), figures(&g));
    }
    let count_s: f64 = scored
        .iter()
        .filter_map(|s| s.json["count_seconds"].as_f64())
        .sum();
    let frames: usize = cases.iter().map(|c| c.track.n_frames()).sum();
    let report = json!({
        "kind": "repetition_count_synthetic",
        "seed": seed, "count_param_overrides": overrides, "cases_requested": n_cases, "cases": scored.len(),
        "counter": "mp_pipeline::count(track, None, &Params::default()) — what `mp run` / `mp loops` use on keypoints",
        "definition": "RepNet's synthetic recipe on real keypoints: a cycle of 0.5–3 s of a real clip (a natural near-loop: pose at its end close to its start on the body scale, no shorter period inside, seam cross-faded over 0.1 s) repeated N ∈ 2..=20 times with per-repetition speed ±15 %, amplitude ±10 % around the cycle's mean pose and a slow drift, between 0–3 s of the least periodic of several stretches of the same source played once (cross-faded); 15 % of cases hold N = 0 (2–6 s of motion played once) or N = 1. MAE = mean of |count − N| / N over cases with N ≥ 1; OBO = share of those with |count − N| ≤ 1. Reliability: cases with N ≥ 2 by confidence bin.",
        "overall": figures(&all),
        "by_source": by_source,
        "reliability_truth_ge_2": reliability(&scored),
        "calibration": calibration(&scored),
        "fitted_confidence": fitted,
        "non_repetitive": non_repetitive(&scored),
        "sources": sources.iter().map(|s| json!({"name": s.name, "clips": s.clips.len(), "units": s.units.as_str(), "skeleton": s.skeleton.name})).collect::<Vec<_>>(),
        "data_dir": data.display().to_string(),
        "frames": frames,
        "count_ms_per_frame": 1000.0 * count_s / frames.max(1) as f64,
        "generate_s": t_gen,
        "runtime_s": t0.elapsed().as_secs_f64(),
        "threads": rayon::current_num_threads(),
        "cases_detail": scored.iter().map(|s| s.json.clone()).collect::<Vec<_>>(),
    });
    if let Some(dir) = out.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    mp_geom::write_atomic(out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    let mut summary = report.clone();
    if let Value::Object(m) = &mut summary {
        for k in ["cases_detail", "sources", "definition", "counter"] {
            m.remove(k);
        }
    }
    println!("{}", serde_json::to_string_pretty(&summary)?);
    eprintln!("written to {}", out.display());
    Ok(())
}
