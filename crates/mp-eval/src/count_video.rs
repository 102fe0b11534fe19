//! `cargo xtask eval count --synthetic-video --seed S --out FILE.json`:
//! repetition counts of made videos of known count ([`crate::synth_video`]),
//! exactly as `mp run` makes them (`mp_pipeline::Analyser` with
//! `Params::default()`), by variant: MAE and OBO over the cases with at
//! least one repetition, the counts of the 0- and 1-repetition cases, which
//! signal decided, confidences, and each case's count features with its
//! truth (so that the confidence model can be fitted on frame cases too).

use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use mp_geom::CancelToken;
use mp_pipeline::{Analyser, Input, Params, Silent, Stage};
use serde_json::{json, Map, Value};

use crate::synth_video::{make_case, sources, COUNTS, VARIANTS};

/// Where the made clips are kept between runs.
pub const CACHE_DIR: &str = "mp-out/video_cases";

/// Which frame signal was read (the usual thumbnails or a moving region,
/// as rows and columns of the 32 × 32 grid) and the candidates' periodicity.
pub fn frame_signal_json(choice: Option<&mp_pipeline::FrameChoice>) -> Value {
    let Some(ch) = choice else {
        return Value::Null;
    };
    let reg = |r: &mp_pose::CellRegion| json!([r.r0, r.c0, r.r1, r.c1]);
    json!({
        "region": ch.region.as_ref().map(reg),
        "usual_periodicity": ch.base_periodicity,
        "regions": ch.regions.iter().map(|(r, ratio, p)| json!({"cells": reg(r), "energy_ratio": ratio, "periodicity": p})).collect::<Vec<_>>(),
    })
}

/// One counted case of the report.
fn case_json(case: &crate::synth_video::VideoCase, out: &mp_pipeline::Outcome) -> Value {
    let c = &out.counts;
    let region = out
        .keypoints
        .frame_choice
        .as_ref()
        .is_some_and(|f| f.region.is_some());
    let decided_by = match (c.signal.as_str(), region) {
        ("frames", true) => "frames_region",
        (s, _) => s,
    };
    json!({
        "decided_by": decided_by,
        "variant": case.variant, "index": case.index, "file": case.path.display().to_string(),
        "true_count": case.truth, "count": c.total,
        "source": case.source, "cycles": {"first": case.cycles.0, "per_repeat": case.cycles.1},
        "speeds": case.speeds, "pad_s": [case.pad_s.0, case.pad_s.1],
        "signal": c.signal.as_str(), "method": c.method.as_str(),
        "confidence": c.confidence, "periodicity": c.periodicity, "features": c.features,
        "person_found": out.keypoints.found_fraction,
        "frame_signal": frame_signal_json(out.keypoints.frame_choice.as_ref()),
        "frames": c.frames, "fps": c.fps,
        "motion_ms": 1000.0 * out.stages.iter().filter(|t| t.stage == Stage::Motion).map(|t| t.time.as_secs_f64()).sum::<f64>(),
    })
}

/// MAE (over truth ≥ 1), OBO, counts of the 0/1 cases, signals and
/// confidence of a group of cases.
fn summary(cases: &[&Value]) -> Value {
    let num = |v: &Value, k: &str| v[k].as_f64().unwrap_or(0.0);
    let pos: Vec<&&Value> = cases
        .iter()
        .filter(|c| num(c, "true_count") >= 1.0)
        .collect();
    let err = |c: &Value| (num(c, "count") - num(c, "true_count")).abs();
    let k = pos.len().max(1) as f64;
    let mut signals = Map::new();
    for c in cases {
        let s = c["decided_by"].as_str().unwrap_or("?").to_string();
        let e = signals.entry(s).or_insert(json!(0));
        *e = json!(e.as_u64().unwrap_or(0) + 1);
    }
    let at = |n: f64| -> Vec<u64> {
        cases
            .iter()
            .filter(|c| num(c, "true_count") == n)
            .map(|c| num(c, "count") as u64)
            .collect()
    };
    let confident: Vec<&&Value> = cases
        .iter()
        .filter(|c| num(c, "confidence") >= 0.9)
        .collect();
    json!({
        "cases": cases.len(),
        "count_mae": pos.iter().map(|c| err(c) / num(c, "true_count")).sum::<f64>() / k,
        "obo_acc": pos.iter().filter(|c| err(c) <= 1.0).count() as f64 / k,
        "zero_counts": pos.iter().filter(|c| num(c, "count") == 0.0).count(),
        "count_at_truth_0": at(0.0),
        "count_at_truth_1": at(1.0),
        "signals": signals,
        "mean_confidence": cases.iter().map(|c| num(c, "confidence")).sum::<f64>() / cases.len().max(1) as f64,
        "confident_0_9": confident.len(),
        "confident_0_9_within_1": confident.iter().filter(|c| err(c) <= 1.0).count(),
        "motion_ms_per_frame": cases.iter().map(|c| num(c, "motion_ms")).sum::<f64>() / cases.iter().map(|c| num(c, "frames")).sum::<f64>().max(1.0),
        "person_found_mean": cases.iter().map(|c| num(c, "person_found")).sum::<f64>() / cases.len().max(1) as f64,
    })
}

pub fn run(
    out_path: &Path,
    seed: u64,
    videos: &Path,
    labels: &Path,
    golf: &Path,
    params: &Params,
    overrides: &[String],
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let srcs = sources(videos, labels)?;
    anyhow::ensure!(
        !srcs.is_empty(),
        "no labelled video with three cycles or more in {}",
        videos.display()
    );
    anyhow::ensure!(
        golf.is_file(),
        "the golf swing {} is missing",
        golf.display()
    );
    let cache = Path::new(CACHE_DIR);
    let mut analyser = Analyser::new(params.clone())?;
    let mut all = Vec::new();
    let mut make_s = 0.0;
    for variant in VARIANTS {
        for index in 0..COUNTS.len() {
            let t1 = Instant::now();
            let case = make_case(&srcs, golf, cache, seed, variant, index)?;
            make_s += t1.elapsed().as_secs_f64();
            let out = analyser
                .analyse(Input::open(&case.path, None)?, &Silent, &CancelToken::new())
                .with_context(|| format!("analysing {}", case.path.display()))?;
            let v = case_json(&case, &out);
            eprintln!(
                "{variant} {index}: {} (true {}) {}{} conf {:.2} person {:.0}%",
                out.counts.total,
                case.truth,
                out.counts.signal.as_str(),
                if v["frame_signal"]["region"].is_null() {
                    ""
                } else {
                    " (region)"
                },
                out.counts.confidence,
                100.0 * out.keypoints.found_fraction
            );
            all.push(v);
        }
    }
    let mut by_variant = Map::new();
    for variant in VARIANTS {
        let group: Vec<&Value> = all.iter().filter(|c| c["variant"] == variant).collect();
        by_variant.insert(variant.to_string(), summary(&group));
    }
    let refs: Vec<&Value> = all.iter().collect();
    let report = json!({
        "kind": "repetition_count_made_videos",
        "seed": seed,
        "definition": "QUVA cycles (labelled) repeated N times with a speed of 0.85–1.15 per repeat, between 1.5–4 s of the golf swing; variants plain, small (a third of the side over panned golf footage), covered (a blurred block sliding across). Counted by mp_pipeline::Analyser with the parameters below (mp run's). MAE = mean |count − N| / N over N ≥ 1; OBO = share within ±1 over N ≥ 1.",
        "count_param_overrides": overrides,
        "overall": summary(&refs),
        "by_variant": by_variant,
        "make_s": make_s,
        "runtime_s": t0.elapsed().as_secs_f64(),
        "cases": all,
    });
    if let Some(dir) = out_path.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    crate::write_file(out_path, serde_json::to_string_pretty(&report)?)?;
    let mut s = report.clone();
    if let Value::Object(m) = &mut s {
        m.remove("cases");
    }
    println!("{}", serde_json::to_string_pretty(&s)?);
    eprintln!("written to {}", out_path.display());
    Ok(())
}
