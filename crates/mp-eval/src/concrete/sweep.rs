//! `cargo xtask eval concrete --sweep`: the rate–distortion frontier (KD
//! against parameter ratio per action over fixed λ and the product's
//! default), written as JSON and plotted as an SVG with the Python peer's
//! points.

use std::time::Instant;

use anyhow::Context;
use indicatif::ProgressBar;
use mp_concrete::Lambda;
use mp_geom::PennAction;
use rayon::prelude::*;
use serde_json::json;

use super::{fit, mean, product_params, EvalConcreteArgs};

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
    let st = program.stats(&track)?;
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
pub(super) fn sweep(
    a: &EvalConcreteArgs,
    pa: &PennAction,
    clips: &[usize],
    path: &std::path::Path,
) -> anyhow::Result<()> {
    let product = product_params(a, false)?;
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
    mp_geom::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())
        .with_context(|| format!("writing {}", a.out.display()))?;
    if let Some(dir) = a.svg.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    mp_geom::write_atomic(&a.svg, frontier_svg(&curves, &marks).as_bytes())
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
