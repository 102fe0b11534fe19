//! `cargo xtask eval count --videos DIR --labels DIR --out FILE.json`:
//! repetition counts from video, exactly as `mp run` makes them
//! (`mp_pipeline::analyse_input` with `Params::default()`: decoding, pose,
//! programs, counting from keypoints and frame thumbnails), against labels
//! in QUVA's form (`<video stem>.npy` = the frame where each cycle ends, so
//! the count is its length).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Args;
use mp_geom::CancelToken;
use mp_pipeline::{analyse_input, Input, Params, Silent, Stage};
use serde_json::{json, Map, Value};

/// Arguments of `cargo xtask eval count`.
#[derive(Args, Debug)]
pub struct EvalCountArgs {
    /// A folder of videos (or one video). Required unless `--synthetic`; with
    /// `--synthetic-video`, the labelled videos the cases are cut from
    /// (default: the shared data folder's QUVA videos).
    #[arg(long, required_unless_present_any = ["synthetic", "synthetic_video"])]
    pub videos: Option<PathBuf>,
    /// A folder of labels: `<video stem>.npy`, one entry per repetition. Required unless `--synthetic`.
    #[arg(long, required_unless_present_any = ["synthetic", "synthetic_video"])]
    pub labels: Option<PathBuf>,
    /// Output JSON.
    #[arg(long)]
    pub out: PathBuf,
    /// Count synthetic cases of known count built from the real keypoints of
    /// the shared data folder instead of videos (`eval_count_synth`).
    #[arg(long, conflicts_with_all = ["videos", "labels"])]
    pub synthetic: bool,
    /// Count made videos of known count (QUVA cycles repeated between
    /// stretches of the golf swing, plain, small over moving footage, and
    /// partly covered; `synth_video`), clips cached under mp-out/video_cases.
    #[arg(long, conflicts_with = "synthetic")]
    pub synthetic_video: bool,
    /// Seed of the synthetic cases.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Number of synthetic cases.
    #[arg(long, default_value_t = 600, requires = "synthetic")]
    pub cases: usize,
    /// Changes a field of the counting parameters (`mp_abstract::CountParams`,
    /// e.g. `mismatch_fraction=0.4`), for choosing a default; the report
    /// names every change. Without it: the product's defaults.
    #[arg(long = "count-param", value_name = "KEY=VALUE")]
    pub count_params: Vec<String>,
    /// Fit the confidence model on the synthetic cases of these seeds
    /// (comma-separated) and score the cases of `--seed` with it; the
    /// report gives the coefficients (how `ConfidenceModel::default` is made).
    #[arg(
        long = "fit-confidence",
        value_name = "SEEDS",
        value_delimiter = ',',
        requires = "synthetic"
    )]
    pub fit_confidence: Vec<u64>,
    /// Long recordings of several activities: with `--videos`/`--labels`,
    /// every labelled video and `--golf` scaled to 640×360 at 30 fps and
    /// played in order `--repeats` times (`eval_count_long`); with
    /// `--synthetic`, synthetic long recordings of several repetitive
    /// stretches and real long recordings (`eval_count_long_synth`).
    #[arg(long)]
    pub long: bool,
    /// Non-repetitive footage (a golf swing): around the repetitions of
    /// `--synthetic-video` (default: the shared data folder's golf swing),
    /// and played after the labelled videos with `--long`.
    #[arg(long)]
    pub golf: Option<PathBuf>,
    /// Folder of the scaled clips and their keypoints (`--long`).
    #[arg(long, default_value = "mp-out/long_cache", requires = "long")]
    pub cache: PathBuf,
    /// How many times the clips are played (`--long`): 25 make about an hour.
    #[arg(long, default_value_t = 25, requires = "long")]
    pub repeats: usize,
    /// Synthetic long recordings per keypoint source (`--long --synthetic`).
    #[arg(long, default_value_t = 20, requires = "long")]
    pub long_cases: usize,
}

/// The product's parameters with `overrides` (`KEY=VALUE`, VALUE as JSON)
/// applied to the counting parameters.
pub fn params_with(overrides: &[String]) -> anyhow::Result<Params> {
    let mut params = Params::default();
    if overrides.is_empty() {
        return Ok(params);
    }
    let mut count = serde_json::to_value(&params.count)?;
    for o in overrides {
        let (k, v) = o
            .split_once('=')
            .with_context(|| format!("--count-param {o}: expected KEY=VALUE"))?;
        let field = count
            .get_mut(k)
            .with_context(|| format!("--count-param: no counting parameter `{k}`"))?;
        *field = serde_json::from_str(v)
            .with_context(|| format!("--count-param {k}: `{v}` is not a JSON value"))?;
    }
    params.count = serde_json::from_value(count)?;
    params.validate()?;
    Ok(params)
}

/// One video through `mp_pipeline::analyse_input` (what `mp run` does).
pub(crate) fn analyse_video(video: &Path, params: &Params) -> anyhow::Result<mp_pipeline::Outcome> {
    analyse_input(
        Input::open(video, None)?,
        params,
        &Silent,
        &CancelToken::new(),
    )
    .with_context(|| format!("analysing {}", video.display()))
}

/// A labelled video's name (its file stem) and its labelled count (the
/// label file's length).
pub(crate) fn name_and_count(video: &Path, label: &Path) -> anyhow::Result<(String, usize)> {
    let truth = mp_geom::read_npy(label)?.to_i64()?.len();
    let name = video
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    Ok((name, truth))
}

/// Seconds an analysis spent in `stage`.
pub(crate) fn stage_seconds(out: &mp_pipeline::Outcome, stage: Stage) -> f64 {
    out.stages
        .iter()
        .filter(|t| t.stage == stage)
        .map(|t| t.time.as_secs_f64())
        .sum()
}

/// Videos of a folder (or the one given) that have a label file.
pub(crate) fn labelled(videos: &Path, labels: &Path) -> anyhow::Result<Vec<(PathBuf, PathBuf)>> {
    let files: Vec<PathBuf> = if videos.is_dir() {
        let mut v: Vec<PathBuf> = std::fs::read_dir(videos)
            .with_context(|| format!("listing {}", videos.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| Input::is_video(p))
            .collect();
        v.sort();
        v
    } else {
        vec![videos.to_path_buf()]
    };
    Ok(files
        .into_iter()
        .filter_map(|v| {
            let stem = v.file_stem()?.to_string_lossy().to_string();
            let l = labels.join(format!("{stem}.npy"));
            l.is_file().then_some((v, l))
        })
        .collect())
}

pub fn run(a: &EvalCountArgs) -> anyhow::Result<()> {
    if a.long && a.synthetic {
        return crate::count_long_synth::run(
            &a.out,
            a.seed,
            a.long_cases,
            &params_with(&a.count_params)?,
            &a.count_params,
        );
    }
    if a.long {
        let (Some(videos), Some(labels)) = (a.videos.as_deref(), a.labels.as_deref()) else {
            bail!("--long needs --videos DIR and --labels DIR (or --synthetic)");
        };
        return crate::count_long::run(&crate::count_long::LongArgs {
            videos,
            labels,
            golf: a.golf.as_deref(),
            cache: &a.cache,
            repeats: a.repeats,
            out: &a.out,
            params: params_with(&a.count_params)?,
            overrides: &a.count_params,
        });
    }
    if a.synthetic {
        return crate::count_synth::run(
            &a.out,
            a.seed,
            a.cases,
            &params_with(&a.count_params)?,
            &a.count_params,
            &a.fit_confidence,
        );
    }
    if a.synthetic_video {
        let quva = Path::new("../shared/data/quva_repetition");
        return crate::count_video::run(
            &a.out,
            a.seed,
            &a.videos.clone().unwrap_or_else(|| quva.join("videos")),
            &a.labels.clone().unwrap_or_else(|| quva.join("annotations")),
            &a.golf
                .clone()
                .unwrap_or_else(|| Path::new("../shared/data/golfdb/golf_swing.mp4").to_path_buf()),
            &params_with(&a.count_params)?,
            &a.count_params,
        );
    }
    let (Some(videos), Some(labels)) = (a.videos.as_deref(), a.labels.as_deref()) else {
        bail!("--videos DIR and --labels DIR are required (or give --synthetic)");
    };
    let t0 = Instant::now();
    let items = labelled(videos, labels)?;
    if items.is_empty() {
        bail!(
            "no video in {} has a label file <stem>.npy in {}",
            videos.display(),
            labels.display()
        );
    }
    let params = params_with(&a.count_params)?;
    let mut by_video = Map::new();
    let (mut errs, mut obos) = (Vec::new(), Vec::new());
    let (mut frames_total, mut count_s, mut total_s) = (0usize, 0.0f64, 0.0f64);
    let mut motion_s = 0.0f64;
    // Keypoints, thumbnails and labels of each video, for leave-one-video-out.
    let mut kept: Vec<(String, mp_geom::Track, Option<mp_geom::Track>, usize)> = Vec::new();
    for (video, label) in &items {
        let (name, truth) = crate::count::name_and_count(video, label)?;
        eprint!("{name} … ");
        let out = analyse_video(video, &params)?;
        let c = &out.counts;
        let err = (c.total as f64 - truth as f64).abs() / truth.max(1) as f64;
        let obo = (c.total as i64 - truth as i64).abs() <= 1;
        eprintln!("{} (labelled {truth})", c.total);
        errs.push(err);
        obos.push(obo);
        let n = out.keypoints.track.n_frames();
        frames_total += n;
        let stage_s = |st: Stage| stage_seconds(&out, st);
        count_s += stage_s(Stage::Count);
        motion_s += stage_s(Stage::Motion);
        total_s += out.total.as_secs_f64();
        kept.push((
            name.clone(),
            out.keypoints.track.clone(),
            out.keypoints.thumbnails.clone(),
            truth,
        ));
        by_video.insert(
            name,
            json!({
                "true_count": truth, "count": c.total, "abs_rel_error": err, "obo": obo,
                "signal": c.signal.as_str(), "method": c.method.as_str(), "confidence": c.confidence,
                "periodicity": c.periodicity, "features": c.features,
                "intervals": c.intervals, "frames": n, "fps": c.fps,
                "person_found": out.keypoints.found_fraction,
                "count_ms_per_frame": 1000.0 * stage_s(Stage::Count) / n.max(1) as f64,
                "seconds": out.total.as_secs_f64(),
            }),
        );
    }
    let k = errs.len().max(1) as f64;
    let report = json!({
        "kind": "repetition_count_from_video",
        "videos": errs.len(),
        "count_mae": errs.iter().sum::<f64>() / k,
        "obo_acc": obos.iter().filter(|&&b| b).count() as f64 / k,
        "count_ms_per_frame": 1000.0 * count_s / frames_total.max(1) as f64,
        "motion_ms_per_frame": 1000.0 * motion_s / frames_total.max(1) as f64,
        "total_ms_per_frame": 1000.0 * total_s / frames_total.max(1) as f64,
        "frames": frames_total,
        "count_param_overrides": a.count_params, "definition": "mp_pipeline::analyse_input with Params::default() on each video (what `mp run` writes as loops.json total_repetitions). MAE = mean over videos of |count − true| / true; OBO = fraction with |count − true| ≤ 1. count_ms_per_frame: the counting stage alone (after keypoints); motion_ms_per_frame: locating the region that moves on its own and choosing the frame signal; total_ms_per_frame: decoding, pose, programs and counting.",
        "leave_one_video_out": leave_one_out(&kept)?,
        "videos_dir": videos.display().to_string(),
        "labels_dir": labels.display().to_string(),
        "runtime_s": t0.elapsed().as_secs_f64(),
        "by_video": by_video,
    });
    if let Some(dir) = a.out.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    mp_geom::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    let mut summary = report.clone();
    if let Value::Object(m) = &mut summary {
        m.remove("by_video");
    }
    println!("{}", serde_json::to_string_pretty(&summary)?);
    eprintln!("written to {}", a.out.display());
    Ok(())
}

/// The counting settings tried by leave-one-video-out: how periodic a
/// recording must be to count, and the smoothing of the frame signal. The
/// defaults are one of them.
fn candidates() -> Vec<(String, Params)> {
    let mut out = Vec::new();
    for strength in [0.02, 0.05, 0.1] {
        for smooth in [0.1, 0.25, 0.5] {
            let mut p = Params::default();
            p.count.min_strength = strength;
            p.count.frame_period.smooth_s = smooth;
            out.push((
                format!("min_strength {strength}, frame_period.smooth_s {smooth}"),
                p,
            ));
        }
    }
    out
}

/// For each video, the candidate with the lowest MAE on the other videos
/// (the first on ties) counts the video left out; returns the left-out
/// figures and each fold's choice.
fn leave_one_out(
    kept: &[(String, mp_geom::Track, Option<mp_geom::Track>, usize)],
) -> anyhow::Result<Value> {
    let cands = candidates();
    let mut errs = vec![vec![0.0; kept.len()]; cands.len()];
    let mut counts = vec![vec![0usize; kept.len()]; cands.len()];
    for (ci, (_, p)) in cands.iter().enumerate() {
        for (vi, (_, track, thumbs, truth)) in kept.iter().enumerate() {
            let c = mp_pipeline::count(track, thumbs.as_ref(), p)?;
            counts[ci][vi] = c.total;
            errs[ci][vi] = (c.total as f64 - *truth as f64).abs() / (*truth).max(1) as f64;
        }
    }
    let (mut held_err, mut held_obo) = (Vec::new(), Vec::new());
    let mut folds = Vec::new();
    for (vi, (name, _, _, truth)) in kept.iter().enumerate() {
        let mut best = (f64::INFINITY, 0usize);
        for (ci, row) in errs.iter().enumerate() {
            let m = row
                .iter()
                .enumerate()
                .filter(|(k, _)| *k != vi)
                .map(|(_, e)| e)
                .sum::<f64>()
                / (kept.len() - 1).max(1) as f64;
            if m < best.0 - 1e-12 {
                best = (m, ci);
            }
        }
        let c = counts[best.1][vi];
        held_err.push(errs[best.1][vi]);
        held_obo.push((c as i64 - *truth as i64).abs() <= 1);
        folds.push(
            json!({"left_out": name, "chosen": cands[best.1].0, "count": c, "true_count": truth}),
        );
    }
    let k = held_err.len().max(1) as f64;
    Ok(json!({
        "definition": "for each video, the candidate with the lowest MAE on the other videos counts the one left out (keypoints and thumbnails as mp run makes them)",
        "candidates": cands.iter().map(|c| c.0.clone()).collect::<Vec<_>>(),
        "count_mae": held_err.iter().sum::<f64>() / k,
        "obo_acc": held_obo.iter().filter(|&&b| b).count() as f64 / k,
        "folds": folds,
    }))
}
