//! `cargo xtask eval video-predict`: the first half of each video observed,
//! the second half predicted and scored against the real one (KD, PSNR,
//! SSIM); see the parent module.

use std::path::PathBuf;
use std::time::Instant;

use super::metrics::PixelBox;
use clap::Args;
use mp_pipeline::Params;
use mp_pose::VideoReader;
use mp_video::{VideoMotion, VideoPredictMethod, VideoPredictParams};
use serde_json::{json, Map, Value};

use super::{common_kd, kd, mean, num, shared_videos, stem, PoseStream, Scores, MIN_CONF};

/// Arguments of `cargo xtask eval video-predict`.
#[derive(Args, Debug)]
pub struct EvalVideoPredictArgs {
    /// Videos (default: the shared QUVA videos).
    #[arg(long)]
    pub videos: Vec<PathBuf>,
    /// Output JSON.
    #[arg(long)]
    pub out: PathBuf,
}

/// `cargo xtask eval video-predict`.
pub fn run_video_predict(a: &EvalVideoPredictArgs) -> anyhow::Result<()> {
    let t_all = Instant::now();
    let videos = if a.videos.is_empty() {
        shared_videos(false)?
    } else {
        a.videos.clone()
    };
    let params = Params::default();
    let pparams = VideoPredictParams::default();
    let methods = [
        VideoPredictMethod::Loop,
        VideoPredictMethod::Nearest,
        VideoPredictMethod::Constant,
    ];
    let mut per_video = Map::new();
    let mut pooled: std::collections::BTreeMap<&'static str, (Vec<f64>, Scores)> =
        Default::default();
    let mut kd_by: std::collections::BTreeMap<
        &'static str,
        std::collections::BTreeMap<String, f64>,
    > = Default::default();
    for video in &videos {
        let name = stem(video);
        let n = VideoReader::open(video)?.count();
        let half = n / 2;
        if half < 2 {
            continue;
        }
        let horizon = n - half;
        eprint!("{name}: observing {half} frames … ");
        let m = VideoMotion::analyse(video, &params, Some(half))?;
        // The poses of the real second half, from the pose model run on those frames alone.
        let info = mp_pose::probe(video)?;
        let (w, h) = (info.width, info.height);
        let mut ps = PoseStream::start(w, h, info.fps)?;
        for f in VideoReader::open(video)?.skip(half) {
            ps.push(&f?.rgb)?;
        }
        let truth = ps.finish()?;
        eprintln!("{} loop(s) counted", m.counts.intervals.len());
        let mut vres = Map::new();
        for method in methods {
            let t0 = Instant::now();
            let plan = match m.plan_prediction(horizon, method, &pparams) {
                Ok(p) => p,
                Err(e) => {
                    vres.insert(method.as_str().into(), json!({"error": e.to_string()}));
                    continue;
                }
            };
            let mut truth_frames = VideoReader::open(video)?.skip(half);
            let mut ps = PoseStream::start(w, h, info.fps)?;
            let mut scores = Scores::default();
            let mut t = 0usize;
            plan.plan.render(video, &pparams.render, |rgb| {
                let tf = truth_frames
                    .next()
                    .ok_or_else(|| mp_video::VideoError::Edit("the truth ended early".into()))??;
                ps.push(rgb)
                    .map_err(|e| mp_video::VideoError::Edit(e.to_string()))?;
                let pbox = PixelBox::around_pose(&truth, t, MIN_CONF, 0.1, w, h);
                scores
                    .add(rgb, &tf.rgb, w, h, pbox)
                    .map_err(|e| mp_video::VideoError::Edit(e.to_string()))?;
                t += 1;
                Ok(())
            })?;
            let pose = ps.finish()?;
            let frames: Vec<usize> = (0..horizon).collect();
            let (kd_all, pairs) = kd(&pose, &truth, &frames, None);
            eprintln!(
                "  {:<9} KD {kd_all:.2} px, PSNR {:.2} dB, SSIM {:.4}, cycle {:?} ({}, {})",
                method.as_str(),
                mean(&scores.psnr),
                mean(&scores.ssim),
                plan.cycle,
                plan.used.as_str(),
                plan.source
            );
            vres.insert(
                method.as_str().into(),
                json!({
                    "kd_px": num(kd_all),
                    "kd_pairs": pairs,
                    "psnr_db": num(mean(&scores.psnr)),
                    "ssim": num(mean(&scores.ssim)),
                    "psnr_box_db": num(mean(&scores.psnr_box)),
                    "ssim_box": num(mean(&scores.ssim_box)),
                    "used": plan.used.as_str(),
                    "source": plan.source,
                    "cycle": [plan.cycle.0, plan.cycle.1],
                    "seconds": num(t0.elapsed().as_secs_f64()),
                }),
            );
            kd_by
                .entry(method.as_str())
                .or_default()
                .insert(name.clone(), kd_all);
            let e = pooled.entry(method.as_str()).or_default();
            if kd_all.is_finite() {
                e.0.push(kd_all);
            }
            e.1.psnr.push(mean(&scores.psnr));
            e.1.ssim.push(mean(&scores.ssim));
            e.1.psnr_box.push(mean(&scores.psnr_box));
            e.1.ssim_box.push(mean(&scores.ssim_box));
        }
        per_video.insert(
            name,
            json!({"frames": n, "observed": half, "predicted": horizon, "methods": vres}),
        );
    }
    let mut summary = Map::new();
    println!("method     KD (px)  PSNR (dB)  SSIM    PSNR box  SSIM box  videos");
    for (m, (kds, s)) in &pooled {
        println!(
            "{:<9}  {:>7.2}  {}    {}",
            m,
            mean(kds),
            s.columns(),
            s.psnr.len()
        );
        summary.insert((*m).into(), s.summary("kd_px", mean(kds), s.psnr.len()));
    }
    let keys: Vec<&'static str> = methods.iter().map(|m| m.as_str()).collect();
    let (means, n_common) = common_kd(&kd_by, &keys);
    let text: Vec<String> = keys
        .iter()
        .zip(&means)
        .map(|(m, x)| format!("{m} {x:.2}"))
        .collect();
    println!(
        "KD over the {n_common} videos where every method has one: {}",
        text.join(", ")
    );
    for (m, x) in keys.iter().zip(&means) {
        if let Some(Value::Object(o)) = summary.get_mut(*m) {
            o.insert("kd_common_px".into(), num(*x));
            o.insert("kd_common_videos".into(), json!(n_common));
        }
    }
    let report = json!({
        "task": "video-predict",
        "protocol": "observe the first half of each video, predict the second half; KD of the pose model on predicted vs real frames (all COCO-17 joints seen in both), PSNR/SSIM per frame; means over videos of per-video means",
        "videos": videos.iter().map(|v| stem(v)).collect::<Vec<_>>(),
        "summary": summary,
        "per_video": per_video,
        "seconds": num(t_all.elapsed().as_secs_f64()),
    });
    mp_geom::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    eprintln!("written to {}", a.out.display());
    Ok(())
}
