//! `cargo xtask eval forecast`: the forecasting protocol ([`protocol`])
//! for every method on the validation clips of a Penn Action (2D: PCK@0.05)
//! or MSR Action3D (3D: MPJPE, PA-MPJPE in mm) npz, with and without DTW,
//! overall and per action. The nearest-neighbour index holds the other clips.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use mp_forecast::Clip;
use mp_forecast::ForecastDataset;
use mp_forecast::{
    ArForecaster, ArParams, ArSpace, Constant, ForecastModels, Forecaster, LoopUnroll,
    NearestNeighbour, NnParams,
};
use mp_pose::SessionParams;
use serde_json::{json, Value};

pub mod protocol;

/// Penn Action's repetitive classes (exercises performed as repetitions).
pub const PENN_REPETITIVE_CLASSES: [&str; 7] = [
    "bench_press",
    "jump_rope",
    "jumping_jacks",
    "pullup",
    "pushup",
    "situp",
    "squat",
];

pub use protocol::{evaluate, EvalParams, MethodReport};

use crate::table::{Align, Table};

/// Arguments of `cargo xtask eval forecast`.
#[derive(Args, Debug)]
pub struct EvalForecastArgs {
    /// Penn Action or MSR Action3D npz (default: the shared Penn Action train split).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Output JSON report.
    #[arg(long)]
    pub out: PathBuf,
    /// Methods to run (comma separated): constant, nn, loop (15 context frames), loop_all
    /// (loop unrolling on every observed frame before the start: more context than the
    /// others get), ar, ar_free (latent AR without the anchored read-out), ar_single (ar without the
    /// left-right mirror average), ar_pose.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "constant,nn,loop,ar,ar_pose"
    )]
    pub methods: Vec<String>,
    /// At most this many validation clips (spread evenly over the split).
    #[arg(long)]
    pub max_clips: Option<usize>,
    /// Frames between prediction start frames (default: 1 for 2D, 25 for 3D).
    #[arg(long)]
    pub stride: Option<usize>,
    /// Model folder (default: models/forecast/DATASET).
    #[arg(long)]
    pub models: Option<PathBuf>,
    /// Also write the tables as Markdown to this file.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

fn spread<T: Clone>(v: &[T], n: Option<usize>) -> Vec<T> {
    match n {
        Some(n) if n < v.len() && n > 0 => (0..n).map(|i| v[i * v.len() / n].clone()).collect(),
        _ => v.to_vec(),
    }
}

fn method(
    name: &str,
    train: &[&Clip],
    models: &mut Option<Arc<ForecastModels>>,
    model_dir: &std::path::Path,
) -> Result<Box<dyn Forecaster>> {
    let mut load = || -> Result<Arc<ForecastModels>> {
        if models.is_none() {
            *models = Some(Arc::new(
                ForecastModels::load(model_dir, &SessionParams::default())
                    .with_context(|| format!("loading {}", model_dir.display()))?,
            ));
        }
        models.clone().context("models not loaded")
    };
    Ok(match name {
        "constant" => Box::new(Constant),
        "nn" => {
            let tracks: Vec<_> = train.iter().map(|c| c.track.clone()).collect();
            let t0 = Instant::now();
            let nn = NearestNeighbour::build(&tracks, NnParams::default())?;
            eprintln!(
                "nn: {} training windows from {} clips ({:.1} s)",
                nn.n_windows(),
                tracks.len(),
                t0.elapsed().as_secs_f64()
            );
            Box::new(nn)
        }
        "loop" => Box::new(LoopUnroll::new(LoopUnroll::default_params(), Some(15))?),
        "loop_all" => Box::new(LoopUnroll::new(LoopUnroll::default_params(), None)?),
        "ar" => Box::new(ArForecaster::new(
            load()?,
            ArSpace::Latent,
            ArParams::default(),
        )?),
        "ar_free" => Box::new(ArForecaster::new(
            load()?,
            ArSpace::Latent,
            ArParams {
                anchored_readout: false,
                ..ArParams::default()
            },
        )?),
        "ar_single" => Box::new(ArForecaster::new(
            load()?,
            ArSpace::Latent,
            ArParams {
                mirror_average: false,
                ..ArParams::default()
            },
        )?),
        "ar_pose" => Box::new(ArForecaster::new(
            load()?,
            ArSpace::Pose,
            ArParams::default(),
        )?),
        other => {
            bail!("unknown method `{other}` (constant, nn, loop, loop_all, ar, ar_free, ar_single, ar_pose)")
        }
    })
}

fn table_md(reports: &[MethodReport], metric: &str, horizons: &[usize]) -> String {
    let mut table = Table::new([metric.to_string()]);
    for h in horizons {
        table.column(h.to_string(), Align::Left);
    }
    for r in reports {
        if let Some(t) = r.metrics.get(metric) {
            let mut cells = vec![r.method.clone()];
            for h in horizons {
                cells.push(format!(
                    "{:.1}",
                    t.overall.get(&format!("h{h}")).copied().unwrap_or(f64::NAN)
                ));
            }
            table.row(cells);
        }
    }
    table.markdown()
}

fn per_action_md(reports: &[MethodReport], metric: &str, h: usize) -> String {
    let mut actions: Vec<String> = Vec::new();
    for r in reports {
        if let Some(t) = r.metrics.get(metric) {
            for a in t.per_action.keys() {
                if !actions.contains(a) {
                    actions.push(a.clone());
                }
            }
        }
    }
    let mut table = Table::new([format!("{metric} @ h{h}")]);
    for r in reports {
        table.column(r.method.clone(), Align::Left);
    }
    let mut groups: Vec<String> = Vec::new();
    for r in reports {
        if let Some(t) = r.metrics.get(metric) {
            for g in t.per_group.keys() {
                if !groups.contains(g) {
                    groups.push(g.clone());
                }
            }
        }
    }
    let rows = actions
        .iter()
        .map(|a| (a.clone(), a, false))
        .chain(groups.iter().map(|g| (format!("**{g}** (group)"), g, true)));
    for (label, key, group) in rows {
        let mut cells = vec![label];
        for r in reports {
            let v = r
                .metrics
                .get(metric)
                .and_then(|t| {
                    if group {
                        t.per_group.get(key)
                    } else {
                        t.per_action.get(key)
                    }
                })
                .and_then(|x| x.get(&format!("h{h}")))
                .copied()
                .unwrap_or(f64::NAN);
            cells.push(format!("{v:.1}"));
        }
        table.row(cells);
    }
    table.markdown()
}

pub fn run(a: &EvalForecastArgs) -> Result<()> {
    let data = match &a.data {
        Some(p) => p.clone(),
        None => mp_geom::data_file("penn_action/penn_action_train.npz")
            .context("no --data and the shared Penn Action train split was not found")?,
    };
    let ds = ForecastDataset::open(&data).with_context(|| format!("reading {}", data.display()))?;
    let (train, val) = ds.split();
    let val = spread(&val, a.max_clips);
    let first = val.first().context("no validation clip")?;
    let mut params = EvalParams::for_track(&first.track);
    if let Some(s) = a.stride {
        params.start_stride_frames = s;
    }
    if ds.kind == "penn_action" {
        params.action_groups.insert(
            "repetitive".into(),
            PENN_REPETITIVE_CLASSES
                .iter()
                .map(|c| c.to_string())
                .collect(),
        );
    }
    let model_dir = match &a.models {
        Some(p) => p.clone(),
        None => ForecastModels::find_dir(ds.kind)
            .unwrap_or_else(|_| PathBuf::from("models/forecast").join(ds.kind)),
    };
    let clips: Vec<Clip> = val.iter().map(|c| (*c).clone()).collect();
    eprintln!(
        "{}: {} validation clips (of {}), {} training clips; starts every {} frame(s)",
        ds.kind,
        clips.len(),
        ds.clips.len() / 10 + 1,
        train.len(),
        params.start_stride_frames
    );
    let mut models = None;
    let mut reports = Vec::new();
    for name in &a.methods {
        let m = match method(name, &train, &mut models, &model_dir) {
            Ok(m) => m,
            Err(e) if name.starts_with("ar") => {
                eprintln!("skipping {name}: {e:#}");
                continue;
            }
            Err(e) => return Err(e),
        };
        let pb = ProgressBar::new(clips.len() as u64);
        pb.set_style(
            ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} clips {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        pb.set_message(name.clone());
        let r = evaluate(m.as_ref(), &clips, &params, |i, _| {
            pb.set_position(i as u64)
        })?;
        pb.finish_and_clear();
        let main = if ds.kind == "penn_action" {
            "pck_dtw"
        } else {
            "pa_mpjpe_dtw"
        };
        let shown: Vec<String> = params
            .horizons
            .iter()
            .map(|h| {
                let v = r
                    .metrics
                    .get(main)
                    .and_then(|t| t.overall.get(&format!("h{h}")))
                    .copied()
                    .unwrap_or(f64::NAN);
                format!("h{h} {v:.1}")
            })
            .collect();
        eprintln!(
            "{name}: {} predictions in {:.1} s; {main}: {}",
            r.predictions,
            r.seconds,
            shown.join(", ")
        );
        reports.push(r);
    }
    let mut methods = serde_json::Map::new();
    for r in &reports {
        let mut m = serde_json::Map::new();
        for (metric, t) in &r.metrics {
            m.insert(metric.clone(), serde_json::to_value(&t.overall)?);
        }
        let per_action: BTreeMap<&String, BTreeMap<&String, &BTreeMap<String, f64>>> = r
            .metrics
            .iter()
            .map(|(metric, t)| (metric, t.per_action.iter().collect()))
            .collect();
        m.insert("per_action".into(), serde_json::to_value(per_action)?);
        let per_group: BTreeMap<&String, BTreeMap<&String, &BTreeMap<String, f64>>> = r
            .metrics
            .iter()
            .map(|(metric, t)| (metric, t.per_group.iter().collect()))
            .collect();
        m.insert("per_group".into(), serde_json::to_value(per_group)?);
        m.insert("predictions".into(), json!(r.predictions));
        m.insert("clips".into(), json!(r.clips));
        m.insert("seconds".into(), json!(r.seconds));
        methods.insert(r.method.clone(), Value::Object(m));
    }
    let report = json!({
        "data": data.display().to_string(),
        "dataset": ds.kind,
        "split": "validation = clips with index % 10 == 0; nearest-neighbour index = the other clips",
        "clips": clips.len(),
        "context_frames": params.context_frames,
        "horizons": params.horizons,
        "start_stride_frames": params.start_stride_frames,
        "units": if ds.kind == "penn_action" { "PCK % (alpha 0.05 of the bbox of visible joints, after optimal scale + translation)" } else { "mm" },
        "dtw": "steps (1,0),(0,1),(1,1) over the predicted window; local cost = mean Euclidean joint distance, summed, no square root",
        "models": model_dir.display().to_string(),
        "methods": methods,
    });
    crate::write_file(&a.out, serde_json::to_string_pretty(&report)?)
        .with_context(|| format!("writing {}", a.out.display()))?;
    eprintln!("report written to {}", a.out.display());
    let metrics: Vec<&str> = if ds.kind == "penn_action" {
        vec!["pck_dtw", "pck"]
    } else {
        vec!["pa_mpjpe_dtw", "pa_mpjpe", "mpjpe_dtw", "mpjpe"]
    };
    let mut md = String::new();
    for m in &metrics {
        md += &table_md(&reports, m, &params.horizons);
        md += "\n";
    }
    md += &per_action_md(&reports, metrics[0], 30);
    md += "\n";
    md += &per_action_md(&reports, metrics[1], 30);
    println!("{md}");
    if let Some(p) = &a.markdown {
        crate::write_file(p, &md).with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::protocol::MetricTable;
    use super::*;

    fn report(method: &str, x: f64) -> MethodReport {
        let scores: BTreeMap<String, f64> = [("h10".to_string(), x), ("h30".to_string(), 2.0 * x)]
            .into_iter()
            .collect();
        let table = MetricTable {
            overall: scores.clone(),
            per_action: [("golf".to_string(), scores.clone())].into_iter().collect(),
            per_group: [("repetitive".to_string(), scores)].into_iter().collect(),
        };
        MethodReport {
            method: method.into(),
            clips: 1,
            predictions: 1,
            seconds: 0.0,
            metrics: [("pck".to_string(), table)].into_iter().collect(),
        }
    }

    #[test]
    fn markdown_tables_layout() {
        let reports = [report("nn", 1.0), report("ar", 2.0)];
        assert_eq!(
            table_md(&reports, "pck", &[10, 30]),
            "| pck | 10 | 30 |\n|---|---|---|\n| nn | 1.0 | 2.0 |\n| ar | 2.0 | 4.0 |\n"
        );
        assert_eq!(
            per_action_md(&reports, "pck", 30),
            "| pck @ h30 | nn | ar |\n|---|---|---|\n| golf | 2.0 | 4.0 |\n| **repetitive** (group) | 2.0 | 4.0 |\n"
        );
    }
}
