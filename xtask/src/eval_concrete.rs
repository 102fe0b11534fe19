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

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use mp_concrete::{
    interpolation_experiment, program_stats, Continuity, InterpParams, Lambda, Program,
    ProgramStats, RefitNorm, Transition,
};
use mp_geom::io::datasets::PennAction;
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

/// The product's parameters (`mp fit`, `mp run`) with the window, continuity,
/// kinds and circle options given (λ as the product's unless set later).
fn product_params(a: &EvalConcreteArgs) -> mp_pipeline::Params {
    let mut p = mp_pipeline::Params::default();
    p.analysis.synth.max_segment_frames = a.window;
    p.analysis.synth.continuity = a.continuity;
    p.analysis.synth.refit_norm = a.refit_norm;
    p.analysis.synth.fit.kinds = a.kinds.clone();
    p.analysis.synth.fit.quadratic_angle |= a.quadratic_angle;
    if let Some(s) = a.lambda_spread {
        p.analysis.synth.lambda = Lambda::spread(s);
    }
    p
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
    /// step → (program, linear) KD at 512 px, when the clip is long enough.
    interp: BTreeMap<usize, (f64, f64)>,
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
    let st = program_stats(&program, &track)?;
    let mut interp = BTreeMap::new();
    for &s in &a.steps {
        let ip = InterpParams {
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
            interp.insert(s, (r.kd_program * to512, r.kd_linear * to512));
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

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 {
        f64::NAN
    } else {
        s / n as f64
    }
}

fn summary(rs: &[&ClipResult], steps: &[usize]) -> Value {
    let sum_prog: usize = rs.iter().map(|r| r.params_program).sum();
    let sum_raw: usize = rs.iter().map(|r| r.params_raw).sum();
    let mut interp = serde_json::Map::new();
    for &s in steps {
        let v: Vec<(f64, f64)> = rs
            .iter()
            .filter_map(|r| r.interp.get(&s).copied())
            .collect();
        interp.insert(
            format!("x{s}"),
            json!({
                "clips": v.len(),
                "kd_program_px_512": mean(v.iter().map(|p| p.0)),
                "kd_linear_px_512": mean(v.iter().map(|p| p.1)),
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
    let mut s = String::new();
    let interp_head: Vec<String> = steps
        .iter()
        .map(|k| format!("interp ×{k} prog / lin"))
        .collect();
    s.push_str(&format!(
        "| action | clips | frames | primitives | params prog / raw (ratio) | KD px@512 | max jump raw / prog | {} |\n",
        interp_head.join(" | ")
    ));
    s.push_str(&format!(
        "|---|---:|---:|---:|---:|---:|---:|{}\n",
        "---:|".repeat(steps.len())
    ));
    let mut rows: Vec<(String, &Value)> = Vec::new();
    if let Some(m) = report["by_action"].as_object() {
        for (k, v) in m {
            rows.push((k.clone(), v));
        }
    }
    rows.push(("**overall**".into(), &report["overall"]));
    for (name, v) in rows {
        let interp: Vec<String> = steps
            .iter()
            .map(|k| {
                let key = format!("x{k}");
                format!(
                    "{:.2} / {:.2}",
                    num(v, &["interpolation", &key, "kd_program_px_512"]),
                    num(v, &["interpolation", &key, "kd_linear_px_512"])
                )
            })
            .collect();
        s.push_str(&format!(
            "| {name} | {} | {:.1} | {:.2} | {:.0} / {:.0} ({:.3}) | {:.2} | {:.1} / {:.1} | {} |\n",
            num(v, &["clips"]),
            num(v, &["frames_per_clip"]),
            num(v, &["primitives_per_clip"]),
            num(v, &["params_program"]),
            num(v, &["params_raw"]),
            num(v, &["params_ratio"]),
            num(v, &["kd_px_512"]),
            num(v, &["max_jump_raw_px_512"]),
            num(v, &["max_jump_program_px_512"]),
            interp.join(" | ")
        ));
    }
    s
}

/// The public Python peer's points at its defaults: (action, KD px@512, params ratio).
const PEER: [(&str, f64, f64); 2] = [("golf_swing", 4.86, 0.105), ("jumping_jacks", 10.17, 0.105)];

/// (program params, raw params, KD at 512 px) of one clip.
type SweepRow = (usize, usize, f64);

/// One clip at one setting: (program params, raw params, KD at 512 px).
fn sweep_clip(pa: &PennAction, i: usize, base: &mp_pipeline::Params) -> anyhow::Result<SweepRow> {
    let info = pa.clip_info(i)?;
    let track = pa.clip(i)?;
    let frame_px = info.height_px.max(info.width_px) as f64;
    let program = fit(&track, frame_px, base)?;
    let st = program_stats(&program, &track)?;
    Ok((st.params_program, st.params_raw, st.kd * 512.0 / frame_px))
}

/// A point of the frontier for one action: (KD mean over clips, Σ prog / Σ raw, clips).
fn frontier_point(rows: &[(&str, usize, usize, f64)], action: &str) -> (f64, f64, usize) {
    let rs: Vec<_> = rows.iter().filter(|r| r.0 == action).collect();
    let prog: usize = rs.iter().map(|r| r.1).sum();
    let raw: usize = rs.iter().map(|r| r.2).sum();
    let ratio = if raw > 0 {
        prog as f64 / raw as f64
    } else {
        f64::NAN
    };
    (mean(rs.iter().map(|r| r.3)), ratio, rs.len())
}

/// A small SVG line plot: KD (y) against parameter ratio (x), one polyline per action.
fn frontier_svg(
    curves: &[(String, Vec<(f64, f64)>)],
    marks: &[(String, f64, f64, &str)],
) -> String {
    let (w, h, ml, mr, mt, mb) = (760.0, 520.0, 60.0, 190.0, 20.0, 50.0);
    let xmax = curves
        .iter()
        .flat_map(|c| c.1.iter().map(|p| p.0))
        .chain(marks.iter().map(|m| m.1))
        .filter(|v| v.is_finite())
        .fold(0.05f64, f64::max)
        .min(0.6);
    let ymax = curves
        .iter()
        .flat_map(|c| c.1.iter().map(|p| p.1))
        .chain(marks.iter().map(|m| m.2))
        .filter(|v| v.is_finite())
        .fold(1.0f64, f64::max)
        .min(40.0);
    let xmax = (xmax * 10.0).ceil() / 10.0;
    let ymax = ymax.ceil();
    let px = |x: f64| ml + (x / xmax).clamp(0.0, 1.0) * (w - ml - mr);
    let py = |y: f64| h - mb - (y / ymax).clamp(0.0, 1.0) * (h - mt - mb);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n"
    );
    // axes and ticks
    s += &format!(
        "<line x1=\"{ml}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n<line x1=\"{ml}\" y1=\"{mt}\" x2=\"{ml}\" y2=\"{}\" stroke=\"black\"/>\n",
        h - mb,
        w - mr,
        h - mb,
        h - mb
    );
    for i in 0..=5 {
        let x = xmax * i as f64 / 5.0;
        s += &format!(
            "<line x1=\"{0:.1}\" y1=\"{1}\" x2=\"{0:.1}\" y2=\"{2}\" stroke=\"#ddd\"/><text x=\"{0:.1}\" y=\"{3}\" text-anchor=\"middle\">{4:.2}</text>\n",
            px(x),
            mt,
            h - mb,
            h - mb + 16.0,
            x
        );
        let y = ymax * i as f64 / 5.0;
        s += &format!(
            "<line x1=\"{0}\" y1=\"{1:.1}\" x2=\"{2}\" y2=\"{1:.1}\" stroke=\"#ddd\"/><text x=\"{3}\" y=\"{4:.1}\" text-anchor=\"end\">{5:.1}</text>\n",
            ml,
            py(y),
            w - mr,
            ml - 6.0,
            py(y) + 4.0,
            y
        );
    }
    s += &format!(
        "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">program parameters / raw parameters</text>\n<text x=\"16\" y=\"{:.1}\" transform=\"rotate(-90 16 {:.1})\" text-anchor=\"middle\">KD (px at 512 px)</text>\n",
        (ml + w - mr) / 2.0,
        h - 12.0,
        (mt + h - mb) / 2.0,
        (mt + h - mb) / 2.0
    );
    let palette = [
        "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#7f7f7f",
        "#bcbd22", "#17becf", "#393b79", "#637939", "#8c6d31", "#843c39", "#7b4173",
    ];
    for (ci, (name, pts)) in curves.iter().enumerate() {
        let col = palette[ci % palette.len()];
        let bold = name == "golf_swing" || name == "jumping_jacks";
        let path: Vec<String> = pts
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1)))
            .collect();
        s += &format!(
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{col}\" stroke-width=\"{}\" opacity=\"{}\"/>\n",
            path.join(" "),
            if bold { 2.5 } else { 1.0 },
            if bold { 1.0 } else { 0.6 }
        );
        for p in &path {
            let (x, y) = p.split_once(',').unwrap_or(("0", "0"));
            s += &format!(
                "<circle cx=\"{x}\" cy=\"{y}\" r=\"{}\" fill=\"{col}\"/>\n",
                if bold { 3 } else { 2 }
            );
        }
        let ly = mt + 14.0 * ci as f64 + 8.0;
        s += &format!(
            "<line x1=\"{0}\" y1=\"{1:.1}\" x2=\"{2}\" y2=\"{1:.1}\" stroke=\"{col}\" stroke-width=\"{3}\"/><text x=\"{4}\" y=\"{5:.1}\">{6}</text>\n",
            w - mr + 10.0,
            ly,
            w - mr + 30.0,
            if bold { 2.5 } else { 1.0 },
            w - mr + 35.0,
            ly + 4.0,
            name
        );
    }
    for (mi, (label, x, y, shape)) in marks.iter().enumerate() {
        let (cx, cy) = (px(*x), py(*y));
        s += &match *shape {
            "square" => format!(
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"9\" height=\"9\" fill=\"none\" stroke=\"black\" stroke-width=\"2\"/>\n",
                cx - 4.5,
                cy - 4.5
            ),
            _ => format!(
                "<path d=\"M{:.1},{:.1} l5,-8 l5,8 z\" fill=\"black\"/>\n",
                cx - 5.0,
                cy + 4.0
            ),
        };
        let ly = mt + 14.0 * (curves.len() + mi) as f64 + 16.0;
        s += &format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"10\">{} {label}</text>\n",
            w - mr + 10.0,
            ly,
            if *shape == "square" { "□" } else { "▲" }
        );
    }
    s += "</svg>\n";
    s
}

/// The λ sweep (`--sweep`).
fn sweep(
    a: &EvalConcreteArgs,
    pa: &PennAction,
    clips: &[usize],
    path: &std::path::Path,
) -> anyhow::Result<()> {
    let product = product_params(a);
    let mut settings: Vec<(String, mp_pipeline::Params)> = a
        .sweep_lambdas
        .iter()
        .map(|&l| {
            let mut p = product.clone();
            p.analysis.synth.lambda = Lambda::fixed(l);
            (format!("{l}"), p)
        })
        .collect();
    settings.push(("default".into(), product.clone()));
    let t0 = Instant::now();
    let bar = ProgressBar::new((clips.len() * settings.len()) as u64);
    let work: Vec<(usize, usize)> = (0..settings.len())
        .flat_map(|s| clips.iter().map(move |&c| (s, c)))
        .collect();
    let results: Vec<(usize, usize, anyhow::Result<SweepRow>)> = work
        .par_iter()
        .map(|&(si, c)| {
            let r = sweep_clip(pa, c, &settings[si].1);
            bar.inc(1);
            (si, c, r)
        })
        .collect();
    bar.finish();
    let wall = t0.elapsed().as_secs_f64();
    let mut actions: Vec<String> = clips
        .iter()
        .filter_map(|&c| pa.clip_info(c).ok().map(|i| i.action.clone()))
        .collect();
    actions.sort();
    actions.dedup();
    let mut per_setting = Vec::new();
    let mut curves: Vec<(String, Vec<(f64, f64)>)> =
        actions.iter().map(|a| (a.clone(), Vec::new())).collect();
    let mut marks: Vec<(String, f64, f64, &str)> = Vec::new();
    let mut failed = 0usize;
    for (si, (name, params)) in settings.iter().enumerate() {
        let mut rows: Vec<(&str, usize, usize, f64)> = Vec::new();
        for (s2, c, r) in &results {
            if *s2 != si {
                continue;
            }
            match (r, pa.clip_info(*c)) {
                (Ok((p, raw, kd)), Ok(info)) => rows.push((info.action.as_str(), *p, *raw, *kd)),
                _ => failed += 1,
            }
        }
        let mut by_action = serde_json::Map::new();
        for (ai, act) in actions.iter().enumerate() {
            let (kd, ratio, n) = frontier_point(&rows, act);
            by_action.insert(
                act.clone(),
                json!({ "clips": n, "kd_px_512": kd, "params_ratio": ratio }),
            );
            if name == "default" {
                if act == "golf_swing" || act == "jumping_jacks" {
                    marks.push((format!("{act}: default (mp fit)"), ratio, kd, "square"));
                }
            } else {
                curves[ai].1.push((ratio, kd));
            }
        }
        per_setting.push(json!({
            "setting": name,
            "lambda": serde_json::to_value(params.analysis.synth.lambda)?,
            "by_action": by_action,
        }));
    }
    for (act, kd, ratio) in PEER {
        if actions.iter().any(|a| a == act) {
            marks.push((format!("{act}: Python peer"), ratio, kd, "triangle"));
        }
    }
    let report = json!({
        "data": path.display().to_string(),
        "split": format!("{:?}", a.split),
        "what": "KD (px at 512 px, mean over clips) and parameter ratio (Σ program / Σ raw) per action, for fixed λ (512-px reference scale) and the product's default parameters",
        "params": serde_json::to_value(&product.analysis.synth)?,
        "peer": PEER.iter().map(|(a, kd, r)| json!({"action": a, "kd_px_512": kd, "params_ratio": r})).collect::<Vec<_>>(),
        "settings": per_setting,
        "failed": failed,
        "wall_seconds": wall,
        "threads": rayon::current_num_threads(),
    });
    mp_geom::io::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())
        .with_context(|| format!("writing {}", a.out.display()))?;
    if let Some(dir) = a.svg.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    mp_geom::io::write_atomic(&a.svg, frontier_svg(&curves, &marks).as_bytes())
        .with_context(|| format!("writing {}", a.svg.display()))?;
    for (act, pts) in &curves {
        let row: Vec<String> = pts
            .iter()
            .zip(&a.sweep_lambdas)
            .map(|(p, l)| format!("λ{l}: {:.3}/{:.2}", p.0, p.1))
            .collect();
        println!("{act}: {}", row.join("  "));
    }
    for (label, x, y, _) in &marks {
        println!("{label}: ratio {x:.3}, KD {y:.2}");
    }
    eprintln!(
        "{} clips × {} settings ({failed} failed) in {wall:.1} s → {}, {}",
        clips.len(),
        settings.len(),
        a.out.display(),
        a.svg.display()
    );
    Ok(())
}

/// Runs the evaluation and writes the report.
pub fn run(a: &EvalConcreteArgs) -> anyhow::Result<()> {
    let path = match &a.data {
        Some(p) => p.clone(),
        None => mp_geom::paths::data_file(PennAction::TRAIN_FILE)
            .context("Penn Action not found: pass --data or set MP_DATA_DIR")?,
    };
    let pa = PennAction::open(&path).with_context(|| format!("opening {}", path.display()))?;
    // The product's parameters (`mp fit`, `mp run`), with the options given.
    let mut base = product_params(a);
    if let Some(l) = a.lambda {
        base.analysis.synth.lambda = Lambda::fixed(l);
    }
    if let Some(b) = a.budget {
        base.analysis.synth.lambda = Lambda::budget(b);
    }
    base.validate()?;
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
        return sweep(a, &pa, &clips, &path);
    }
    if a.compare_continuity {
        return compare_continuity(a, &pa, &clips, &path, &base);
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

/// One clip under one continuity: its action, the program's stats, and the factor to 512-px pixels.
type ContinuityRow = (String, ProgramStats, f64);

fn continuity_clip(
    pa: &PennAction,
    i: usize,
    params: &mp_pipeline::Params,
) -> anyhow::Result<ContinuityRow> {
    let info = pa.clip_info(i)?;
    let track = pa.clip(i)?;
    let frame_px = info.height_px.max(info.width_px) as f64;
    let program = fit(&track, frame_px, params)?;
    Ok((
        info.action.clone(),
        program_stats(&program, &track)?,
        512.0 / frame_px,
    ))
}

/// `--compare-continuity`: the product's programs with and without shared boundary poses.
fn compare_continuity(
    a: &EvalConcreteArgs,
    pa: &PennAction,
    clips: &[usize],
    path: &std::path::Path,
    base: &mp_pipeline::Params,
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let modes = [Continuity::None, Continuity::C0];
    let work: Vec<(usize, usize)> = (0..modes.len())
        .flat_map(|m| clips.iter().map(move |&c| (m, c)))
        .collect();
    let bar = ProgressBar::new(work.len() as u64);
    let results: Vec<(usize, anyhow::Result<ContinuityRow>)> = work
        .par_iter()
        .map(|&(m, c)| {
            let mut p = base.clone();
            p.analysis.synth.continuity = modes[m];
            let r = continuity_clip(pa, c, &p);
            bar.inc(1);
            (m, r)
        })
        .collect();
    bar.finish();
    let wall = t0.elapsed().as_secs_f64();
    let mut failed = 0usize;
    // (mode, action) → per-clip rows
    let mut rows: BTreeMap<(usize, String), Vec<(ProgramStats, f64)>> = BTreeMap::new();
    for (m, r) in results {
        match r {
            Ok((act, st, to512)) => {
                rows.entry((m, "overall".into()))
                    .or_default()
                    .push((st.clone(), to512));
                rows.entry((m, act)).or_default().push((st, to512));
            }
            Err(_) => failed += 1,
        }
    }
    let summarise = |rs: &[(ProgramStats, f64)]| -> Value {
        let prog: usize = rs.iter().map(|r| r.0.params_program).sum();
        let numbers: usize = rs.iter().map(|r| r.0.numbers_program).sum();
        let raw: usize = rs.iter().map(|r| r.0.params_raw).sum();
        let ratio = |x: usize| {
            if raw > 0 {
                x as f64 / raw as f64
            } else {
                f64::NAN
            }
        };
        json!({
            "clips": rs.len(),
            "kd_px_512": mean(rs.iter().map(|r| r.0.kd * r.1)),
            "params_ratio": ratio(prog),
            "numbers_ratio": ratio(numbers),
            "max_jump_raw_px_512": mean(rs.iter().map(|r| r.0.max_jump_raw * r.1)),
            "max_jump_program_px_512": mean(rs.iter().map(|r| r.0.max_jump_program * r.1)),
            "clips_program_jump_above_raw": rs.iter().filter(|r| r.0.max_jump_program > r.0.max_jump_raw).count(),
        })
    };
    let mut by_action = serde_json::Map::new();
    let mut md = String::from(
        "| action | clips | continuity | KD px@512 | params ratio (numbers written) | max jump raw / program (px@512) | clips with program jump > raw |\n|---|---:|---|---:|---:|---:|---:|\n",
    );
    let mut names: Vec<String> = rows.keys().map(|k| k.1.clone()).collect();
    names.sort();
    names.dedup();
    names.retain(|n| n != "overall");
    names.push("overall".into());
    for name in &names {
        let mut entry = serde_json::Map::new();
        for (m, mode) in modes.iter().enumerate() {
            let Some(rs) = rows.get(&(m, name.clone())) else {
                continue;
            };
            let v = summarise(rs);
            md.push_str(&format!(
                "| {name} | {} | {mode} | {:.2} | {:.3} ({:.3}) | {:.1} / {:.1} | {} |\n",
                num(&v, &["clips"]),
                num(&v, &["kd_px_512"]),
                num(&v, &["params_ratio"]),
                num(&v, &["numbers_ratio"]),
                num(&v, &["max_jump_raw_px_512"]),
                num(&v, &["max_jump_program_px_512"]),
                num(&v, &["clips_program_jump_above_raw"]),
            ));
            entry.insert(mode.to_string(), v);
        }
        by_action.insert(name.clone(), Value::Object(entry));
    }
    let report = json!({
        "data": path.display().to_string(),
        "split": format!("{:?}", a.split),
        "what": "the product's programs (mp_pipeline::concrete_program, Params::default() with the options given) with independently fitted segments and with shared boundary poses (C0); KD and max adjacent-frame jump in px at 512 px (means over clips), parameter ratio Σ program / Σ raw",
        "params": serde_json::to_value(&base.analysis.synth)?,
        "by_action": by_action,
        "failed": failed,
        "wall_seconds": wall,
        "threads": rayon::current_num_threads(),
    });
    mp_geom::io::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())
        .with_context(|| format!("writing {}", a.out.display()))?;
    println!("{md}");
    if let Some(m) = &a.markdown {
        std::fs::write(m, &md).with_context(|| format!("writing {}", m.display()))?;
    }
    eprintln!(
        "{} clips × 2 ({failed} failed) in {wall:.1} s → {}",
        clips.len(),
        a.out.display()
    );
    Ok(())
}
