//! `cargo xtask eval concrete`: concrete programs on Penn Action (paper §4.1, §4.2).
//!
//! For every clip: synthesise a program (scale from the frame size), then
//! measure segments ("primitives per clip"), program parameters vs raw
//! (`T·J·D`), KD against the observed keypoints, the largest adjacent-frame
//! jump of raw and program poses, and the interpolation experiment (×2, ×4,
//! ×8: program vs linear interpolation on the dropped frames). Distances are
//! reported in pixels of a 512-px frame: `px · 512 / max(H, W)` of the clip.
//!
//! Programs come from `mp_pipeline::concrete_program` — the function `mp fit`
//! calls — with `mp_pipeline::Params::default()` and the options given.
//!
//! `--compare-continuity`: for every clip the product's program with
//! independently fitted segments (`--continuity none`) and with shared
//! boundary poses (`c0`, the default): KD, parameter ratio and the largest
//! adjacent-frame jump of the input and of each executed program, per action.
//!
//! `--sweep`: the rate–distortion frontier instead. For every clip and every
//! fixed λ of `--sweep-lambdas` (and the product's default parameters), the
//! program's KD and parameter count; per action the KD (mean over clips) and
//! the parameter ratio (Σ program / Σ raw), written as JSON (`--out`) and
//! plotted as an SVG (`--svg`) with the public Python peer's points (its
//! defaults: golf swings 4.86 px at 10.5 %, jumping jacks 10.17 px at 10.5 %).
//!
//! The two other modes have their own submodules (`sweep`, `continuity`);
//! this module holds the arguments, the evaluation itself and what the
//! modes share (the product's parameters, the fit, means).

mod continuity;
pub mod interpolation;
mod sweep;

use crate::stats::mean;
use crate::table::{Align::Left, Align::Right, Table};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use interpolation::{interpolation_experiment, InterpolationExperiment};
use mp_concrete::{Continuity, Program, RefitNorm, Transition};
use mp_geom::PennAction;
use rayon::prelude::*;
use serde_json::{json, Value};

/// Arguments of `cargo xtask eval concrete`.
#[derive(Args, Debug)]
pub struct EvalConcreteArgs {
    /// Penn Action npz (default: the shared train split).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Output JSON report.
    #[arg(long)]
    pub out: PathBuf,
    /// A fixed λ at the 512-px reference scale (the paper's setting; `Lambda::DEFAULT_FIXED`
    /// is 1600) instead of the product's default (`mp_pipeline::Params::default()`: the local
    /// spread held for one second), which `mp fit` and `mp run` use.
    #[arg(long, conflicts_with = "budget")]
    pub lambda: Option<f64>,
    /// A parameter budget per clip instead of a price per segment (`mp fit --budget`).
    #[arg(long, conflicts_with = "lambda_spread")]
    pub budget: Option<f64>,
    /// λ from the local spread held for this many seconds (`mp fit
    /// --lambda-spread`, `Lambda::Spread`; the default holds it for one
    /// second); also the sweep's "default" setting.
    #[arg(long, conflicts_with = "lambda")]
    pub lambda_spread: Option<f64>,
    /// Maximum segment length in frames.
    #[arg(long, default_value_t = mp_pipeline::Params::default().analysis.synth.max_segment_frames)]
    pub window: usize,
    /// Whether consecutive segments share their boundary pose (`c0`) or are fitted independently (`none`).
    #[arg(long, default_value_t = mp_pipeline::Params::default().analysis.synth.continuity)]
    pub continuity: Continuity,
    /// What the C0 refit minimises (`mp fit --refit-norm`).
    #[arg(long, default_value_t = mp_pipeline::Params::default().analysis.synth.refit_norm)]
    pub refit_norm: RefitNorm,
    /// Every clip with `--continuity none` and `c0` (see the module docs) instead of the evaluation.
    #[arg(long)]
    pub compare_continuity: bool,
    /// Only these action classes (repeatable).
    #[arg(long)]
    pub action: Vec<String>,
    /// At most this many clips per action (the first ones in the file).
    #[arg(long)]
    pub max_clips_per_action: Option<usize>,
    /// Which clips: `all`, `validation` (the 1st, 3rd, 5th … clip of each
    /// action in the file: where defaults are chosen) or `held-out` (the 2nd,
    /// 4th …: where they are reported).
    #[arg(long, value_enum, default_value_t = Split::All)]
    pub split: Split,
    /// Subsampling factors of the interpolation experiment.
    #[arg(long, value_delimiter = ',', default_value = "2,4,8")]
    pub steps: Vec<usize>,
    /// Interpolation: keep λ as is on the subsampled track (default: divide it by the factor).
    #[arg(long)]
    pub interp_same_lambda: bool,
    /// Interpolation: continue primitives between segments instead of blending.
    #[arg(long)]
    pub interp_extrapolate: bool,
    /// Also write a Markdown table to this file.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// Rate–distortion sweep over fixed λ (see the module docs) instead of the evaluation.
    #[arg(long)]
    pub sweep: bool,
    /// λ values of the sweep (512-px reference scale).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "50,100,200,400,800,1600,3200,6400,12800"
    )]
    pub sweep_lambdas: Vec<f64>,
    /// SVG plot of the sweep.
    #[arg(long, default_value = "docs/img/concrete_frontier.svg")]
    pub svg: PathBuf,
    /// The primitive kinds a segment may use (`mp fit --kinds`).
    #[arg(long, value_delimiter = ',', default_values_t = mp_pipeline::Params::default().analysis.synth.fit.kinds)]
    pub kinds: Vec<mp_geom::PrimitiveKind>,
    /// Circles with an angular acceleration (`mp fit --quadratic-angle`).
    #[arg(long)]
    pub quadratic_angle: bool,
}

/// A part of the clips (`--split`).
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Split {
    /// Every clip.
    All,
    /// Odd positions within each action (1st, 3rd, …): for choosing defaults.
    Validation,
    /// Even positions within each action (2nd, 4th, …): for reporting them.
    HeldOut,
}

impl Split {
    /// Whether the clip at 0-based position `i` within its action belongs here.
    fn contains(self, i: usize) -> bool {
        match self {
            Split::All => true,
            Split::Validation => i.is_multiple_of(2),
            Split::HeldOut => !i.is_multiple_of(2),
        }
    }
}

/// The product's parameters (`mp fit`, `mp run`) with the window,
/// continuity, kinds and circle options given, through the options type of
/// `mp fit` ([`mp_pipeline::FitOptions`]); `with_lambda` adds `--lambda` and
/// `--budget` (the sweep sets its own λ).
fn product_params(a: &EvalConcreteArgs, with_lambda: bool) -> anyhow::Result<mp_pipeline::Params> {
    Ok(mp_pipeline::FitOptions {
        lambda: a.lambda.filter(|_| with_lambda),
        budget: a.budget.filter(|_| with_lambda),
        lambda_spread: a.lambda_spread,
        max_segment_frames: Some(a.window),
        continuity: Some(a.continuity),
        refit_norm: Some(a.refit_norm),
        kinds: Some(a.kinds.clone()),
        quadratic_angle: a.quadratic_angle,
        ..mp_pipeline::FitOptions::default()
    }
    .params()?)
}

#[derive(Debug, Clone, Default)]
struct ClipResult {
    action: String,
    frames: usize,
    segments: usize,
    params_program: usize,
    params_raw: usize,
    kd_512: f64,
    jump_raw_512: f64,
    jump_program_512: f64,
    /// step → (program, linear, in-between) KD at 512 px, when the clip is long enough.
    interp: BTreeMap<usize, (f64, f64, f64)>,
    seconds: f64,
}

/// The program `mp fit --frame-size FRAME_PX` writes for a track with these parameters.
fn fit(
    track: &mp_geom::Track,
    frame_px: f64,
    params: &mp_pipeline::Params,
) -> anyhow::Result<Program> {
    Ok(mp_pipeline::concrete_program(track, Some(frame_px), params)?.program)
}

fn run_clip(
    pa: &PennAction,
    i: usize,
    base: &mp_pipeline::Params,
    a: &EvalConcreteArgs,
) -> anyhow::Result<ClipResult> {
    let info = pa.clip_info(i)?;
    let track = pa.clip(i)?;
    let frame_px = info.height_px.max(info.width_px) as f64;
    let to512 = 512.0 / frame_px;
    let params = base.synth_for(Some(frame_px));
    let t0 = Instant::now();
    let program = fit(&track, frame_px, base)?;
    let seconds = t0.elapsed().as_secs_f64();
    let st = program.stats(&track)?;
    let mut interp = BTreeMap::new();
    for &s in &a.steps {
        let ip = InterpolationExperiment {
            step: s,
            synth: params.clone(),
            transition: if a.interp_extrapolate {
                Transition::Extrapolate
            } else {
                Transition::Blend
            },
            lambda_per_time: !a.interp_same_lambda,
        };
        // Short clips (fewer than 2 kept frames or nothing to score) are skipped for that factor.
        if let Ok(r) = interpolation_experiment(&track, &ip) {
            interp.insert(
                s,
                (
                    r.kd_program * to512,
                    r.kd_linear * to512,
                    r.kd_inbetween * to512,
                ),
            );
        }
    }
    Ok(ClipResult {
        action: info.action.clone(),
        frames: st.n_frames,
        segments: st.n_segments,
        params_program: st.params_program,
        params_raw: st.params_raw,
        kd_512: st.kd * to512,
        jump_raw_512: st.max_jump_raw * to512,
        jump_program_512: st.max_jump_program * to512,
        interp,
        seconds,
    })
}

fn summary(rs: &[&ClipResult], steps: &[usize]) -> Value {
    let sum_prog: usize = rs.iter().map(|r| r.params_program).sum();
    let sum_raw: usize = rs.iter().map(|r| r.params_raw).sum();
    let mut interp = serde_json::Map::new();
    for &s in steps {
        let v: Vec<(f64, f64, f64)> = rs
            .iter()
            .filter_map(|r| r.interp.get(&s).copied())
            .collect();
        interp.insert(
            format!("x{s}"),
            json!({
                "clips": v.len(),
                "kd_program_px_512": mean(v.iter().map(|p| p.0)),
                "kd_linear_px_512": mean(v.iter().map(|p| p.1)),
                "kd_inbetween_px_512": mean(v.iter().map(|p| p.2)),
            }),
        );
    }
    json!({
        "clips": rs.len(),
        "frames_per_clip": mean(rs.iter().map(|r| r.frames as f64)),
        "primitives_per_clip": mean(rs.iter().map(|r| r.segments as f64)),
        "params_program": mean(rs.iter().map(|r| r.params_program as f64)),
        "params_raw": mean(rs.iter().map(|r| r.params_raw as f64)),
        "params_ratio": if sum_raw > 0 { sum_prog as f64 / sum_raw as f64 } else { f64::NAN },
        "kd_px_512": mean(rs.iter().map(|r| r.kd_512)),
        "max_jump_raw_px_512": mean(rs.iter().map(|r| r.jump_raw_512)),
        "max_jump_program_px_512": mean(rs.iter().map(|r| r.jump_program_512)),
        "interpolation": interp,
        "synthesis_seconds_per_clip": mean(rs.iter().map(|r| r.seconds)),
    })
}

fn num(v: &Value, path: &[&str]) -> f64 {
    let mut cur = v;
    for p in path {
        cur = &cur[*p];
    }
    cur.as_f64().unwrap_or(f64::NAN)
}

fn markdown(report: &Value, steps: &[usize]) -> String {
    let mut t = Table::new([
        "action",
        "clips",
        "frames",
        "primitives",
        "params prog / raw (ratio)",
        "KD px@512",
        "max jump raw / prog",
    ])
    .align([Left, Right, Right, Right, Right, Right, Right]);
    for k in steps {
        t.column(format!("interp ×{k} prog / lin"), Right);
    }
    let mut rows: Vec<(String, &Value)> = Vec::new();
    if let Some(m) = report["by_action"].as_object() {
        for (k, v) in m {
            rows.push((k.clone(), v));
        }
    }
    rows.push(("**overall**".into(), &report["overall"]));
    for (name, v) in rows {
        let mut cells = vec![
            name,
            num(v, &["clips"]).to_string(),
            format!("{:.1}", num(v, &["frames_per_clip"])),
            format!("{:.2}", num(v, &["primitives_per_clip"])),
            format!(
                "{:.0} / {:.0} ({:.3})",
                num(v, &["params_program"]),
                num(v, &["params_raw"]),
                num(v, &["params_ratio"])
            ),
            format!("{:.2}", num(v, &["kd_px_512"])),
            format!(
                "{:.1} / {:.1}",
                num(v, &["max_jump_raw_px_512"]),
                num(v, &["max_jump_program_px_512"])
            ),
        ];
        for k in steps {
            let key = format!("x{k}");
            cells.push(format!(
                "{:.2} / {:.2}",
                num(v, &["interpolation", &key, "kd_program_px_512"]),
                num(v, &["interpolation", &key, "kd_linear_px_512"])
            ));
        }
        t.row(cells);
    }
    t.markdown()
}

/// Runs the evaluation and writes the report.
pub fn run(a: &EvalConcreteArgs) -> anyhow::Result<()> {
    let path = match &a.data {
        Some(p) => p.clone(),
        None => mp_geom::data_file(PennAction::TRAIN_FILE)
            .context("Penn Action not found: pass --data or set MP_DATA_DIR")?,
    };
    let pa = PennAction::open(&path).with_context(|| format!("opening {}", path.display()))?;
    // The product's parameters (`mp fit`, `mp run`), with the options given.
    let base = product_params(a, true)?;
    let mut per_action: BTreeMap<&str, usize> = BTreeMap::new();
    let mut position: BTreeMap<&str, usize> = BTreeMap::new();
    let clips: Vec<usize> = pa
        .clips()
        .iter()
        .filter(|c| a.action.is_empty() || a.action.contains(&c.action))
        .filter(|c| {
            let i = position.entry(c.action.as_str()).or_insert(0);
            *i += 1;
            a.split.contains(*i - 1)
        })
        .filter(|c| {
            let n = per_action.entry(c.action.as_str()).or_insert(0);
            *n += 1;
            a.max_clips_per_action.is_none_or(|m| *n <= m)
        })
        .map(|c| c.index)
        .collect();
    if a.sweep {
        return sweep::sweep(a, &pa, &clips, &path);
    }
    if a.compare_continuity {
        return continuity::compare_continuity(a, &pa, &clips, &path, &base);
    }
    let bar = ProgressBar::new(clips.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} clips [{elapsed_precise} < {eta_precise}] {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t0 = Instant::now();
    let results: Vec<(usize, anyhow::Result<ClipResult>)> = clips
        .par_iter()
        .map(|&i| {
            let r = run_clip(&pa, i, &base, a);
            bar.inc(1);
            (i, r)
        })
        .collect();
    bar.finish_with_message("done");
    let wall = t0.elapsed().as_secs_f64();
    let mut ok: Vec<ClipResult> = Vec::new();
    let mut failed = Vec::new();
    for (i, r) in results {
        match r {
            Ok(c) => ok.push(c),
            Err(e) => {
                let id = pa
                    .clip_info(i)
                    .map(|c| c.clip_id.clone())
                    .unwrap_or_default();
                failed.push(json!({ "clip": i, "clip_id": id, "error": format!("{e:#}") }));
            }
        }
    }
    let all: Vec<&ClipResult> = ok.iter().collect();
    let mut by_action = serde_json::Map::new();
    let mut names: Vec<&str> = ok.iter().map(|c| c.action.as_str()).collect();
    names.sort();
    names.dedup();
    for name in names {
        let rs: Vec<&ClipResult> = ok.iter().filter(|c| c.action == name).collect();
        by_action.insert(name.to_string(), summary(&rs, &a.steps));
    }
    let report = json!({
        "data": path.display().to_string(),
        "split": format!("{:?}", a.split),
        "params": serde_json::to_value(&base.analysis.synth)?,
        "interpolation": {
            "steps": a.steps,
            "lambda_per_time": !a.interp_same_lambda,
            "transition": if a.interp_extrapolate { "extrapolate" } else { "blend" },
        },
        "distances": "pixels of a 512-px frame (px · 512 / max(H, W) of each clip); means over clips",
        "wall_seconds": wall,
        "threads": rayon::current_num_threads(),
        "overall": summary(&all, &a.steps),
        "by_action": by_action,
        "failed": failed,
    });
    std::fs::write(&a.out, serde_json::to_string_pretty(&report)?)
        .with_context(|| format!("writing {}", a.out.display()))?;
    let md = markdown(&report, &a.steps);
    println!("{md}");
    if let Some(m) = &a.markdown {
        std::fs::write(m, &md).with_context(|| format!("writing {}", m.display()))?;
    }
    eprintln!(
        "{} clips ({} failed) in {wall:.1} s → {}",
        ok.len(),
        report["failed"].as_array().map_or(0, Vec::len),
        a.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_table_layout() {
        let v = json!({"clips": 3, "frames_per_clip": 10.0, "primitives_per_clip": 2.5,
            "params_program": 100.0, "params_raw": 400.0, "params_ratio": 0.25, "kd_px_512": 1.234,
            "max_jump_raw_px_512": 5.0, "max_jump_program_px_512": 4.0,
            "interpolation": {"x2": {"kd_program_px_512": 1.0, "kd_linear_px_512": 2.0}}});
        let report = json!({"by_action": {"golf": v.clone()}, "overall": v});
        assert_eq!(
            markdown(&report, &[2]),
            "| action | clips | frames | primitives | params prog / raw (ratio) | KD px@512 | max jump raw / prog | interp ×2 prog / lin |\n\
             |---|---:|---:|---:|---:|---:|---:|---:|\n\
             | golf | 3 | 10.0 | 2.50 | 100 / 400 (0.250) | 1.23 | 5.0 / 4.0 | 1.00 / 2.00 |\n\
             | **overall** | 3 | 10.0 | 2.50 | 100 / 400 (0.250) | 1.23 | 5.0 / 4.0 | 1.00 / 2.00 |\n"
        );
    }
}
