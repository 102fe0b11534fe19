//! `cargo xtask eval pose-rate --videos DIR --labels DIR --out FILE.json`:
//! the pose model on a subset of the frames (`mp run --pose-fps`), against
//! the same run on every frame. Each labelled video goes through
//! `mp_pipeline::analyse_input` (what `mp run` does) once per stride
//! (`--strides 1,2,3`: every frame, every second, every third), with
//! `Params::default()` and only `pose.rate` changed. Per stride: the counts
//! (MAE and OBO against the labels, and the change from every frame), the
//! main person's keypoints against those of every frame (pixels: on the
//! frames the model ran on and on the filled ones), the concrete program
//! (segments, and its distance from the every-frame keypoints) and the time
//! of the pose stage.

use std::path::PathBuf;

use anyhow::bail;
use clap::Args;
use mp_geom::Track;
use mp_pipeline::{Params, PoseRate, Stage};
use serde_json::{json, Map, Value};

/// Arguments of `cargo xtask eval pose-rate`.
#[derive(Args, Debug)]
pub struct EvalPoseRateArgs {
    /// A folder of videos (or one video) with labels.
    #[arg(long, default_value = "../shared/data/quva_repetition/videos")]
    pub videos: PathBuf,
    /// A folder of labels: `<video stem>.npy`, one entry per repetition.
    #[arg(long, default_value = "../shared/data/quva_repetition/annotations")]
    pub labels: PathBuf,
    /// Strides compared (1 = every frame, the reference; must include 1).
    #[arg(long, value_delimiter = ',', default_value = "1,2,3")]
    pub strides: Vec<usize>,
    /// Output JSON.
    #[arg(long)]
    pub out: PathBuf,
}

/// Distances (pixels) between the joints valid in both tracks, on the frames
/// `which` accepts.
fn distances(a: &Track, b: &Track, which: impl Fn(usize) -> bool) -> Vec<f64> {
    let n = a.n_frames().min(b.n_frames());
    let mut d = Vec::new();
    for t in (0..n).filter(|&t| which(t)) {
        for j in 0..a.n_joints().min(b.n_joints()) {
            if a.is_valid(t, j, 0.0) && b.is_valid(t, j, 0.0) {
                let (p, q) = (a.point(t, j), b.point(t, j));
                d.push(((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt());
            }
        }
    }
    d
}

fn quantile(v: &[f64], q: f64) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    Some(s[((s.len() - 1) as f64 * q).round() as usize])
}

/// One video at one stride.
struct RateRun {
    count: usize,
    track: Track,
    program: Option<mp_concrete::Program>,
    pose_s: f64,
    total_s: f64,
}

fn run_one(video: &std::path::Path, stride: usize, fps: f64) -> anyhow::Result<RateRun> {
    let mut params = Params::default();
    params.pose.rate = if stride <= 1 {
        PoseRate::Every
    } else {
        PoseRate::Fps(fps / stride as f64)
    };
    if params.pose.rate.stride(fps) != stride {
        bail!("stride {stride} at {fps} fps is not reachable");
    }
    let out = crate::count::analyse_video(video, &params)?;
    let pose_s = crate::count::stage_seconds(&out, Stage::Pose);
    Ok(RateRun {
        count: out.counts.total,
        program: out.analysis.map(|a| a.concrete),
        track: out.keypoints.track,
        pose_s,
        total_s: out.total.as_secs_f64(),
    })
}

pub fn run(a: &EvalPoseRateArgs) -> anyhow::Result<()> {
    if !a.strides.contains(&1) {
        bail!("--strides must include 1 (every frame, the reference)");
    }
    let items = crate::count::labelled(&a.videos, &a.labels)?;
    if items.is_empty() {
        bail!("no labelled video in {}", a.videos.display());
    }
    let mut by_video = Map::new();
    // Per stride: abs. rel. count errors, OBO, count changes, distances posed / filled,
    // program distances, pose seconds, frames.
    let k = a.strides.len();
    let mut errs = vec![Vec::new(); k];
    let mut obo = vec![0usize; k];
    let mut changed = vec![0usize; k];
    let mut d_posed = vec![Vec::new(); k];
    let mut d_filled = vec![Vec::new(); k];
    let mut d_prog = vec![Vec::new(); k];
    let mut pose_s = vec![0.0f64; k];
    let mut total_s = vec![0.0f64; k];
    let mut frames = 0usize;
    for (video, label) in &items {
        let (name, truth) = crate::count::name_and_count(video, label)?;
        let fps = mp_pose::VideoReader::open(video)?.info().fps;
        let runs = a
            .strides
            .iter()
            .map(|&s| run_one(video, s, fps))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let Some(full) = a.strides.iter().position(|&s| s == 1).map(|i| &runs[i]) else {
            bail!("no every-frame run");
        };
        frames += full.track.n_frames();
        let mut per = Map::new();
        for (i, (&s, r)) in a.strides.iter().zip(&runs).enumerate() {
            let n = r.track.n_frames();
            let posed = |t: usize| mp_pose::is_posed_frame(t, s, Some(n));
            let dp = distances(&r.track, &full.track, posed);
            let df = distances(&r.track, &full.track, |t| !posed(t));
            let prog = match &r.program {
                Some(p) => distances(&p.execute()?, &full.track, |_| true),
                None => Vec::new(),
            };
            let err = (r.count as f64 - truth as f64).abs() / truth.max(1) as f64;
            errs[i].push(err);
            obo[i] += usize::from((r.count as i64 - truth as i64).abs() <= 1);
            changed[i] += usize::from(r.count != full.count);
            pose_s[i] += r.pose_s;
            total_s[i] += r.total_s;
            eprintln!(
                "{name} every {s}: count {} (labelled {truth}), filled median {:.2} px, pose {:.1} s",
                r.count,
                quantile(&df, 0.5).unwrap_or(0.0),
                r.pose_s
            );
            per.insert(
                format!("stride_{s}"),
                json!({
                    "count": r.count, "abs_rel_error": err,
                    "posed_median_px": quantile(&dp, 0.5), "filled_median_px": quantile(&df, 0.5),
                    "filled_p90_px": quantile(&df, 0.9),
                    "segments": r.program.as_ref().map(|p| p.n_segments()),
                    "program_median_px_to_every_frame": quantile(&prog, 0.5),
                    "pose_s": r.pose_s, "total_s": r.total_s,
                }),
            );
            d_posed[i].extend(dp);
            d_filled[i].extend(df);
            d_prog[i].extend(prog);
        }
        per.insert("true_count".into(), json!(truth));
        per.insert("frames".into(), json!(full.track.n_frames()));
        per.insert("fps".into(), json!(fps));
        by_video.insert(name, Value::Object(per));
    }
    let nv = items.len() as f64;
    let summary: Vec<Value> = a
        .strides
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            json!({
                "stride": s,
                "count_mae": errs[i].iter().sum::<f64>() / nv,
                "obo_acc": obo[i] as f64 / nv,
                "counts_changed": changed[i],
                "posed_median_px": quantile(&d_posed[i], 0.5),
                "filled_median_px": quantile(&d_filled[i], 0.5),
                "filled_p90_px": quantile(&d_filled[i], 0.9),
                "all_frames_median_px": quantile(&[d_posed[i].clone(), d_filled[i].clone()].concat(), 0.5),
                "program_median_px_to_every_frame": quantile(&d_prog[i], 0.5),
                "pose_ms_per_frame": 1000.0 * pose_s[i] / frames.max(1) as f64,
                "total_ms_per_frame": 1000.0 * total_s[i] / frames.max(1) as f64,
            })
        })
        .collect();
    let report = json!({
        "kind": "pose_rate",
        "definition": "mp_pipeline::analyse_input with Params::default() and pose.rate = every s-th frame, on each labelled video; distances in pixels between the main person's keypoints (COCO-17) and those of the every-frame run, on joints valid in both; posed = frames the model ran on, filled = the frames between; program = the concrete program executed against the every-frame keypoints; MAE = mean |count − true| / true",
        "videos": items.len(), "frames": frames,
        "by_stride": summary,
        "by_video": by_video,
    });
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    mp_geom::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    println!("{}", serde_json::to_string_pretty(&report["by_stride"])?);
    eprintln!("written to {}", a.out.display());
    Ok(())
}
