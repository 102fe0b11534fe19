//! `cargo xtask eval loops --data PATH --out FILE.json`: repetition detection,
//! counting and prediction by unrolling, on the kinds of data the shared folder holds.
//!
//! The kind of PATH is detected:
//! * CMU mocap6 features (`*_features10fps.npz`, a file or a folder of them):
//!   detected intervals vs labelled exercise blocks, precision/recall at IoM > 0.5 and IoU ≥ 0.5;
//! * AIST++ keypoints (`*.npz` with `keypoints2d`): intervals and iterations per camera view,
//!   and agreement across the views of one routine;
//! * Penn Action npz: fraction of repetitive-class clips with a loop, and prediction by
//!   unrolling vs Constant at horizons 5/10/20/30 after observing the first half (KD, PCK@0.05);
//! * a QUVA-style folder (`annotations/<name>.npy` = frame where each cycle ends) with keypoint
//!   tracks (`--tracks DIR`, default: the folder itself; any format `read_track` reads, named
//!   `<name>.*`): count MAE and off-by-one accuracy.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use mp_abstract::predict_constant;
use mp_abstract::{analyse, unroll, AbstractParams, PredictParams, RepetitiveInterval};
use mp_abstract::{
    estimate_period, segment_repetitions, IntervalParams, PeriodParams, PeriodicSegment,
};
use mp_concrete::Scale;
use mp_geom::Npz;
use mp_geom::Track;
use mp_geom::{AistPlusPlus, PennAction};
use rayon::prelude::*;
use serde_json::{json, Map, Value};

/// Arguments of `cargo xtask eval loops`.
#[derive(Args, Debug)]
pub struct EvalLoopsArgs {
    /// A file or folder of one of the supported kinds.
    #[arg(long)]
    pub data: PathBuf,
    /// Keypoint tracks for a QUVA-style folder (default: the data folder).
    #[arg(long)]
    pub tracks: Option<PathBuf>,
    /// Output JSON.
    #[arg(long)]
    pub out: PathBuf,
    /// At most this many clips per class (Penn Action).
    #[arg(long, default_value_t = usize::MAX)]
    pub max_clips: usize,
}

use crate::forecast::PENN_REPETITIVE_CLASSES as PENN_REPETITIVE;
const HORIZONS: [usize; 4] = [5, 10, 20, 30];

fn bar(n: usize, what: &str) -> ProgressBar {
    let b = ProgressBar::new(n as u64);
    if let Ok(s) = ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} {elapsed}") {
        b.set_style(s.progress_chars("=> "));
    }
    b.set_message(what.to_string());
    b
}

fn write_json(path: &Path, v: &Value) -> anyhow::Result<()> {
    if let Some(dir) = path.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    mp_geom::write_atomic(path, serde_json::to_string_pretty(v)?.as_bytes())?;
    Ok(())
}

fn intervals_json(iv: &[RepetitiveInterval], fps: f64) -> Value {
    Value::Array(
        iv.iter()
            .map(|i| {
                json!({"start_frame": i.start_frame, "end_frame": i.end_frame, "start_s": i.start_frame as f64 / fps,
                       "end_s": i.end_frame as f64 / fps, "body": i.body_size, "iterations": i.iterations})
            })
            .collect(),
    )
}

pub fn run(a: &EvalLoopsArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let data = &a.data;
    if !data.exists() {
        bail!("{} does not exist", data.display());
    }
    let mut report = if data.is_dir() && data.join("annotations").is_dir() {
        eval_quva(data, a.tracks.as_deref().unwrap_or(data))?
    } else {
        let files: Vec<PathBuf> = if data.is_dir() {
            let mut v: Vec<PathBuf> = std::fs::read_dir(data)?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "npz"))
                .collect();
            v.sort();
            v
        } else {
            vec![data.clone()]
        };
        if files.is_empty() {
            bail!("{}: no .npz files", data.display());
        }
        let npz = Npz::open(&files[0])?;
        if npz.contains("X") && npz.contains("labels") {
            crate::intervals::eval_cmu(&files)?
        } else if npz.contains("keypoints2d") {
            eval_aist(&files)?
        } else if npz.contains("keypoints") && npz.contains("offsets") && npz.contains("action") {
            eval_penn(&files[0], a.max_clips)?
        } else {
            bail!(
                "{}: not a recognised data set (keys: {})",
                files[0].display(),
                npz.names().join(", ")
            )
        }
    };
    if let Value::Object(m) = &mut report {
        m.insert("data".into(), json!(data.display().to_string()));
        m.insert("runtime_s".into(), json!(t0.elapsed().as_secs_f64()));
        m.insert(
            "params".into(),
            serde_json::to_value(AbstractParams::default())?,
        );
    }
    write_json(&a.out, &report)?;
    println!("{}", serde_json::to_string_pretty(&summary(&report))?);
    eprintln!("written to {}", a.out.display());
    Ok(())
}

/// The top-level numbers of a report (everything but per-item detail).
fn summary(v: &Value) -> Value {
    match v {
        Value::Object(m) => Value::Object(
            m.iter()
                .filter(|(k, _)| {
                    !matches!(
                        k.as_str(),
                        "by_file" | "by_clip" | "by_video" | "params" | "by_view"
                    )
                })
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect(),
        ),
        other => other.clone(),
    }
}

fn segments_json(segs: &[PeriodicSegment], fps: f64) -> Value {
    Value::Array(
        segs.iter()
            .map(|s| {
                json!({"start_frame": s.start_frame, "end_frame": s.end_frame, "start_s": s.start_frame as f64 / fps,
                       "end_s": s.end_frame as f64 / fps, "period_frames": s.period_frames, "score": s.score, "count": s.count})
            })
            .collect(),
    )
}

pub(crate) fn ratio(a: usize, b: usize) -> f64 {
    if b == 0 {
        0.0
    } else {
        a as f64 / b as f64
    }
}

/// Frames covered by any interval.
fn mask(iv: &[RepetitiveInterval], n: usize) -> Vec<bool> {
    let mut m = vec![false; n];
    for i in iv {
        for x in m.iter_mut().take(i.end_frame.min(n)).skip(i.start_frame) {
            *x = true;
        }
    }
    m
}

fn eval_aist(files: &[PathBuf]) -> anyhow::Result<Value> {
    let mut by_file = Map::new();
    let mut agreements = Vec::new();
    let mut found_views = 0usize;
    let mut views_total = 0usize;
    for f in files {
        let a = AistPlusPlus::open(f)?;
        let frame_px = 1920.0;
        let res: Vec<anyhow::Result<mp_abstract::Analysis>> = a
            .views
            .par_iter()
            .map(|v| {
                let mut p = AbstractParams::default();
                p.synth.scale = Scale::FrameSize { frame_px };
                let mut v = v.clone();
                v.fill_missing();
                Ok(analyse(&v, &p)?)
            })
            .collect();
        let mut views = Vec::new();
        let mut masks = Vec::new();
        for (vi, r) in res.into_iter().enumerate() {
            let an = r.with_context(|| format!("{} view {vi}", f.display()))?;
            views_total += 1;
            if !an.intervals.is_empty() {
                found_views += 1;
            }
            masks.push(mask(&an.intervals, a.views[vi].n_frames()));
            views.push(json!({
                "view": vi,
                "intervals": intervals_json(&an.intervals, a.fps),
                "iterations": an.intervals.iter().map(|i| i.iterations).sum::<usize>(),
                "covered_fraction": masks[vi].iter().filter(|&&b| b).count() as f64 / masks[vi].len().max(1) as f64,
            }));
        }
        // Agreement: mean IoU of the covered-frame masks over all pairs of views.
        let mut pair = Vec::new();
        for i in 0..masks.len() {
            for j in i + 1..masks.len() {
                let inter = masks[i]
                    .iter()
                    .zip(&masks[j])
                    .filter(|(a, b)| **a && **b)
                    .count();
                let uni = masks[i]
                    .iter()
                    .zip(&masks[j])
                    .filter(|(a, b)| **a || **b)
                    .count();
                pair.push(if uni == 0 {
                    1.0
                } else {
                    inter as f64 / uni as f64
                });
            }
        }
        let agree = pair.iter().sum::<f64>() / pair.len().max(1) as f64;
        agreements.push(agree);
        let name = f
            .file_name()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        by_file.insert(name, json!({"view_agreement": agree, "by_view": views}));
    }
    Ok(json!({
        "kind": "aistpp_keypoints2d",
        "routines": files.len(),
        "views_with_loop_fraction": ratio(found_views, views_total),
        "view_agreement": agreements.iter().sum::<f64>() / agreements.len().max(1) as f64,
        "view_agreement_definition": "mean over pairs of camera views of the IoU of the frames covered by detected loops",
        "by_file": by_file,
    }))
}

fn eval_penn(path: &Path, max_clips: usize) -> anyhow::Result<Value> {
    let penn = PennAction::open(path)?;
    let mut jobs = Vec::new();
    for cls in PENN_REPETITIVE {
        for i in penn.clips_of_action(cls).into_iter().take(max_clips) {
            jobs.push((cls, i));
        }
    }
    let pb = bar(jobs.len(), "penn clips");
    let results: Vec<(String, usize, anyhow::Result<Value>)> = jobs
        .par_iter()
        .map(|&(cls, i)| {
            let r = penn_clip(&penn, i);
            pb.inc(1);
            (cls.to_string(), i, r)
        })
        .collect();
    pb.finish_and_clear();
    let mut by_action: Map<String, Value> = Map::new();
    let mut all = Vec::new();
    let mut errors = Vec::new();
    for (cls, i, r) in results {
        match r {
            Ok(v) => {
                all.push(v.clone());
                if let Some(a) = by_action
                    .entry(cls)
                    .or_insert_with(|| json!([]))
                    .as_array_mut()
                {
                    a.push(v);
                }
            }
            Err(e) => errors.push(format!("clip {i}: {e:#}")),
        }
    }
    let agg = |rows: &[Value]| -> Value {
        let n = rows.len().max(1) as f64;
        let found = rows
            .iter()
            .filter(|r| r["loop_found"].as_bool() == Some(true))
            .count() as f64;
        let mut m = Map::new();
        m.insert("clips".into(), json!(rows.len()));
        m.insert("loop_found_fraction".into(), json!(found / n));
        let mut paths = Map::new();
        for p in ["loop", "period", "self_match", "constant"] {
            let k = rows
                .iter()
                .filter(|r| r["path"].as_str() == Some(p))
                .count() as f64;
            paths.insert(p.into(), json!(k / n));
        }
        let refl = rows
            .iter()
            .filter(|r| r["self_match"]["kind"].as_str() == Some("Reflection"))
            .count() as f64;
        paths.insert("self_match_reflection".into(), json!(refl / n));
        m.insert("path_fraction".into(), Value::Object(paths));
        for method in ["loop", "constant"] {
            for metric in ["kd_px_512", "pck"] {
                let mut hm = Map::new();
                for h in HORIZONS {
                    let vals: Vec<f64> = rows
                        .iter()
                        .filter_map(|r| r[method][metric][format!("h{h}")].as_f64())
                        .filter(|v| v.is_finite())
                        .collect();
                    let mean = if vals.is_empty() {
                        f64::NAN
                    } else {
                        vals.iter().sum::<f64>() / vals.len() as f64
                    };
                    hm.insert(format!("h{h}"), json!(mean));
                }
                m.entry(method.to_string())
                    .or_insert_with(|| json!({}))
                    .as_object_mut()
                    .map(|o| o.insert(metric.into(), Value::Object(hm)));
            }
        }
        Value::Object(m)
    };
    let mut by = Map::new();
    for (k, v) in &by_action {
        if let Some(rows) = v.as_array() {
            by.insert(k.clone(), agg(rows));
        }
    }
    Ok(json!({
        "kind": "penn_action",
        "classes": PENN_REPETITIVE,
        "overall": agg(&all),
        "by_action": by,
        "errors": errors,
        "protocol": "observe the first half of each clip, predict the next 5/10/20/30 frames (clips too short for a horizon are skipped at that horizon); KD in px rescaled to a 512-px frame; PCK@0.05 of the bbox after the optimal scale+translation fit; path_fraction: share of clips predicted by each path of mp_abstract::unroll (loop, autocorrelation period, self-match by lag or reflection, constant)",
    }))
}

fn penn_clip(penn: &PennAction, i: usize) -> anyhow::Result<Value> {
    let info = penn.clip_info(i)?.clone();
    let mut track = penn.clip(i)?;
    let frame_px = info.height_px.max(info.width_px) as f64;
    let scale512 = 512.0 / frame_px;
    let mut params = PredictParams::default();
    params.analysis.synth.scale = Scale::FrameSize { frame_px };
    params.analysis.synth.unobserved_joints = mp_concrete::UnobservedJoints::Ignore;
    let truth_conf = track.confidence().to_owned();
    track.fill_missing();
    let n = track.n_frames();
    let full = { analyse(&track, &params.analysis).ok() };
    let loop_found = full.as_ref().is_some_and(|a| !a.intervals.is_empty());
    let observe = n / 2;
    let mut out = json!({"clip_id": info.clip_id, "frames": n, "loop_found": loop_found,
        "count": full.as_ref().map(|a| a.intervals.iter().map(|i| i.count).sum::<usize>()).unwrap_or(0)});
    if observe < 8 {
        return Ok(out);
    }
    let max_h = *HORIZONS
        .iter()
        .filter(|&&h| observe + h <= n)
        .max()
        .unwrap_or(&0);
    if max_h == 0 {
        return Ok(out);
    }
    let pred_loop = unroll(&track, observe, max_h, &params)?;
    let pred_const = predict_constant(&track.slice_frames(0, observe)?, max_h)?;
    let truth = track.slice_frames(observe, observe + max_h)?;
    let tconf = truth_conf
        .slice(ndarray::s![observe..observe + max_h, ..])
        .to_owned();
    let mut gt = truth.clone();
    gt.confidence_mut().assign(&tconf);
    for (name, pred) in [("loop", &pred_loop.track), ("constant", &pred_const)] {
        let mut kdm = Map::new();
        let mut pckm = Map::new();
        for h in HORIZONS {
            if h > max_h {
                continue;
            }
            let p = pred.slice_frames(h - 1, h)?;
            let g = gt.slice_frames(h - 1, h)?;
            let kd = mp_geom::kd(&p, &g)
                .map(|v| v * scale512)
                .unwrap_or(f64::NAN);
            let pck = mp_geom::pck(&p, &g, 0.05).unwrap_or(f64::NAN);
            kdm.insert(format!("h{h}"), json!(kd));
            pckm.insert(format!("h{h}"), json!(pck));
        }
        out[name] = json!({"kd_px_512": kdm, "pck": pckm});
    }
    out["used_loop"] = json!(pred_loop.used.is_some());
    out["path"] = json!(pred_loop.method().as_str());
    out["self_match"] = json!(pred_loop.self_match);
    Ok(out)
}

fn eval_quva(dir: &Path, tracks: &Path) -> anyhow::Result<Value> {
    let ann = dir.join("annotations");
    let mut names: Vec<String> = std::fs::read_dir(&ann)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "npy"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().to_string()))
        .collect();
    names.sort();
    let mut by_video = Map::new();
    let (mut maes, mut obos) = (Vec::new(), Vec::new());
    let (mut pmaes, mut pobos) = (Vec::new(), Vec::new());
    let (mut rmaes, mut robos) = (Vec::new(), Vec::new());
    let (mut smaes, mut sobos) = (Vec::new(), Vec::new());
    let (mut lmaes, mut lobos) = (Vec::new(), Vec::new());
    let mut skipped = Vec::new();
    for name in &names {
        let truth = mp_geom::read_npy(ann.join(format!("{name}.npy")))?.to_i64()?;
        let true_count = truth.len();
        let Some(tp) = find_track(tracks, name) else {
            skipped.push(json!({"video": name, "reason": "no keypoint track"}));
            continue;
        };
        let mut track: Track = mp_geom::read_track(&tp)?;
        let valid_frames = (0..track.n_frames())
            .filter(|&t| (0..track.n_joints()).any(|j| track.confidence()[[t, j]] > 0.0))
            .count();
        if valid_frames < track.n_frames() / 2 {
            skipped.push(json!({"video": name, "reason": format!("a person in only {valid_frames} of {} frames", track.n_frames())}));
            continue;
        }
        let product = mp_pipeline::count(&track, None, &mp_pipeline::Params::default())?;
        let pred = product.total;
        track.fill_missing();
        let an = analyse(&track, &AbstractParams::default())?;
        let loops_count: usize = an.intervals.iter().map(|i| i.count).sum();
        let lmae = (loops_count as f64 - true_count as f64).abs() / true_count.max(1) as f64;
        lmaes.push(lmae);
        lobos.push((loops_count as i64 - true_count as i64).abs() <= 1);
        let mae = (pred as f64 - true_count as f64).abs() / true_count.max(1) as f64;
        let obo = (pred as i64 - true_count as i64).abs() <= 1;
        maes.push(mae);
        obos.push(obo);
        let period = estimate_period(&track, 0, track.n_frames(), &PeriodParams::legacy())?;
        let pc = period.map(|p| p.count.round() as usize).unwrap_or(0);
        let pmae = (pc as f64 - true_count as f64).abs() / true_count.max(1) as f64;
        pmaes.push(pmae);
        pobos.push((pc as i64 - true_count as i64).abs() <= 1);
        let rep = estimate_period(&track, 0, track.n_frames(), &PeriodParams::default())?;
        let rc = rep.map(|p| p.count.round() as usize).unwrap_or(0);
        let rmae = (rc as f64 - true_count as f64).abs() / true_count.max(1) as f64;
        rmaes.push(rmae);
        robos.push((rc as i64 - true_count as i64).abs() <= 1);
        let segs = segment_repetitions(&track, &IntervalParams::default())?;
        let sc = segs.iter().map(|s| s.count).sum::<f64>().round() as usize;
        let smae = (sc as f64 - true_count as f64).abs() / true_count.max(1) as f64;
        smaes.push(smae);
        sobos.push((sc as i64 - true_count as i64).abs() <= 1);
        by_video.insert(name.clone(), json!({"true_count": true_count, "pred_count": pred, "mae": mae, "obo": obo,
            "method": product.method.as_str(), "confidence": product.confidence, "loops_count": loops_count,
            "period": period, "period_count": pc, "period_mae": pmae,
            "repetition": rep, "repetition_count": rc, "repetition_mae": rmae,
            "segments": segments_json(&segs, track.fps()), "segment_count": sc, "segment_mae": smae,
            "intervals": intervals_json(&an.intervals, track.fps()), "track": tp.display().to_string()}));
    }
    Ok(json!({
        "kind": "quva_repetition",
        "videos": maes.len(),
        "count_mae": maes.iter().sum::<f64>() / maes.len().max(1) as f64,
        "obo_acc": obos.iter().filter(|&&b| b).count() as f64 / obos.len().max(1) as f64,
        "count_definition": "count_mae/obo_acc: the product's count (mp_pipeline::count with Params::default(), keypoints only: these tracks come without frames); loops.*: sum of the iterations of the loops of the abstract program; period.*: frames / dominant period of the joint velocities (PeriodParams::legacy(): all joints, unbiased autocorrelation); repetition.*: the same with PeriodParams::default() (limb joints, biased autocorrelation, at least 3 cycles); segments.*: sum over the intervals of segment_repetitions of length / period. MAE = mean over videos of |pred − true| / true (counts rounded); OBO: |pred − true| ≤ 1",
        "loops": {
            "count_mae": lmaes.iter().sum::<f64>() / lmaes.len().max(1) as f64,
            "obo_acc": lobos.iter().filter(|&&b| b).count() as f64 / lobos.len().max(1) as f64,
        },
        "period": {
            "count_mae": pmaes.iter().sum::<f64>() / pmaes.len().max(1) as f64,
            "obo_acc": pobos.iter().filter(|&&b| b).count() as f64 / pobos.len().max(1) as f64,
        },
        "repetition": {
            "count_mae": rmaes.iter().sum::<f64>() / rmaes.len().max(1) as f64,
            "obo_acc": robos.iter().filter(|&&b| b).count() as f64 / robos.len().max(1) as f64,
            "params": serde_json::to_value(PeriodParams::default())?,
        },
        "segments": {
            "count_mae": smaes.iter().sum::<f64>() / smaes.len().max(1) as f64,
            "obo_acc": sobos.iter().filter(|&&b| b).count() as f64 / sobos.len().max(1) as f64,
            "params": serde_json::to_value(IntervalParams::default())?,
        },
        "skipped": skipped,
        "by_video": by_video,
    }))
}

fn find_track(dir: &Path, stem: &str) -> Option<PathBuf> {
    for sub in [dir.to_path_buf(), dir.join("tracks")] {
        for ext in ["npz", "json", "csv", "npy"] {
            let p = sub.join(format!("{stem}.{ext}"));
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}
