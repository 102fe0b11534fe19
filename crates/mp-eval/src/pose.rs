//! `cargo xtask eval pose`: keypoints of mp-pose against the original
//! MediaPipe BlazePose on the shared videos, PCK on the COCO sample, speed.
//!
//! For each video with a reference `<stem>.npz`: median / p90 pixel distance
//! of the 33 landmarks on frames where both found a pose (reference
//! visibility > 0.5), fraction of frames with a pose (and agreement of that
//! flag with the reference), frames per second of the estimator (overall and
//! on tracking frames) against the reference's ms/frame. On the COCO sample:
//! PCK@0.2 (torso: left shoulder – right hip of the annotation) against the
//! annotated person with the largest box, for us and for MediaPipe's output.

use std::fs::File;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use ndarray::{Array1, Array2, Array3};
use ndarray_npy::NpzReader;
use serde_json::{json, Value};

use mp_geom::BLAZEPOSE_TO_COCO17;
use mp_pose::{extract_track, ExtractOptions, ModelChoice, SmoothingParams};
use mp_pose::{open_source, read_image};
use mp_pose::{BlazePose, BlazePoseParams, MoveNet, MoveNetParams, PoseEstimator, SessionParams};

use crate::table::Table;

#[derive(clap::Args, Debug)]
pub struct EvalPoseArgs {
    /// Folders with videos (repeatable). Default: shared golfdb/ and quva_repetition/videos/.
    #[arg(long)]
    pub videos: Vec<PathBuf>,
    /// Folder with the MediaPipe reference `<stem>.npz` files. Default: shared reference_keypoints/.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// COCO sample folder (`*.jpg`, `test_coco.json`, `mediapipe_reference.json`). Default: shared coco_sample/.
    #[arg(long)]
    pub coco: Option<PathBuf>,
    /// Output JSON file.
    #[arg(long, default_value = "mp-out/eval_pose.json")]
    pub out: PathBuf,
    /// Model: full, lite, heavy or movenet.
    #[arg(long, default_value = "full")]
    pub model: String,
    /// ONNX Runtime intra-op threads.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Only the first N frames of each video (quick runs).
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Only videos whose stem contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// Smooth the keypoints (One-Euro, as MediaPipe's `smooth_landmarks=True`)
    /// and compare with the reference's `*_smooth` arrays.
    #[arg(long)]
    pub smooth: bool,
}

struct Reference {
    landmarks_px: Array3<f32>,
    visibility: Array2<f32>,
    found: Array1<bool>,
    process_ms: Array1<f32>,
}

fn read_reference(path: &Path, smooth: bool) -> Result<Reference> {
    let sfx = if smooth { "_smooth" } else { "" };
    let f = File::open(path).with_context(|| format!("opening {}", path.display()))?;
    let mut npz = NpzReader::new(f).with_context(|| format!("reading {}", path.display()))?;
    let get = |e: ndarray_npy::ReadNpzError, k: &str| {
        anyhow::anyhow!("{}: array `{k}`: {e}", path.display())
    };
    Ok(Reference {
        landmarks_px: npz
            .by_name(&format!("landmarks_px{sfx}"))
            .map_err(|e| get(e, "landmarks_px"))?,
        visibility: npz
            .by_name(&format!("visibility{sfx}"))
            .map_err(|e| get(e, "visibility"))?,
        found: npz
            .by_name(&format!("found{sfx}"))
            .map_err(|e| get(e, "found"))?,
        process_ms: npz
            .by_name(&format!("process_ms{sfx}"))
            .map_err(|e| get(e, "process_ms"))?,
    })
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    // Linear interpolation between order statistics (numpy's default).
    let pos = q * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    let w = pos - lo as f64;
    sorted[lo] * (1.0 - w) + sorted[hi] * w
}

fn round(v: f64, digits: i32) -> Value {
    if v.is_finite() {
        let m = 10f64.powi(digits);
        json!((v * m).round() / m)
    } else {
        Value::Null
    }
}

fn open(model: ModelChoice, threads: usize, tracking: bool) -> Result<Box<dyn PoseEstimator>> {
    let session = SessionParams {
        intra_threads: threads,
        ..Default::default()
    };
    let Some(lm) = model.landmark_model() else {
        return Ok(Box::new(
            MoveNet::new(MoveNetParams {
                session,
                ..Default::default()
            })
            .map_err(|e| anyhow::anyhow!("{e}"))?,
        ));
    };
    Ok(Box::new(
        BlazePose::new(BlazePoseParams {
            model: lm,
            session,
            tracking,
            // The reference was produced through MediaPipe's Python API, which
            // stamps frames 1/30 s apart whatever the video's rate.
            fixed_frame_interval_s: Some(1.0 / 30.0),
            ..Default::default()
        })
        .map_err(|e| anyhow::anyhow!("{e}"))?,
    ))
}

fn list_videos(dirs: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for d in dirs {
        let rd = std::fs::read_dir(d).with_context(|| format!("reading {}", d.display()))?;
        for e in rd {
            let p = e?.path();
            let ext = p
                .extension()
                .and_then(|e| e.to_str())
                .unwrap_or("")
                .to_ascii_lowercase();
            if matches!(ext.as_str(), "mp4" | "avi" | "mov" | "mkv" | "webm") {
                out.push(p);
            }
        }
    }
    out.sort();
    Ok(out)
}

pub fn run(args: &EvalPoseArgs) -> Result<()> {
    let model = ModelChoice::parse(&args.model).map_err(|e| anyhow::anyhow!("{e}"))?;
    let data = mp_geom::data_dir();
    let need = |what: &str| {
        anyhow::anyhow!(
            "{what} not given and no shared data folder found (set MP_DATA_DIR or pass the folder)"
        )
    };
    let video_dirs = if args.videos.is_empty() {
        let d = data.clone().ok_or_else(|| need("--videos"))?;
        vec![d.join("golfdb"), d.join("quva_repetition/videos")]
    } else {
        args.videos.clone()
    };
    let ref_dir = match &args.reference {
        Some(r) => r.clone(),
        None => data
            .clone()
            .ok_or_else(|| need("--reference"))?
            .join("reference_keypoints"),
    };
    let coco_dir = match &args.coco {
        Some(c) => Some(c.clone()),
        None => data.as_ref().map(|d| d.join("coco_sample")),
    };

    let videos = list_videos(&video_dirs)?;
    let mut by_video = serde_json::Map::new();
    let mut pooled: Vec<f64> = Vec::new();
    let (mut frames_all, mut est_ms_all, mut track_ms_all, mut track_frames_all) =
        (0usize, 0.0, 0.0, 0usize);
    let (mut ref_ms_all, mut ref_frames_all) = (0.0f64, 0usize);
    let mut agree_all = 0usize;
    let mut found_all = 0usize;
    let mut rows = Vec::new();
    let (mut all_ms, mut all_ref_ms): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut estimator = open(model, args.threads, true)?;
    let coco_map = estimator.skeleton().name == "coco17";

    for video in &videos {
        let stem = video
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("")
            .to_string();
        if let Some(o) = &args.only {
            if !stem.contains(o.as_str()) {
                continue;
            }
        }
        let ref_path = ref_dir.join(format!("{stem}.npz"));
        if !ref_path.is_file() {
            eprintln!("eval pose: no reference for {} (skipped)", video.display());
            continue;
        }
        let r = read_reference(&ref_path, args.smooth)?;
        let source = open_source(video).map_err(|e| anyhow::anyhow!("{e}"))?;
        let opts = ExtractOptions {
            max_frames: args.max_frames,
            smoothing: args.smooth.then(SmoothingParams::default),
            // MediaPipe's Python API stamps frames 1/30 s apart.
            fixed_frame_interval_s: Some(1.0 / 30.0),
            ..ExtractOptions::default()
        };
        let ex = extract_track(source, estimator.as_mut(), &opts, |_, _| {})
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let t = ex.track.n_frames();
        if r.found.len() < t {
            bail!(
                "{}: reference has {} frames, decoding gave {t}",
                ref_path.display(),
                r.found.len()
            );
        }
        let pos = ex.track.positions();
        let mut errs = Vec::new();
        let mut agree = 0usize;
        for ti in 0..t {
            if ex.found[ti] == r.found[ti] {
                agree += 1;
            }
            if !(ex.found[ti] && r.found[ti]) {
                continue;
            }
            let joints: Vec<(usize, usize)> = if coco_map {
                BLAZEPOSE_TO_COCO17
                    .iter()
                    .enumerate()
                    .map(|(c, &b)| (c, b))
                    .collect()
            } else {
                (0..33).map(|k| (k, k)).collect()
            };
            for (ours, theirs) in joints {
                if r.visibility[[ti, theirs]] <= 0.5 {
                    continue;
                }
                let dx = pos[[ti, ours, 0]] - r.landmarks_px[[ti, theirs, 0]] as f64;
                let dy = pos[[ti, ours, 1]] - r.landmarks_px[[ti, theirs, 1]] as f64;
                let d = (dx * dx + dy * dy).sqrt();
                if d.is_finite() {
                    errs.push(d);
                }
            }
        }
        errs.sort_by(f64::total_cmp);
        pooled.extend(&errs);
        let est_ms: f64 = ex.estimate_ms.iter().sum();
        let (mut tr_ms, mut tr_n) = (0.0, 0usize);
        for (ti, ms) in ex.estimate_ms.iter().enumerate() {
            if ex.found[ti] && !ex.detector_ran[ti] {
                tr_ms += ms;
                tr_n += 1;
            }
        }
        let ref_ms: f64 = r.process_ms.iter().take(t).map(|&v| v as f64).sum();
        let mut ms_sorted = ex.estimate_ms.clone();
        ms_sorted.sort_by(f64::total_cmp);
        let mut ref_sorted: Vec<f64> = r.process_ms.iter().take(t).map(|&v| v as f64).collect();
        ref_sorted.sort_by(f64::total_cmp);
        all_ms.extend(&ex.estimate_ms);
        all_ref_ms.extend(&ref_sorted);
        let found_n = ex.found.iter().filter(|&&f| f).count();
        let ref_found_n = r.found.iter().take(t).filter(|&&f| f).count();
        let det_n = ex.detector_ran.iter().filter(|&&d| d).count();
        frames_all += t;
        est_ms_all += est_ms;
        track_ms_all += tr_ms;
        track_frames_all += tr_n;
        ref_ms_all += ref_ms;
        ref_frames_all += t;
        agree_all += agree;
        found_all += found_n;
        let fps = t as f64 * 1000.0 / est_ms;
        let track_fps = if tr_n > 0 {
            tr_n as f64 * 1000.0 / tr_ms
        } else {
            f64::NAN
        };
        let ref_fps = t as f64 * 1000.0 / ref_ms;
        let entry = json!({
            "frames": t,
            "width": ex.width,
            "height": ex.height,
            "fps_video": round(ex.track.fps(), 3),
            "median_px": round(quantile(&errs, 0.5), 3),
            "p90_px": round(quantile(&errs, 0.9), 3),
            "mean_px": round(errs.iter().sum::<f64>() / errs.len().max(1) as f64, 3),
            "compared_points": errs.len(),
            "found_frac": round(found_n as f64 / t as f64, 4),
            "reference_found_frac": round(ref_found_n as f64 / t as f64, 4),
            "found_agreement": round(agree as f64 / t as f64, 4),
            "detector_frames_with_pose": det_n,
            "fps": round(fps, 1),
            "fps_tracking": round(track_fps, 1),
            "fps_with_decoding": round(t as f64 * 1000.0 / ex.total_ms, 1),
            "reference_fps": round(ref_fps, 1),
            "ms_per_frame_median": round(quantile(&ms_sorted, 0.5), 2),
            "reference_ms_per_frame_median": round(quantile(&ref_sorted, 0.5), 2),
        });
        println!(
            "{stem:<22} frames {t:>4}  median {:>6.2} px  p90 {:>6.2} px  found {:.3} (ref {:.3}, agree {:.3})  {:>5.1} fps (tracking {:>5.1}; ref {:>5.1})",
            quantile(&errs, 0.5),
            quantile(&errs, 0.9),
            found_n as f64 / t as f64,
            ref_found_n as f64 / t as f64,
            agree as f64 / t as f64,
            fps,
            track_fps,
            ref_fps
        );
        rows.push((stem.clone(), entry.clone()));
        by_video.insert(stem, entry);
    }
    if frames_all == 0 {
        bail!(
            "no video with a reference found in {:?} / {}",
            video_dirs,
            ref_dir.display()
        );
    }
    pooled.sort_by(f64::total_cmp);
    all_ms.sort_by(f64::total_cmp);
    all_ref_ms.sort_by(f64::total_cmp);
    let overall = json!({
        "ms_per_frame_median": round(quantile(&all_ms, 0.5), 2),
        "reference_ms_per_frame_median": round(quantile(&all_ref_ms, 0.5), 2),
        "videos": by_video.len(),
        "frames": frames_all,
        "median_px": round(quantile(&pooled, 0.5), 3),
        "p90_px": round(quantile(&pooled, 0.9), 3),
        "mean_px": round(pooled.iter().sum::<f64>() / pooled.len().max(1) as f64, 3),
        "compared_points": pooled.len(),
        "found_frac": round(found_all as f64 / frames_all as f64, 4),
        "found_agreement": round(agree_all as f64 / frames_all as f64, 4),
        "fps": round(frames_all as f64 * 1000.0 / est_ms_all, 1),
        "fps_tracking": round(track_frames_all as f64 * 1000.0 / track_ms_all, 1),
        "reference_fps": round(ref_frames_all as f64 * 1000.0 / ref_ms_all, 1),
    });
    println!(
        "overall: {} frames, median {:.2} px, p90 {:.2} px, {:.1} fps (tracking {:.1}; MediaPipe {:.1})",
        frames_all,
        quantile(&pooled, 0.5),
        quantile(&pooled, 0.9),
        frames_all as f64 * 1000.0 / est_ms_all,
        track_frames_all as f64 * 1000.0 / track_ms_all,
        ref_frames_all as f64 * 1000.0 / ref_ms_all
    );

    let coco = match coco_dir.filter(|d| d.join("test_coco.json").is_file()) {
        Some(d) => Some(eval_coco(&d, model, args.threads)?),
        None => {
            eprintln!("eval pose: no COCO sample folder; PCK skipped");
            None
        }
    };

    let report = json!({
        "model": model.as_str(),
        "threads": args.threads,
        "smooth": args.smooth,
        "overall": overall,
        "by_video": Value::Object(by_video),
        "coco_sample": coco,
    });
    if let Some(parent) = args.out.parent() {
        if !parent.as_os_str().is_empty() {
            std::fs::create_dir_all(parent)?;
        }
    }
    crate::write_file(&args.out, serde_json::to_string_pretty(&report)?)
        .with_context(|| format!("writing {}", args.out.display()))?;
    println!("wrote {}", args.out.display());
    print_markdown(model, &report, &rows);
    Ok(())
}

/// The per-video table of [`print_markdown`], with the overall row last.
fn markdown_table(model: ModelChoice, report: &Value, rows: &[(String, Value)]) -> String {
    let f = |v: &Value| match v {
        Value::Null => "–".to_string(),
        other => other.to_string(),
    };
    let mut t = Table::new([
        "video",
        "frames",
        "median px",
        "p90 px",
        "found (ours / MediaPipe)",
        "agree",
        "fps (all / tracking)",
        "MediaPipe fps",
        "ms/frame median (ours / MediaPipe)",
    ]);
    for (stem, e) in rows {
        t.row([
            stem.clone(),
            e["frames"].to_string(),
            f(&e["median_px"]),
            f(&e["p90_px"]),
            format!("{} / {}", e["found_frac"], e["reference_found_frac"]),
            e["found_agreement"].to_string(),
            format!("{} / {}", f(&e["fps"]), f(&e["fps_tracking"])),
            f(&e["reference_fps"]),
            format!(
                "{} / {}",
                f(&e["ms_per_frame_median"]),
                f(&e["reference_ms_per_frame_median"])
            ),
        ]);
    }
    let o = &report["overall"];
    t.row([
        format!("**all ({})**", model.as_str()),
        o["frames"].to_string(),
        format!("**{}**", f(&o["median_px"])),
        format!("**{}**", f(&o["p90_px"])),
        o["found_frac"].to_string(),
        o["found_agreement"].to_string(),
        format!("**{} / {}**", f(&o["fps"]), f(&o["fps_tracking"])),
        f(&o["reference_fps"]),
        format!(
            "{} / {}",
            f(&o["ms_per_frame_median"]),
            f(&o["reference_ms_per_frame_median"])
        ),
    ]);
    t.markdown()
}

fn print_markdown(model: ModelChoice, report: &Value, rows: &[(String, Value)]) {
    println!();
    print!("{}", markdown_table(model, report, rows));
    let f = |v: &Value| match v {
        Value::Null => "–".to_string(),
        other => other.to_string(),
    };
    if let Some(c) = report.get("coco_sample").filter(|c| !c.is_null()) {
        println!();
        println!(
            "COCO sample ({} images): PCK@0.2·torso {} (MediaPipe {}), PCK@0.2·bbox-diagonal {} (MediaPipe {}); mean distance to MediaPipe's landmarks {} px",
            c["images"], c["pck_torso"], c["mediapipe_pck_torso"], c["pck_bbox"], c["mediapipe_pck_bbox"], f(&c["mean_px_vs_mediapipe"])
        );
    }
}

fn eval_coco(dir: &Path, model: ModelChoice, threads: usize) -> Result<Value> {
    let ann: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("test_coco.json")).context("reading test_coco.json")?,
    )?;
    let mp_ref: Option<Value> = std::fs::read_to_string(dir.join("mediapipe_reference.json"))
        .ok()
        .and_then(|s| serde_json::from_str(&s).ok());
    let images = ann["images"]
        .as_array()
        .context("test_coco.json: no images")?;
    let anns = ann["annotations"]
        .as_array()
        .context("test_coco.json: no annotations")?;
    let mut estimator = open(model, threads, false)?;
    let coco_out = estimator.skeleton().name == "coco17";
    let (mut ok_t, mut ok_b, mut n_lab) = (0usize, 0usize, 0usize);
    let (mut mp_ok_t, mut mp_ok_b) = (0usize, 0usize);
    let mut vs_mp = Vec::new();
    let mut per_image = Vec::new();
    for img in images {
        let file = img["file_name"]
            .as_str()
            .context("image without file_name")?;
        let id = img["id"].as_i64().context("image without id")?;
        let frame = read_image(dir.join(file)).map_err(|e| anyhow::anyhow!("{e}"))?;
        estimator.reset();
        let pose = estimator
            .estimate(&frame)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        // Our COCO-17 prediction.
        let pred: Option<Vec<[f64; 2]>> = pose.as_ref().map(|p| {
            if coco_out {
                p.keypoints_px.clone()
            } else {
                BLAZEPOSE_TO_COCO17
                    .iter()
                    .map(|&b| p.keypoints_px[b])
                    .collect()
            }
        });
        // MediaPipe's prediction for the same image.
        let mp_img = mp_ref
            .as_ref()
            .and_then(|r| r["images"].as_array())
            .and_then(|a| a.iter().find(|i| i["file_name"].as_str() == Some(file)));
        let mp_pred: Option<Vec<[f64; 2]>> = mp_img
            .and_then(|i| i["coco17_pred_px"].as_array())
            .map(|a| {
                a.iter()
                    .map(|p| {
                        [
                            p[0].as_f64().unwrap_or(f64::NAN),
                            p[1].as_f64().unwrap_or(f64::NAN),
                        ]
                    })
                    .collect()
            });
        if let (Some(p), Some(lms)) = (&pose, mp_img.and_then(|i| i["landmarks"].as_array())) {
            if !coco_out {
                for (k, l) in lms.iter().enumerate().take(33) {
                    let (x, y) = (
                        l[0].as_f64().unwrap_or(f64::NAN),
                        l[1].as_f64().unwrap_or(f64::NAN),
                    );
                    let d = ((p.keypoints_px[k][0] - x).powi(2)
                        + (p.keypoints_px[k][1] - y).powi(2))
                    .sqrt();
                    if d.is_finite() {
                        vs_mp.push(d);
                    }
                }
            }
        }
        // The annotated person with the largest box.
        let best = anns
            .iter()
            .filter(|a| {
                a["image_id"].as_i64() == Some(id) && a["num_keypoints"].as_i64().unwrap_or(0) > 0
            })
            .max_by(|a, b| {
                let area = |a: &Value| {
                    a["bbox"][2].as_f64().unwrap_or(0.0) * a["bbox"][3].as_f64().unwrap_or(0.0)
                };
                area(a).total_cmp(&area(b))
            });
        let Some(best) = best else { continue };
        let kp: Vec<f64> = best["keypoints"]
            .as_array()
            .context("annotation without keypoints")?
            .iter()
            .map(|v| v.as_f64().unwrap_or(0.0))
            .collect();
        let gt = |j: usize| (kp[3 * j], kp[3 * j + 1], kp[3 * j + 2]);
        let dist = |a: usize, b: usize| {
            let (ax, ay, av) = gt(a);
            let (bx, by, bv) = gt(b);
            (av > 0.0 && bv > 0.0).then(|| ((ax - bx).powi(2) + (ay - by).powi(2)).sqrt())
        };
        let torso = dist(5, 12).or_else(|| dist(6, 11)).unwrap_or(f64::NAN);
        let bw = best["bbox"][2].as_f64().unwrap_or(0.0);
        let bh = best["bbox"][3].as_f64().unwrap_or(0.0);
        let diag = (bw * bw + bh * bh).sqrt();
        let count = |pred: &Option<Vec<[f64; 2]>>, ok_t: &mut usize, ok_b: &mut usize| -> usize {
            let mut lab = 0;
            for j in 0..17 {
                let (x, y, v) = gt(j);
                if v <= 0.0 {
                    continue;
                }
                lab += 1;
                if let Some(p) = pred {
                    let d = ((p[j][0] - x).powi(2) + (p[j][1] - y).powi(2)).sqrt();
                    if d <= 0.2 * torso {
                        *ok_t += 1;
                    }
                    if d <= 0.2 * diag {
                        *ok_b += 1;
                    }
                }
            }
            lab
        };
        let (mut it, mut ib) = (0, 0);
        let lab = count(&pred, &mut it, &mut ib);
        let (mut mt, mut mb) = (0, 0);
        count(&mp_pred, &mut mt, &mut mb);
        ok_t += it;
        ok_b += ib;
        mp_ok_t += mt;
        mp_ok_b += mb;
        n_lab += lab;
        per_image.push(json!({
            "file": file,
            "found": pose.is_some(),
            "labelled": lab,
            "correct_torso": it,
            "correct_bbox": ib,
            "mediapipe_correct_torso": mt,
            "torso_px": round(torso, 1),
        }));
        println!(
            "coco {file}: found {} PCK@0.2 torso {it}/{lab} (MediaPipe {mt}/{lab})",
            pose.is_some()
        );
    }
    let frac = |a: usize| {
        if n_lab > 0 {
            a as f64 / n_lab as f64
        } else {
            f64::NAN
        }
    };
    Ok(json!({
        "images": per_image.len(),
        "labelled_keypoints": n_lab,
        "pck_torso": round(frac(ok_t), 3),
        "pck_bbox": round(frac(ok_b), 3),
        "mediapipe_pck_torso": round(frac(mp_ok_t), 3),
        "mediapipe_pck_bbox": round(frac(mp_ok_b), 3),
        "mean_px_vs_mediapipe": round(
            if vs_mp.is_empty() { f64::NAN } else { vs_mp.iter().sum::<f64>() / vs_mp.len() as f64 },
            2
        ),
        "per_image": per_image,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_table_keeps_the_old_layout() {
        let e = json!({"frames": 10, "median_px": 1.5, "p90_px": null, "found_frac": 0.9,
            "reference_found_frac": 1.0, "found_agreement": 0.8, "fps": 30.0, "fps_tracking": null,
            "reference_fps": 25.0, "ms_per_frame_median": 3.0, "reference_ms_per_frame_median": 4.0});
        let report = json!({ "overall": e.clone() });
        let got = markdown_table(ModelChoice::Full, &report, &[("v1".to_string(), e)]);
        let want = "| video | frames | median px | p90 px | found (ours / MediaPipe) | agree | fps (all / tracking) | MediaPipe fps | ms/frame median (ours / MediaPipe) |\n\
            |---|---|---|---|---|---|---|---|---|\n\
            | v1 | 10 | 1.5 | – | 0.9 / 1.0 | 0.8 | 30.0 / – | 25.0 | 3.0 / 4.0 |\n\
            | **all (full)** | 10 | **1.5** | **–** | 0.9 | 0.8 | **30.0 / –** | 25.0 | 3.0 / 4.0 |\n";
        assert_eq!(got, want);
    }
}
